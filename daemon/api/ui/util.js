// Small DOM and number helpers the pages share.

// el('div#id.card', {onclick}, child, 'text', ...): an element with an id, classes,
// properties (on* as listeners, dataset, style objects) and children.
export function el(tag, props, ...children) {
  const name = tag.match(/^[a-z0-9]*/i)[0];
  const node = document.createElement(name || 'div');
  const classes = [];
  for (const [, kind, value] of tag.slice(name.length).matchAll(/([.#])([^.#]+)/g))
    kind === '#' ? (node.id = value) : classes.push(value);
  if (classes.length)
    node.className = classes.join(' ');
  if (props && (typeof props !== 'object' || props instanceof Node || Array.isArray(props))) {
    children.unshift(props);
    props = null;
  }
  for (const [k, v] of Object.entries(props || {})) {
    if (v === undefined || v === null || v === false)
      continue;
    if (k.startsWith('on'))
      node.addEventListener(k.slice(2), v);
    else if (k === 'dataset')
      Object.assign(node.dataset, v);
    else if (k === 'style' && typeof v === 'object')
      Object.assign(node.style, v);
    else if (k in node && typeof v !== 'string')
      node[k] = v;
    else
      node.setAttribute(k, v === true ? '' : v);
  }
  append(node, children);
  return node;
}

export function append(node, children) {
  for (const c of children.flat(Infinity)) {
    if (c === null || c === undefined || c === false)
      continue;
    node.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return node;
}

export function clear(node) {
  while (node.firstChild)
    node.firstChild.remove();
  return node;
}

// Numbers people read: 4 significant digits, no exponent for the usual range.
export function num(v, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v))
    return '–';
  if (typeof v !== 'number')
    return String(v);
  if (Number.isInteger(v) && Math.abs(v) < 1e9)
    return v.toLocaleString('en-US').replace(/,/g, '\u202f');
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-4 || a >= 1e9))
    return v.toExponential(digits - 1);
  return String(Number(v.toPrecision(digits)));
}

export function ms(v) {
  return v === null || v === undefined ? '–' : `${num(v)} ms`;
}

export function interval(ci, unit = '') {
  if (!Array.isArray(ci) || ci.length !== 2)
    return '';
  return `[${num(ci[0])}, ${num(ci[1])}]${unit}`;
}

export function pct(v) {
  return v === null || v === undefined ? '–' : `${num(100 * v, 3)}%`;
}

export function seconds(s) {
  if (s === null || s === undefined || !Number.isFinite(s))
    return '–';
  if (s < 60)
    return `${num(s, 2)} s`;
  const m = Math.floor(s / 60);
  if (m < 60)
    return `${m} min ${Math.round(s - 60 * m)} s`;
  return `${Math.floor(m / 60)} h ${m % 60} min`;
}

export function when(iso) {
  if (!iso)
    return '–';
  const d = new Date(iso);
  return Number.isNaN(d.getTime()) ? iso : d.toLocaleString();
}

// A JSON value as a readable table: objects become rows of name and value,
// nested objects nested tables, arrays of numbers one line, arrays of
// objects a table with a column per key.
export function valueTable(value, depth = 0) {
  if (value === null || value === undefined)
    return '–';
  if (typeof value !== 'object')
    return typeof value === 'number' ? num(value, 6) : String(value);
  if (Array.isArray(value)) {
    if (value.every((v) => v === null || typeof v !== 'object'))
      return value.map((v) => (typeof v === 'number' ? num(v, 6) : String(v))).join(', ');
    if (value.every((v) => v && typeof v === 'object' && !Array.isArray(v))) {
      const keys = [...new Set(value.flatMap((v) => Object.keys(v)))];
      return el('table.kv.columns',
        el('thead', el('tr', keys.map((k) => el('th', k)))),
        el('tbody', value.map((row) => el('tr', keys.map((k) => el('td', valueTable(row[k], depth + 1)))))));
    }
    return value.map((v) => valueTable(v, depth + 1));
  }
  return el('table.kv',
    el('tbody', Object.entries(value).map(([k, v]) =>
      el('tr', el('th', k), el('td', valueTable(v, depth + 1))))));
}

export function statusBadge(status) {
  return el(`span.badge.s-${status || 'unknown'}`, status || '?');
}

export function link(href, text) {
  return el('a', { href }, text);
}

export function errorBox(err) {
  return el('p.error', err && err.message ? err.message : String(err));
}

// Query string of a page's hash route: #/jobs?technique=osl -> URLSearchParams.
export function hashQuery() {
  const h = location.hash;
  const q = h.indexOf('?');
  return new URLSearchParams(q < 0 ? '' : h.slice(q + 1));
}

// Replaces a node's children (null, undefined and false left out).
export function fill(node, ...children) {
  return append(clear(node), children);
}
