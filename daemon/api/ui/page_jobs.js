// Jobs: the list, a page at a time, newest first, with the API's filters;
// live progress and the time left of queued and running jobs; cancel; two
// ticked jobs open the comparison.
import * as api from './api.js';
import { clear, el, errorBox, hashQuery, interval, num, seconds, statusBadge, when } from './util.js';

const STATUSES = ['queued', 'running', 'done', 'failed', 'cancelled', 'interrupted'];
const POLL_MS = 1000;

// The time left of a running job: the daemon's own figure when it gives one
// (seconds_left), else the frames left at the rate of the frames drawn.
export function timeLeft(job, now = Date.now()) {
  const sl = job.seconds_left;
  if (sl && typeof sl === 'object') {
    const v = sl.frames ?? sl.estimate;
    if (typeof v === 'number')
      return { seconds: v, how: sl.rule || 'the daemon\'s estimate' };
  }
  const p = job.progress || {};
  if (job.status !== 'running' || !job.started || !(p.frames_done > 0) || !(p.frames_total > 0))
    return null;
  const elapsed = (now - new Date(job.started).getTime()) / 1000;
  if (!(elapsed > 0))
    return null;
  const left = (elapsed / p.frames_done) * (p.frames_total - p.frames_done);
  return { seconds: left, how: 'the frames left at the rate of the frames drawn so far (set-up included)' };
}

export function progressCell(job) {
  const p = job.progress || {};
  if (job.status !== 'running' && job.status !== 'queued')
    return '';
  const total = p.frames_total || 0, done = p.frames_done || 0;
  const frac = total ? Math.min(1, done / total) : 0;
  const left = timeLeft(job);
  return el('div.progress-cell',
    el('progress', { max: 1, value: frac, title: `${done} of ${total} frames` }),
    el('span.progress-text', `${done}/${total}${job.phase ? ' · ' + job.phase : ''}`),
    left ? el('span.eta', { title: left.how }, `${seconds(left.seconds)} left`) : null,
    job.estimate && job.estimate.duration_s && job.status === 'queued'
      ? el('span.eta', { title: job.estimate.rule || '' }, `~${seconds(job.estimate.duration_s)}`) : null);
}

function figureCell(f) {
  if (!f || typeof f.median !== 'number')
    return '–';
  return el('span', { title: `95% interval ${interval(f.ci95)} over the ${f.over || 'frames'}` },
    `${num(f.median)} ms`, el('small.muted', ` ${interval(f.ci95)}`));
}

async function cancel(job, button) {
  button.disabled = true;
  try {
    await api.send('DELETE', `/v1/jobs/${job.id}`);
  } catch (err) {
    button.title = err.message;
  }
}

export async function render(main) {
  const query = hashQuery();
  const info = await api.info().catch(() => ({}));
  const techniques = (info.techniques || []).map((t) => t.name);
  const form = el('form.filters', { id: 'job-filters' },
    el('label', 'technique ', el('select', { name: 'technique' },
      el('option', { value: '' }, 'any'), techniques.map((t) => el('option', { value: t }, t)))),
    el('label', 'status ', el('select', { name: 'status' },
      el('option', { value: '' }, 'any'), STATUSES.map((s) => el('option', { value: s }, s)))),
    el('label', 'labels ', el('input', { name: 'labels', placeholder: 'branch=main commit=abc', size: 24 })),
    el('label', 'since ', el('input', { name: 'since', type: 'date' })),
    el('label', 'per page ', el('select', { name: 'limit' },
      [25, 50, 100, 250].map((n) => el('option', { value: n }, String(n))))),
    el('button', { type: 'submit' }, 'Filter'),
    el('button#compare-ticked', { type: 'button', disabled: true }, 'Compare ticked'));
  form.technique.value = query.get('technique') || '';
  form.status.value = query.get('status') || '';
  form.since.value = query.get('since') || '';
  form.limit.value = query.get('limit') || '50';
  form.labels.value = [...query.entries()].filter(([k]) => k.startsWith('label.'))
    .map(([k, v]) => `${k.slice(6)}=${v}`).join(' ');
  form.onsubmit = (ev) => {
    ev.preventDefault();
    const q = new URLSearchParams();
    for (const name of ['technique', 'status', 'since', 'limit'])
      if (form[name].value)
        q.set(name, form[name].value);
    for (const pair of form.labels.value.split(/\s+/).filter(Boolean)) {
      const eq = pair.indexOf('=');
      if (eq > 0)
        q.append(`label.${pair.slice(0, eq)}`, pair.slice(eq + 1));
    }
    location.hash = `#/jobs?${q}`;
  };

  // The API's question: the same filters, newest first, this page's cursor.
  const apiQuery = new URLSearchParams();
  for (const [k, v] of query.entries())
    if (k !== 'page')
      apiQuery.append(k, v);
  apiQuery.set('order', 'newest');
  if (!apiQuery.has('limit'))
    apiQuery.set('limit', '50');
  const pageUrl = `/v1/jobs?${apiQuery}`;

  const table = el('table.list#job-list');
  const pager = el('div.pager');
  const status = el('p.muted');
  main.append(el('h1', 'Jobs'), form, status, table, pager);

  const ticked = new Set();
  const compareButton = form.querySelector('#compare-ticked');
  compareButton.onclick = () => {
    const [a, b] = [...ticked];
    location.hash = `#/compare?a=${a}&b=${b}`;
  };

  let timer = null, stopped = false;
  async function load() {
    let page;
    try {
      page = await api.json(pageUrl);
    } catch (err) {
      clear(status).append(errorBox(err));
      return;
    }
    if (stopped)
      return;
    const jobs = page.jobs || [];
    clear(table).append(
      el('thead', el('tr', ['', 'job', 'status', 'technique', 'labels', 'created', 'progress',
        'frame_ms (95% interval)', 'worst SSIM', ''].map((h) => el('th', h)))),
      el('tbody', jobs.map((j) => {
        const figs = j.figures || {};
        const tick = el('input', { type: 'checkbox', title: 'tick two to compare', checked: ticked.has(j.id) });
        tick.onchange = () => {
          tick.checked ? ticked.add(j.id) : ticked.delete(j.id);
          compareButton.disabled = ticked.size !== 2;
        };
        const live = j.status === 'queued' || j.status === 'running';
        const cancelButton = live ? el('button.small', { type: 'button' }, 'Cancel') : null;
        if (cancelButton)
          cancelButton.onclick = () => cancel(j, cancelButton).then(load);
        return el('tr', { dataset: { id: j.id, status: j.status } },
          el('td', tick),
          el('td', el('a', { href: `#/job/${j.id}` }, j.id)),
          el('td', statusBadge(j.status), j.error ? el('div.small.bad', { title: j.error }, j.error.slice(0, 80)) : null),
          el('td', j.technique || ''),
          el('td.labels', Object.entries(j.labels || {}).map(([k, v]) => el('span.tag', `${k}=${v}`))),
          el('td', when(j.created)),
          el('td', progressCell(j)),
          el('td', figureCell(figs.frame_ms)),
          el('td', typeof figs.worst_ssim === 'number' ? num(figs.worst_ssim, 6) : '–'),
          el('td', cancelButton));
      })));
    if (!jobs.length)
      table.append(el('tr', el('td', { colSpan: 10 }, 'No job matches.')));
    clear(status).append(`${jobs.length} job${jobs.length === 1 ? '' : 's'} on this page, newest first`);
    // Pages: the cursors seen, kept in the hash so that Back works.
    const cursor = query.get('cursor');
    clear(pager);
    if (cursor) {
      const first = new URLSearchParams(query);
      first.delete('cursor');
      pager.append(el('a.button', { href: `#/jobs?${first}` }, 'First page'));
    }
    if (page.next) {
      const nextCursor = new URL(page.next, location.origin).searchParams.get('cursor');
      const q = new URLSearchParams(query);
      q.set('cursor', nextCursor);
      pager.append(el('a.button#next-page', { href: `#/jobs?${q}` }, 'Older jobs →'));
    }
    if (jobs.some((j) => j.status === 'queued' || j.status === 'running'))
      timer = setTimeout(load, POLL_MS);
  }
  await load();
  return () => {
    stopped = true;
    clearTimeout(timer);
  };
}
