// The image comparison: two images of one size (a job's capture and its
// reference, or two jobs' captures) side by side, by a swipe slider, or
// flipped A/B on a key; a magnifier that follows the pointer in every
// panel at once; difference views with adjustable contrast: the absolute
// difference of the two, the API's SSIM map and FLIP map, and
// PerceptualDiff's failing pixels as a mask; a jump to the worst SSIM
// window. Every image comes from the API; the page only scales and colours.
import * as api from './api.js';
import { el, num } from './util.js';

// The FLIP map's colour ramp as the daemon writes it (/v1/info's
// maps.flip.ramp): the page maps each colour back to its value to stretch
// the contrast, and the stretched value to its colour.
let ramp = null;
let flipInverse = null;

// C's lrintf: halves to even.
function roundEven(x) {
  const r = Math.round(x);
  return Math.abs(x % 1) === 0.5 && r % 2 ? r - 1 : r;
}

function rampColour(v, round = roundEven) {
  const stops = ramp.length - 1;
  v = Math.min(1, Math.max(0, v));
  const pos = v * stops;
  const k = Math.min(Math.floor(pos), stops - 1);
  const t = pos - k;
  return ramp[k].map((c, i) => round((c + (ramp[k + 1][i] - c) * t) * 255));
}

// Colour (packed RGB) to FLIP value, for every colour the ramp writes.
function flipValueOf(r, g, b) {
  if (!flipInverse) {
    flipInverse = new Map();
    const steps = 1 << 16;
    for (let i = 0; i <= steps; i++)
      for (const round of [roundEven, Math.round]) { // float rounding may differ from C's
        const [cr, cg, cb] = rampColour(i / steps, round);
        const key = (cr << 16) | (cg << 8) | cb;
        if (!flipInverse.has(key))
          flipInverse.set(key, i / steps);
      }
  }
  const v = flipInverse.get((r << 16) | (g << 8) | b);
  if (v !== undefined)
    return v;
  // Not a ramp colour (a resampled map): by its brightness.
  return Math.min(1, (0.2126 * r + 0.7152 * g + 0.0722 * b) / 255);
}

function pixels(img, w, h) {
  const c = document.createElement('canvas');
  c.width = w;
  c.height = h;
  const ctx = c.getContext('2d', { willReadFrequently: true });
  ctx.drawImage(img, 0, 0);
  return ctx.getImageData(0, 0, w, h);
}

export const VIEWS = ['side', 'swipe', 'flip', 'diff'];

export class ImageCompare {
  // a, b: {url, label}; maps: {ssim, flip, pdiff} URLs (absent ones are
  // left out); worst: {x, y, value} (the worst SSIM window's centre);
  // pdiffCount: failing pixels.
  constructor(opts) {
    this.opts = opts;
    this.view = opts.view || 'side';
    this.diffKind = opts.diffKind || (opts.maps && opts.maps.flip ? 'flip' : 'abs');
    this.gain = opts.gain || 1;
    this.zoom = 1;
    this.showB = false;
    this.swipe = 0.5;
    this.lens = null;         // {x, y} in image pixels, or null
    this.lensZoom = 8;
    this.root = el('div.imgcmp', { tabIndex: 0 });
    this.cache = {};
  }

  async mount(parent) {
    parent.append(this.root);
    if (!ramp) {
      const info = await api.info();
      ramp = ((info.maps || {}).flip || {}).ramp || [[0, 0, 0], [1, 1, 1]];
    }
    const [a, b] = await Promise.all([api.image(this.opts.a.url), api.image(this.opts.b.url)]);
    this.w = a.naturalWidth;
    this.h = a.naturalHeight;
    this.imgA = a;
    this.imgB = b;
    this.pixA = pixels(a, this.w, this.h);
    this.pixB = b.naturalWidth === this.w && b.naturalHeight === this.h ? pixels(b, this.w, this.h) : null;
    this.buildControls();
    this.stage = el('div.stage');
    this.caption = el('p.caption.muted');
    this.root.append(this.controls, this.stage, this.caption);
    this.root.addEventListener('keydown', (ev) => this.onKey(ev));
    await this.render();
    return this;
  }

  buildControls() {
    const maps = this.opts.maps || {};
    const viewButtons = VIEWS.map((v) => {
      const b = el('button.small', { type: 'button', dataset: { view: v } },
        { side: 'Side by side', swipe: 'Swipe', flip: 'Flip (F)', diff: 'Difference' }[v]);
      b.onclick = () => this.setView(v);
      return b;
    });
    this.viewButtons = viewButtons;
    const kinds = [['abs', 'absolute difference', this.pixB], ['ssim', 'SSIM map', maps.ssim],
      ['flip', 'FLIP map', maps.flip], ['pdiff', 'PerceptualDiff mask', maps.pdiff]]
      .filter(([, , ok]) => ok);
    if (!kinds.some(([k]) => k === this.diffKind) && kinds.length)
      this.diffKind = kinds[0][0];
    this.kindSelect = el('select.diff-kind', kinds.map(([k, label]) => el('option', { value: k }, label)));
    this.kindSelect.value = this.diffKind;
    this.kindSelect.onchange = () => {
      this.diffKind = this.kindSelect.value;
      this.setView('diff');
    };
    this.gainInput = el('input.contrast', { type: 'range', min: 0, max: 6, step: 0.25, value: Math.log2(this.gain),
      title: 'contrast: errors times 2^k' });
    this.gainLabel = el('span.gain', `×${num(this.gain)}`);
    this.gainInput.oninput = () => {
      this.gain = 2 ** Number(this.gainInput.value);
      this.gainLabel.textContent = `×${num(this.gain)}`;
      if (this.view === 'diff')
        this.render();
    };
    this.zoomSelect = el('select.zoom', [['fit', 'fit'], ['1', '1:1'], ['2', '2×'], ['4', '4×']]
      .map(([v, t]) => el('option', { value: v }, t)));
    this.zoomSelect.value = this.opts.zoom || 'fit';
    this.zoomSelect.onchange = () => this.render();
    const worst = this.opts.worst;
    const worstButton = worst ? el('button.small.worst', { type: 'button',
      title: `the 11×11 window whose SSIM is lowest (${num(worst.value, 5)}), centred at ${worst.x}, ${worst.y}` },
    'Worst SSIM window') : null;
    if (worstButton)
      worstButton.onclick = () => this.jumpTo(worst.x, worst.y);
    this.flipButton = el('button.small.flip', { type: 'button' }, 'A/B');
    this.flipButton.onclick = () => this.flip();
    this.controls = el('div.controls',
      el('span.group', viewButtons),
      el('span.group', 'difference ', this.kindSelect, ' contrast ', this.gainInput, this.gainLabel),
      el('span.group', 'zoom ', this.zoomSelect, ' ', this.flipButton, ' ', worstButton));
  }

  setView(v) {
    this.view = v;
    this.render();
    this.root.focus({ preventScroll: true });
  }

  flip() {
    this.showB = !this.showB;
    if (this.view !== 'flip')
      this.view = 'flip';
    this.render();
  }

  onKey(ev) {
    if (ev.target.tagName === 'INPUT' || ev.target.tagName === 'SELECT')
      return;
    if (ev.key === 'f' || ev.key === 'F' || ev.key === ' ') {
      ev.preventDefault();
      this.flip();
    } else if (ev.key === 'Escape') {
      this.lens = null;
      this.drawLenses();
    }
  }

  jumpTo(x, y) {
    this.lens = { x, y, pinned: true };
    this.drawLenses();
    const panel = this.panels[0];
    if (panel)
      panel.wrap.scrollIntoView({ block: 'nearest', inline: 'nearest' });
  }

  scale() {
    const z = this.zoomSelect.value;
    if (z !== 'fit')
      return Number(z);
    // Fit: the width there is, up to 4 times a small capture's pixels
    // (nearest-neighbour from 2x up), never cut.
    const avail = Math.max(200, (this.root.clientWidth || 900) - 8);
    const across = this.view === 'side' ? 2 : 1;
    const s = (avail / across - 12) / this.w;
    return s >= 1 ? Math.min(4, Math.floor(s * 4) / 4) : s;
  }

  // The difference view as ImageData, for the kind and contrast chosen.
  async diffImage() {
    const w = this.w, h = this.h, g = this.gain;
    const out = new ImageData(w, h);
    const o = out.data;
    const maps = this.opts.maps || {};
    if (this.diffKind === 'abs') {
      const a = this.pixA.data, b = this.pixB.data;
      let differing = 0, max = 0;
      for (let i = 0; i < a.length; i += 4) {
        let m = 0;
        for (let c = 0; c < 3; c++) {
          const d = Math.abs(a[i + c] - b[i + c]);
          o[i + c] = Math.min(255, d * g);
          m = Math.max(m, d);
        }
        o[i + 3] = 255;
        differing += m > 0;
        max = Math.max(max, m);
      }
      this.caption.textContent = `|A − B| per channel × ${num(g)}: ${differing.toLocaleString('en-US')} pixels differ, ` +
        `the largest by ${max} of 255.`;
      return out;
    }
    const map = await this.map(this.diffKind, maps[this.diffKind]);
    if (this.diffKind === 'ssim') {
      // The valid region, 5 pixels in from each edge (11x11 windows).
      const ox = Math.round((w - map.width) / 2), oy = Math.round((h - map.height) / 2);
      const m = map.data;
      for (let i = 3; i < o.length; i += 4)
        o[i] = 255;
      for (let y = 0; y < map.height; y++)
        for (let x = 0; x < map.width; x++) {
          const s = m[(y * map.width + x) * 4];
          const v = 255 - Math.min(255, (255 - s) * g);
          const j = ((y + oy) * w + (x + ox)) * 4;
          o[j] = o[j + 1] = o[j + 2] = v;
        }
      this.caption.textContent = `SSIM map (white = 1), its shortfall × ${num(g)}; the 5-pixel border has no window.`;
    } else if (this.diffKind === 'flip') {
      const m = map.data;
      for (let i = 0; i < m.length; i += 4) {
        const [r, gg, b] = rampColour(flipValueOf(m[i], m[i + 1], m[i + 2]) * g);
        o[i] = r; o[i + 1] = gg; o[i + 2] = b; o[i + 3] = 255;
      }
      this.caption.textContent = `FLIP error map × ${num(g)} (black 0, pale yellow 1).`;
    } else if (this.diffKind === 'pdiff') {
      const a = this.pixA.data, m = map.data;
      let failing = 0;
      for (let i = 0; i < m.length; i += 4) {
        const fail = m[i] > 127;
        failing += fail;
        const grey = (a[i] + a[i + 1] + a[i + 2]) / 3 * 0.35;
        o[i] = fail ? 255 : grey; o[i + 1] = fail ? 0 : grey; o[i + 2] = fail ? 255 : grey; o[i + 3] = 255;
      }
      const count = this.opts.pdiffCount;
      this.caption.textContent = `PerceptualDiff: ${failing.toLocaleString('en-US')} failing pixels in magenta` +
        (count !== undefined && count !== null ? ` (the job counted ${count.toLocaleString('en-US')})` : '') + '.';
    }
    return out;
  }

  async map(kind, url) {
    if (!this.cache[kind]) {
      const img = await api.image(url);
      this.cache[kind] = pixels(img, img.naturalWidth, img.naturalHeight);
    }
    return this.cache[kind];
  }

  panel(label, draw) {
    const s = this.scale();
    const canvas = el('canvas.view', { width: this.w, height: this.h });
    canvas.style.width = `${Math.round(this.w * s)}px`;
    canvas.style.height = `${Math.round(this.h * s)}px`;
    if (s >= 2)
      canvas.style.imageRendering = 'pixelated';
    const ctx = canvas.getContext('2d');
    draw(ctx);
    const lens = el('canvas.lens', { width: 160, height: 160 });
    lens.hidden = true;
    const mark = el('div.mark');
    mark.hidden = true;
    const wrap = el('div.panel', el('div.label', label), el('div.canvas-wrap', canvas, mark, lens));
    const p = { canvas, lens, mark, wrap, scale: s, source: canvas };
    const at = (ev) => {
      const r = canvas.getBoundingClientRect();
      return { x: Math.floor((ev.clientX - r.left) / r.width * this.w),
        y: Math.floor((ev.clientY - r.top) / r.height * this.h) };
    };
    canvas.addEventListener('mousemove', (ev) => {
      if (this.view === 'swipe' && ev.buttons === 1) {
        this.setSwipe(at(ev).x / this.w);
        return;
      }
      if (this.lens && this.lens.pinned)
        return;
      this.lens = at(ev);
      this.drawLenses();
    });
    canvas.addEventListener('mousedown', (ev) => {
      if (this.view === 'swipe')
        this.setSwipe(at(ev).x / this.w);
    });
    canvas.addEventListener('mouseleave', () => {
      if (this.lens && !this.lens.pinned) {
        this.lens = null;
        this.drawLenses();
      }
    });
    canvas.addEventListener('click', (ev) => {
      if (this.view === 'swipe')
        return;
      this.lens = this.lens && this.lens.pinned ? null : { ...at(ev), pinned: true };
      this.drawLenses();
    });
    return p;
  }

  setSwipe(f) {
    this.swipe = Math.min(1, Math.max(0, f));
    if (this.swipeInput)
      this.swipeInput.value = String(this.swipe);
    this.drawSwipe();
  }

  drawSwipe() {
    const p = this.panels && this.panels[0];
    if (!p || this.view !== 'swipe')
      return;
    const ctx = p.canvas.getContext('2d');
    const cut = Math.round(this.swipe * this.w);
    ctx.drawImage(this.imgB, 0, 0);
    ctx.save();
    ctx.beginPath();
    ctx.rect(0, 0, cut, this.h);
    ctx.clip();
    ctx.drawImage(this.imgA, 0, 0);
    ctx.restore();
    ctx.fillStyle = '#fff';
    ctx.fillRect(cut - 1, 0, 2, this.h);
    p.wrap.dataset.swipe = String(cut);
    this.drawLenses();
  }

  async render() {
    const { a, b } = this.opts;
    this.viewButtons.forEach((btn) => btn.classList.toggle('active', btn.dataset.view === this.view));
    this.root.dataset.view = this.view;
    this.stage.replaceChildren();
    this.swipeInput = null;
    if (this.view === 'side') {
      this.panels = [this.panel(`A: ${a.label}`, (c) => c.drawImage(this.imgA, 0, 0)),
        this.panel(`B: ${b.label}`, (c) => c.drawImage(this.imgB, 0, 0))];
      this.caption.textContent = 'Hover for a magnifier in both panels; click pins it.';
    } else if (this.view === 'swipe') {
      this.panels = [this.panel(`A: ${a.label} | B: ${b.label}`, () => {})];
      this.swipeInput = el('input.swipe', { type: 'range', min: 0, max: 1, step: 0.001, value: this.swipe });
      this.swipeInput.oninput = () => this.setSwipe(Number(this.swipeInput.value));
      this.panels[0].wrap.append(this.swipeInput);
      this.caption.textContent = 'A left of the line, B right of it: drag on the image or the slider.';
    } else if (this.view === 'flip') {
      const img = this.showB ? this.imgB : this.imgA;
      this.panels = [this.panel(this.showB ? `B: ${b.label}` : `A: ${a.label}`, (c) => c.drawImage(img, 0, 0))];
      this.panels[0].wrap.dataset.showing = this.showB ? 'B' : 'A';
      this.caption.textContent = 'Press F (or Space) to flip between A and B.';
    } else {
      const data = await this.diffImage();
      this.panels = [this.panel(this.kindSelect.selectedOptions[0].textContent, (c) => c.putImageData(data, 0, 0))];
      this.panels[0].wrap.dataset.kind = this.diffKind;
      this.panels[0].wrap.dataset.gain = String(this.gain);
    }
    this.stage.append(...this.panels.map((p) => p.wrap));
    this.root.dataset.showing = this.showB ? 'B' : 'A';
    this.drawSwipe();
    this.drawLenses();
  }

  // The magnifier: the same image pixels in every panel, nearest-neighbour.
  drawLenses() {
    for (const p of this.panels || []) {
      if (!this.lens) {
        p.lens.hidden = true;
        p.mark.hidden = !this.lens;
        continue;
      }
      const { x, y } = this.lens;
      const n = p.lens.width / this.lensZoom;
      const ctx = p.lens.getContext('2d');
      ctx.imageSmoothingEnabled = false;
      ctx.fillStyle = '#000';
      ctx.fillRect(0, 0, p.lens.width, p.lens.height);
      ctx.drawImage(p.canvas, x - n / 2, y - n / 2, n, n, 0, 0, p.lens.width, p.lens.height);
      ctx.strokeStyle = 'rgba(255,255,255,0.8)';
      ctx.strokeRect(p.lens.width / 2 - this.lensZoom / 2, p.lens.height / 2 - this.lensZoom / 2,
        this.lensZoom, this.lensZoom);
      const s = p.canvas.getBoundingClientRect().width / this.w || p.scale;
      let lx = x * s + 16, ly = y * s + 16;
      if (lx + p.lens.width > this.w * s)
        lx = x * s - p.lens.width - 16;
      if (ly + p.lens.height > this.h * s)
        ly = Math.max(0, y * s - p.lens.height - 16);
      p.lens.style.left = `${Math.max(0, lx)}px`;
      p.lens.style.top = `${Math.max(0, ly)}px`;
      p.lens.hidden = false;
      // The SSIM window (11x11) around the point.
      p.mark.style.left = `${(x - 5) * s}px`;
      p.mark.style.top = `${(y - 5) * s}px`;
      p.mark.style.width = p.mark.style.height = `${11 * s}px`;
      p.mark.hidden = false;
    }
    this.root.dataset.lens = this.lens ? `${this.lens.x},${this.lens.y}` : '';
  }
}
