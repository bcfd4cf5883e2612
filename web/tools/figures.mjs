// Makes the docs' pictures (docs/figures/) in Debian's headless Chromium:
//   flat45_<pattern>.png  centre crops, 3x: woven render | viewer | glTF in three.js
//                         (from the images `web/test/browser.test.mjs --keep DIR` leaves)
//   drape_<pattern>.png   the draped sheet (the first pattern), key light alone:
//                         woven scene | viewer | glTF in three.js
//   viewer_ui.png         the viewer's page: the draped sheet under the studio lights
// Usage: node web/tools/figures.mjs WOVEN SOURCE_DIR KEEP_DIR [patterns...]
import { execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';

const [WOVEN, SRC, KEEP] = process.argv.slice(2, 5).map((a) => resolve(a));
const patterns = process.argv.slice(5).length ? process.argv.slice(5) : ['twill', 'satin'];
const { chromium } = createRequire(join(SRC, 'web/package.json'))('playwright-core');
const out = join(SRC, 'docs/figures');
mkdirSync(out, { recursive: true });
const work = mkdtempSync(join(tmpdir(), 'woven-figures-'));
const browser = await chromium.launchPersistentContext(join(work, 'profile'), {
  executablePath: '/usr/bin/chromium', headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'],
  viewport: { width: 1000, height: 600 }, deviceScaleFactor: 1,
});

// Images side by side (crop x, y, w, h of each, scaled by k), with captions.
async function panel(file, imgs, labels, [x, y, w, h], k) {
  const page = await browser.newPage();
  await page.setViewportSize({ width: imgs.length * (w * k + 8) - 8, height: h * k + 20 });
  const srcs = imgs.map((f) => 'data:image/png;base64,' + readFileSync(f).toString('base64'));
  await page.setContent(`<body style="margin:0;background:#fff;font:13px sans-serif;display:flex;gap:8px">${srcs.map((_, i) =>
    `<div><canvas id=c${i} width=${w * k} height=${h * k} style="display:block"></canvas>` +
    `<div style="height:18px">${labels[i]}</div></div>`).join('')}</body>`);
  await page.evaluate(async ([s, r, kk]) => {
    for (let i = 0; i < s.length; i++) {
      const im = new Image();
      im.src = s[i];
      await im.decode();
      const c = document.getElementById('c' + i).getContext('2d');
      c.imageSmoothingEnabled = false;
      c.drawImage(im, r[0], r[1], r[2], r[3], 0, 0, r[2] * kk, r[3] * kk);
    }
  }, [srcs, [x, y, w, h], k]);
  await page.screenshot({ path: file });
  await page.close();
}

for (const p of patterns) {
  await panel(join(out, `flat45_${p}.png`), ['c', 'viewer', 'gltf'].map((s) => join(KEEP, `${p}_${s}.png`)),
              ['woven render (C, 64 spp)', 'viewer (WebGL, 4 spp)', 'glTF in three.js'], [208, 208, 96, 96], 3);
}
const dp = patterns[0];
await panel(join(out, `drape_${dp}.png`), ['c', 'viewer', 'gltf'].map((s) => join(KEEP, `${dp}_drape_${s}.png`)),
            ['woven scene (C path tracer)', 'viewer: the true model', 'glTF in three.js: the baked approximation'],
            [0, 0, 384, 288], 1);

const html = join(work, 'satin.html');
if (process.env.WOVEN_FIGURES_NO_UI) { // the panels only
  await browser.close();
  rmSync(work, { recursive: true, force: true });
  process.exit(0);
}
execFileSync(WOVEN, ['view', join(SRC, 'examples/satin.json'), '-o', html, '-q']);
const page = await browser.newPage();
await page.goto(`file://${html}?mode=drape&frames=1`);
await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 120000 });
await page.evaluate(() => window.woven.render({ frames: 16, spp: 4 }));
await page.screenshot({ path: join(out, 'viewer_ui.png'), timeout: 300000 });
await browser.close();
rmSync(work, { recursive: true, force: true });
console.log(`wrote ${out}`);
