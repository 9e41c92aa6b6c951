// The report page of an ifab run folder. ifab inlines this bundle and the run's data (a JSON
// element #ifab-data: results.json, the results table, CSV texts, scene.json, decimated clouds)
// into report.html; everything drawn here comes from that data. window.ifabReport tells a test
// (tests/browser) what was drawn and when the page is ready.
import css from './style.css';
import uplotCss from 'uplot/dist/uPlot.min.css';
import { xyChart, seriesChart, histogram, registry, drawnCounts } from './charts.js';
import { parseCsv, stats } from './csv.js';
import { createReplay } from './replay.js';
import { createViewer, boxMesh, mat4 } from './viewer.js';
import { PAPER } from './paper.js';

const report = { ready: false, figures: {}, errors: [], replay: null, charts: registry, scriptStart: performance.now() };
// What each chart drew, per series (label, points): read from the charts themselves.
report.drawn = () => Object.fromEntries(Object.entries(registry).map(([id, u]) => [id, drawnCounts(u)]));
window.ifabReport = report;

const data = JSON.parse(document.getElementById('ifab-data').textContent);
const csv = {};
for (const [name, text] of Object.entries(data.csv || {})) csv[name] = parseCsv(text);
const app = document.getElementById('app');
const style = document.createElement('style');
style.textContent = uplotCss + css;
document.head.appendChild(style);

const el = (tag, attrs = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v; else e.setAttribute(k, v);
  }
  for (const k of kids) e.append(k);
  return e;
};
const nav = el('nav');
const main = el('main');
const pending = [];  // figure draws, in order (each after the previous one)

function section(id, title, caption) {
  const s = el('section', { class: 'fig', id });
  s.append(el('h2', {}, title));
  if (caption) s.append(el('p', { class: 'cap' }, caption));
  main.append(s);
  nav.append(el('a', { href: `#${id}` }, title.split(':')[0]));
  return s;
}

// A chart drawn after the page's text is up (in order, each after the previous one).
function chart(parent, draw) {
  const holder = el('div', { class: 'plot' });
  parent.append(holder);
  pending.push(async () => { draw(holder); });
  return holder;
}
const count = (a) => a.filter((v) => v !== null && v !== undefined).length;
// Per-group polylines joined into one trace, separated by nulls (no line across groups).
function joinGroups(groupCol, cols, table) {
  const out = cols.map(() => []);
  for (let r = 0; r < table.rows; r++) {
    if (r > 0 && table.col[groupCol][r] !== table.col[groupCol][r - 1]) out.forEach((o) => o.push(null));
    cols.forEach((c, i) => out[i].push(table.col[c][r]));
  }
  return out;
}

// Footprints of the site's walls and obstacles as one closed polyline series for x-y charts.
function siteSeries(site) {
  const xs = [], ys = [];
  for (const b of [...(site.walls || []), ...(site.obstacles || [])]) {
    const m = b.pose;  // column-major 4x4
    const h = [b.size[0] / 2, b.size[1] / 2];
    for (const [a, c] of [[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]) {
      xs.push(m[12] + m[0] * a * h[0] + m[4] * c * h[1]);
      ys.push(m[13] + m[1] * a * h[0] + m[5] * c * h[1]);
    }
    xs.push(null); ys.push(null);
  }
  return { label: 'walls, obstacles', x: xs, y: ys, color: '#8a939c', noRange: true };
}

function header() {
  const r = data.results || {};
  const title = data.experiment === 'estimate' ? 'ifab estimate' : `ifab run ${data.experiment}`;
  const bits = [];
  if (r.seed !== undefined) bits.push(`seed ${r.seed}`);
  if (r.runs !== undefined) bits.push(`${r.runs} runs`);
  if (r.sim_seconds !== undefined) bits.push(`${r.sim_seconds.toFixed(0)} s simulated`);
  if (r.wall_seconds !== undefined) bits.push(`${r.wall_seconds.toFixed(0)} s wall`);
  app.append(el('header', {}, el('h1', {}, title), el('div', { class: 'sub' }, `${data.folder} · ${bits.join(' · ')}`)));
  app.append(nav, main);
}

function resultsTable() {
  if (!data.table) return;
  const s = section('results', 'Results beside the paper', 'The figures of results.json, named and in units as on the terminal; the last column is the paper\'s.');
  const t = el('table', { class: 'results' });
  t.append(el('tr', {}, ...data.table.header.map((h) => el('th', {}, h))));
  for (const row of data.table.rows) {
    t.append(el('tr', {}, ...row.map((c, i) => el('td', i === row.length - 1 && i > 1 ? { class: 'paper' } : {}, c))));
  }
  s.append(t);
  report.figures.results = { rows: data.table.rows.length };
}

// ---- brick stack ---------------------------------------------------------------------------

const cloudOf = (visit) => (data.clouds || []).find((c) => c.file === `cloud_visit_${String(visit).padStart(2, '0')}.ply`);
const visitRow = (v) => { const V = csv['visits.csv']; const r = V ? V.col.visit.indexOf(v) : -1; return r; };
// The pose the mission took for a visit's cloud: its registration's, else the estimate.
function cloudPose(v) {
  const V = csv['visits.csv'], r = visitRow(v);
  const loc = V.col.localized[r] === 1 || V.col.localized[r] === 'true';
  return loc ? [V.col.loc_x[r], V.col.loc_y[r], V.col.loc_theta[r]] : [V.col.end_x[r], V.col.end_y[r], V.col.end_theta[r]];
}
function toSite(c, pose) {
  const n = c.xyz_mm.length / 3, x = new Array(n), y = new Array(n), z = new Array(n);
  const cs = Math.cos(pose[2]), sn = Math.sin(pose[2]);
  for (let i = 0; i < n; i++) {
    const px = c.xyz_mm[3 * i] / 1000, py = c.xyz_mm[3 * i + 1] / 1000;
    x[i] = pose[0] + cs * px - sn * py; y[i] = pose[1] + sn * px + cs * py; z[i] = c.xyz_mm[3 * i + 2] / 1000;
  }
  return { x, y, z, n };
}
// Bricks standing when visit v scanned: those placed at earlier visits (designed poses).
function bricksBefore(v) {
  const out = [];
  for (const vi of data.scene.visits) if (vi.visit < v) out.push(...vi.bricks_placed);
  return out;
}
// Fig. 3 in three.js: the cloud coloured by height, the bricks below in grey, the registered one
// in red. Returns what the view holds, read back from its scene graph.
function fig3View(container) {
  const v = createViewer(container, { position: [0.9, -1.3, 1.0], target: [0, 0, 0.1] });
  const { THREE } = v;
  let group = null;
  const show = (visit) => {
    if (group) v.scene.remove(group);
    group = new THREE.Group();
    const c = cloudOf(visit);
    const pts = toSite(c, cloudPose(visit));
    const before = bricksBefore(visit);
    const top = before[before.length - 1];
    const m = data.scene.designed_bricks[top];
    const pos = new Float32Array(3 * pts.n), col = new Float32Array(3 * pts.n);
    const zs = pts.z.slice().sort((a, b) => a - b);
    const z0 = zs[Math.floor(0.02 * zs.length)] ?? 0, z1 = zs[Math.floor(0.98 * zs.length)] ?? 1;
    const color = new THREE.Color();
    for (let i = 0; i < pts.n; i++) {
      pos.set([pts.x[i] - m[12], pts.y[i] - m[13], pts.z[i]], 3 * i);
      color.setHSL(0.65 - 0.5 * Math.min(1, Math.max(0, (pts.z[i] - z0) / (z1 - z0 || 1))), 0.8, 0.42);
      col.set([color.r, color.g, color.b], 3 * i);
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    const cloud = new THREE.Points(g, new THREE.PointsMaterial({ size: 0.008, vertexColors: true }));
    cloud.name = 'cloud';
    group.add(cloud);
    const size = data.scene.site.brick;
    const place = (mesh, k) => {
      mesh.applyMatrix4(mat4(data.scene.designed_bricks[k]));
      mesh.position.x -= m[12]; mesh.position.y -= m[13];
      group.add(mesh);
      return mesh;
    };
    before.slice(0, -1).forEach((k) => place(boxMesh(size, 0x9aa3ad, 0.35), k).name = `brick ${k + 1}`);
    if (top !== undefined) {
      const red = place(boxMesh(size, 0xd62728, 0.55), top);
      red.name = 'registered brick';
      red.add(new THREE.LineSegments(new THREE.EdgesGeometry(red.geometry), new THREE.LineBasicMaterial({ color: 0x8b0000 })));
    }
    // Frame the cloud: the camera at 1.5 times its horizontal radius, from the robot's side.
    const r = pts.x.map((x, i) => Math.hypot(x - m[12], pts.y[i] - m[13])).sort((a, b) => a - b)[Math.floor(0.9 * pts.n)] || 0.5;
    const pose = cloudPose(visit);
    const dir = new THREE.Vector2(pose[0] - m[12], pose[1] - m[13]).normalize();
    v.camera.position.set(1.3 * r * dir.x - 0.5 * r * dir.y, 1.3 * r * dir.y + 0.5 * r * dir.x, m[14] + 1.1 * r);
    v.controls.target.set(0, 0, m[14]);
    v.controls.update();
    v.scene.add(group);
    v.render();
    report.figures.fig3 = { visit, stride: c.stride, cloud_points: c.points };
  };
  // Read back from the scene what is drawn: the cloud's points and the registered brick.
  const inspect = () => {
    const cloud = group && group.getObjectByName('cloud');
    const brick = group && group.getObjectByName('registered brick');
    const px = v.litPixels();
    return { points: cloud ? cloud.geometry.getAttribute('position').count : 0,
      registered_brick: brick ? brick.geometry.getAttribute('position').count : 0,
      lit: px.lit, red: px.red, total: px.total, visit: report.figures.fig3 && report.figures.fig3.visit, stride: report.figures.fig3 && report.figures.fig3.stride };
  };
  return { show, inspect };
}

function brickStack() {
  const sc = data.scene;
  const hasClouds = (data.clouds || []).some((c) => /cloud_visit_/.test(c.file));
  // Fig. 3
  if (hasClouds && sc && csv['visits.csv']) {
    const visits = data.clouds.map((c) => /cloud_visit_(\d+)/.exec(c.file)).filter(Boolean).map((m) => Number(m[1]))
      .filter((v) => bricksBefore(v).length > 0);
    const s = section('fig3', 'Fig. 3: the assembled cloud of a visit and the registered brick',
      'The arm laser\'s sweep at a building position (eq. 6), placed in the site by the pose its registration gave (eq. 7); ' +
      'the brick registered against in red, the bricks below it in grey (designed poses). Pick the visit:');
    const sel = el('select', { id: 'fig3-visit' });
    visits.forEach((v) => sel.append(el('option', { value: v }, `visit ${v} (${sc.visits.find((x) => x.visit === v)?.position ?? ''})`)));
    s.append(el('div', { class: 'controls' }, 'visit ', sel));
    const view = el('div', { id: 'fig3-view', class: 'view3d' });
    s.append(view);
    if (visits.length) {
      const first = visits[visits.length - 1];  // the last: the stack at its highest
      sel.value = String(first);
      pending.push(async () => {
        const f = fig3View(view);
        f.show(first);
        report.fig3 = f;
        sel.addEventListener('change', () => f.show(Number(sel.value)));
      });
    }
    // Fig. 4 on the sweep with the most shadow points (the figure is about them).
    const shadows = (v) => Number((cloudOf(v).label_counts || {})['1'] || 0);
    if (visits.length) fig4(visits.reduce((a, b) => (shadows(b) > shadows(a) ? b : a)));
  }
  fig6();
  brickErrors();
  replaySection();
}

// Fig. 4: the points of one sweep in the registered top brick's frame, seen along its long axis.
function fig4(visit) {
  const c = cloudOf(visit);
  if (!c || !c.label) return;
  const pts = toSite(c, cloudPose(visit));
  const before = bricksBefore(visit);
  const m = data.scene.designed_bricks[before[before.length - 1]];
  const size = data.scene.site.brick;
  const groups = { 0: [[], []], 1: [[], []], other: [[], []] };
  const add = (g, x, y, z) => {
    const d = [x - m[12], y - m[13], z - m[14]];
    const bx = d[0] * m[0] + d[1] * m[1] + d[2] * m[2];
    const by = d[0] * m[4] + d[1] * m[5] + d[2] * m[6];
    const bz = d[0] * m[8] + d[1] * m[9] + d[2] * m[10];
    if (Math.abs(bx) > size[0] / 2 || Math.abs(by) > 0.3 || bz < -0.3) return;
    g[0].push(by); g[1].push(bz);
  };
  // The decimated cloud for the rest, every shadow point of the full cloud.
  for (let i = 0; i < pts.n; i++) if (c.label[i] !== 1) add(c.label[i] === 0 ? groups[0] : groups.other, pts.x[i], pts.y[i], pts.z[i]);
  if (c.shadow_xyz_mm) {
    const sh = toSite({ xyz_mm: c.shadow_xyz_mm }, cloudPose(visit));
    for (let i = 0; i < sh.n; i++) add(groups[1], sh.x[i], sh.y[i], sh.z[i]);
  }
  const counts = c.label_counts || {};
  const s = section('fig4', 'Fig. 4: shadow points, before and after removal',
    `Visit ${visit}: the points within the top brick's length, seen along it (brick frame; the brick in red; every shadow point, every ${c.stride}th of the others). ` +
    `The registration flagged ${counts['1'] || 0} of ${c.points} points as shadow points (a ray past an edge, far from the model) ` +
    'and gave them zero error; right: what it fitted.');
  const row = el('div', { class: 'row' });
  s.append(row);
  const hy = size[1] / 2, hz = size[2] / 2;
  const brick = { label: 'brick', x: [-hy, hy, hy, -hy, -hy], y: [-hz, -hz, hz, hz, -hz], color: '#d62728' };
  const fitted = { label: 'fitted', x: groups[0][0], y: groups[0][1], line: false, points: true, markerSize: 3, color: '#1f77b4' };
  const shadow = { label: 'shadow points', x: groups[1][0], y: groups[1][1], line: false, points: true, markerSize: 4, color: '#ff7f0e' };
  const other = { label: 'other zero-error (outlier, grazing, fixed)', x: groups.other[0], y: groups.other[1], line: false, points: true, markerSize: 3, color: '#b0b7be' };
  const o = (title) => ({ title, xlabel: 'across the brick [m]', ylabel: 'up [m]', height: 400, equal: true });
  chart(row, (h) => xyChart(h, 'fig4-before', [brick, fitted, shadow, other], o('before removal')));
  chart(row, (h) => xyChart(h, 'fig4-after', [brick, fitted, other], o('after removal')));
}

const isLocalized = (v) => v === 1 || v === 'true' || v === true;

function fig6() {
  const P = csv['trajectory_planned.csv'], E = csv['trajectory_estimated.csv'], T = csv['trajectory_true.csv'], V = csv['visits.csv'];
  if (!E || !T) return;
  const s = section('fig6', 'Fig. 6: planned, estimated and true base trajectories',
    'Every maneuver between building positions: the planner\'s trajectory, the estimator\'s poses while driving (eq. 1-3) and the simulator\'s true pose; ' +
    'a red step marks each localization (from the estimate at the end of the maneuver to the registered pose). Drag to zoom, double-click to reset.');
  const series = [];
  if (data.scene && data.scene.site) series.push(siteSeries(data.scene.site));
  if (P) { const [x, y] = joinGroups('visit', ['x', 'y'], P); series.push({ label: 'planned', x, y, color: '#2ca02c', dash: [6, 4] }); }
  { const [x, y] = joinGroups('visit', ['x', 'y'], E); series.push({ label: 'estimated', x, y, color: '#1f77b4' }); }
  series.push({ label: 'true', x: T.col.x, y: T.col.y, color: '#111111', width: 1 });
  if (V && V.col.loc_x) {
    const x = [], y = [];
    for (let r = 0; r < V.rows; r++) {
      if (!isLocalized(V.col.localized[r])) continue;
      x.push(V.col.end_x[r], V.col.loc_x[r], null); y.push(V.col.end_y[r], V.col.loc_y[r], null);
    }
    series.push({ label: 'localization step', x, y, color: '#d62728', width: 2.5, points: true, markerSize: 5 });
  }
  if (data.scene && data.scene.positions) {
    const ps = data.scene.positions;
    series.push({ label: 'building positions', x: ps.map((p) => p.x), y: ps.map((p) => p.y), line: false, points: true, markerSize: 9, color: '#9467bd' });
  }
  chart(s, (h) => xyChart(h, 'fig6-plot', series, { xlabel: 'x [m]', ylabel: 'y [m]', height: 620, equal: true }));
  // Per maneuver: the localization correction.
  if (V && V.col.loc_x) {
    const vx = [], dm = [], dd = [];
    for (let r = 0; r < V.rows; r++) {
      if (!isLocalized(V.col.localized[r])) continue;
      vx.push(V.col.visit[r]);
      dm.push(100 * Math.hypot(V.col.loc_x[r] - V.col.end_x[r], V.col.loc_y[r] - V.col.end_y[r]));
      const a = V.col.loc_theta[r] - V.col.end_theta[r];
      dd.push(Math.abs(Math.atan2(Math.sin(a), Math.cos(a))) * 180 / Math.PI);
    }
    if (vx.length) {
      chart(s, (h) => seriesChart(h, 'fig6-steps', vx, [
        { label: 'correction [cm]', y: dm, kind: 'dots' }, { label: 'correction [deg]', y: dd, kind: 'dots' },
        { label: `paper mean [cm] (${PAPER.localization_cm})`, y: vx.map(() => PAPER.localization_cm), kind: 'line', dash: [3, 3], color: '#8a3b12' },
      ], { title: 'localization correction per visit', xlabel: 'visit', ylabel: 'cm / deg' }));
    }
  }
}

function brickErrors() {
  const B = csv['brick_errors.csv'];
  if (!B) return;
  const s = section('bricks', 'Brick errors: per brick and per building position',
    'Signed error of every placed brick against its designed pose, along its long and short faces, and away from the side the robot placed it from ' +
    `(the paper's range-bias effect). Dotted: the paper's mean errors (long ${PAPER.brick_long_mm} mm, short ${PAPER.brick_short_mm} mm); dashed: the 1 mm target.`);
  const k = B.col.brick.map((b) => b + 1);
  const flat = (v) => k.map(() => v);
  chart(s, (h) => seriesChart(h, 'bricks-plot', k, [
    { label: 'long face [mm]', y: B.col.error_long_mm, kind: 'dots', color: '#1f77b4' },
    { label: 'short face [mm]', y: B.col.error_short_mm, kind: 'dots', color: '#ff7f0e' },
    { label: 'away from the robot [mm]', y: B.col.error_away_mm, kind: 'dots', color: '#2ca02c' },
    { label: `paper mean, long (±${PAPER.brick_long_mm})`, y: flat(PAPER.brick_long_mm), kind: 'line', dash: [2, 3], color: '#1f77b4', width: 1 },
    { label: '(−)', y: flat(-PAPER.brick_long_mm), kind: 'line', dash: [2, 3], color: '#1f77b4', width: 1 },
    { label: `paper mean, short (±${PAPER.brick_short_mm})`, y: flat(PAPER.brick_short_mm), kind: 'line', dash: [2, 3], color: '#ff7f0e', width: 1 },
    { label: '(−)', y: flat(-PAPER.brick_short_mm), kind: 'line', dash: [2, 3], color: '#ff7f0e', width: 1 },
    { label: '1 mm target', y: flat(1), kind: 'line', dash: [6, 4], color: '#555555', width: 1 },
    { label: '(−)', y: flat(-1), kind: 'line', dash: [6, 4], color: '#555555', width: 1 },
  ], { xlabel: 'brick (bottom to top)', ylabel: 'error [mm]', height: 380 }));
  // Per building position (where the robot stood when it placed the brick): each brick a dot.
  if (data.scene && data.scene.visits) {
    const pos = new Array(B.rows).fill('?');
    for (const v of data.scene.visits) for (const b of v.bricks_placed) pos[b] = v.position;
    const names = [...new Set(pos)];
    const mk = (col, off, label, c) => ({ label, x: pos.map((p, i) => names.indexOf(p) + off + 0.04 * ((i % 5) - 2)), y: B.col[col], line: false, points: true, markerSize: 6, color: c });
    chart(s, (h) => {
      const u = xyChart(h, 'bricks-by-position', [mk('error_long_mm', -0.25, 'long face', '#1f77b4'), mk('error_short_mm', 0, 'short face', '#ff7f0e'),
        mk('error_away_mm', 0.25, 'away from the robot', '#2ca02c')], { xlabel: `building position: ${names.map((n, i) => `${i} ${n}`).join(', ')}`, ylabel: 'error [mm]', height: 360, extraX: [-0.6, names.length - 0.4] });
      return u;
    });
    s.append(el('p', { class: 'note' }, 'Mean per building position [mm] (long / short / away): ' + names.map((n) => {
      const idx = pos.map((p, i) => (p === n ? i : -1)).filter((i) => i >= 0);
      const mean = (col) => (idx.reduce((a, i) => a + B.col[col][i], 0) / idx.length).toFixed(2);
      return `${n} ${mean('error_long_mm')} / ${mean('error_short_mm')} / ${mean('error_away_mm')} (${idx.length} bricks)`;
    }).join('; ')));
  }
}

function replaySection() {
  const R = csv['replay.csv'];
  if (!R || !data.scene || !data.scene.arm || !csv['brick_errors.csv']) return;
  const s = section('replay', '3D replay of the mission',
    'The site, the stack as built (true poses), the base footprint and the arm (the URDF chain\'s links, posed from the recorded joint angles), and each sweep\'s cloud as it was taken. ' +
    'Drag to orbit, scroll to zoom; the slider replays the mission.');
  const view = el('div', { id: 'replay-view' });
  const slider = el('input', { type: 'range', id: 'replay-slider', value: '0' });
  const play = el('button', { id: 'replay-play' }, 'play');
  const lab = el('span', { id: 'replay-label' });
  s.append(el('div', { class: 'controls' }, play, slider), lab, view);
  // The replay's WebGL view is made when it comes near the screen: setting up a WebGL context
  // is the dearest step of the page without a GPU (software rendering), and it sits at the end.
  const make = () => {
    if (report.replay) return;
    const r = createReplay(view, slider, lab, { scene: data.scene, replay: R, sweeps: csv['sweeps.csv'], bricks: csv['brick_errors.csv'],
      visits: data.scene.visits, clouds: data.clouds || [], visitsCsv: csv['visits.csv'] });
    report.replay = r;
    report.figures.replay = { samples: r.samples };
    let timer = null;
    play.addEventListener('click', () => {
      if (timer) { clearInterval(timer); timer = null; play.textContent = 'play'; return; }
      play.textContent = 'pause';
      timer = setInterval(() => {
        const i = Number(slider.value) + Math.max(1, Math.round(r.samples / 600));
        if (i >= r.samples) { clearInterval(timer); timer = null; play.textContent = 'play'; return; }
        r.setIndex(i);
      }, 40);
    });
  };
  pending.push(async () => {
    new IntersectionObserver((entries, obs) => {
      if (entries.some((e) => e.isIntersecting)) { obs.disconnect(); make(); }
    }, { rootMargin: '300px' }).observe(view);
  });
}

// ---- other experiments ----------------------------------------------------------------------

function lrfBias() {
  const L = csv['lrf_bias_points.csv'];
  if (!L) return;
  const s = section('fig7', 'Fig. 7: floor scans below the laser (short-range bias)',
    'Stationary scans of a flat floor from three heights; a flat floor would read as a straight line. The bump below the scanner is the UTM-30LX\'s short-range bias ' +
    '(the paper: about 3 cm at 0.4 m).');
  const heights = [...new Set(L.col.height_m)];
  const series = heights.map((h, i) => {
    const x = [], z = [];
    for (let r = 0; r < L.rows; r++) if (L.col.height_m[r] === h) { x.push(L.col.x_m[r]); z.push(L.col.z_m[r]); }
    return { label: `scanner at ${h} m`, x, y: z, line: false, points: true, markerSize: 2 };
  });
  chart(s, (h) => xyChart(h, 'fig7-plot', series, { xlabel: 'along the floor [m]', ylabel: 'measured floor height [m]', height: 460 }));
}

function hist(parent, id, values, title, xlabel, extra = {}) {
  return chart(parent, (h) => histogram(h, id, values, { title, xlabel, ...extra }));
}

function basePlanning() {
  const C = csv['base_planning_cases.csv'];
  if (!C) return;
  const s = section('base-planning', 'Base planning (STOMP): success and plan time', `${C.rows} seeded start/goal pairs (base_planning_cases.csv).`);
  const row = el('div', { class: 'row' });
  s.append(row);
  hist(row, 'bp-status', C.col.status, 'outcome', 'status', { categories: true });
  hist(row, 'bp-time', C.col.plan_ms, 'plan time', 'ms');
  const P = csv['base_planning_plans.csv'];
  if (P) {
    const s2 = section('base-plans', 'Some plans drawn in the site', 'The first plans of base_planning_cases.csv (the base pose along each trajectory).');
    const series = [];
    if (data.scene && data.scene.site) series.push(siteSeries(data.scene.site));
    for (const id of [...new Set(P.col.case)]) {
      const x = [], y = [];
      for (let r = 0; r < P.rows; r++) if (P.col.case[r] === id) { x.push(P.col.x[r]); y.push(P.col.y[r]); }
      series.push({ label: `case ${id} (${C.col.status[id]})`, x, y, width: 2 });
    }
    chart(s2, (h) => xyChart(h, 'bp-plans', series, { xlabel: 'x [m]', ylabel: 'y [m]', height: 560, equal: true }));
  }
}

function armPlanning() {
  const C = csv['arm_planning_cases.csv'];
  if (!C) return;
  const s = section('arm-planning', 'Arm planning (iLQG): iterations and time',
    `${C.rows} seeded motions (arm_planning_cases.csv). The paper: fewer than ${PAPER.ilqg_iterations} iterations and under ${PAPER.ilqg_seconds} s.`);
  const row = el('div', { class: 'row' });
  s.append(row);
  hist(row, 'ap-iterations', C.col.iterations, 'iterations', 'iterations', { categories: true });
  hist(row, 'ap-time', C.col.plan_ms, 'plan time', 'ms');
}

function consistency(C, id, title, keys, paperStd, units, caption) {
  const s = section(id, title, caption);
  const t = el('table', { class: 'results' });
  t.append(el('tr', {}, el('th', {}, ''), ...keys.map((k) => el('th', {}, k))));
  const st = keys.map((k) => stats(C.col[k]));
  const fmt = (v, i) => (units[i] === 'mm' ? v.toFixed(2) : v.toFixed(3));
  t.append(el('tr', {}, el('td', {}, 'mean'), ...st.map((x, i) => el('td', {}, fmt(x.mean, i)))));
  t.append(el('tr', {}, el('td', {}, 'std (ifab)'), ...st.map((x, i) => el('td', {}, fmt(x.std, i)))));
  t.append(el('tr', {}, el('td', {}, 'std (paper)'), ...paperStd.map((x) => el('td', { class: 'paper' }, String(x)))));
  s.append(t);
  // Each scan's (data set's) deviation from the mean, per coordinate.
  const x = Array.from({ length: C.rows }, (_, i) => i + 1);
  const row = el('div', { class: 'row' });
  s.append(row);
  chart(row, (h) => seriesChart(h, `${id}-mm`, x, keys.filter((k, i) => units[i] === 'mm').map((k) => ({ label: k, y: C.col[k].map((v) => v - st[keys.indexOf(k)].mean), kind: 'dots' })),
    { title: 'deviation from the mean [mm]', xlabel: 'scan / data set', ylabel: 'mm' }));
  chart(row, (h) => seriesChart(h, `${id}-deg`, x, keys.filter((k, i) => units[i] === 'deg').map((k) => ({ label: k, y: C.col[k].map((v) => v - st[keys.indexOf(k)].mean), kind: 'dots' })),
    { title: 'deviation from the mean [deg]', xlabel: 'scan / data set', ylabel: 'deg' }));
}

function registrationConsistency() {
  const C = csv['registration_scans.csv'];
  if (!C) return;
  const conv = { ...C, col: { ...C.col } };
  for (const k of ['x_m', 'y_m', 'z_m']) conv.col[k.replace('_m', '_mm')] = C.col[k].map((v) => 1000 * v);
  consistency(conv, 'table1', 'Table I: registration consistency', ['x_mm', 'y_mm', 'z_mm', 'roll_deg', 'pitch_deg', 'yaw_deg'],
    PAPER.table1_std, ['mm', 'mm', 'mm', 'deg', 'deg', 'deg'], 'The registered brick\'s pose from each scan (registration_scans.csv), its std beside the paper\'s.');
}

function calibrationConsistency() {
  const C = csv['calibration_datasets.csv'];
  if (!C) return;
  consistency(C, 'table2', 'Table II: extrinsic calibration consistency', ['x_mm', 'y_mm', 'z_mm', 'roll_deg', 'pitch_deg', 'yaw_deg'],
    PAPER.table2_std, ['mm', 'mm', 'mm', 'deg', 'deg', 'deg'], 'The arm laser\'s mount from each data set (calibration_datasets.csv), its std beside the paper\'s.');
}

function estimate() {
  const T = csv['trajectory.csv'];
  if (!T || data.experiment !== 'estimate') return;
  const R = csv['relations.csv'];
  const s = section('estimate', 'Base state estimator on a recorded log', `${T.rows} scans of ${data.metrics?.log ?? 'the log'}; relations: ${data.metrics?.relations_file ?? 'none'}.`);
  const series = [{ label: 'estimated trajectory', x: T.col.x, y: T.col.y, color: '#1f77b4', width: 1 }];
  if (R) {
    // Relations with an error above the 90th percentile, drawn at their first scan's pose.
    const idx = (t) => { let lo = 0, hi = T.rows - 1; while (lo < hi) { const m = (lo + hi) >> 1; if (T.col.t[m] < t) lo = m + 1; else hi = m; } return lo; };
    const sorted = R.col.translation_error_m.slice().sort((a, b) => a - b);
    const p90 = sorted[Math.floor(0.9 * sorted.length)] ?? 0;
    const x = [], y = [];
    for (let r = 0; r < R.rows; r++) if (R.col.translation_error_m[r] >= p90) { const i = idx(R.col.t1[r]); x.push(T.col.x[i]); y.push(T.col.y[i]); }
    series.push({ label: `relations with the largest errors (>= ${p90.toFixed(3)} m)`, x, y, line: false, points: true, markerSize: 4, color: '#d62728' });
  }
  chart(s, (h) => xyChart(h, 'estimate-trajectory', series, { xlabel: 'x [m]', ylabel: 'y [m]', height: 560, equal: true }));
  if (R) {
    const s2 = section('estimate-errors', 'Relation errors over time', 'Translation and rotation error of every reference relation (Kümmerle et al. 2009), at the relation\'s first time.');
    const row = el('div', { class: 'row' });
    s2.append(row);
    const t0 = T.col.t[0];
    const t = R.col.t1.map((v) => v - t0);
    chart(row, (h) => xyChart(h, 'estimate-errors-m', [{ label: 'translation error [m]', x: t, y: R.col.translation_error_m, line: false, points: true, markerSize: 2 }], { xlabel: 'time since the first scan [s]', ylabel: 'm', height: 320 }));
    chart(row, (h) => xyChart(h, 'estimate-errors-deg', [{ label: 'rotation error [deg]', x: t, y: R.col.rotation_error_deg, line: false, points: true, markerSize: 2, color: '#ff7f0e' }], { xlabel: 'time since the first scan [s]', ylabel: 'deg', height: 320 }));
  }
}

function maneuvers() {
  const M = csv['maneuvers.csv'];
  if (!M) return;
  const s = section('maneuvers', 'Maneuvers without localization: end error and estimator drift', `${M.rows} maneuvers (maneuvers.csv).`);
  chart(s, (h) => seriesChart(h, 'maneuvers-plot', M.col.visit, [
    { label: 'end vs desired [cm]', y: M.col.end_error_m.map((v) => 100 * v), kind: 'dots' },
    { label: 'estimator drift [cm]', y: M.col.drift_m.map((v) => 100 * v), kind: 'dots' },
  ], { xlabel: 'visit', ylabel: 'cm', height: 340 }));
}

// --runs N: the distribution of every figure over the runs.
function overRuns() {
  const runs = data.runs || [];
  if (!runs.length) return;
  const s = section('over-runs', `Distributions over ${runs.length} runs`, 'Each figure of results.json over the runs (run_*/results.json); ifab report DIR/run_NNN draws one run\'s page.');
  const row = el('div', { class: 'row' });
  s.append(row);
  // Every number of a run's results.json, and every element of a list of numbers (key[i]).
  const figures = [];
  for (const [k, v] of Object.entries(runs[0])) {
    if (k === 'seed') continue;
    if (typeof v === 'number') figures.push([k, (r) => r[k]]);
    else if (Array.isArray(v) && v.every((x) => typeof x === 'number')) v.forEach((_, i) => figures.push([`${k}[${i}]`, (r) => (r[k] || [])[i]]));
  }
  const keys = figures.map((f) => f[0]);
  figures.forEach(([k, get], i) => hist(row, `runs-${i}`, runs.map(get).filter((v) => typeof v === 'number'), k, '', { bins: 10 }));
  report.figures['over-runs'] = { runs: runs.length, figures: keys.length };
}

function leftOut() {
  if (!(data.left_out || []).length) return;
  main.append(el('p', { class: 'note' }, `Left out of the page (too large): ${data.left_out.join(', ')}`));
}

async function draw() {
  try {
    header();
    resultsTable();
    overRuns();
    brickStack();
    maneuvers();
    lrfBias();
    basePlanning();
    armPlanning();
    registrationConsistency();
    calibrationConsistency();
    estimate();
    leftOut();
    main.append(el('p', { class: 'note' }, 'Drawn by ifab from the run folder; clouds are decimated for display (the PLY files keep every point).'));
    report.timings = [Math.round(performance.now() - report.scriptStart)];
    // Each draw, then a turn of the event loop: charts commit their drawing in a microtask.
    for (const f of pending) {
      const t0 = performance.now();
      await f();
      await new Promise((r) => setTimeout(r, 0));
      report.timings.push(Math.round(performance.now() - t0));
    }
    // Ready once the browser has painted a frame with everything (3D views render in a frame).
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
  } catch (e) {
    report.errors.push(String(e && e.stack || e));
    console.error(e);
  }
  report.ready = true;
  report.loadMs = performance.now();
}
draw();
