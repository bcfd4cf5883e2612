// woven's browser test (run by ctest): in Debian's headless Chromium (software
// GL), per weave pattern,
//   1. on the flat45 capture scene, the viewer (`woven view`) renders the
//      capture view; its screenshot is compared with `woven render` of the same
//      scene: SSIM of 4-px Gaussian blurs of both (`woven compare --blur 4`)
//      must reach 0.9;
//   2. the glTF export (`woven export`) passes the Khronos validator with no
//      error, and three.js's own loader and physical material render it in the
//      same scene: its SSIM against woven's render is reported;
//   3. on the flat swatch and on the draped sheet, the viewer's studio view with
//      its key light alone is written as a `woven scene` file (camera, light,
//      the page's own mesh, uv scale, response) and rendered by woven's path
//      tracer: viewer vs that render must reach SSIM 0.9 (4-px blur); the glTF
//      of the same mesh in three.js, same view, is reported against it; and
//      spp frames of one sample give the picture of one frame of spp samples
//      (the progressive accumulation);
//   4. the viewer's back-lit rig view (`?back=1`: the light behind the cloth,
//      flat45-back; 16 frames of spp samples) against `woven render --scene
//      flat45-back`: SSIM of 4-px blurs >= 0.999 and their MAE <= 0.002, on
//      each pattern and on twill with open gaps (yarn width 0.75) and specular transmission colours of its own, where the
//      centre's mean (the gap glow, clipped) must also be within 5 % of woven's, and on twill with a forward
//      band (transmission_forward of its own per yarn type, forward_width 0.15); woven's renders without the diffuse
//      transmission, without the specular transmission, without the forward band (where there is one) and without
//      the gap glow must each miss those bounds (so a viewer without them would fail); the
//      glTF export carries KHR_materials_diffuse_transmission (and, with open
//      gaps, KHR_materials_transmission), validates, and three.js's render of it
//      in flat45-back (the light seen through the gaps as a lamp behind the
//      cloth) is brighter at the centre than the same file without
//      KHR_materials_transmission (its SSIM against woven's render is reported);
// and the viewer refuses out-of-range parameters visibly. Nothing is fetched:
// the viewer is a file, the glTF page is served from web/ by request
// interception, and any other request fails the test.
// Usage: node browser.test.mjs WOVEN SOURCE_DIR [--patterns a,b,..] [--keep DIR] [--spp N]
//        [--scene-spp N] [--size WxH]
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
const cspp = Number(opt('--scene-spp', '16')); // woven scene's camera rays per pixel (x 4 yarn samples)
const studioSize = opt('--size', '384x288').split('x').map(Number);
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

// A float32 array from base64 (the page's meshes) or from a .glb's accessor.
const f32 = (buf) => new Float32Array(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
function glbPositions(file) {
  const b = readFileSync(file), jlen = b.readUInt32LE(12);
  const j = JSON.parse(b.subarray(20, 20 + jlen).toString('utf8'));
  const bin = b.subarray(20 + jlen + 8);
  const acc = j.accessors[j.meshes[0].primitives[0].attributes.POSITION], bv = j.bufferViews[acc.bufferView];
  const off = (bv.byteOffset || 0) + (acc.byteOffset || 0);
  return f32(bin.subarray(off, off + 12 * acc.count));
}

// The page's mesh as an OBJ with exactly its float vertices (printed in full:
// they read back bit for bit), normals and UVs. The viewer takes fabric y = -v
// (its bitangent points along -dP/dv); woven scene takes fabric y = +v, so the
// file carries -v: the same fabric point at every vertex, the same frame.
function writeObj(mesh, file) {
  const p = f32(Buffer.from(mesh.positions, 'base64')), n = f32(Buffer.from(mesh.normals, 'base64'));
  const uv = f32(Buffer.from(mesh.uvs, 'base64')), ib = Buffer.from(mesh.indices, 'base64');
  const idx = new Uint32Array(ib.buffer.slice(ib.byteOffset, ib.byteOffset + ib.byteLength));
  const out = ['# woven viewer mesh (metres)'];
  for (let i = 0; i < p.length; i += 3) out.push(`v ${p[i]} ${p[i + 1]} ${p[i + 2]}`);
  for (let i = 0; i < n.length; i += 3) out.push(`vn ${n[i]} ${n[i + 1]} ${n[i + 2]}`);
  for (let i = 0; i < uv.length; i += 2) out.push(`vt ${uv[i]} ${-uv[i + 1]}`);
  for (let i = 0; i < idx.length; i += 3) {
    const [a, b, c] = [idx[i] + 1, idx[i + 1] + 1, idx[i + 2] + 1];
    out.push(`f ${a}/${a}/${a} ${b}/${b}/${b} ${c}/${c}/${c}`);
  }
  writeFileSync(file, out.join('\n') + '\n');
  return p;
}

// woven scene's file for the viewer's studio view v (woven.view() with
// ?lights=point): its camera, its key light, its mesh and uv scale, direct light
// only, the studio display (exposure, clip at 1, sRGB). The page works in
// metres, scenes in millimetres: positions x 1000, intensity x 1000^2 (I / r^2).
function studioScene(v, params, obj, uvMm, cspp) {
  const mm = (a) => a.map((x) => 1000 * x);
  return {
    name: `viewer-${v.mode}`,
    image: { width: v.size[0], height: v.size[1], spp: cspp },
    camera: { position_mm: mm(v.camera.position), look_at_mm: mm(v.camera.target), up: v.camera.up, vfov_deg: v.camera.fov },
    lights: [{ type: 'point', position_mm: mm(v.light.position), intensity: v.light.intensity * 1e6 }],
    materials: { fabric: { fabric: params, uv_mm: [uvMm, uvMm] } },
    objects: [{ mesh: obj, material: 'fabric', transform: { scale: 1000 } }],
    render: { max_bounces: 0, yarn_samples: 4, seed: 1 },
    response: { exposure: v.exposure, clip: 1, encoding: 'srgb' },
    falloff: { type: 'none' },
  };
}

// The rig with cloth turned, out of square and bent (sample.rotation_deg, skew_deg, distortion,
// as a capture writes them): the viewer must lay the yarns where woven render does: its SSIM
// against that render must beat that against the square one and the one without the bend.
async function skewedRig(pat, params, square) {
  const sc = JSON.parse(JSON.stringify(flat45));
  sc.sample.rotation_deg = 8, sc.sample.skew_deg = 5;
  const file = join(work, `${pat}_skewed_scene.json`), c = join(work, `${pat}_skewed_c.png`);
  const straight = join(work, `${pat}_straight_c.png`);
  writeFileSync(file, JSON.stringify(sc));
  woven('render', '--params', params, '--scene', file, '-o', straight, '-q');
  sc.sample.distortion = { extent_mm: 32, x: [0, 0, 0.4, 0, -0.3, 0, 0, 0.2, 0], y: [0.1, 0, 0, 0.3, 0, 0, 0, 0, -0.2] };
  const html = join(work, `${pat}_skewed.html`), v = join(work, `${pat}_skewed_viewer.png`);
  writeFileSync(file, JSON.stringify(sc));
  woven('render', '--params', params, '--scene', file, '-o', c, '-q');
  woven('view', params, '--scene', file, '-o', html, '-q');
  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${pat} skewed viewer: ${e.message}`));
  await page.goto(`file://${html}?frames=1&spp=${spp}`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 60000 });
  await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp);
  png(await page.evaluate(() => window.woven.snapshot()), v);
  await page.close();
  const turned = compare(c, v, 0).ssim, sq = compare(square, v, 0).ssim, st = compare(straight, v, 0).ssim;
  console.log(`${pat} turned 8, skewed 5 degrees and bent: viewer vs woven render SSIM ${turned.toFixed(4)}, ` +
              `vs the square render ${sq.toFixed(4)}, vs the unbent one ${st.toFixed(4)}`);
  if (!(turned > sq + 0.05)) fail(`${pat}: the viewer does not lay the skewed cloth as woven render does`);
  if (!(turned > st + 0.05)) fail(`${pat}: the viewer does not bend the cloth as woven render does`);
}

// Mean luma (0..1) of the centre 48 x 48 pixels of a PNG, decoded in the glTF page.
const centreMean = (file) => gpage.evaluate(async (url) => {
  const img = new Image();
  img.src = url;
  await img.decode();
  const cv = document.createElement('canvas');
  cv.width = img.width, cv.height = img.height;
  const g = cv.getContext('2d');
  g.drawImage(img, 0, 0);
  const d = g.getImageData(img.width / 2 - 24, img.height / 2 - 24, 48, 48).data;
  let s = 0;
  for (let i = 0; i < d.length; i += 4) s += 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
  return s / (255 * d.length / 4);
}, `data:image/png;base64,${readFileSync(file).toString('base64')}`);

// The back-lit rig (flat45-back) of one parameter file: the viewer with its back light on
// against woven render, and woven's renders with a part of the transmission taken away.
const BACK_SSIM = 0.999, BACK_MAE = 0.002, GLOW_REL = 0.05, BACK_FRAMES = 16;
async function backLit(name, paramsFile) {
  const base = join(work, `${name}_back`), c = `${base}_c.png`, v = `${base}_viewer.png`, html = `${base}.html`;
  woven('render', '--params', paramsFile, '--scene', 'flat45-back', '-o', c, '-q');
  woven('view', paramsFile, '-o', html, '-q'); // the flat45 page: its back light makes flat45-back
  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${name} back-lit viewer: ${e.message}`));
  await page.goto(`file://${html}?frames=1&spp=${spp}&back=1`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 60000 });
  const t1 = Date.now();
  await page.evaluate(([n, s]) => window.woven.render({ frames: n, spp: s }), [BACK_FRAMES, spp]);
  const ms = Date.now() - t1;
  png(await page.evaluate(() => window.woven.snapshot()), v);
  const view = await page.evaluate(() => window.woven.view());
  await page.close();
  const back = JSON.parse(readFileSync(join(SRC, 'scenes/flat45-back.json'), 'utf8'));
  if (!view.back || view.light.intensity !== back.light.intensity ||
      view.light.position.some((x, i) => Math.abs(x - back.light.position_mm[i]) > 1e-9))
    fail(`${name}: the viewer's back light is not flat45-back's (${JSON.stringify(view.light)})`);
  const params = JSON.parse(readFileSync(paramsFile, 'utf8'));
  const open = (params.yarn_width ?? 1) < 1;
  const pass = (r) => r.ssim >= BACK_SSIM && r.mae <= BACK_MAE;
  const sv = compare(c, v), raw = compare(c, v, 0);
  const cc = await centreMean(c), cvm = await centreMean(v);
  const glowOk = (m) => Math.abs(m - cc) <= GLOW_REL * cc;
  if (!pass(sv)) fail(`${name} back-lit: viewer vs woven render SSIM ${sv.ssim.toFixed(4)} (>= ${BACK_SSIM}), MAE ${sv.mae.toFixed(4)} (<= ${BACK_MAE})`);
  if (open && !glowOk(cvm)) fail(`${name} back-lit: the centre's mean ${cvm.toFixed(4)} is not within ${GLOW_REL} of woven's ${cc.toFixed(4)}`);
  // woven's render without each part: the bounds must reject it
  const parts = { diffuse_transmission: { transmission: { warp: [0, 0, 0], weft: [0, 0, 0] } },
                  specular_transmission: { transmission_specular: { warp: [0, 0, 0], weft: [0, 0, 0] } } };
  if (params.transmission_forward) parts.forward_band = { transmission_forward: { warp: [0, 0, 0], weft: [0, 0, 0] } };
  const without = {};
  for (const [part, edit] of Object.entries(parts)) {
    const pf = `${base}_no_${part}.json`, pc = `${base}_no_${part}.png`;
    writeFileSync(pf, JSON.stringify({ ...params, ...edit }));
    woven('render', '--params', pf, '--scene', 'flat45-back', '-o', pc, '-q');
    const r = compare(c, pc);
    without[part] = { ssim_blur4: r.ssim, mae_blur4: r.mae };
    if (pass(r)) fail(`${name} back-lit: the bounds accept woven's render without the ${part.replace('_', ' ')}`);
  }
  if (open) {
    const sf = `${base}_no_glow_scene.json`, pc = `${base}_no_gap_glow.png`;
    writeFileSync(sf, JSON.stringify({ ...back, response: { ...back.response, gap_glow: { ...back.response.gap_glow, radiance: 0 } } }));
    woven('render', '--params', paramsFile, '--scene', sf, '-o', pc, '-q');
    const m = await centreMean(pc);
    without.gap_glow = { centre_mean: m };
    if (glowOk(m)) fail(`${name} back-lit: the centre's bound accepts woven's render without the gap glow`);
  }
  // the glTF: its transmission extensions, and three.js's back-lit render of it
  const glb = `${base}.glb`;
  woven('export', paramsFile, '--gltf', glb, '--texture', '32', '-q');
  const report = await validateBytes(new Uint8Array(readFileSync(glb)), { uri: glb });
  if (report.issues.numErrors) fail(`${name}: the glTF validator reports ${report.issues.numErrors} errors`);
  const used = report.info?.extensionsUsed || [];
  if (!used.includes('KHR_materials_diffuse_transmission')) fail(`${name}: the glTF has no KHR_materials_diffuse_transmission`);
  if (used.includes('KHR_materials_transmission') !== open) fail(`${name}: KHR_materials_transmission ${open ? 'missing' : 'without open gaps'}`);
  let gltf = null;
  if (open) {
    const u = `http://woven.test/work/${name}_back.glb`, t = `${base}_gltf.png`, ts = `${base}_gltf_stripped.png`;
    png(await gpage.evaluate(([x, sc]) => window.renderGltf(x, sc), [u, back]), t);
    png(await gpage.evaluate(([x, sc]) => window.renderGltf(x, sc, { strip: 'KHR_materials_transmission' }), [u, back]), ts);
    const mt = await centreMean(t), ms0 = await centreMean(ts), st = compare(c, t);
    gltf = { centre: mt, centre_stripped: ms0, ssim_blur4: st.ssim, mae_blur4: st.mae };
    if (!(mt > ms0 + 0.05)) fail(`${name}: three.js shows no light through the glTF's gaps (centre ${mt.toFixed(4)} vs ${ms0.toFixed(4)} without KHR_materials_transmission)`);
  }
  return { name, ssim_blur4: sv.ssim, mae_blur4: sv.mae, ssim: raw.ssim, centre_viewer: cvm, centre_woven: cc,
           viewer_ms: ms, without, gltf, gltf_validator: { errors: report.issues.numErrors, warnings: report.issues.numWarnings } };
}

// One studio view (swatch or drape) of one pattern, key light alone: the viewer,
// woven scene of the same view, and the glTF of the same mesh in three.js.
async function studioCompare(pat, params, html, mode) {
  const base = join(work, `${pat}_${mode}`), glb = `${base}.glb`;
  woven('export', params, '--gltf', glb, '--texture', '32', '-q',
        ...(mode === 'drape' ? ['--mesh', 'drape'] : ['--mesh', 'quad', '--size-mm', '20']));
  const page = await browser.newPage();
  page.on('pageerror', (e) => fail(`${pat} ${mode} viewer: ${e.message}`));
  await page.goto(`file://${html}?mode=${mode}&lights=point&w=${studioSize[0]}&h=${studioSize[1]}`);
  await page.waitForFunction(() => window.woven !== undefined, null, { timeout: 60000 });
  const t1 = Date.now();
  await page.evaluate((s) => window.woven.render({ frames: 1, spp: s }), spp);
  const ms = Date.now() - t1;
  const v = `${base}_viewer.png`, t = `${base}_gltf.png`, c = `${base}_c.png`, vf = `${base}_viewer_frames.png`;
  png(await page.evaluate(() => window.woven.snapshot()), v);
  // The same samples as spp frames of 1: the frames' sum (accumulated over the
  // first frame's surfaces) must give the one frame's picture.
  await page.evaluate((s) => window.woven.render({ frames: s, spp: 1 }), spp);
  png(await page.evaluate(() => window.woven.snapshot()), vf);
  const frames = compare(v, vf, 0);
  if (!(frames.mae < 2e-3)) fail(`${pat} ${mode}: ${spp} frames of 1 sample differ from 1 frame of ${spp}: MAE ${frames.mae}`);
  const view = await page.evaluate(() => window.woven.view());
  const mesh = await page.evaluate((m) => JSON.parse(document.getElementById('woven-data').textContent).meshes[m], mode);
  await page.close();
  if (view.backdrop || Math.abs(view.camera.aspect - view.size[0] / view.size[1]) > 1e-12)
    fail(`${pat} ${mode}: the view is not the key light alone at the canvas's aspect`);
  // The mesh woven scene renders is the page's, and the page's is the export's.
  const pos = writeObj(mesh, `${base}.obj`), gpos = glbPositions(glb);
  if (pos.length !== gpos.length || pos.some((x, i) => x !== gpos[i]))
    fail(`${pat} ${mode}: the viewer's mesh differs from woven export's`);
  writeFileSync(`${base}_scene.json`, JSON.stringify(studioScene(view, params, `${base}.obj`, mesh.uv_mm, cspp), null, 1));
  const t2 = Date.now();
  woven('scene', `${base}_scene.json`, '-o', c, '-q');
  const cms = Date.now() - t2;
  png(await gpage.evaluate(([u, vw]) => window.renderGltfView(u, vw), [`http://woven.test/work/${pat}_${mode}.glb`, view]), t);
  const sv = compare(c, v), sg = compare(c, t), rv = compare(c, v, 0), rg = compare(c, t, 0), gv = compare(v, t);
  if (!(sv.ssim >= 0.9)) fail(`${pat} ${mode}: viewer vs woven scene SSIM ${sv.ssim.toFixed(4)} < 0.9`);
  return { pattern: pat, mode, viewer_ssim_blur4: sv.ssim, viewer_mae_blur4: sv.mae, viewer_ssim: rv.ssim, viewer_mae: rv.mae,
           gltf_ssim_blur4: sg.ssim, gltf_mae_blur4: sg.mae, gltf_ssim: rg.ssim, gltf_mae: rg.mae,
           gltf_vs_viewer_ssim_blur4: gv.ssim, viewer_frames_mae: frames.mae, viewer_ms: ms, scene_ms: cms,
           vertices: pos.length / 3 };
}

const rows = [], studio = [], backRows = [];
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
  for (const mode of ['swatch', 'drape']) studio.push(await studioCompare(pat, params, html, mode));
  if (pat === (patterns.includes('twill') ? 'twill' : patterns[0])) await skewedRig(pat, params, c);
  backRows.push(await backLit(pat, params));
  if (pat === (patterns.includes('twill') ? 'twill' : patterns[0])) { // open gaps: the light seen through them
    // (and a specular transmission colour of its own, unlike the specular reflection's)
    const pf = join(work, `${pat}_open.json`);
    writeFileSync(pf, JSON.stringify({ ...JSON.parse(readFileSync(params, 'utf8')), yarn_width: 0.75,
                                       transmission_specular: { warp: [0.2, 0.9, 0.3], weft: [0.8, 0.3, 0.6] } }));
    backRows.push(await backLit(`${pat}_open`, pf));
    // a forward band of its own colour per yarn type, narrower than the default
    const ff = join(work, `${pat}_forward.json`);
    writeFileSync(ff, JSON.stringify({ ...JSON.parse(readFileSync(params, 'utf8')), forward_width: 0.15,
                                       transmission_forward: { warp: [0.6, 0.5, 0.3], weft: [0.2, 0.4, 0.5] } }));
    backRows.push(await backLit(`${pat}_forward`, ff));
  }
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
console.log(`studio views (${studioSize.join(' x ')}, key light alone) against woven scene of the same view:`);
console.log('pattern   view     viewer: SSIM    MAE   SSIM raw  MAE raw | glTF: SSIM    MAE   SSIM raw  MAE raw | viewer ms | scene ms');
for (const r of studio)
  console.log(`${r.pattern.padEnd(9)} ${r.mode.padEnd(7)} ${f(r.viewer_ssim_blur4)} ${f(r.viewer_mae_blur4)} ${f(r.viewer_ssim)} ${f(r.viewer_mae)}   ` +
              `${f(r.gltf_ssim_blur4)} ${f(r.gltf_mae_blur4)} ${f(r.gltf_ssim)} ${f(r.gltf_mae)}   ${String(r.viewer_ms).padStart(8)}   ${String(r.scene_ms).padStart(7)}`);
console.log('flat45-back (viewer ?back=1) against woven render: SSIM and MAE of 4-px blurs, SSIM unblurred, centre 48 px mean');
console.log('params        SSIM     MAE  SSIM raw | centre viewer  woven | without k_t: SSIM   MAE | without k_s: SSIM   MAE');
for (const r of backRows) {
  const d = r.without.diffuse_transmission, sp = r.without.specular_transmission;
  console.log(`${r.name.padEnd(11)} ${f(r.ssim_blur4)} ${f(r.mae_blur4)} ${f(r.ssim)}   ${f(r.centre_viewer)} ${f(r.centre_woven)}   ` +
              `${f(d.ssim_blur4)} ${f(d.mae_blur4)}   ${f(sp.ssim_blur4)} ${f(sp.mae_blur4)}` +
              (r.without.gap_glow ? `   (without the glow: centre ${r.without.gap_glow.centre_mean.toFixed(4)})` : '') +
              (r.without.forward_band ? `   (without the forward band: SSIM ${r.without.forward_band.ssim_blur4.toFixed(4)} ` +
                                        `MAE ${r.without.forward_band.mae_blur4.toFixed(4)})` : ''));
  if (r.gltf)
    console.log(`  ${r.name} glTF in three.js, flat45-back: centre ${r.gltf.centre.toFixed(4)} (without KHR_materials_transmission ` +
                `${r.gltf.centre_stripped.toFixed(4)}), vs woven render SSIM ${r.gltf.ssim_blur4.toFixed(4)} MAE ${r.gltf.mae_blur4.toFixed(4)} (4-px blurs)`);
}
console.log(JSON.stringify({ renderer: rendererName, spp, seconds: (Date.now() - t0) / 1000, scene_spp: cspp, results: rows, studio,
                             back_lit: backRows }));
console.log(failures ? `${failures} failed` : 'all passed');
process.exit(failures ? 1 : 0);
