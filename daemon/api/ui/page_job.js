// A job: its headline figures and noise verdict first, then live progress
// (while it runs), frame times over the run and their distribution, the
// time of each pass, every capture with the image comparison against its
// reference, heat maps, and the technique's own figures as tables.
import * as api from './api.js';
import * as charts from './charts.js';
import { ImageCompare } from './imagecmp.js';
import { progressCell } from './page_jobs.js';
import { clear, el, errorBox, fill, interval, num, pct, seconds, statusBadge, valueTable, when } from './util.js';

const POLL_MS = 1000;
// Sections of the result that are not the technique's and have their own place.
const HARNESS_KEYS = new Set(['frames', 'warmup_frames', 'gpu_ms', 'cpu_ms', 'frame_ms', 'runs', 'repeat',
  'gpu_sections_ms', 'captures', 'heatmap', 'quality', 'interference', 'device', 'technique', 'wall_s',
  'wall_s_including_captures', 'fps', 'capture_policy', 'timing_method', 'started_unix', 'fidelity']);

export function seriesFor(result) {
  const r = ((result && result.device) || {}).gl_renderer || '';
  return /llvmpipe|softpipe|SwiftShader/.test(r) ? 'frame_ms' : 'gpu_ms';
}

function figure(name, stats, note) {
  if (!stats || typeof stats.median !== 'number')
    return null;
  return el('div.figure', { dataset: { figure: name } },
    el('div.name', name),
    el('div.value', `${num(stats.median)} ms`),
    el('div.sub', stats.median_ci95 ? `95% ${interval(stats.median_ci95)}` : '',
      stats.p95 !== undefined ? ` · p95 ${num(stats.p95)}` : ''),
    note ? el('div.sub', note) : null);
}

export function noiseVerdict(result) {
  const i = result && result.interference;
  if (!i)
    return el('div.verdict.unknown', 'No interference figures: whether other work disturbed this run is unknown.');
  const share = i.other_cpu_share;
  const load = (i.loadavg_start || [])[0];
  if (i.noisy)
    return el('div.verdict.noisy', el('b', 'Noisy run. '),
      `Other processes took ${pct(share)} of the CPU during the timed frames (load ${num(load, 3)} at the start, ` +
      `${i.cpus} CPUs); its times are inflated: compare it with runs made on a quiet machine. `,
      el('span.muted', i.rule || ''));
  return el('div.verdict.quiet', el('b', 'Quiet run. '),
    `Other processes took ${pct(share)} of the CPU during the timed frames (load ${num(load, 3)}). `,
    el('span.muted', i.rule || ''));
}

export function headline(job) {
  const r = job.result || {};
  const q = r.quality || {};
  const series = seriesFor(r);
  const cards = [
    figure('frame_ms', r.frame_ms, series === 'frame_ms' ? 'the figure that compares techniques on this device' : ''),
    figure('gpu_ms', r.gpu_ms, series === 'gpu_ms' ? 'the figure that compares techniques on this device' : ''),
    figure('cpu_ms', r.cpu_ms),
  ];
  if (typeof r.fps === 'number')
    cards.push(el('div.figure', el('div.name', 'fps'), el('div.value', num(r.fps)),
      el('div.sub', `${r.frames} frames in ${seconds(r.wall_s)}`)));
  if (q.worst_ssim)
    cards.push(el('div.figure', { dataset: { figure: 'worst_ssim' } }, el('div.name', 'worst SSIM'),
      el('div.value', num(q.worst_ssim.value, 6)), el('div.sub', `frame ${q.worst_ssim.frame} against ${q.reference}`)));
  if (q.worst_flip)
    cards.push(el('div.figure', el('div.name', 'worst FLIP'), el('div.value', num(q.worst_flip.mean ?? q.worst_flip.value, 4)),
      el('div.sub', `mean over frame ${q.worst_flip.frame}; max ${num(q.worst_flip.max, 3)}`)));
  if (q.worst_psnr)
    cards.push(el('div.figure', el('div.name', 'worst PSNR'),
      el('div.value', q.worst_psnr.value === null ? '∞' : `${num(q.worst_psnr.value, 4)} dB`), el('div.sub', `frame ${q.worst_psnr.frame}`)));
  if (q.captures_compared !== undefined)
    cards.push(el('div.figure', el('div.name', 'PerceptualDiff'),
      el('div.value', q.pdiff_failed_captures ? `${q.pdiff_failed_captures} failed` : 'passes'),
      el('div.sub', `${q.captures_compared} captures compared`)));
  if (r.repeat)
    cards.push(el('div.figure', el('div.name', 'runs'), el('div.value', String((r.runs || []).length)),
      el('div.sub', r.repeat.stable === false ? 'the interval never tightened' : 'stable')));
  return el('div.headline', cards.filter(Boolean));
}

function passTable(r) {
  const sections = r.gpu_sections_ms;
  if (!sections || !Object.keys(sections).length)
    return null;
  const total = Object.values(sections).reduce((s, v) => s + (v.median || 0), 0) || 1;
  return el('table.list.passes',
    el('thead', el('tr', ['pass', 'median GPU ms', '95% interval', 'p95', 'share of the passes', ''].map((h) => el('th', h)))),
    el('tbody', Object.entries(sections).map(([name, s]) => el('tr',
      el('td', name), el('td.num', num(s.median)), el('td', interval(s.median_ci95)), el('td.num', num(s.p95)),
      el('td.num', pct((s.median || 0) / total)),
      el('td', el('div.bar', { style: { width: `${Math.round(200 * (s.median || 0) / total)}px` } }))))));
}

function runsTable(r) {
  if (!r.runs || !r.runs.length)
    return null;
  return el('table.list.runs',
    el('thead', el('tr', ['run', 'frame_ms median', 'gpu_ms median', 'cpu_ms median', 'wall s', 'others\' CPU'].map((h) => el('th', h)))),
    el('tbody', r.runs.map((run, i) => el('tr', el('td', String(i + 1)),
      el('td.num', num((run.frame_ms || {}).median)), el('td.num', num((run.gpu_ms || {}).median)),
      el('td.num', num((run.cpu_ms || {}).median)), el('td.num', num(run.wall_s)),
      el('td', run.interference ? `${pct(run.interference.other_cpu_share)}${run.interference.noisy ? ' (noisy)' : ''}` : '–')))));
}

async function captureSection(job, cap, heat) {
  const m = cap.metrics || {};
  const box = el('section.capture', { dataset: { frame: cap.frame } },
    el('h3', `Frame ${cap.frame}`));
  const facts = [];
  if (m.ssim !== undefined)
    facts.push(`SSIM ${num(m.ssim, 6)}`);
  if (m.ssim_min)
    facts.push(`worst window ${num(m.ssim_min.value, 4)} at ${m.ssim_min.x}, ${m.ssim_min.y}`);
  if (m.flip)
    facts.push(`FLIP mean ${num(m.flip.mean, 4)}`);
  if (m.psnr)
    facts.push(`PSNR ${m.psnr.overall === null ? '∞' : num(m.psnr.overall, 4) + ' dB'}`);
  if (m.pdiff)
    facts.push(`PerceptualDiff ${m.pdiff.pass ? 'passes' : 'fails'}: ${(m.pdiff.failing_pixels || 0).toLocaleString('en-US')} failing pixels (threshold ${m.pdiff.threshold_pixels})`);
  if (cap.nonfinite && cap.nonfinite.pixels)
    facts.push(`${cap.nonfinite.pixels} non-finite pixels`);
  if (facts.length)
    box.append(el('p.facts', facts.join(' · ')));
  if (cap.reference_url) {
    const ref = (job.result.quality || {}).reference || 'reference';
    const cmp = new ImageCompare({
      a: { url: cap.url, label: job.technique },
      b: { url: cap.reference_url, label: ref },
      maps: { ssim: cap.ssim_map_url, flip: cap.flip_map_url, pdiff: cap.pdiff_mask_url },
      worst: m.ssim_min, pdiffCount: m.pdiff ? m.pdiff.failing_pixels : undefined,
    });
    await cmp.mount(box);
  } else {
    const img = el('img.full', { alt: `frame ${cap.frame}` });
    api.imageUrl(cap.url).then((u) => { img.src = u; });
    box.append(img);
  }
  if (heat) {
    const img = el('img.heat', { alt: `light evaluations per pixel, frame ${cap.frame}` });
    api.imageUrl(heat.url).then((u) => { img.src = u; });
    // One scale for every job and technique where the daemon states it
    // (heatmap.scale), else the capture's own (scale_max).
    const scale = job.result.heatmap.scale;
    const how = scale
      ? `${scale.kind || 'log'} scale, white = ${num(scale.max)} evaluations, the same for every job and technique` +
        `${scale.legend ? `; ${scale.legend}` : ''}`
      : `white = ${num(heat.scale_max)} evaluations (this capture's own scale; ${job.result.heatmap.ramp || ''})`;
    box.append(el('div.heatmap', el('h4', 'Light evaluations per pixel'), img,
      el('p.muted', `mean ${num(heat.mean)}, max ${num(heat.max)}; ${how}`)));
  }
  return box;
}

// A fidelity job's comparison with the Khronos glTF Sample Viewer
// (result.fidelity): each channel's figures, and its two images in the
// image comparison with the channel's SSIM and FLIP maps.
async function fidelitySection(job) {
  const f = job.result.fidelity;
  const channels = Object.entries(f.channels || {});
  const box = el('section.fidelity', el('h2', 'Fidelity against the Khronos glTF Sample Viewer'),
    el('p.muted', `${f.viewer || f.renderer || ''} in ${f.browser || 'Chromium'} (${f.webgl_renderer || 'WebGL'}); ` +
      `the viewer's image is B, the reference of every figure${f.cache_hit ? '; from the cache' : ''}.`),
    el('table.list#fidelity-channels',
      el('thead', el('tr', ['channel', 'SSIM', 'worst window', 'FLIP mean', 'PerceptualDiff', 'PSNR',
        'pixels off by > 8', '> 32', 'largest difference'].map((h) => el('th', h)))),
      el('tbody', channels.map(([name, c]) => el('tr', { dataset: { channel: name } }, el('td', name),
        c.error ? el('td.bad', { colSpan: 8 }, c.error) : [
          el('td.num', num(c.ssim, 6)), el('td.num', c.ssim_min ? num(c.ssim_min.value, 4) : '–'),
          el('td.num', num((c.flip || {}).mean, 4)),
          el('td', c.pdiff ? `${c.pdiff.pass ? 'passes' : 'fails'}, ${c.pdiff.failing_pixels} failing` : '–'),
          el('td.num', c.psnr ? (c.psnr.overall === null ? '∞' : `${num(c.psnr.overall, 4)} dB`) : '–'),
          el('td.num', num(c.pixels_over_8)), el('td.num', num(c.pixels_over_32)), el('td.num', num(c.max_difference)),
        ])))));
  for (const [name, c] of channels) {
    if (c.error || !c.files)
      continue;
    const url = (file) => `${job.url}/${file}`;
    const sub = el('section.capture', { dataset: { channel: name } }, el('h3', name));
    box.append(sub);
    await new ImageCompare({
      a: { url: url(c.files.shadebench), label: `shadebench ${job.technique}` },
      b: { url: url(c.files.khronos), label: 'Khronos viewer' },
      maps: { ssim: c.files.ssim_map && url(c.files.ssim_map), flip: c.files.flip_map && url(c.files.flip_map) },
      worst: c.ssim_min && c.ssim_min.x !== undefined ? c.ssim_min : undefined,
      pdiffCount: c.pdiff ? c.pdiff.failing_pixels : undefined,
    }).mount(sub);
  }
  return box;
}

export async function render(main, id) {
  let job = await api.json(`/v1/jobs/${id}`);
  const head = el('div.job-head');
  const live = el('div.live');
  const body = el('div.job-body');
  main.append(head, live, body);
  let timer = null, stopped = false;

  function drawHead() {
    const spec = job.spec || {};
    const cancel = job.status === 'queued' || job.status === 'running'
      ? el('button#cancel-job', { type: 'button' }, 'Cancel') : null;
    if (cancel)
      cancel.onclick = async () => {
        cancel.disabled = true;
        try { await api.send('DELETE', `/v1/jobs/${id}`); } catch (err) { cancel.title = err.message; }
        poll();
      };
    fill(head, 
      el('h1', `Job ${job.id} `, statusBadge(job.status)),
      el('p', el('b', job.technique), ' · ', `${(spec.scene || {}).preset || (spec.scene || {}).asset || ''} `,
        `${(spec.scene || {}).width || ''}×${(spec.scene || {}).height || ''}`,
        ` · ${spec.frames || ''} frames · created ${when(job.created)}`,
        job.finished ? ` · finished ${when(job.finished)}` : '',
        Object.entries(job.labels || spec.labels || {}).map(([k, v]) => el('span.tag', `${k}=${v}`))),
      el('p.links', job.status === 'done' ? [
        el('a', { href: `#/compare?a=${id}` }, 'Compare with another job'), ' · ',
        el('a', { href: `#/history?job=${id}` }, 'History of this workload'), ' · ',
        el('a', { href: job.url + '/report.html', target: '_blank' }, 'report.html'), ' · ',
        el('a', { href: job.timings_url, target: '_blank' }, 'timings.csv'), ' · ',
      ] : null, el('a', { href: job.url, target: '_blank' }, 'JSON'), ' ', cancel),
      job.error ? el('p.error', job.error) : null);
  }

  async function poll(fresh = false) {
    try {
      if (!fresh)
        job = await api.json(`/v1/jobs/${id}`);
    } catch (err) {
      live.replaceChildren(errorBox(err));
    }
    if (stopped)
      return;
    drawHead();
    if (job.status === 'queued' || job.status === 'running') {
      live.replaceChildren(el('h2', 'Progress'), progressCell(job));
      timer = setTimeout(poll, POLL_MS);
    } else {
      live.replaceChildren();
      if (job.status === 'done' && !body.firstChild)
        await drawResult();
    }
  }

  async function drawResult() {
    const r = job.result || {};
    // Everything the page shows is asked for at once, drawn as it comes.
    const timings = api.text(job.timings_url);
    timings.catch(() => {});
    for (const cap of r.captures || [])
      for (const url of [cap.url, cap.reference_url])
        if (url)
          api.imageUrl(url).catch(() => {});
    body.append(noiseVerdict(r), headline(job));
    // Frame times.
    const series = seriesFor(r);
    const timesBox = el('section.times', el('h2', 'Frame times'),
      el('p.muted', `Drag to zoom, double-click to zoom out; ${series} is the figure that compares techniques on this device.`));
    body.append(timesBox);
    try {
      const csv = charts.parseCsv(await timings);
      const shown = ['frame_ms', 'gpu_ms', 'cpu_ms'].filter((s) => csv.header.includes(s));
      await charts.frameTimes(timesBox, csv, shown);
      const col = csv.header.indexOf(series);
      timesBox.append(el('h3', `Distribution of ${series}`));
      await charts.histogram(timesBox, csv.rows.map((row) => row[col]), series);
    } catch (err) {
      timesBox.append(errorBox(err));
    }
    const passes = passTable(r);
    if (passes)
      body.append(el('section', el('h2', 'Time per pass'), passes));
    const runs = runsTable(r);
    if (runs)
      body.append(el('section', el('h2', 'Runs'), runs));
    // Captures, with their heat maps.
    const heat = new Map(((r.heatmap || {}).captures || []).map((h) => [h.frame, h]));
    if ((r.captures || []).length) {
      const caps = el('section.captures', el('h2', 'Captures'));
      body.append(caps);
      for (const cap of r.captures)
        caps.append(await captureSection(job, cap, heat.get(cap.frame)));
    }
    if (r.fidelity)
      body.append(await fidelitySection(job));
    // The technique's own figures, then the rest of the result.
    const own = r[job.technique];
    if (own && typeof own === 'object')
      body.append(el('section.technique', el('h2', `${job.technique}'s figures`), valueTable(own)));
    const rest = Object.keys(r).filter((k) => !HARNESS_KEYS.has(k) && k !== job.technique);
    const more = el('section.more', el('h2', 'Everything else the result says'));
    const scalars = Object.fromEntries(rest.filter((k) => r[k] === null || typeof r[k] !== 'object').map((k) => [k, r[k]]));
    more.append(valueTable(scalars));
    for (const k of rest.filter((k) => r[k] !== null && typeof r[k] === 'object'))
      more.append(el('details', el('summary', k), valueTable(r[k])));
    more.append(el('details', el('summary', 'device'), valueTable(r.device)),
      el('details', el('summary', 'spec (the job as understood)'), valueTable(job.spec)));
    body.append(more);
  }

  drawHead();
  await poll(true);
  return () => {
    stopped = true;
    clearTimeout(timer);
  };
}
