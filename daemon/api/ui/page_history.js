// History: one workload's figure over time with its intervals, and the
// changes the client's gate would flag (GET /v1/jobs/ID/history). The
// workload is a job's: pick one from the list (filters narrow it), or come
// from a job's page.
import * as api from './api.js';
import * as charts from './charts.js';
import { el, errorBox, hashQuery, interval, num, pct, when } from './util.js';

function describe(workload) {
  const s = workload.scene || {};
  const own = workload[workload.technique];
  return `${workload.technique}${own ? ' ' + JSON.stringify(own) : ''} · ${s.preset || s.asset || ''} ` +
    `${s.width || ''}×${s.height || ''}, ${s.lights ?? ''} lights${s.dynamic ? ', moving' : ''} · ${workload.frames} frames`;
}

export async function render(main) {
  const q = hashQuery();
  const job = q.get('job');
  const figure = q.get('figure') || '';
  main.append(el('h1', 'History'));
  // Choosing the workload: a done job of it.
  const pick = el('form.filters#history-form',
    el('label', 'a job of the workload ', el('input', { name: 'job', value: job || '', size: 24 })),
    el('label', 'figure ', el('select', { name: 'figure' },
      [['', 'the device\'s'], ['frame_ms', 'frame_ms'], ['gpu_ms', 'gpu_ms'], ['cpu_ms', 'cpu_ms']]
        .map(([v, t]) => el('option', { value: v }, t)))),
    el('button', { type: 'submit' }, 'Show'));
  pick.figure.value = figure;
  pick.onsubmit = (ev) => {
    ev.preventDefault();
    const p = new URLSearchParams({ job: pick.job.value.trim() });
    if (pick.figure.value)
      p.set('figure', pick.figure.value);
    location.hash = `#/history?${p}`;
  };
  main.append(pick);
  if (!job) {
    const recent = await api.json('/v1/jobs?status=done&order=newest&limit=20');
    main.append(el('p.muted', 'Pick a workload by one of its jobs: the recent done jobs are'),
      el('ul', (recent.jobs || []).map((j) => el('li', el('a', { href: `#/history?job=${j.id}` }, j.id),
        ` ${j.technique} · ${when(j.created)} · ${num(((j.figures || {}).frame_ms || {}).median)} ms`))));
    return;
  }
  const h = await api.json(`/v1/jobs/${job}/history${figure ? `?figure=${figure}` : ''}`);
  const pts = h.points || [];
  main.append(el('p', el('b', describe(h.workload || {})), el('span.muted',
    ` · ${pts.length} done job${pts.length === 1 ? '' : 's'} of this workload${h.complete ? '' : ` (the newest ${h.scanned} of the technique's jobs were searched)`}`)));
  const changed = new Map();
  for (const c of h.changes || [])
    changed.set(c.to, c);
  if (pts.length) {
    const chartPts = pts.map((p, i) => ({
      series: p.noisy ? 'noisy runs' : (changed.has(p.id) ? `flagged (${changed.get(p.id).change})` : h.figure),
      x: new Date(p.created).getTime() + i * 1e-3, y: p.median, lo: (p.ci95 || [])[0], hi: (p.ci95 || [])[1],
      label: `${p.id}${p.labels && Object.keys(p.labels).length ? ' ' + Object.entries(p.labels).map(([k, v]) => `${k}=${v}`).join(' ') : ''}`,
      onClick: () => { location.hash = `#/job/${p.id}`; },
    }));
    const box = el('section', el('h2', `${h.figure} over time`),
      el('p.muted', 'Median with its 95% interval; click a point to open its job. Drag to zoom.'));
    main.append(box);
    await charts.points(box, chartPts, {
      cls: 'history', xlabel: 'time', ylabel: `${h.figure} (ms)`, lines: false,
      xformat: (v) => new Date(v).toLocaleString(), yformat: (v) => `${num(v)} ms`,
      xaxis: (v) => new Date(v).toLocaleDateString(),
    });
  }
  main.append(el('section', el('h2', 'Changes the gate would flag'),
    (h.changes || []).length ? el('ul.history-changes#history-changes', h.changes.map((c) => el('li',
      el('b', { className: c.change === 'slower' ? 'bad' : 'good' }, c.change), ` by ${pct(Math.abs(c.ratio - 1))}: `,
      el('a', { href: `#/job/${c.from}` }, c.from), ' → ', el('a', { href: `#/job/${c.to}` }, c.to),
      ` (ratio ${num(c.ratio, 4)}, interval ${interval(c.ratio_ci)}) · `,
      el('a', { href: `#/compare?a=${c.from}&b=${c.to}` }, 'compare'))))
      : el('p.muted#history-changes', 'None: no step between two quiet runs is larger than the gate\'s 5% with its interval clear of no change.'),
    el('p.muted.small', (h.rule || {}).change || '')));
  main.append(el('section', el('h2', 'The jobs'), el('table.list',
    el('thead', el('tr', ['job', 'created', `${h.figure} median`, '95% interval', 'over', 'others\' CPU', 'worst SSIM', 'labels'].map((t) => el('th', t)))),
    el('tbody', pts.slice().reverse().map((p) => el('tr', { className: p.noisy ? 'warn' : '' },
      el('td', el('a', { href: `#/job/${p.id}` }, p.id)), el('td', when(p.created)), el('td.num', num(p.median)),
      el('td', interval(p.ci95)), el('td', p.over || ''),
      el('td', p.other_cpu_share === undefined || p.other_cpu_share === null ? '–' : `${pct(p.other_cpu_share)}${p.noisy ? ' (noisy)' : ''}`),
      el('td.num', num(p.worst_ssim, 6)),
      el('td', Object.entries(p.labels || {}).map(([k, v]) => el('span.tag', `${k}=${v}`)))))))));
  void errorBox;
}
