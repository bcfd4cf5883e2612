// woven's browser test (run by ctest): in Debian's headless Chromium (software
// GL), per weave pattern on the flat45 capture scene,
//   1. the viewer (`woven view`) renders the capture view; its screenshot is
//      compared with `woven render` of the same scene: SSIM of 4-px Gaussian
//      blurs of both (`woven compare --blur 4`) must reach 0.9;
//   2. the glTF export (`woven export`) passes the Khronos validator with no
//      error, and three.js's own loader and physical material render it in the
//      same scene: its SSIM against woven's render is reported;
// and the viewer refuses out-of-range parameters visibly. Nothing is fetched:
// the viewer is a file, the glTF page is served from web/ by request
// interception, and any other request fails the test.
// Usage: node browser.test.mjs WOVEN SOURCE_DIR [--patterns a,b,..] [--keep DIR] [--spp N]
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync, mkdirSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, extname } from 'node:path';
import { chromium } from 'playwright-core';
import { validateBytes } from 'gltf-validator';

const args = process.argv.slice(2);
const opt = (name, dflt) => { const i = args.indexOf(name); return i >= 0 ? args[i + 1] : dflt; };
const [WOVEN, SRC] = args.map((a) => resolve(a));
const patterns = opt('--patterns', 'plain,twill,satin').split(',');
const spp = Number(opt('--spp', '16'));
const keep = opt('--keep', null);
const work = keep ? resolve(keep) : mkdtempSync(join(tmpdir(), 'woven-browser-'));
mkdirSync(work, { recursive: true });
const profile = mkdtempSync(join(tmpdir(), 'woven-chromium-profile-'));
let failures = 0;
const fail = (msg) => { console.log(`FAIL ${msg}`); failures++; };
const woven = (...a) => execFileSync(WOVEN, a, { encoding: 'utf8' });
const png = (dataUrl, file) => writeFileSync(file, Buffer.from(dataUrl.split(',')[1], 'base64'));
const compare = (a, b, blur = 4) => JSON.parse(woven('compare', a, b, '--blur', String(blur), '--json'));

const t0 = Date.now();
const browser = await chromium.launchPersistentContext(profile, {
  executablePath: '/usr/bin/chromium',
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync',
         '--enable-unsafe-swiftshader'],
  viewport: { width: 1200, height: 800 },
  deviceScaleFactor: 1,
});
const MIME = { '.js': 'text/javascript', '.html': 'text/html', '.frag': 'text/plain', '.vert': 'text/plain',
               '.glb': 'model/gltf-binary' };
// The glTF page's origin: files from web/ and the work directory, nothing else.
await browser.route('**/*', (route) => {
  const u = new URL(route.request().url());
  if (u.protocol === 'file:' || u.protocol === 'blob:' || u.protocol === 'data:') return route.continue();
  if (u.host !== 'woven.test') {
    fail(`request to ${u.href}`);
    return route.abort();
  }
  const p = u.pathname;
  const file = p.startsWith('/three/') ? join(SRC, 'web/node_modules', p)
             : p.startsWith('/work/') ? join(work, p.slice(6)) : join(SRC, 'web', p);
  if (!existsSync(file)) return route.fulfill({ status: 404, body: 'not found' });
  return route.fulfill({ status: 200, contentType: MIME[extname(file)] || 'application/octet-stream', body: readFileSync(file) });
});

const rows = [];
const flat45 = JSON.parse(readFileSync(join(SRC, 'scenes/flat45.json'), 'utf8'));
const gpage = await browser.newPage();
gpage.on('pageerror', (e) => fail(`glTF page: ${e.message}`));
await gpage.goto('http://woven.test/test/gltf_page.html');
await gpage.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
let rendererName = '';
for (const pat of patterns) {
  const params = join(SRC, 'examples', `${pat}.json`);
  const c = join(work, `${pat}_c.png`), html = join(work, `${pat}.html`), glb = join(work, `${pat}.glb`);
  woven('render', '--params', params, '--scene', 'flat45', '-o', c, '-q');
  woven('view', params, '-o', html, '-q');
  const exp = JSON.parse(woven('export', params, '--gltf', glb, '--texture', '32', '--json'));
  const report = await validateBytes(new Uint8Array(readFileSync(glb)), { uri: glb });
  if (report.issues.numErrors) fail(`${pat}: the glTF validator reports ${report.issues.numErrors} errors`);

  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${pat} viewer: ${e.message}`));
  await page.goto(`file://${html}?frames=1&spp=${spp}`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 60000 });
  const t1 = Date.now();
  const r = await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp);
  const ms = Date.now() - t1;
  if (!r.valid) fail(`${pat}: the viewer refused the example's parameters`);
  const v = join(work, `${pat}_viewer.png`);
  png(await page.evaluate(() => window.woven.snapshot()), v);
  if (!rendererName)
    rendererName = await page.evaluate(() => {
      const gl = document.querySelector('canvas').getContext('webgl2');
      const d = gl.getExtension('WEBGL_debug_renderer_info');
      return gl.getParameter(d ? d.UNMASKED_RENDERER_WEBGL : gl.RENDERER);
    });
  if (pat === patterns[0]) { // out-of-range parameters: refused, and shown
    const bad = await page.evaluate(() => window.woven.setParam('density.warp', 400));
    const shown = await page.evaluate(() => getComputedStyle(document.getElementById('error')).display !== 'none' &&
                                            document.getElementById('error').textContent);
    if (!bad.length || !shown || !shown.includes('density.warp')) fail('out-of-range density was not refused visibly');
  }
  await page.close();

  const t = join(work, `${pat}_gltf.png`);
  png(await gpage.evaluate(([u, sc]) => window.renderGltf(u, sc), [`http://woven.test/work/${pat}.glb`, flat45]), t);
  const sv = compare(c, v), sg = compare(c, t), rv = compare(c, v, 0), rg = compare(c, t, 0);
  rows.push({ pattern: pat, viewer_ssim_blur4: sv.ssim, viewer_mae_blur4: sv.mae, viewer_ssim: rv.ssim, viewer_ms: ms,
              gltf_ssim_blur4: sg.ssim, gltf_mae_blur4: sg.mae, gltf_ssim: rg.ssim, bake_relative_residual: exp.fit.relative,
              validator_errors: report.issues.numErrors, validator_warnings: report.issues.numWarnings });
  if (!(sv.ssim >= 0.9)) fail(`${pat}: viewer vs woven render SSIM ${sv.ssim.toFixed(4)} < 0.9`);
}

// The draped sheet (first pattern): the viewer's true model against the glTF of
// the same mesh in three.js, one point light, the viewer's camera. No woven
// render of a mesh exists yet to compare both with; this says how far the
// baked approximation is from the true model there.
const drape = {};
{
  const pat = patterns[0], html = join(work, `${pat}.html`), glb = join(work, `${pat}_drape.glb`);
  woven('export', join(SRC, 'examples', `${pat}.json`), '--gltf', glb, '--mesh', 'drape', '--texture', '32', '-q');
  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${pat} drape viewer: ${e.message}`));
  await page.goto(`file://${html}?mode=drape&lights=point&w=384&h=288`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 60000 });
  await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp);
  const v = join(work, `${pat}_drape_viewer.png`), t = join(work, `${pat}_drape_gltf.png`);
  png(await page.evaluate(() => window.woven.snapshot()), v);
  const view = await page.evaluate(() => window.woven.view());
  await page.close();
  png(await gpage.evaluate(([u, vw]) => window.renderGltfView(u, vw), [`http://woven.test/work/${pat}_drape.glb`, view]), t);
  const s = compare(v, t);
  Object.assign(drape, { pattern: pat, gltf_vs_viewer_ssim_blur4: s.ssim, gltf_vs_viewer_mae_blur4: s.mae });
  writeFileSync(join(work, 'drape_pattern.txt'), pat);
}
await browser.close();
rmSync(profile, { recursive: true, force: true });
if (!keep) rmSync(work, { recursive: true, force: true });

console.log('flat45 against woven render: SSIM and MAE of 4-px blurs, SSIM unblurred');
console.log('pattern   viewer: SSIM    MAE   SSIM raw | glTF: SSIM    MAE   SSIM raw | bake residual | viewer ms');
const f = (x, n = 4) => x.toFixed(n).padStart(8);
for (const r of rows)
  console.log(`${r.pattern.padEnd(9)} ${f(r.viewer_ssim_blur4)} ${f(r.viewer_mae_blur4)} ${f(r.viewer_ssim)}   ` +
              `${f(r.gltf_ssim_blur4)} ${f(r.gltf_mae_blur4)} ${f(r.gltf_ssim)}   ${(100 * r.bake_relative_residual).toFixed(1).padStart(9)} %` +
              `   ${String(r.viewer_ms).padStart(8)}`);
console.log(`draped sheet (${drape.pattern}): glTF in three.js vs the viewer, SSIM ${drape.gltf_vs_viewer_ssim_blur4.toFixed(4)} (4-px blur)`);
console.log(JSON.stringify({ renderer: rendererName, spp, seconds: (Date.now() - t0) / 1000, results: rows, drape }));
console.log(failures ? `${failures} failed` : 'all passed');
process.exit(failures ? 1 : 0);
