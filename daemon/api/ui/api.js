// The daemon's public API, as any client calls it: JSON, CSV and images
// fetched with the bearer token when the daemon has one. A 401 opens the
// token dialog and the request is retried with what the user gives; the
// token is kept in sessionStorage (this tab) only.

const TOKEN_KEY = 'shadebench.token';
let tokenWaiters = null;

export function token() {
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

export function forgetToken() {
  sessionStorage.removeItem(TOKEN_KEY);
}

function askToken(message) {
  if (tokenWaiters)
    return new Promise((resolve) => tokenWaiters.push(resolve));
  tokenWaiters = [];
  const dialog = document.getElementById('token-dialog');
  const form = document.getElementById('token-form');
  const input = document.getElementById('token-input');
  document.getElementById('token-error').textContent = message || '';
  input.value = '';
  return new Promise((resolve) => {
    form.onsubmit = (ev) => {
      ev.preventDefault();
      sessionStorage.setItem(TOKEN_KEY, input.value.trim());
      dialog.close();
      const waiters = tokenWaiters;
      tokenWaiters = null;
      resolve();
      waiters.forEach((w) => w());
    };
    if (!dialog.open)
      dialog.showModal();
    input.focus();
  });
}

export class ApiError extends Error {
  constructor(status, field, message) {
    super(field ? `${field}: ${message}` : message);
    this.status = status;
    this.field = field;
  }
}

// fetch() with the token; asks for a token (again) on 401.
export async function request(url, options = {}) {
  for (let attempt = 0; ; attempt++) {
    const headers = new Headers(options.headers || {});
    if (token())
      headers.set('Authorization', `Bearer ${token()}`);
    const resp = await fetch(url, { ...options, headers });
    if (resp.status !== 401 || attempt > 5)
      return resp;
    await askToken(attempt || token() ? 'That token was refused; try again.' : '');
  }
}

async function failure(resp) {
  let field = '', message = `${resp.status} ${resp.statusText}`;
  try {
    const body = await resp.json();
    if (body && body.error) {
      field = body.error.field || '';
      message = body.error.message || message;
    }
  } catch (e) { /* not JSON */ }
  return new ApiError(resp.status, field, message);
}

export async function json(url, options) {
  const resp = await request(url, options);
  if (!resp.ok)
    throw await failure(resp);
  return resp.json();
}

export async function text(url) {
  const resp = await request(url);
  if (!resp.ok)
    throw await failure(resp);
  return resp.text();
}

// Sends a body (JSON value, or a File/Blob as is) and answers the JSON with
// the status.
export async function send(method, url, body) {
  const options = { method };
  if (body !== undefined)
    options.body = body instanceof Blob ? body : JSON.stringify(body);
  const resp = await request(url, options);
  let data = null;
  try { data = await resp.json(); } catch (e) { /* empty */ }
  if (!resp.ok) {
    const err = data && data.error;
    throw new ApiError(resp.status, err ? err.field : '', err ? err.message : `${resp.status}`);
  }
  return { status: resp.status, body: data };
}

// Images come through fetch (an <img src> cannot carry the token): a blob:
// URL per API URL, kept for the page's life.
const blobs = new Map();
export function imageUrl(url) {
  if (!blobs.has(url)) {
    const p = request(url).then(async (resp) => {
      if (!resp.ok)
        throw await failure(resp);
      return URL.createObjectURL(await resp.blob());
    });
    p.catch(() => blobs.delete(url));
    blobs.set(url, p);
  }
  return blobs.get(url);
}

// A decoded image, ready for a canvas.
export async function image(url) {
  const img = new Image();
  img.src = await imageUrl(url);
  await img.decode();
  return img;
}

// Every page of a list, following next (bounded: at most max records).
export async function listAll(url, key, max = 5000) {
  const out = [];
  while (url && out.length < max) {
    const page = await json(url);
    out.push(...(page[key] || []));
    url = page.next;
  }
  return out;
}

// /v1/info, asked once a page load (the header and the filters share it).
let infoPromise = null;
export function info() {
  if (!infoPromise) {
    infoPromise = json('/v1/info');
    infoPromise.catch(() => { infoPromise = null; });
  }
  return infoPromise;
}
