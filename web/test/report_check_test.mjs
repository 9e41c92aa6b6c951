// The test of the browser test: report_check.mjs must fail when a figure is missing or empty.
// From a good run folder it makes broken copies (a trajectory CSV emptied, the clouds removed),
// draws their pages with `ifab report`, checks them against the good run's files, and expects
// the named failure for each; the good run's own page must pass.
//   node report_check_test.mjs --run DIR --ifab PATH --work DIR
import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { checkReport } from './report_check.mjs';

const args = process.argv.slice(2);
const opt = {};
for (let i = 0; i < args.length; i += 2) opt[args[i].replace(/^--/, '')] = args[i + 1];
if (!opt.run || !opt.ifab || !opt.work) {
  console.error('usage: node report_check_test.mjs --run DIR --ifab PATH --work DIR');
  process.exit(1);
}

function brokenCopy(name, breakIt) {
  const dir = path.join(opt.work, name);
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  for (const f of fs.readdirSync(opt.run)) {
    const src = path.join(opt.run, f);
    if (fs.statSync(src).isFile() && f !== 'report.html') fs.copyFileSync(src, path.join(dir, f));
  }
  breakIt(dir);
  execFileSync(opt.ifab, ['report', dir], { stdio: 'inherit' });
  return path.join(dir, 'report.html');
}

const cases = [
  {
    name: 'good page passes',
    report: () => path.join(opt.run, 'report.html'),
    expect: null,
  },
  {
    name: 'empty true trajectory (Fig. 6)',
    report: () => brokenCopy('empty_true_trajectory', (d) => {
      const f = path.join(d, 'trajectory_true.csv');
      fs.writeFileSync(f, fs.readFileSync(f, 'utf8').split('\n')[0] + '\n');
    }),
    expect: /fig6: 'true' trajectory drew 0 points/,
  },
  {
    name: 'no clouds (Fig. 3, 4)',
    report: () => brokenCopy('no_clouds', (d) => {
      for (const f of fs.readdirSync(d)) if (f.endsWith('.ply')) fs.rmSync(path.join(d, f));
    }),
    expect: /fig3: figure missing/,
  },
  {
    name: 'no brick errors (bricks figure, replay)',
    report: () => brokenCopy('no_brick_errors', (d) => fs.rmSync(path.join(d, 'brick_errors.csv'))),
    expect: /bricks-plot: figure missing/,
  },
];

let passed = 0, failed = 0;
for (const c of cases) {
  const { failures } = await checkReport({ report: c.report(), run: opt.run, log: () => {} });
  const ok = c.expect === null ? failures.length === 0 : failures.some((f) => c.expect.test(f));
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${c.name}: ${failures.length ? failures.join(' | ') : 'no failures'}`);
  if (ok) passed++; else failed++;
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
