// The dashboard's router: pages by the URL's hash (#/jobs, #/job/ID,
// #/compare?a=ID&b=ID, #/sweeps, #/sweep/ID, #/history, #/assets), each a
// module whose render(main, arg) may return a function that stops it
// (polling) when the page changes.
import * as api from './api.js';
import { clear, el, errorBox } from './util.js';
import * as jobs from './page_jobs.js';
import * as job from './page_job.js';
import * as compare from './page_compare.js';
import * as sweeps from './page_sweeps.js';
import * as history from './page_history.js';
import * as assets from './page_assets.js';

const ROUTES = [
  [/^#\/jobs(?:\?.*)?$/, 'jobs', () => jobs.render],
  [/^#\/job\/([0-9-]+)/, 'jobs', () => job.render],
  [/^#\/compare/, 'compare', () => compare.render],
  [/^#\/sweeps(?:\?.*)?$/, 'sweeps', () => sweeps.renderList],
  [/^#\/sweep\/([0-9-]+)/, 'sweeps', () => sweeps.render],
  [/^#\/history/, 'history', () => history.render],
  [/^#\/assets(?:\?.*)?$/, 'assets', () => assets.renderList],
  [/^#\/asset\/(.+)$/, 'assets', () => assets.render],
];

let stop = null;
let generation = 0;

async function route() {
  const gen = ++generation;
  if (stop) {
    try { stop(); } catch (e) { /* already gone */ }
    stop = null;
  }
  // Each page renders into a view of its own, so that a page left while it
  // loads writes into a detached view, never into the next page's.
  const main = el('div.view');
  clear(document.getElementById('main')).append(main);
  const hash = location.hash || '#/jobs';
  for (const [re, nav, page] of ROUTES) {
    const m = hash.match(re);
    if (!m)
      continue;
    document.querySelectorAll('[data-nav]').forEach((a) =>
      a.classList.toggle('active', a.dataset.nav === nav));
    try {
      const result = await page()(main, m[1] ? decodeURIComponent(m[1]) : undefined);
      if (typeof result === 'function') {
        if (gen !== generation)
          result(); // left while it loaded: stop its polling now
        else
          stop = result;
      }
    } catch (err) {
      if (gen === generation)
        main.append(errorBox(err));
    }
    if (gen !== generation)
      return;
    document.body.dataset.page = nav;
    document.body.dataset.ready = hash;
    return;
  }
  main.append(el('p.error', `No page ${hash}`), el('a', { href: '#/jobs' }, 'the jobs'));
}

async function header() {
  try {
    const info = await api.info();
    const d = info.device || {};
    document.getElementById('device').textContent =
      `${info.name || 'shadebenchd'} ${info.version || ''} · ${d.gl_renderer || d.renderer || ''}`;
  } catch (err) {
    document.getElementById('device').textContent = '';
  }
  const logout = document.getElementById('logout');
  logout.hidden = !api.token();
  logout.onclick = () => {
    api.forgetToken();
    location.reload();
  };
}

window.addEventListener('hashchange', route);
header().then(() => {
  document.getElementById('logout').hidden = !api.token();
});
route();
