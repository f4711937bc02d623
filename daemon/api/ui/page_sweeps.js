// Sweeps: the list, and a sweep's page: the summary first (per workload,
// the fastest technique and its ratio to the reference, with intervals,
// from the daemon's verdict), the verdict's findings, the table, and the
// interactive charts (speed against accuracy on an axis that spreads the
// points, time against the swept parameter); a click on a point opens its
// job.
import * as api from './api.js';
import * as charts from './charts.js';
import { clear, el, errorBox, fill, hashQuery, interval, num, pct, statusBadge, when } from './util.js';

const POLL_MS = 2000;

// An id is the UTC second of its submission and a serial:
// 20261121-113512-0003.
function idTime(id) {
  const m = /^(\d{4})(\d\d)(\d\d)-(\d\d)(\d\d)(\d\d)/.exec(id || '');
  return m ? `${m[1]}-${m[2]}-${m[3]}T${m[4]}:${m[5]}:${m[6]}Z` : null;
}

export async function renderList(main) {
  const q = hashQuery();
  const url = `/v1/sweeps?order=newest&limit=50${q.get('cursor') ? `&cursor=${encodeURIComponent(q.get('cursor'))}` : ''}`;
  const page = await api.json(url);
  const sweeps = page.sweeps || [];
  main.append(el('h1', 'Sweeps'),
    el('p.muted', 'Start one with ', el('code', 'curl -d @examples/sweep-async.json $S/v1/sweeps'), ' or ',
      el('code', 'shadebench sweep'), '.'),
    el('table.list#sweep-list',
      el('thead', el('tr', ['sweep', 'status', 'kind', 'points', 'submitted'].map((h) => el('th', h)))),
      el('tbody', sweeps.map((s) => el('tr', { dataset: { id: s.id } },
        el('td', el('a', { href: `#/sweep/${s.id}` }, s.id)), el('td', statusBadge(s.status)),
        el('td', s.preset || s.kind || ''),
        el('td', `${(s.progress || {}).points_done ?? ''}/${(s.progress || {}).points_total ?? ''}`),
        el('td', when(s.created || idTime(s.id))))))));
  if (!sweeps.length)
    main.append(el('p.muted', 'No sweep yet.'));
  if (page.next) {
    const cursor = new URL(page.next, location.origin).searchParams.get('cursor');
    main.append(el('div.pager', el('a.button', { href: `#/sweeps?cursor=${encodeURIComponent(cursor)}` }, 'Older sweeps →')));
  }
}

function valuesText(values, skipTechnique = true) {
  return Object.entries(values || {}).filter(([k]) => !(skipTechnique && k === 'technique'))
    .map(([k, v]) => `${k}=${typeof v === 'object' ? JSON.stringify(v) : v}`).join(', ');
}

function ratioText(f) {
  if (!f || typeof f.ratio !== 'number')
    return '–';
  return `${num(f.ratio, 3)}× ${f.ratio_ci ? interval(f.ratio_ci) : ''}`;
}

function summaryTable(verdict) {
  const rows = verdict.against_reference || [];
  if (!rows.length)
    return el('p.muted', 'No workload has a timed reference to compare with.');
  return el('table.list.summary#sweep-summary',
    el('thead', el('tr', ['workload', 'reference (ms)', 'wins', 'fastest swept point', 'its time (ms)', 'ratio to the reference [95%]',
      'tied with', 'fastest passing PerceptualDiff', 'its ratio'].map((h) => el('th', h)))),
    el('tbody', rows.map((w) => {
      const f = w.fastest || {}, p = w.fastest_passing || {}, win = w.winner || {};
      return el('tr',
        el('td', w.workload || 'all points'),
        el('td', `${w.reference || ''} ${num(w.reference_ms)} `, el('small.muted', interval(w.reference_ci))),
        el('td.winner', el('b', win.technique || '–'),
          win.values ? el('div.small.muted', valuesText(win.values)) : null,
          win.reference ? el('div.small', 'the reference') : null,
          win.tied_with_reference ? el('div.small', 'not told apart from the reference') : null),
        el('td', el('b', f.technique || '–'), f.values ? el('div.small.muted', valuesText(f.values)) : null),
        el('td.num', num(f.ms)),
        el('td', { className: f.distinguishable ? (f.ratio < 1 ? 'good' : 'bad') : 'muted' }, ratioText(f),
          f.distinguishable === false ? el('div.small', 'not distinguishable at this noise') : null),
        el('td', (f.tied_with || []).map((t) => (typeof t === 'string' ? t : `${t.technique} ${valuesText(t.values)}`)).join('; ') || '–'),
        el('td', p.technique ? `${p.technique} ${valuesText(p.values)}` : '–'),
        el('td', ratioText(p)));
    })));
}

function findings(verdict) {
  const items = [];
  if (verdict.partial)
    items.push(el('li.bad', `Partial: ${(verdict.missing || []).length} point(s) did not finish`,
      (verdict.missing || []).length ? `: ${verdict.missing.map((m) => `${m.technique} ${valuesText(m.values)} (${m.status})`).join('; ')}` : ''));
  for (const n of verdict.noisy || [])
    items.push(el('li.warn', `Noisy: ${n.technique} ${valuesText(n.values)} (others took ${pct(n.other_cpu_share)} of the CPU)`));
  if (verdict.largest_pdiff_pass)
    items.push(el('li', `Largest ${verdict.largest_pdiff_pass.param} passing PerceptualDiff: `,
      el('b', verdict.largest_pdiff_pass.value === null ? 'none' : String(verdict.largest_pdiff_pass.value))));
  else if (verdict.pdiff_judged)
    items.push(el('li', `${(verdict.pdiff_passing || []).length} of ${verdict.pdiff_judged} judged points pass PerceptualDiff`));
  for (const c of verdict.crossovers || [])
    items.push(el('li', c.distinguishable
      ? `${c.faster_below} is faster below and ${c.faster_above} above ${c.param} ≈ ${num(c.at)} (between ${(c.between || []).join(' and ')})`
      : `By their medians ${c.faster_below} and ${c.faster_above} cross between ${(c.between || []).join(' and ')}, but their intervals overlap: not distinguishable at this noise`,
    c.workload ? ` (${c.workload})` : ''));
  for (const f of verdict.front || [])
    items.push(el('li', `Pareto front${f.workload ? ` (${f.workload})` : ''}: `,
      (f.points || []).map((p) => `${p.name} ${num(p.ms)} ms${p.tied ? ' (tied)' : ''}`).join(' → ')));
  if (verdict.breaking_point)
    items.push(el('li', `Breaking point: ${JSON.stringify(verdict.breaking_point)}`));
  return el('ul.findings', items);
}

function pointTable(sweep, series) {
  const rows = sweep.points || [];
  const fields = [...new Set(rows.flatMap((r) => Object.keys(r.values || {})))].filter((f) => f !== 'technique');
  return el('table.list.points#sweep-points',
    el('thead', el('tr', [...fields, 'technique', 'status', `${series} (ms)`, '95% interval', 'worst SSIM',
      'worst FLIP', 'PerceptualDiff failed', 'job'].map((h) => el('th', h)))),
    el('tbody', rows.map((r) => {
      const cell = r[series] || {};
      return el('tr', { dataset: { job: r.job || '' } },
        fields.map((f) => el('td', r.values && f in r.values ? String(r.values[f]) : '')),
        el('td', r.technique || ''), el('td', statusBadge(r.status)),
        el('td.num', num(cell.median)), el('td', interval(cell.ci95)),
        el('td.num', num(r.worst_ssim, 6)), el('td.num', num(r.worst_flip)),
        el('td.num', r.pdiff_failed_captures ?? '–'),
        el('td', r.job ? el('a', { href: `#/job/${r.job}` }, r.job) : ''));
    })));
}

// Speed against accuracy: x the time, y the worst SSIM on -log10(1 - SSIM),
// as the report's chart has it, so that 0.999, 0.9999 and 0.99999 are a
// decade apart instead of a hair at the top of 0.99 to 1; exact points
// (the reference) sit at the top, a decade above the best inexact score.
function ssimText(ssim) {
  if (ssim >= 1)
    return '1 (exact)';
  const nines = Math.max(2, Math.ceil(-Math.log10(1 - ssim) - 1e-9));
  return ssim.toFixed(Math.min(8, nines + 1)).replace(/0$/, '');
}

function speedAccuracy(parent, sweep, series, reference) {
  const rows = (sweep.points || []).filter((r) => r[series] && typeof r[series].median === 'number');
  const losses = rows.map((r) => 1 - r.worst_ssim).filter((v) => Number.isFinite(v) && v > 0);
  const floor = losses.length ? Math.min(...losses) / 10 : 1e-6;
  const top = -Math.log10(floor);
  const pts = rows.filter((r) => typeof r.worst_ssim === 'number' || r.technique === reference).map((r) => {
    const ssim = typeof r.worst_ssim === 'number' ? r.worst_ssim : 1;
    return {
      series: r.technique, x: r[series].median, y: -Math.log10(Math.max(1 - ssim, floor)), ssim,
      label: `${valuesText(r.values)} (SSIM ${ssimText(ssim)})`,
      onClick: r.job ? () => { location.hash = `#/job/${r.job}`; } : null, job: r.job,
    };
  });
  if (!pts.length)
    return parent.append(el('p.muted', 'No point has both a time and an SSIM yet.'));
  parent.append(el('h3', 'Speed against accuracy'),
    el('p.muted', `x: median ${series}; y: the worst SSIM on a log scale of 1 − SSIM (higher is more accurate; the top line is exact). Click a point to open its job.`));
  const bottom = Math.min(2, ...pts.map((p) => p.y));
  return charts.points(parent, pts, {
    cls: 'speed-accuracy', xlabel: `${series} (ms)`, ylabel: 'worst SSIM',
    yformat: (v) => ssimText(v >= top - 1e-9 ? 1 : 1 - 10 ** -v),
    yaxis: (v) => ssimText(v >= top - 1e-9 ? 1 : 1 - 10 ** -v),
    yticker: () => {
      const ticks = [];
      const fine = top - bottom < 3;
      for (let e = Math.floor(bottom); e <= Math.ceil(top); e++)
        for (const m of fine ? [5, 2, 1] : [1]) {
          const v = -Math.log10(m * 10 ** -e);
          if (v >= bottom - 0.3 && v < top - 0.3)
            ticks.push({ v, label: ssimText(1 - m * 10 ** -e) });
        }
      ticks.push({ v: top, label: '1 (exact)' });
      return ticks;
    },
  });
}

function timeVsParam(parent, sweep, series, verdict) {
  const rows = (sweep.points || []).filter((r) => r[series] && typeof r[series].median === 'number');
  const numeric = [...new Set(rows.flatMap((r) => Object.entries(r.values || {})
    .filter(([, v]) => typeof v === 'number').map(([k]) => k)))];
  const param = numeric[0];
  if (!param)
    return null;
  const xs = rows.map((r) => r.values[param]).filter((v) => typeof v === 'number');
  const logx = xs.every((v) => v > 0) && Math.max(...xs) / Math.min(...xs) > 10;
  const pts = rows.filter((r) => typeof r.values[param] === 'number').map((r) => {
    const rest = Object.entries(r.values).filter(([k]) => k !== param && k !== 'technique')
      .map(([k, v]) => `${k}=${v}`).join(', ');
    return {
      series: rest ? `${r.technique} ${rest}` : r.technique, x: r.values[param], y: r[series].median,
      lo: (r[series].ci95 || [])[0], hi: (r[series].ci95 || [])[1], label: `${param}=${r.values[param]}`,
      onClick: r.job ? () => { location.hash = `#/job/${r.job}`; } : null,
    };
  });
  // The reference, timed once per workload without the parameter: a level
  // across the chart, with its interval.
  const xs2 = pts.map((p) => p.x);
  for (const r of rows.filter((q) => typeof q.values[param] !== 'number'))
    for (const x of [Math.min(...xs2), Math.max(...xs2)])
      pts.push({
        series: `${r.technique} (reference)`, x, y: r[series].median, lo: (r[series].ci95 || [])[0],
        hi: (r[series].ci95 || [])[1], label: valuesText(r.values, false),
        onClick: r.job ? () => { location.hash = `#/job/${r.job}`; } : null,
      });
  parent.append(el('h3', `Time against ${param}`),
    el('p.muted', `Median ${series} with its 95% interval, a line per technique${logx ? '; x logarithmic' : ''}. Click a point to open its job.`));
  void verdict;
  return charts.points(parent, pts, {
    cls: 'time-param', xlabel: param, ylabel: `${series} (ms)`, logx, lines: true,
    yformat: (v) => `${num(v)} ms`,
  });
}

export async function render(main, id) {
  const head = el('div');
  const body = el('div');
  main.append(head, body);
  let timer = null, stopped = false;
  async function load() {
    const sweep = await api.json(`/v1/sweeps/${id}`);
    if (stopped)
      return;
    const verdict = await api.json(`/v1/sweeps/${id}/verdict`).catch(() => ({}));
    const series = verdict.series || 'frame_ms';
    const cancel = sweep.status === 'queued' || sweep.status === 'running'
      ? el('button', { type: 'button' }, 'Cancel') : null;
    if (cancel)
      cancel.onclick = async () => {
        cancel.disabled = true;
        try { await api.send('DELETE', `/v1/sweeps/${id}`); } catch (err) { cancel.title = err.message; }
      };
    const p = sweep.progress || {};
    fill(head, el('h1', `Sweep ${id} `, statusBadge(sweep.status)),
      el('p', `${p.points_done}/${p.points_total} points`, sweep.current_job ? [' · running ',
        el('a', { href: `#/job/${sweep.current_job}` }, sweep.current_job)] : '',
      ' · varies ', Object.keys(((sweep.spec || {}).vary) || ((sweep.spec || {}).find ? { [sweep.spec.find.param]: 1 } : {})).join(', '),
      ' · ', el('a', { href: `${sweep.url}/report.html`, target: '_blank' }, 'report.html'),
      ' · ', el('a', { href: sweep.url, target: '_blank' }, 'JSON'), ' ', cancel),
      sweep.error ? el('p.error', sweep.error) : null);
    fill(body, 
      el('section', el('h2', 'Which technique wins where'), summaryTable(verdict), findings(verdict)),
      el('section', el('h2', 'The table'), pointTable(sweep, series)));
    const chartBox = el('section.sweep-charts', el('h2', 'Charts'));
    body.append(chartBox);
    await speedAccuracy(chartBox, sweep, series, verdict.reference || ((sweep.spec || {}).base || {}).reference);
    await timeVsParam(chartBox, sweep, series, verdict);
    if (sweep.status === 'queued' || sweep.status === 'running')
      timer = setTimeout(() => load().catch((err) => body.append(errorBox(err))), POLL_MS);
  }
  await load();
  return () => {
    stopped = true;
    clearTimeout(timer);
  };
}
