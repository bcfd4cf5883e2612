// The viewer's frame rate in Debian's headless Chromium (software GL unless the
// machine offers more): one progressive frame = the fabric pass with `spp`
// samples per pixel + accumulation + display, finished by the GPU before the
// next (woven.fps). Canvas 1024 x 768 for the swatch and the draped sheet, the
// scene's own size (512 x 512) for the flat45 rig. Median of `runs` windows of
// `seconds` each, and frames per CPU second of all of Chromium's processes
// (steadier than the wall clock on a shared machine). Prints a table, then one
// JSON line.
// With --back, each view also with its back light on (the light through the
// cloth: `?back=1`, the rig's flat45-back view), rows "rig+back" and so on.
// Usage: node bench/viewer_fps.mjs WOVEN SOURCE_DIR [--runs 3] [--seconds 3] [--spp 1,4] [--back]
import { execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { mkdtempSync, readdirSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';

const args = process.argv.slice(2);
const opt = (name, dflt) => { const i = args.indexOf(name); return i >= 0 ? args[i + 1] : dflt; };
const [WOVEN, SRC] = args.slice(0, 2).map((a) => resolve(a));
const { chromium } = createRequire(join(SRC, 'web/package.json'))('playwright-core');
const runs = Number(opt('--runs', '3')), seconds = Number(opt('--seconds', '3'));
const spps = opt('--spp', '1,4').split(',').map(Number);
const work = mkdtempSync(join(tmpdir(), 'woven-fps-'));
const html = join(work, 'twill.html');
execFileSync(WOVEN, ['view', join(SRC, 'examples/twill.json'), '-o', html, '-q']);
const profile = join(work, 'profile');
const context = await chromium.launchPersistentContext(profile, {
  executablePath: '/usr/bin/chromium', headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'],
  viewport: { width: 1400, height: 900 }, deviceScaleFactor: 1,
});
// CPU seconds (user + system) of Chromium: the processes started with this
// profile and all their descendants, from /proc.
function cpuSeconds() {
  const info = new Map();
  for (const d of readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const f = readFileSync(`/proc/${d}/stat`, 'utf8'), rest = f.slice(f.lastIndexOf(')') + 2).split(' ');
      const cmd = readFileSync(`/proc/${d}/cmdline`, 'utf8');
      info.set(Number(d), { ppid: Number(rest[1]), ticks: Number(rest[11]) + Number(rest[12]), root: cmd.includes(profile) });
    } catch { /* the process ended */ }
  }
  let sum = 0;
  const inTree = (pid) => { for (let p = pid; p > 1; p = info.get(p)?.ppid ?? 0) if (info.get(p)?.root) return true; return false; };
  for (const [pid, v] of info) if (inTree(pid)) sum += v.ticks;
  return sum / 100; // clock ticks per second on Linux
}
const results = [];
let renderer = '';
const views = [['rig', 'mode=rig'], ['swatch', 'mode=swatch&w=1024&h=768'], ['drape', 'mode=drape&w=1024&h=768']];
if (args.includes('--back')) for (const [m, q] of views.slice()) views.push([`${m}+back`, `${q}&back=1`]);
for (const [mode, query] of views) {
  const page = await context.newPage();
  await page.goto(`file://${html}?${query}&frames=1`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 120000 });
  for (const spp of spps) {
    await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp); // compiled, warm
    const f = [], fc = [];
    for (let r = 0; r < runs; r++) {
      const c0 = cpuSeconds();
      const m = await page.evaluate(([ms]) => window.woven.fps(ms), [seconds * 1000]);
      f.push(m.fps);
      fc.push(m.frames / (cpuSeconds() - c0));
      renderer = m.renderer;
      if (r === 0) results.push({ mode, size: m.size, spp });
    }
    f.sort((a, b) => a - b);
    fc.sort((a, b) => a - b);
    Object.assign(results[results.length - 1], { fps: f[runs >> 1], frames_per_cpu_second: fc[runs >> 1], runs: f });
  }
  await page.close();
}
await context.close();
rmSync(work, { recursive: true, force: true });
for (const r of results)
  console.log(`${r.mode.padEnd(11)} ${r.size.join(' x ').padEnd(11)} ${String(r.spp).padStart(3)} spp  ` +
              `${r.fps.toFixed(2)} frames/s  ${r.frames_per_cpu_second.toFixed(2)} frames per CPU second`);
const load = readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).join(' ');
console.log(JSON.stringify({ renderer, runs, seconds, load_average: load, results }));
