// Opens an ifab report.html in Debian's headless Chromium (puppeteer-core) and checks, from the
// page itself, that every figure is there with the run's data: no console errors, no network;
// trajectory points drawn == the CSVs' rows, one bar per brick, the registered brick drawn, the
// 3D replay non-blank and moving with its slider. The run folder's files are read here, apart
// from the page, so a page that lost data does not agree with them.
//
//   node report_check.mjs --report DIR/report.html [--run DIR] [--screenshot FILE.png] [--replay-shot FILE.png]
// Exit 0: all checks passed; 3: a check failed (each failure printed); 1: could not run.
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import puppeteer from 'puppeteer-core';

export function chromiumPath() {
  for (const p of [process.env.CHROMIUM, '/usr/bin/chromium', '/usr/bin/chromium-browser']) if (p && fs.existsSync(p)) return p;
  throw new Error('no Chromium found (scripts/install-deps installs Debian\'s chromium; or set CHROMIUM)');
}

const csvRows = (file) => {
  if (!fs.existsSync(file)) return null;
  return fs.readFileSync(file, 'utf8').split('\n').filter((l) => l.length > 0).length - 1;
};
const plyVertices = (file) => {
  const head = fs.readFileSync(file).subarray(0, 2048).toString('latin1');
  const m = /element vertex (\d+)/.exec(head);
  return m ? Number(m[1]) : null;
};

export async function checkReport({ report, run, screenshot, replayShot, log = console.log }) {
  const failures = [];
  const fail = (what) => failures.push(what);
  run = run || path.dirname(report);
  const results = JSON.parse(fs.readFileSync(path.join(run, 'results.json'), 'utf8'));
  const browser = await puppeteer.launch({
    executablePath: chromiumPath(),
    headless: true,
    // No GPU here: WebGL on SwiftShader, the page composited in software (compositing through
    // SwiftShader alone took 2-3 s of CPU for this page).
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-gpu-compositing', '--window-size=1400,1000'],
  });
  const info = { bytes: fs.statSync(report).size };
  try {
    const page = await browser.newPage();
    await page.setViewport({ width: 1400, height: 1000 });
    const consoleErrors = [];
    page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
    page.on('pageerror', (e) => consoleErrors.push(String(e)));
    const network = [];
    await page.setRequestInterception(true);
    page.on('request', (r) => {
      const u = r.url();
      if (u.startsWith('file:') || u.startsWith('data:') || u.startsWith('blob:') || u === 'about:blank') r.continue();
      else { network.push(u); r.abort(); }
    });
    const t0 = Date.now();
    await page.goto(pathToFileURL(path.resolve(report)).href, { waitUntil: 'load', timeout: 120000 });
    await page.waitForFunction(() => window.ifabReport && window.ifabReport.ready, { timeout: 120000 });
    info.open_ms = Date.now() - t0;
    info.ready_ms = await page.evaluate(() => window.ifabReport.loadMs);
    if (consoleErrors.length) fail(`console errors: ${consoleErrors.join(' | ')}`);
    if (network.length) fail(`the page asked the network for: ${network.join(', ')}`);
    const pageErrors = await page.evaluate(() => window.ifabReport.errors);
    if (pageErrors.length) fail(`the page failed to draw: ${pageErrors.join(' | ')}`);

    // What each chart drew, per series, read back from the charts themselves (uPlot's data).
    const drawn = await page.evaluate(() => ({
      plots: window.ifabReport.drawn(),
      figures: window.ifabReport.figures,
      tableRows: document.querySelectorAll('#results table tr').length - 1,
      canvases: Object.fromEntries([...document.querySelectorAll('.chart')].map((c) => [c.id, !!c.querySelector('canvas')])),
    }));
    const trace = (fig, name) => (drawn.plots[fig] || []).find((t) => t.label === name);
    const need = (fig) => {
      if (!drawn.plots[fig] || !drawn.canvases[fig]) { fail(`${fig}: figure missing`); return false; }
      if (drawn.plots[fig].every((t) => t.n === 0)) { fail(`${fig}: figure is empty`); return false; }
      return true;
    };

    if (!(drawn.tableRows > 0)) fail('results table: missing or empty');
    // Fig. 6: every row of the trajectory CSVs drawn.
    if (need('fig6-plot')) {
      for (const [name, file] of [['true', 'trajectory_true.csv'], ['estimated', 'trajectory_estimated.csv'], ['planned', 'trajectory_planned.csv']]) {
        const rows = csvRows(path.join(run, file));
        const t = trace('fig6-plot', name);
        if (rows === null) fail(`fig6: ${file} missing from the run folder`);
        else if (!t) fail(`fig6: no '${name}' trajectory drawn`);
        else if (rows === 0 || t.n !== rows) fail(`fig6: '${name}' trajectory drew ${t.n} points, ${file} has ${rows} rows`);
      }
      const visitsCsv = fs.readFileSync(path.join(run, 'visits.csv'), 'utf8').split('\n').slice(1).filter(Boolean);
      const localized = visitsCsv.filter((l) => l.split(',')[8] === 'true' || l.split(',')[8] === '1').length;
      const steps = trace('fig6-plot', 'localization step');
      if (!steps || steps.n !== 2 * localized) fail(`fig6: ${steps ? steps.n / 2 : 0} localization steps drawn, visits.csv has ${localized}`);
    }
    // Brick errors: one bar per brick placed.
    const bricks = results.bricks_placed;
    if (!(bricks > 0)) fail(`results.json: bricks_placed is ${bricks}`);
    if (need('bricks-plot')) {
      for (const name of ['long face [mm]', 'short face [mm]', 'away from the robot [mm]']) {
        const t = trace('bricks-plot', name);
        if (!t || t.n !== bricks) fail(`bricks: '${name}' has ${t ? t.n : 0} bars, ${bricks} bricks were placed`);
      }
    }
    if (need('bricks-by-position')) {
      const t = trace('bricks-by-position', 'long face');
      if (!t || t.n !== bricks) fail(`bricks by position: ${t ? t.n : 0} bricks drawn, ${bricks} placed`);
    }
    // Fig. 3: the cloud of the chosen visit (decimated) and the registered brick, read back from
    // its 3D scene; its canvas must show them.
    const f3 = await page.evaluate(() => (window.ifabReport.fig3 ? window.ifabReport.fig3.inspect() : null));
    if (!f3) fail('fig3: figure missing');
    else {
      const ply = path.join(run, `cloud_visit_${String(f3.visit).padStart(2, '0')}.ply`);
      const n = fs.existsSync(ply) ? plyVertices(ply) : null;
      if (n === null) fail(`fig3: ${ply} missing`);
      else if (f3.points !== Math.ceil(n / f3.stride) || f3.points < Math.min(n, 1000))
        fail(`fig3: cloud drew ${f3.points} points, expected every ${f3.stride}th of the PLY's ${n} (at least ${Math.min(n, 1000)})`);
      if (f3.registered_brick === 0) fail('fig3: the registered brick is not drawn');
      if (f3.lit < 0.02 * f3.total) fail(`fig3: the view is blank (${f3.lit} of ${f3.total} pixels drawn)`);
      if (f3.red < 0.002 * f3.total) fail(`fig3: the registered brick is not to be seen (${f3.red} red pixels)`);
      info.fig3 = { lit_fraction: +(f3.lit / f3.total).toFixed(3), red_fraction: +(f3.red / f3.total).toFixed(4) };
    }
    if (need('fig4-before')) {
      if (!trace('fig4-before', 'shadow points')) fail('fig4: no shadow points trace');
      if (!drawn.plots['fig4-after'] || trace('fig4-after', 'shadow points')) fail('fig4: the after-removal plot is missing or still shows shadow points');
    }
    // The 3D replay (made when scrolled to, as a person would): pixels drawn, and the robot
    // moves with the slider.
    const hasReplay = await page.evaluate(() => {
      const e = document.getElementById('replay');
      if (e) e.scrollIntoView();
      return !!e;
    });
    if (hasReplay) await page.waitForFunction(() => window.ifabReport.replay, { timeout: 60000 }).catch(() => {});
    const replay = await page.evaluate(() => {
      const r = window.ifabReport.replay;
      if (!r) return null;
      const before = r.litPixels(), p0 = r.robotPosition();
      const slider = document.getElementById('replay-slider');
      slider.value = String(Math.floor(r.samples * 0.45));
      slider.dispatchEvent(new Event('input'));
      const after = r.litPixels(), p1 = r.robotPosition();
      return { samples: r.samples, lit: before.lit, total: before.total, changed: before.url !== after.url, moved: Math.hypot(p1[0] - p0[0], p1[1] - p0[1]) };
    });
    if (!replay) fail('replay: missing');
    else {
      const rows = csvRows(path.join(run, 'replay.csv'));
      if (replay.samples !== rows || rows === 0) fail(`replay: ${replay.samples} samples, replay.csv has ${rows} rows`);
      if (replay.lit < 0.05 * replay.total) fail(`replay: the 3D view is blank (${replay.lit} of ${replay.total} pixels drawn)`);
      if (!(replay.moved > 0.05)) fail(`replay: moving the slider moved the robot ${replay.moved} m`);
      if (!replay.changed) fail('replay: moving the slider did not change the picture');
      info.replay = { lit_fraction: +(replay.lit / replay.total).toFixed(3), robot_moved_m: +replay.moved.toFixed(3) };
    }
    if (screenshot) {
      fs.mkdirSync(path.dirname(screenshot), { recursive: true });
      await page.evaluate(() => window.scrollTo(0, 0));
      await page.screenshot({ path: screenshot, fullPage: true });
    }
    if (replayShot) {
      const s = await page.$('#replay');
      if (s) await s.screenshot({ path: replayShot });
    }
    info.figures = Object.keys(drawn.plots).length;
  } finally {
    await browser.close();
  }
  log(`report ${report}: ${(info.bytes / 1e6).toFixed(1)} MB, ready in ${info.ready_ms?.toFixed(0)} ms (open to ready ${info.open_ms} ms), ` +
    `${info.figures} plots, fig3 ${JSON.stringify(info.fig3)}, replay ${JSON.stringify(info.replay)}`);
  return { failures, info };
}

async function main() {
  const args = process.argv.slice(2);
  const opt = {};
  for (let i = 0; i < args.length; i += 2) opt[args[i].replace(/^--/, '').replace(/-(.)/g, (_, c) => c.toUpperCase())] = args[i + 1];
  if (!opt.report) { console.error('usage: node report_check.mjs --report DIR/report.html [--run DIR] [--screenshot FILE] [--replay-shot FILE]'); process.exit(1); }
  try {
    const { failures } = await checkReport(opt);
    for (const f of failures) console.log(`FAIL ${f}`);
    console.log(failures.length ? `${failures.length} check(s) failed` : 'all checks passed');
    process.exit(failures.length ? 3 : 0);
  } catch (e) {
    console.error(`report_check: could not run: ${e.stack || e}`);
    process.exit(1);
  }
}
if (import.meta.url === pathToFileURL(process.argv[1]).href) main();
