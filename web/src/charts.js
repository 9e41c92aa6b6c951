// Charts on uPlot: x-y plots (uPlot's mode 2: every series its own x and y, drawn as polylines
// with gaps at nulls and/or as markers; optionally with equal axes, for maps of the site), and
// plots over a shared x (mode 1: lines, dots, bars; histograms). Every chart is kept in
// `registry` under its id, so a test can read back what it drew.
import uPlot from 'uplot';

export const registry = {};
const PALETTE = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22', '#17becf'];
export const color = (i) => PALETTE[i % PALETTE.length];

// Polyline through (x, y) in data order with a gap at every null: uPlot's own linear path
// decimates by x pixel column, which assumes x increases.
function polyline(u, si, i0, i1) {
  const [xs, ys] = u.data[si];
  const p = new Path2D();
  let pen = false;
  for (let i = i0; i <= i1; i++) {
    if (xs[i] === null || ys[i] === null || xs[i] === undefined) { pen = false; continue; }
    const px = u.valToPos(xs[i], 'x', true), py = u.valToPos(ys[i], 'y', true);
    if (pen) p.lineTo(px, py); else p.moveTo(px, py);
    pen = true;
  }
  return { stroke: p, fill: null, clip: plotArea(u) };
}
const noPath = () => null;
// The plot area, to clip what is drawn outside the axes' ranges.
function plotArea(u) {
  const c = new Path2D();
  c.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height);
  return c;
}

function markers(u, si, i0, i1) {
  const s = u.series[si];
  const [xs, ys] = u.data[si];
  const r = (s.markerSize || 4) * devicePixelRatio / 2;
  const ctx = u.ctx;
  ctx.save();
  ctx.clip(plotArea(u));
  ctx.fillStyle = s.markerColor || s._stroke || '#333';
  ctx.beginPath();
  for (let i = i0; i <= i1; i++) {
    if (xs[i] === null || ys[i] === null || xs[i] === undefined) continue;
    const px = u.valToPos(xs[i], 'x', true), py = u.valToPos(ys[i], 'y', true);
    ctx.moveTo(px + r, py);
    ctx.arc(px, py, r, 0, 2 * Math.PI);
  }
  ctx.fill();
  ctx.restore();
  return null;
}

function range(values, pad = 0.05) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) if (v !== null && v !== undefined && Number.isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
  if (!(hi >= lo)) return [0, 1];
  const d = hi - lo || Math.abs(hi) || 1;
  return [lo - pad * d, hi + pad * d];
}

function frame(parent, id, title, caption) {
  const div = document.createElement('div');
  div.className = 'chart';
  div.id = id;
  parent.append(div);
  return div;
}

// series: [{label, x, y, line (default true), points (default false), color, dash, width, markerSize}]
export function xyChart(parent, id, series, { title = '', xlabel = '', ylabel = '', height = 420, equal = false, extraX = [], extraY = [] } = {}) {
  const div = frame(parent, id);
  const width = Math.max(320, div.clientWidth || parent.clientWidth || 800);
  // The axes fit the series not marked noRange (e.g. the site's walls around a trajectory).
  const fit = series.filter((s) => !s.noRange);
  let xr = range(fit.flatMap((s) => s.x).concat(extraX)), yr = range(fit.flatMap((s) => s.y).concat(extraY));
  if (equal) {
    // Equal scales: widen the shorter range to the plot's aspect.
    const plotW = width - 80, plotH = height - 90;
    const sx = (xr[1] - xr[0]) / plotW, sy = (yr[1] - yr[0]) / plotH;
    if (sx > sy) { const c = (yr[0] + yr[1]) / 2, h = (sx * plotH) / 2; yr = [c - h, c + h]; }
    else { const c = (xr[0] + xr[1]) / 2, h = (sy * plotW) / 2; xr = [c - h, c + h]; }
  }
  const opts = {
    mode: 2, width, height, title,
    scales: { x: { time: false, auto: false, range: xr }, y: { auto: false, range: yr } },
    axes: [{ label: xlabel }, { label: ylabel }],
    legend: { live: false },
    cursor: { drag: { x: true, y: true, uni: 20 }, points: { show: false } },
    series: [{}, ...series.map((s, i) => ({
      label: s.label,
      stroke: s.color || color(i),
      width: s.line === false ? 0 : (s.width || 1.5),
      dash: s.dash,
      fill: s.fill,
      paths: s.line === false ? noPath : polyline,
      points: { show: false },
      markers: !!s.points,
      markerSize: s.markerSize,
      markerColor: s.color || color(i),
      facets: [{ scale: 'x', auto: false }, { scale: 'y', auto: false }],
    }))],
    // Markers drawn after the lines, for the series that want them.
    hooks: { draw: [(u) => { for (let i = 1; i < u.series.length; i++) if (u.series[i].markers && u.series[i].show !== false) markers(u, i, 0, u.data[i][0].length - 1); }] },
  };
  const data = [null, ...series.map((s) => [s.x, s.y])];
  const u = new uPlot(opts, data, div);
  registry[id] = u;
  return u;
}

// Over one shared x: series [{label, y, kind: 'line' | 'dots' | 'bars', color, dash}].
export function seriesChart(parent, id, x, series, { title = '', xlabel = '', ylabel = '', height = 320, barWidth = 0.8 } = {}) {
  const div = frame(parent, id);
  const width = Math.max(320, div.clientWidth || parent.clientWidth || 800);
  const integer = x.every((v) => Number.isInteger(v));
  const opts = {
    width, height, title,
    scales: { x: { time: false, range: (u, lo, hi) => [lo - 0.6, hi + 0.6] }, y: { range: (u, lo, hi) => range([lo, hi, 0], 0.08) } },
    axes: [integer ? { label: xlabel, incrs: [1, 2, 5, 10, 20, 50, 100, 200, 500] } : { label: xlabel }, { label: ylabel }],
    legend: { live: false },
    series: [{ label: xlabel }, ...series.map((s, i) => {
      const c = s.color || color(i);
      if (s.kind === 'bars') return { label: s.label, stroke: c, fill: c + 'cc', width: 1, paths: uPlot.paths.bars({ size: [barWidth, Infinity] }), points: { show: false } };
      if (s.kind === 'dots') return { label: s.label, stroke: c, width: 0, paths: noPath, points: { show: true, size: 7, fill: c, stroke: c } };
      return { label: s.label, stroke: c, width: s.width || 1.5, dash: s.dash, points: { show: false }, spanGaps: false };
    })],
  };
  const u = new uPlot(opts, [x, ...series.map((s) => s.y)], div);
  registry[id] = u;
  return u;
}

export function histogram(parent, id, values, { title = '', xlabel = '', bins = 20, height = 260, categories = false } = {}) {
  let x, y, labels = null;
  if (categories || values.some((v) => typeof v !== 'number')) {
    labels = [...new Set(values.map(String))];
    x = labels.map((_, i) => i);
    y = labels.map((l) => values.filter((v) => String(v) === l).length);
  } else {
    const v = values.filter((a) => Number.isFinite(a));
    let [lo, hi] = [Math.min(...v), Math.max(...v)];
    if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
    const w = (hi - lo) / bins;
    x = Array.from({ length: bins }, (_, i) => lo + (i + 0.5) * w);
    y = new Array(bins).fill(0);
    for (const a of v) y[Math.min(bins - 1, Math.floor((a - lo) / w))]++;
  }
  const div = frame(parent, id);
  const width = Math.max(280, div.clientWidth || parent.clientWidth || 400);
  const step = x.length > 1 ? x[1] - x[0] : 1;
  const u = new uPlot({
    width, height, title,
    scales: { x: { time: false, range: () => [x[0] - step, x[x.length - 1] + step] }, y: { range: (u, lo, hi) => [0, Math.max(1, hi) * 1.1] } },
    axes: [{ label: xlabel, values: labels ? (u, ticks) => ticks.map((t) => labels[t] ?? '') : undefined, splits: labels ? () => x : undefined }, { label: 'count' }],
    legend: { show: false },
    series: [{}, { label: 'count', stroke: '#2457a6', fill: '#2457a6aa', paths: uPlot.paths.bars({ size: [0.9, Infinity] }), points: { show: false } }],
  }, [x, y], div);
  u.sampleCount = values.length;
  registry[id] = u;
  return u;
}

// What a chart drew: per series, its label and the number of non-null points.
export function drawnCounts(u) {
  const out = [];
  for (let i = 1; i < u.series.length; i++) {
    const ys = u.mode === 2 ? u.data[i][1] : u.data[i];
    out.push({ label: u.series[i].label, n: ys.filter((v) => v !== null && v !== undefined).length });
  }
  return out;
}
