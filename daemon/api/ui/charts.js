// Interactive charts through dygraphs (vendored from Debian's
// libjs-dygraphs, /ui/vendor/): values on hover, drag to zoom, double-click
// to zoom out. Every chart keeps its Dygraph on the container (.dygraph)
// for the tests.
import { el, num } from './util.js';

// dygraphs is loaded when a page first draws a chart: the job list, the
// page most often opened cold, draws none.
let library = null;
function dygraphs() {
  if (!library)
    library = new Promise((resolve, reject) => {
      const script = document.createElement('script');
      script.src = '/ui/vendor/dygraph.min.js';
      script.onload = () => resolve(window.Dygraph);
      script.onerror = () => {
        library = null;
        reject(new Error('the charting library did not load'));
      };
      document.head.append(script);
    });
  return library;
}

const COLOURS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#17becf', '#8c564b',
  '#e377c2', '#7f7f7f', '#bcbd22'];

export function colour(i) {
  return COLOURS[i % COLOURS.length];
}

// A chart's box in parent; null when parent has left the document (the
// page was left while it loaded): dygraphs cannot measure a detached div.
function holder(parent, cls, height = 280) {
  if (!parent.isConnected)
    return null;
  const box = el(`div.chart.${cls}`, { style: { height: `${height}px` } });
  const legend = el('div.chart-legend');
  parent.append(el('div.chart-box', box, legend));
  return { box, legend };
}

// timings.csv (frame,gpu_ms,cpu_ms,frame_ms,gpu_<pass>_ms...) as rows.
export function parseCsv(text) {
  const lines = text.trim().split('\n');
  const header = lines.shift().split(',');
  const rows = lines.map((l) => l.split(',').map(Number));
  return { header, rows };
}

// The frame times over the run, one line per series.
export async function frameTimes(parent, csv, series) {
  const Dygraph = await dygraphs();
  const cols = series.map((s) => csv.header.indexOf(s)).filter((i) => i >= 0);
  const data = csv.rows.map((r) => [r[0], ...cols.map((i) => r[i])]);
  const h = holder(parent, 'frame-times');
  if (!h)
    return null;
  const { box, legend } = h;
  const g = new Dygraph(box, data, {
    labels: ['frame', ...cols.map((i) => csv.header[i])],
    xlabel: 'frame', ylabel: 'ms', legend: 'always', labelsDiv: legend,
    colors: cols.map((_, i) => colour(i)), strokeWidth: 1.2,
    highlightCircleSize: 3, animatedZooms: false,
    axes: { y: { valueFormatter: (v) => `${num(v)} ms`, axisLabelWidth: 64 },
      x: { axisLabelFormatter: (v) => (Number.isInteger(v) ? String(v) : ''), valueFormatter: (v) => `frame ${v}` } },
  });
  box.dygraph = g;
  return g;
}

// The distribution of one series: counts in equal bins (a step line).
export async function histogram(parent, values, label) {
  const Dygraph = await dygraphs();
  const finite = values.filter((v) => Number.isFinite(v));
  if (!finite.length)
    return null;
  const lo = Math.min(...finite), hi = Math.max(...finite);
  const bins = Math.max(5, Math.min(60, Math.ceil(Math.sqrt(finite.length) * 2)));
  const width = (hi - lo) / bins || 1;
  const counts = new Array(bins).fill(0);
  for (const v of finite)
    counts[Math.min(bins - 1, Math.floor((v - lo) / width))]++;
  const data = counts.map((c, i) => [lo + (i + 0.5) * width, c]);
  const h = holder(parent, 'histogram', 200);
  if (!h)
    return null;
  const { box, legend } = h;
  const g = new Dygraph(box, data, {
    labels: [label, 'frames'], xlabel: `${label} (ms)`, ylabel: 'frames', stepPlot: true,
    fillGraph: true, legend: 'always', labelsDiv: legend, colors: [colour(0)],
    axes: { x: { valueFormatter: (v) => `${num(v - width / 2)} to ${num(v + width / 2)} ms` } },
  });
  box.dygraph = g;
  return g;
}

// Points grouped in series: [{series, x, y, lo, hi, label, onClick}] with
// optional intervals on y. A click on a point calls its onClick.
export async function points(parent, pts, opts) {
  const Dygraph = await dygraphs();
  const names = [...new Set(pts.map((p) => p.series))];
  const sorted = [...pts].sort((a, b) => a.x - b.x);
  const bars = pts.some((p) => Number.isFinite(p.lo) && Number.isFinite(p.hi));
  const data = sorted.map((p) => {
    const row = [p.x, ...names.map(() => null)];
    const i = names.indexOf(p.series) + 1;
    row[i] = bars ? [Number.isFinite(p.lo) ? p.lo : p.y, p.y, Number.isFinite(p.hi) ? p.hi : p.y] : p.y;
    return row;
  });
  const h = holder(parent, opts.cls || 'points', opts.height || 340);
  if (!h)
    return null;
  const { box, legend } = h;
  const options = {
    labels: [opts.xlabel, ...names], xlabel: opts.xlabel, ylabel: opts.ylabel,
    customBars: bars, drawPoints: true, pointSize: 4, highlightCircleSize: 7,
    strokeWidth: opts.lines ? 1.5 : 0, connectSeparatedPoints: !!opts.lines,
    legend: 'always', labelsDiv: legend, colors: names.map((_, i) => colour(i)),
    logscale: !!opts.logy,
    axes: {
      x: { logscale: !!opts.logx, valueFormatter: opts.xformat || ((v) => num(v)),
        axisLabelFormatter: opts.xaxis || ((v) => num(v, 3)) },
      y: { valueFormatter: opts.yformat || ((v) => num(v)), axisLabelFormatter: opts.yaxis || ((v) => num(v, 3)),
        axisLabelWidth: 72 },
    },
    xRangePad: 14, yRangePad: 14,

    legendFormatter: (d) => {
      const key = names.map((n, i) => `<span style="color:${colour(i)}">● ${n}</span>`).join(' &nbsp; ');
      if (d.x === undefined || d.x === null)
        return key;
      const s = d.series.find((x) => x.isHighlighted) ||
        d.series.find((x) => x.y !== null && x.y !== undefined && !Number.isNaN(x.y));
      const pt = s && sorted.find((q) => q.series === s.label && q.x === d.x);
      if (!pt)
        return key;
      const fx = opts.xformat || ((v) => num(v)), fy = opts.yformat || ((v) => num(v));
      return `<b>${pt.series}</b> ${pt.label || ''}: ${opts.xlabel} ${fx(pt.x)}, ${opts.ylabel} ${fy(pt.y)}` +
        (Number.isFinite(pt.lo) ? ` [${num(pt.lo)}, ${num(pt.hi)}]` : '') + (pt.onClick ? ' · click to open its job' : '');
    },
    pointClickCallback: (ev, p) => {
      const pt = sorted.find((q) => q.series === p.name && Math.abs(q.x - p.xval) < 1e-12 &&
        (!Number.isFinite(q.y) || Math.abs(q.y - p.yval) <= Math.abs(q.y) * 1e-9 + 1e-15));
      if (pt && pt.onClick)
        pt.onClick();
    },
  };
  if (opts.yticker)
    options.axes.y.ticker = opts.yticker;
  // dygraphs calls any callback option that is not null: leave absent ones out.
  if (opts.lines)
    options.highlightSeriesOpts = { strokeWidth: 2.5 };
  if (opts.drawCallback)
    options.drawCallback = opts.drawCallback;
  const g = new Dygraph(box, data, options);
  box.dygraph = g;
  box.points = sorted;
  return g;
}
