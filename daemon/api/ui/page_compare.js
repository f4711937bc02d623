// Two jobs side by side: their figures (with B's ratio to A), their frame
// times on one chart, and each frame both captured with the image
// comparison (A against B).
import * as api from './api.js';
import * as charts from './charts.js';
import { ImageCompare } from './imagecmp.js';
import { noiseVerdict, seriesFor } from './page_job.js';
import { el, errorBox, hashQuery, interval, num } from './util.js';

function row(name, a, b, digits = 4) {
  const ratio = typeof a === 'number' && typeof b === 'number' && a !== 0 ? b / a : null;
  return el('tr', el('th', name), el('td.num', num(a, digits)), el('td.num', num(b, digits)),
    el('td.num', ratio === null ? '' : `${num(ratio, 3)}×`));
}

export async function render(main) {
  const q = hashQuery();
  const form = el('form.filters', { id: 'compare-form' },
    el('label', 'job A ', el('input', { name: 'a', value: q.get('a') || '', size: 24, placeholder: '20261121-113512-0003' })),
    el('label', 'job B ', el('input', { name: 'b', value: q.get('b') || '', size: 24 })),
    el('button', { type: 'submit' }, 'Compare'));
  form.onsubmit = (ev) => {
    ev.preventDefault();
    location.hash = `#/compare?a=${encodeURIComponent(form.a.value.trim())}&b=${encodeURIComponent(form.b.value.trim())}`;
  };
  main.append(el('h1', 'Compare two jobs'), form);
  const a = q.get('a'), b = q.get('b');
  if (!a || !b) {
    main.append(el('p.muted', 'Give two job ids, or tick two jobs in the job list.'));
    return;
  }
  const [ja, jb] = await Promise.all([api.json(`/v1/jobs/${a}`), api.json(`/v1/jobs/${b}`)]);
  const ra = ja.result || {}, rb = jb.result || {};
  const label = (j) => `${j.technique} (${j.id})`;
  main.append(el('table.list.compare-figures',
    el('thead', el('tr', el('th', ''), el('th', el('a', { href: `#/job/${a}` }, `A: ${label(ja)}`)),
      el('th', el('a', { href: `#/job/${b}` }, `B: ${label(jb)}`)), el('th', 'B / A'))),
    el('tbody',
      ['frame_ms', 'gpu_ms', 'cpu_ms'].map((s) => [
        row(`${s} median`, (ra[s] || {}).median, (rb[s] || {}).median),
        el('tr', el('th.sub', '95% interval'), el('td', interval((ra[s] || {}).median_ci95)),
          el('td', interval((rb[s] || {}).median_ci95)), el('td', '')),
      ]),
      row('fps', ra.fps, rb.fps),
      row('worst SSIM', ((ra.quality || {}).worst_ssim || {}).value, ((rb.quality || {}).worst_ssim || {}).value, 6),
      row('worst FLIP (mean)', ((ra.quality || {}).worst_flip || {}).mean, ((rb.quality || {}).worst_flip || {}).mean),
      row('triangles per frame', ra.triangles_per_frame, rb.triangles_per_frame),
      row('lights', ra.lights, rb.lights))));
  main.append(el('div.two', el('div', el('h3', 'A'), noiseVerdict(ra)), el('div', el('h3', 'B'), noiseVerdict(rb))));

  const times = el('section', el('h2', 'Frame times'));
  main.append(times);
  try {
    const series = seriesFor(ra);
    const [ca, cb] = await Promise.all([api.text(ja.timings_url), api.text(jb.timings_url)]).then((t) => t.map(charts.parseCsv));
    const ia = ca.header.indexOf(series), ib = cb.header.indexOf(series);
    const n = Math.max(ca.rows.length, cb.rows.length);
    const rows = [];
    for (let k = 0; k < n; k++)
      rows.push([k + 1, ca.rows[k] ? ca.rows[k][ia] : NaN, cb.rows[k] ? cb.rows[k][ib] : NaN]);
    await charts.frameTimes(times, { header: ['frame', `A ${series}`, `B ${series}`], rows }, [`A ${series}`, `B ${series}`]);
  } catch (err) {
    times.append(errorBox(err));
  }

  const capsB = new Map((rb.captures || []).map((c) => [c.frame, c]));
  const shared = (ra.captures || []).filter((c) => capsB.has(c.frame));
  const caps = el('section.captures', el('h2', 'Captures'));
  main.append(caps);
  if (!shared.length)
    caps.append(el('p.muted', 'The two jobs captured no frame in common.'));
  for (const c of shared) {
    const box = el('section.capture', { dataset: { frame: c.frame } }, el('h3', `Frame ${c.frame}`));
    caps.append(box);
    await new ImageCompare({ a: { url: c.url, label: label(ja) }, b: { url: capsB.get(c.frame).url, label: label(jb) },
      maps: {}, diffKind: 'abs' }).mount(box);
  }
}
