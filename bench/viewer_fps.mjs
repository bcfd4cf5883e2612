// The viewer's frame rate in Debian's headless Chromium (software GL unless the
// machine offers more): one progressive frame = the fabric pass with `spp`
// samples per pixel + accumulation + display, finished by the GPU before the
// next (woven.fps). Canvas 1024 x 768 for the swatch and the draped sheet, the
// scene's own size (512 x 512) for the flat45 rig. Median of `runs` windows of
// `seconds` each. Prints a table, then one JSON line.
// Usage: node bench/viewer_fps.mjs WOVEN SOURCE_DIR [--runs 3] [--seconds 3] [--spp 1,4]
import { execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
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
const browser = await chromium.launchPersistentContext(join(work, 'profile'), {
  executablePath: '/usr/bin/chromium', headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'],
  viewport: { width: 1400, height: 900 }, deviceScaleFactor: 1,
});
const results = [];
let renderer = '';
for (const [mode, query] of [['rig', 'mode=rig'], ['swatch', 'mode=swatch&w=1024&h=768'], ['drape', 'mode=drape&w=1024&h=768']]) {
  const page = await browser.newPage();
  await page.goto(`file://${html}?${query}&frames=1`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 120000 });
  for (const spp of spps) {
    await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp); // compiled, warm
    const f = [];
    for (let r = 0; r < runs; r++) {
      const m = await page.evaluate(([ms]) => window.woven.fps(ms), [seconds * 1000]);
      f.push(m.fps);
      renderer = m.renderer;
      if (r === 0) results.push({ mode, size: m.size, spp });
    }
    f.sort((a, b) => a - b);
    Object.assign(results[results.length - 1], { fps: f[runs >> 1], runs: f });
  }
  await page.close();
}
await browser.close();
rmSync(work, { recursive: true, force: true });
for (const r of results)
  console.log(`${r.mode.padEnd(7)} ${r.size.join(' x ').padEnd(11)} ${String(r.spp).padStart(3)} spp  ${r.fps.toFixed(2)} frames/s`);
console.log(JSON.stringify({ renderer, runs, seconds, results }));
