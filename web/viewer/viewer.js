// woven viewer: the page's program. It loads the three.js modules inlined in the
// page, shades the true woven model (fabric.frag) on the capture rig, a flat
// swatch or the draped cloth, accumulates frames progressively, and offers the
// parameters as sliders. Everything it needs is in the page (written by
// `woven view`, src/view/view.c); nothing is fetched.
//
// Anti-aliasing: each frame takes uSpp samples per pixel of the fabric position
// inside the pixel's footprint (the parallelogram of the screen-space
// derivatives of the fabric coordinates), light and view directions at the
// pixel centre as in the C renderer; frames continue one low-discrepancy
// sequence and are averaged until `frames` is reached, so a still view
// converges to the C render's pixel average.
//
// A small API for tests and scripts: window.woven.render({frames, spp}) renders
// and resolves when done; snapshot() returns the canvas as a PNG data URL;
// fps(ms) measures frames per second; setParam(key, value) edits a parameter;
// setBackLight(on) switches the light through the cloth (also ?back=1).

const $ = (id) => document.getElementById(id);
const DATA = JSON.parse($('woven-data').textContent);
const status = (s) => { $('status').textContent = s; };
function showError(msg) {
  const e = $('error');
  e.textContent = msg;
  e.style.display = msg ? 'block' : 'none';
}

// ---- three.js from the page: gzip + base64 script blocks become module URLs ----
async function inflate(id) {
  const b64 = $(id).textContent.trim();
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
  return new Response(stream).text();
}
function moduleUrl(text, from, to) {
  const src = from ? text.split(from).join(to) : text;
  return URL.createObjectURL(new Blob([src], { type: 'text/javascript' }));
}
const coreUrl = moduleUrl(await inflate('woven-three-core'));
const threeUrl = moduleUrl(await inflate('woven-three-module'), "'./three.core.js'", JSON.stringify(coreUrl));
const orbitUrl = moduleUrl(await inflate('woven-three-orbit'), "'three'", JSON.stringify(threeUrl));
const THREE = await import(threeUrl);
const { OrbitControls } = await import(orbitUrl);
const shader = (id) => $(id).textContent;

// ---- parameters ----
// Paths like "diffuse.warp[1]" (wv_param_name) into the parameter object.
function pathOf(key) { return key.replace(/\[(\d)\]/, '.$1').split('.'); }
function getP(p, key) { return pathOf(key).reduce((o, k) => (o == null ? undefined : o[k]), p); }
function setP(p, key, v) {
  const path = pathOf(key), last = path.pop();
  path.reduce((o, k) => o[k], p)[last] = v;
}
const RANGES = Object.fromEntries(DATA.ranges.map((r) => [r.key, [r.lo, r.hi]]));

// The parameter's problems, or []: out of range, not a number, unknown pattern.
function problems(p) {
  const out = [];
  for (const [key, [lo, hi]] of Object.entries(RANGES)) {
    const v = getP(p, key);
    if (typeof v !== 'number' || !Number.isFinite(v) || v < lo || v > hi)
      out.push(`${key} = ${v} is outside ${lo}..${hi}`);
  }
  if (!DATA.weaves[p.pattern]) out.push(`pattern '${p.pattern}' is not one of ${Object.keys(DATA.weaves).join(', ')}`);
  if (!(p.yarn_width > 0 && p.yarn_width <= 1)) out.push(`yarn_width = ${p.yarn_width} is outside (0, 1]`);
  if (!(p.thickness > 0 && Number.isFinite(p.thickness))) out.push(`thickness = ${p.thickness} is not positive`);
  if (!Number.isInteger(p.noise_level)) out.push(`noise_level = ${p.noise_level} is not an integer`);
  const fb = DATA.forward_band_mean, fw = p.forward_width ?? 0.2;
  if (typeof fw !== 'number' || !(fw >= fb.lo && fw <= fb.hi)) out.push(`forward_width = ${fw} is outside ${fb.lo}..${fb.hi}`);
  return out;
}

// The forward band's norm at width w: 1 / its mean, linear between the nodes of the
// table of wv_forward_band_mean that woven view writes (src/view/view.c), so the mean
// has its one formula in C; the nodes are 0.01 apart, the width slider's steps.
function forwardNorm(w) {
  const t = DATA.forward_band_mean, n = t.values.length;
  const x = (w - t.lo) / (t.hi - t.lo) * (n - 1), i = Math.min(Math.max(Math.floor(x), 0), n - 2), a = x - i;
  return 1 / (t.values[i] * (1 - a) + t.values[i + 1] * a);
}

// The fabric's uniforms: a mirror of wv_params_yarn_model, wv_yarn_model_update
// and wv_fabric_prepare (float rounding as in C: Math.fround).
function prepareFabric(p, seedWords) {
  const f = Math.fround, DEG = Math.PI / 180, PI_F = f(3.14159265358979);
  const fw = p.forward_width ?? 0.2; // a file without it: 0.2, as wv_params_transmission_default
  const sp = [f(25.4 / p.density.warp), f(25.4 / p.density.weft)];
  const umax = f(p.inclination_deg * DEG), psi = f(p.twist_deg * DEG), width = f(p.yarn_width);
  return {
    uSpacing: sp, uInvSpacing: sp.map((s) => f(1 / s)), uUmaxOverSpacing: sp.map((s) => f(umax / s)),
    uVScale: sp.map((s) => f(PI_F / f(s * width))), uBeta: [p.heightfield.warp, p.heightfield.weft],
    uYarnWidth: width, uSinPsi: f(Math.sin(psi)), uCosPsi: f(Math.cos(psi)), uNoise: p.noise_level,
    uSeed: seedWords, uKd: [new THREE.Vector3(...p.diffuse.warp), new THREE.Vector3(...p.diffuse.weft)],
    uKs: [new THREE.Vector3(...p.specular.warp), new THREE.Vector3(...p.specular.weft)],
    // k_t (woven view writes it; a file without it has k_d / 2, as wv_params_transmission_default)
    uKt: ['warp', 'weft'].map((y) => new THREE.Vector3(...(p.transmission ? p.transmission[y] : p.diffuse[y].map((x) => x / 2)))),
    // k_st (a file without it has k_s, as wv_params_transmission_default)
    uKst: ['warp', 'weft'].map((y) => new THREE.Vector3(...(p.transmission_specular || p.specular)[y])),
    // k_f (a file without it has 0: no forward band, as wv_params_transmission_default)
    uKf: ['warp', 'weft'].map((y) => new THREE.Vector3(...(p.transmission_forward ? p.transmission_forward[y] : [0, 0, 0]))),
    uFwK: f(0.5 / (fw * fw)), uFwNorm: f(forwardNorm(fw)),
    uAlpha: [p.roughness.warp, p.roughness.weft], uBlend: p.diffuse_blend, uThickness: p.thickness,
    uGlints: p.specular_noise !== false, uInvGlintCell: sp.map((s) => f(1 / f(s / 8))),
  };
}

// ---- geometry ----
function floats(b64, Type = Float32Array) {
  const bin = atob(b64), bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}
function meshGeometry(m) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(floats(m.positions), 3));
  g.setAttribute('normal', new THREE.BufferAttribute(floats(m.normals), 3));
  g.setAttribute('tangent', new THREE.BufferAttribute(floats(m.tangents), 4));
  g.setAttribute('uv', new THREE.BufferAttribute(floats(m.uvs), 2));
  g.setIndex(new THREE.BufferAttribute(floats(m.indices, Uint32Array), 1));
  g.computeBoundingSphere();
  return g;
}
// The capture rig's sample (src/render/rig.c): the plane z = 0 or a cylinder
// around the x axis, large enough to fill the camera's view.
function rigGeometry(sc) {
  const cam = new THREE.Vector3(...sc.camera.position_mm);
  const reach = 4 * cam.length() + 10;
  if (sc.sample.shape === 'cylinder') {
    const g = new THREE.CylinderGeometry(sc.sample.radius_mm, sc.sample.radius_mm, 2 * reach, 720, 1, true);
    g.rotateZ(Math.PI / 2); // axis along x
    return g;
  }
  return new THREE.PlaneGeometry(2 * reach, 2 * reach, 1, 1);
}

// ---- renderer and passes ----
const params = structuredClone(DATA.params);
let seedWords = DATA.seed_words.slice();
const stage = $('stage');
const url = new URLSearchParams(location.search);
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true, alpha: false });
renderer.autoClear = false;
stage.appendChild(renderer.domElement);
const gl = renderer.getContext();

const weaveTex = new THREE.DataTexture(new Uint32Array(32 * 32), 32, 32, THREE.RedIntegerFormat, THREE.UnsignedIntType);
weaveTex.internalFormat = 'R32UI';
weaveTex.minFilter = weaveTex.magFilter = THREE.NearestFilter;

const fabricUniforms = {
  uWeave: { value: weaveTex }, uRows: { value: 1 }, uCols: { value: 1 },
  uShape: { value: 0 }, uRadius: { value: 1 }, uRotC: { value: 1 }, uRotS: { value: 0 }, uMmPerUnit: { value: 1 },
  uOffset: { value: [0, 0] }, uAcross0: { value: [1, 0] }, uAcross1: { value: [0, 1] },
  uDistX: { value: new Array(9).fill(0) }, uDistY: { value: new Array(9).fill(0) }, uDistK: { value: 0 }, uWarpAlongAxis: { value: true }, uUvMm: { value: 1 },
  uCamPos: { value: new THREE.Vector3() }, uLightPos: { value: new THREE.Vector3() }, uLightI: { value: 1 },
  uBoxes: { value: 0 }, uBoxC: { value: [0, 1, 2].map(() => new THREE.Vector3()) },
  uBoxU: { value: [0, 1, 2].map(() => new THREE.Vector3()) }, uBoxV: { value: [0, 1, 2].map(() => new THREE.Vector3()) },
  uBoxL: { value: [0, 0, 0] }, uBoxN: { value: [0, 1, 2].map(() => new THREE.Vector3()) },
  uBoxArea: { value: [0, 0, 0] }, uAmbient: { value: 0 }, uSpp: { value: 4 }, uFrame: { value: 0 },
  uShadows: { value: false }, uShadowMap: { value: null }, uShadowMatrix: { value: new THREE.Matrix4() },
  uShadowInvFar: { value: 1 }, uShadowBias: { value: 0 }, uShadowTexel: { value: 0 },
  uBackPos: { value: new THREE.Vector3() }, uBackI: { value: 0 },
};
for (const [k, v] of Object.entries(prepareFabric(params, seedWords))) fabricUniforms[k] = { value: v };
const fabricMaterial = new THREE.RawShaderMaterial({
  glslVersion: THREE.GLSL3, vertexShader: shader('woven-fabric-vert'), fragmentShader: shader('woven-fabric-frag'),
  uniforms: fabricUniforms, side: THREE.DoubleSide,
  blendEquation: THREE.AddEquation, blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor, // the sum of frames
});
const scene = new THREE.Scene();
const fabricMesh = new THREE.Mesh(new THREE.BufferGeometry(), fabricMaterial);
fabricMesh.frustumCulled = false;
scene.add(fabricMesh);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);

// The key light's shadows in the studio: the distance from the light to the
// nearest surface, over the mesh's bounding sphere as the light sees it (both
// sides of the cloth cast), stored as a fraction of the far plane; fabric.frag
// darkens a point farther than that (the point lifted off the surface by 1.5
// texels, plus 0.2% of the mesh's radius). woven scene traces a
// shadow ray to the point light; without this the viewer lit folds that the
// cloth hides from the light. The soft boxes and the sky cast none.
const SHADOW_SIZE = 1024;
const shadowTarget = new THREE.WebGLRenderTarget(SHADOW_SIZE, SHADOW_SIZE, {
  type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
  generateMipmaps: false, depthBuffer: true });
const shadowMaterial = new THREE.RawShaderMaterial({
  glslVersion: THREE.GLSL3, vertexShader: shader('woven-fabric-vert'), side: THREE.DoubleSide,
  fragmentShader: `precision highp float;
in vec3 vWorld;
uniform vec3 uLightPos;
uniform float uInvFar;
out vec4 outColor;
void main() { outColor = vec4(distance(vWorld, uLightPos) * uInvFar, 0.0, 0.0, 1.0); }`,
  uniforms: { uLightPos: fabricUniforms.uLightPos, uInvFar: fabricUniforms.uShadowInvFar },
});
const shadowCamera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
let shadowStale = true;
function renderShadows() {
  shadowStale = false;
  const u = fabricUniforms, bs = fabricMesh.geometry.boundingSphere;
  u.uShadows.value = false;
  if (state.mode === 'rig' || !bs) return; // a plane or a cylinder seen from its light shadows nothing
  const L = u.uLightPos.value, d = L.distanceTo(bs.center), R = bs.radius;
  if (!(d > 1.02 * R)) return; // the light inside the mesh's sphere: no shadows
  shadowCamera.position.copy(L);
  shadowCamera.up.set(0, 1, 0);
  if (Math.abs(new THREE.Vector3().subVectors(bs.center, L).normalize().y) > 0.99) shadowCamera.up.set(1, 0, 0);
  shadowCamera.lookAt(bs.center);
  shadowCamera.fov = 2 * Math.asin(Math.min(1, 1.02 * R / d)) * 180 / Math.PI;
  shadowCamera.near = Math.max(d - 1.1 * R, 1e-3 * d), shadowCamera.far = d + 1.1 * R;
  shadowCamera.updateProjectionMatrix();
  shadowCamera.updateMatrixWorld();
  u.uShadowMatrix.value.multiplyMatrices(shadowCamera.projectionMatrix, shadowCamera.matrixWorldInverse);
  u.uShadowInvFar.value = 1 / shadowCamera.far;
  u.uShadowBias.value = 0.002 * R / shadowCamera.far;
  u.uShadowTexel.value = 2 * Math.tan(shadowCamera.fov * Math.PI / 360) / SHADOW_SIZE;
  renderer.setRenderTarget(shadowTarget);
  renderer.setClearColor(0xffffff, 1); // nothing in front: the far plane
  renderer.clear(true, true, false);
  scene.overrideMaterial = shadowMaterial;
  renderer.render(scene, shadowCamera);
  scene.overrideMaterial = null;
  u.uShadowMap.value = shadowTarget.texture;
  u.uShadows.value = true;
}

function screenPass(fragmentShader, uniforms) {
  const m = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3, vertexShader: shader('woven-screen-vert'), fragmentShader, uniforms,
    depthTest: false, depthWrite: false,
  }));
  m.frustumCulled = false;
  const s = new THREE.Scene();
  s.add(m);
  return { scene: s, uniforms };
}
const accumulate = screenPass(shader('woven-accumulate-frag'), {
  uPrev: { value: null }, uCurrent: { value: null }, uKeep: { value: 0 },
});
const photoTex = new THREE.Texture();
const display = screenPass(shader('woven-display-frag'), {
  uAcc: { value: null }, uInvFrames: { value: 1 }, uRig: { value: true }, uExposure: { value: 1 }, uClip: { value: 1 },
  uGamma: { value: 2.2 }, uSigma: { value: 450 }, uEncoding: { value: 1 }, uFalloff: { value: false },
  uSize: { value: new THREE.Vector2(1, 1) }, uBackdrop: { value: true }, uPhoto: { value: photoTex }, uSplit: { value: 0 },
  uGlow: { value: 0 }, uGlowSigma: { value: 1 },
});
const quadCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);

// Frames accumulate by additive blending into one float target (EXT_float_blend)
// when the GL offers it: the first frame of a view draws the fabric with the
// depth test and writes its depth, later frames shade only the fragments at
// that depth (no pass over hidden folds) and add into the sum. Without the
// extension: a fabric target and an accumulation pass between two sums.
const blendAccumulate = !!gl.getExtension('EXT_float_blend');
let targets = null;
function makeTargets(w, h) {
  if (targets) for (const t of targets) t.dispose();
  const opt = { type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter,
                magFilter: THREE.NearestFilter, generateMipmaps: false };
  targets = blendAccumulate ? [new THREE.WebGLRenderTarget(w, h, { ...opt, depthBuffer: true })]
    : [new THREE.WebGLRenderTarget(w, h, { ...opt, depthBuffer: true }),
       new THREE.WebGLRenderTarget(w, h, { ...opt, depthBuffer: false }),
       new THREE.WebGLRenderTarget(w, h, { ...opt, depthBuffer: false })];
}

// ---- views ----
const SC = DATA.scene;
const studio = { exposure: 1.0 };
const state = {
  mode: ['rig', 'swatch', 'drape'].includes(url.get('mode')) ? url.get('mode') : 'rig',
  spp: Math.max(1, Math.min(256, Number(url.get('spp')) || 4)),
  frames: Math.max(1, Math.min(4096, Number(url.get('frames')) || 64)),
  frame: 0, split: 0, light: null, controls: null, size: [1, 1], valid: true, back: false,
};
const meshes = {};

// A light as (azimuth, elevation, distance) about a centre, with z or y up; intensity.
function lightFromPosition(centre, pos, intensity, upZ) {
  const d = new THREE.Vector3().subVectors(pos, centre), r = d.length();
  const [x, y, up] = upZ ? [d.x, d.y, d.z] : [d.x, d.z, d.y];
  return { centre, r, az: Math.atan2(y, x), el: Math.asin(Math.min(1, up / r)), intensity, pos: pos.clone(), upZ };
}
function lightPosition(L, upZ) {
  const c = Math.cos(L.el);
  const d = upZ ? new THREE.Vector3(c * Math.cos(L.az), c * Math.sin(L.az), Math.sin(L.el))
                : new THREE.Vector3(c * Math.cos(L.az), Math.sin(L.el), c * Math.sin(L.az));
  return d.multiplyScalar(L.r).add(L.centre);
}

function setMode(mode) {
  state.mode = mode;
  $('mode').value = mode;
  if (state.controls) { state.controls.dispose(); state.controls = null; }
  applyBackDefines();
  const u = fabricUniforms;
  if (mode === 'rig') {
    fabricMesh.geometry = rigGeometry(SC);
    fabricMaterial.side = THREE.FrontSide;
    const cyl = SC.sample.shape === 'cylinder';
    u.uShape.value = cyl ? 1 : 0;
    u.uRadius.value = SC.sample.radius_mm || 1;
    const rot = (SC.sample.rotation_deg || 0) * Math.PI / 180, skew = (SC.sample.skew_deg || 0) * Math.PI / 180;
    u.uRotC.value = Math.cos(rot), u.uRotS.value = Math.sin(rot);
    // as woven's plane (src/shape/shape.c): the warp yarns turned by rot - skew / 2, the weft by rot + skew / 2
    const wa = rot - skew / 2, fa = rot + skew / 2;
    u.uAcross0.value = [Math.cos(wa), Math.sin(wa)], u.uAcross1.value = [-Math.sin(fa), Math.cos(fa)];
    u.uMmPerUnit.value = SC.sample.mm_per_unit, u.uOffset.value = SC.sample.offset_mm;
    const bend = cyl ? null : SC.sample.distortion; // the cloth's distortion, as src/shape/plane_impl.h
    u.uDistK.value = bend ? SC.sample.mm_per_unit / bend.extent_mm : 0;
    u.uDistX.value = bend ? bend.x : new Array(9).fill(0), u.uDistY.value = bend ? bend.y : new Array(9).fill(0);
    u.uWarpAlongAxis.value = SC.sample.warp !== 'around_axis';
    u.uBoxes.value = 0, u.uAmbient.value = 0;
    const w = SC.image.width, h = SC.image.height;
    state.size = [w, h];
    camera.fov = SC.camera.vfov_deg;
    camera.aspect = w / h;
    camera.position.set(...SC.camera.position_mm);
    camera.up.set(...SC.camera.up);
    const look = new THREE.Vector3(...SC.camera.look_at_mm);
    camera.lookAt(look);
    const dist = camera.position.distanceTo(look);
    camera.near = dist * 1e-3, camera.far = dist * 100;
    const rl = rigLights(cyl);
    state.light = lightFromPosition(look, state.back ? rl.back : rl.front, SC.light.intensity, true);
    display.uniforms.uGlow.value = state.back ? rl.glow : 0;
    display.uniforms.uGlowSigma.value = rl.glowSigma;
    u.uBackI.value = 0;
    renderer.setPixelRatio(1);
  } else {
    const m = meshes[mode] || (meshes[mode] = meshGeometry(DATA.meshes[mode]));
    fabricMesh.geometry = m;
    fabricMaterial.side = THREE.DoubleSide;
    u.uShape.value = 2;
    u.uUvMm.value = DATA.meshes[mode].uv_mm;
    const bs = m.boundingSphere, R = bs.radius, c = bs.center;
    const w = Number(url.get('w')) || Math.max(64, stage.clientWidth), h = Number(url.get('h')) || Math.max(64, stage.clientHeight);
    state.size = [w, h];
    camera.fov = 30, camera.aspect = w / h;
    camera.up.set(0, 1, 0);
    const d = R / Math.sin(camera.fov * Math.PI / 360) * 1.05;
    camera.position.set(c.x + 0.55 * d, c.y + 0.5 * d, c.z + 0.67 * d);
    camera.near = d * 1e-3, camera.far = d * 100;
    camera.lookAt(c);
    // Studio: a key point light, three soft boxes (key above left, fill right, rim
    // behind) and a dim uniform sky, all scaled to the object.
    const key = new THREE.Vector3(c.x - 1.2 * R, c.y + 2.2 * R, c.z + 1.6 * R);
    state.light = lightFromPosition(c, key, 12.0 * R * R, false);
    u.uBackI.value = state.back ? state.light.intensity : 0; // placed behind the cloth each frame (renderFrame)
    display.uniforms.uGlow.value = 0;
    const boxes = [
      { c: [c.x - 2.0 * R, c.y + 2.5 * R, c.z + 1.0 * R], u: [0.9 * R, 0, 0.5 * R], v: [0, 0.2 * R, -0.9 * R], L: 0.9 },
      { c: [c.x + 2.6 * R, c.y + 0.8 * R, c.z + 0.8 * R], u: [0, 0.8 * R, 0], v: [-0.3 * R, 0, 0.9 * R], L: 0.35 },
      { c: [c.x + 0.5 * R, c.y + 1.5 * R, c.z - 2.6 * R], u: [1.0 * R, 0, 0], v: [0, 0.6 * R, 0.3 * R], L: 0.6 },
    ];
    const pointOnly = url.get('lights') === 'point'; // the key light alone (for comparisons)
    u.uBoxes.value = pointOnly ? 0 : 3;
    boxes.forEach((b, i) => {
      u.uBoxC.value[i].set(...b.c), u.uBoxU.value[i].set(...b.u), u.uBoxV.value[i].set(...b.v);
      u.uBoxL.value[i] = b.L;
      // the box's constants, once here instead of per sample in the shader
      const n = new THREE.Vector3().crossVectors(u.uBoxU.value[i], u.uBoxV.value[i]);
      u.uBoxArea.value[i] = 4 * n.length();
      u.uBoxN.value[i].copy(n.normalize());
    });
    u.uAmbient.value = pointOnly ? 0 : 0.08;
    display.uniforms.uBackdrop.value = !pointOnly; // the key light alone: nothing else, black behind
    renderer.setPixelRatio(url.get('w') ? 1 : Math.min(2, window.devicePixelRatio || 1));
    state.controls = new OrbitControls(camera, renderer.domElement);
    state.controls.target.copy(c);
    state.controls.update(); // settle on the target before listening: only the user's moves restart
    state.controls.addEventListener('change', restart);
  }
  camera.updateProjectionMatrix();
  renderer.setSize(state.size[0], state.size[1]);
  const px = renderer.getDrawingBufferSize(new THREE.Vector2());
  makeTargets(px.x, px.y);
  display.uniforms.uSize.value.copy(px);
  const rig = mode === 'rig';
  display.uniforms.uRig.value = rig;
  display.uniforms.uExposure.value = rig ? SC.response.exposure : studio.exposure;
  display.uniforms.uClip.value = rig ? SC.response.clip : 1;
  display.uniforms.uEncoding.value = rig ? { linear: 0, srgb: 1, gamma: 2 }[SC.response.encoding] : 1;
  display.uniforms.uGamma.value = SC.response.gamma || 2.2;
  display.uniforms.uFalloff.value = rig && SC.falloff.type === 'gaussian';
  display.uniforms.uSigma.value = SC.falloff.sigma_px || 1;
  $('photoRow').style.display = rig && DATA.photo ? '' : 'none';
  display.uniforms.uSplit.value = rig && DATA.photo ? state.split : 0;
  buildLightControls();
  applyLight();
}

// The rig's lights: the scene's, and with the back light on a light behind the
// cloth on the camera's axis, as the flat45-back preset places it (its distance
// behind the look-at point in camera distances, the same intensity, its gap
// glow); a scene that transmits itself (light below the plane) keeps its light
// and glow, and its front light is that light mirrored through the plane.
function rigLights(cyl) {
  const cam = new THREE.Vector3(...SC.camera.position_mm), look = new THREE.Vector3(...SC.camera.look_at_mm);
  const lp = new THREE.Vector3(...SC.light.position_mm);
  if (!cyl && lp.z < 0)
    return { front: new THREE.Vector3(lp.x, lp.y, -lp.z), back: lp,
             glow: SC.response.gap_glow ? SC.response.gap_glow.radiance : 0,
             glowSigma: SC.response.gap_glow ? SC.response.gap_glow.sigma_px : 1 };
  const B = DATA.back_scene, bc = new THREE.Vector3(...B.camera.position_mm), bl = new THREE.Vector3(...B.camera.look_at_mm);
  const k = new THREE.Vector3(...B.light.position_mm).distanceTo(bl) / bc.distanceTo(bl);
  const back = new THREE.Vector3().subVectors(look, cam).multiplyScalar(k).add(look);
  return { front: lp, back, glow: B.response.gap_glow.radiance, glowSigma: B.response.gap_glow.sigma_px };
}

// The light through the cloth on or off: the fabric shader with or without
// WV_TRANSMIT (off, it is the reflection model alone, at its cost).
function setBackLight(on) {
  state.back = !!on;
  setMode(state.mode);
}
function applyBackDefines() {
  if (state.back && state.mode === 'rig' && SC.sample.shape === 'cylinder') state.back = false; // woven transmits through a plane only
  const on = 'WV_TRANSMIT' in fabricMaterial.defines;
  if (on === state.back) return;
  fabricMaterial.defines = state.back ? { WV_TRANSMIT: '' } : {};
  fabricMaterial.needsUpdate = true;
}

function applyLight() {
  const L = state.light;
  fabricUniforms.uLightPos.value.copy(L.moved ? lightPosition(L, L.upZ) : L.pos);
  fabricUniforms.uLightI.value = L.intensity;
  shadowStale = true;
  restart();
}

function restart() { state.frame = 0; }

// One frame of the progressive render: fabric pass (accumulating), display.
function renderFrame() {
  if (shadowStale) renderShadows();
  fabricUniforms.uCamPos.value.copy(camera.position);
  if (state.back && state.controls) { // studio: the back light on the camera's axis behind the orbit target
    const t = state.controls.target;
    fabricUniforms.uBackPos.value.subVectors(t, camera.position).multiplyScalar(1.2).add(t);
  }
  fabricUniforms.uSpp.value = state.spp;
  fabricUniforms.uFrame.value = state.frame;
  let sum;
  if (blendAccumulate) {
    [sum] = targets;
    const first = state.frame === 0;
    renderer.setRenderTarget(sum);
    if (first) {
      renderer.setClearColor(0x000000, 0);
      renderer.clear(true, true, false);
    }
    fabricMaterial.blending = first ? THREE.NoBlending : THREE.CustomBlending;
    fabricMaterial.depthFunc = first ? THREE.LessEqualDepth : THREE.EqualDepth;
    fabricMaterial.depthWrite = first;
    if (state.valid) renderer.render(scene, camera);
  } else {
    const [cur, a, b] = targets;
    const prev = state.frame % 2 ? b : a;
    sum = state.frame % 2 ? a : b;
    renderer.setRenderTarget(cur);
    renderer.setClearColor(0x000000, 0);
    renderer.clear(true, true, false);
    if (state.valid) renderer.render(scene, camera);
    accumulate.uniforms.uPrev.value = prev.texture;
    accumulate.uniforms.uCurrent.value = cur.texture;
    accumulate.uniforms.uKeep.value = state.frame > 0 ? 1 : 0;
    renderer.setRenderTarget(sum);
    renderer.render(accumulate.scene, quadCamera);
  }
  state.frame++;
  display.uniforms.uAcc.value = sum.texture;
  display.uniforms.uInvFrames.value = 1 / state.frame;
  renderer.setRenderTarget(null);
  renderer.render(display.scene, quadCamera);
}

function loop() {
  if (state.controls) state.controls.update();
  if (state.frame < state.frames) {
    renderFrame();
    status(`${state.frame} / ${state.frames} frames, ${state.frame * state.spp} samples per pixel`);
  }
  requestAnimationFrame(loop);
}

// ---- fabric uniforms from the parameters ----
function applyParams() {
  const bad = problems(params);
  state.valid = bad.length === 0;
  if (!state.valid) { // refused visibly: nothing is drawn from invalid parameters
    showError(`These parameters are refused:\n${bad.join('\n')}`);
    restart();
    return;
  }
  showError('');
  const wv = DATA.weaves[params.pattern];
  const data = weaveTex.image.data;
  data.fill(0);
  for (let r = 0; r < wv.rows; r++) for (let c = 0; c < wv.cols; c++) data[r * 32 + c] = wv.cells[r * wv.cols + c];
  weaveTex.needsUpdate = true;
  fabricUniforms.uRows.value = wv.rows, fabricUniforms.uCols.value = wv.cols;
  for (const [k, v] of Object.entries(prepareFabric(params, seedWords))) fabricUniforms[k].value = v;
  restart();
}

// ---- controls ----
function slider(parent, label, lo, hi, step, get, set, key) {
  const row = document.createElement('div');
  row.className = 'row';
  row.innerHTML = `<label title="${key || label}">${label}</label><input type="range"><input type="number">`;
  const [range, num] = row.querySelectorAll('input');
  for (const el of [range, num]) el.min = lo, el.max = hi, el.step = step;
  const show = () => { range.value = get(); num.value = +(+get()).toPrecision(6); num.classList.remove('bad'); };
  range.addEventListener('input', () => { set(Number(range.value)); show(); $('msg').textContent = ''; });
  num.addEventListener('change', () => {
    const v = Number(num.value);
    if (num.value === '' || !Number.isFinite(v) || v < lo || v > hi) { // refused, shown, not applied
      num.classList.add('bad');
      $('msg').textContent = `${key || label} = ${num.value} is outside ${lo}..${hi}: not applied`;
      return;
    }
    $('msg').textContent = '';
    set(v);
    show();
  });
  show();
  parent.appendChild(row);
  return show;
}

const srgbEnc = (x) => (x <= 0.0031308 ? 12.92 * x : 1.055 * x ** (1 / 2.4) - 0.055);
const srgbDec = (y) => (y <= 0.04045 ? y / 12.92 : ((y + 0.055) / 1.055) ** 2.4);
function colour(parent, label, key) {
  const row = document.createElement('div');
  row.className = 'wide';
  row.innerHTML = `<label>${label}</label><input type="color">`;
  const input = row.querySelector('input');
  const hex = (v) => '#' + v.map((x) => Math.round(255 * srgbEnc(Math.min(1, Math.max(0, x)))).toString(16).padStart(2, '0')).join('');
  input.value = hex(getP(params, key));
  input.addEventListener('input', () => {
    const v = [1, 3, 5].map((i) => Math.round(1e4 * srgbDec(parseInt(input.value.slice(i, i + 2), 16) / 255)) / 1e4);
    setP(params, key, v);
    applyParams();
  });
  parent.appendChild(row);
}

function buildFabricControls() {
  const box = $('fabricControls');
  box.innerHTML = '';
  const onP = (key) => (v) => { setP(params, key, v); applyParams(); };
  const num = (key, label, step) => slider(box, label, RANGES[key][0], RANGES[key][1], step, () => getP(params, key), onP(key), key);
  num('density.warp', 'density warp /in', 1);
  num('density.weft', 'density weft /in', 1);
  num('heightfield.warp', 'heightfield warp', 0.01);
  num('heightfield.weft', 'heightfield weft', 0.01);
  num('roughness.warp', 'roughness warp', 0.005);
  num('roughness.weft', 'roughness weft', 0.005);
  colour(box, 'diffuse warp', 'diffuse.warp');
  colour(box, 'diffuse weft', 'diffuse.weft');
  colour(box, 'specular warp', 'specular.warp');
  colour(box, 'specular weft', 'specular.weft');
  if (params.transmission) { // k_t: seen with the back light
    colour(box, 'transmission warp', 'transmission.warp');
    colour(box, 'transmission weft', 'transmission.weft');
  }
  if (params.transmission_specular) { // k_st: likewise
    colour(box, 'specular transmission warp', 'transmission_specular.warp');
    colour(box, 'specular transmission weft', 'transmission_specular.weft');
  }
  if (params.transmission_forward) { // k_f and the band's width: likewise
    colour(box, 'forward transmission warp', 'transmission_forward.warp');
    colour(box, 'forward transmission weft', 'transmission_forward.weft');
    const fb = DATA.forward_band_mean; // its range: forward_width's
    slider(box, 'forward width', fb.lo, fb.hi, 0.01, () => params.forward_width ?? 0.2, onP('forward_width'), 'forward_width');
  }
  num('twist_deg', 'twist (deg)', 1);
  num('inclination_deg', 'inclination (deg)', 0.5);
  num('diffuse_blend', 'diffuse blend', 0.01);
  num('noise_level', 'noise level Q', 1);
  slider(box, 'seed', 0, 2147483647, 1, () => params.seed, (v) => {
    params.seed = Math.round(v);
    seedWords = [0, params.seed >>> 0];
    applyParams();
  }, 'seed');
  const row = document.createElement('div');
  row.className = 'wide';
  row.innerHTML = '<label>glints U_s</label><input type="checkbox">';
  const cb = row.querySelector('input');
  cb.checked = params.specular_noise !== false;
  cb.addEventListener('change', () => { params.specular_noise = cb.checked; applyParams(); });
  box.appendChild(row);
}

function buildViewControls() {
  const box = $('viewControls');
  box.innerHTML = '';
  slider(box, 'samples / frame', 1, 64, 1, () => state.spp, (v) => { state.spp = v; restart(); });
  slider(box, 'frames', 1, 1024, 1, () => state.frames, (v) => { state.frames = v; restart(); });
  slider(box, 'studio exposure', 0.05, 8, 0.05, () => studio.exposure, (v) => {
    studio.exposure = v;
    if (state.mode !== 'rig') display.uniforms.uExposure.value = v;
    restart();
  });
}

function buildLightControls() {
  const box = $('lightControls'), L = state.light;
  box.innerHTML = '';
  const deg = 180 / Math.PI;
  const moved = (fn) => (v) => { fn(v); L.moved = true; applyLight(); };
  slider(box, 'azimuth (deg)', -180, 180, 1, () => Math.round(L.az * deg), moved((v) => { L.az = v / deg; }));
  const below = state.back && state.mode === 'rig'; // the rig's back light is the light, below the plane
  slider(box, 'elevation (deg)', below ? -90 : 1, below ? -1 : 90, 1, () => Math.round(L.el * deg), moved((v) => { L.el = v / deg; }));
  slider(box, 'distance', +(0.2 * L.r).toPrecision(3), +(5 * L.r).toPrecision(3), +(L.r / 100).toPrecision(2),
         () => +L.r.toPrecision(4), moved((v) => { L.r = v; }));
  slider(box, 'intensity', +(L.intensity / 20).toPrecision(3), +(L.intensity * 20).toPrecision(3),
         +(L.intensity / 100).toPrecision(2), () => +L.intensity.toPrecision(4), (v) => { L.intensity = v; applyLight(); });
  const row = document.createElement('div');
  row.className = 'wide';
  row.innerHTML = '<label title="light behind the cloth on the camera\'s axis: in the rig the flat45-back view, ' +
    'in the studio a second light">back light</label><input type="checkbox" id="backLight">';
  const cb = row.querySelector('input');
  cb.checked = state.back;
  cb.disabled = state.mode === 'rig' && SC.sample.shape === 'cylinder';
  cb.addEventListener('change', () => setBackLight(cb.checked));
  box.appendChild(row);
  const reset = document.createElement('button');
  reset.textContent = 'reset light';
  reset.addEventListener('click', () => { setMode(state.mode); });
  box.appendChild(reset);
}

// ---- start ----
$('title').textContent = DATA.title || 'woven';
$('subtitle').textContent = `${params.pattern} — scene ${SC.name}${DATA.photo ? ', with the photo' : ''}`;
$('about').textContent = `The true woven model in WebGL (three.js r${THREE.REVISION}): yarn geometry, ` +
  'SGGX/SpongeCake specular, blended diffuse and glints computed per sample, as woven renders them; ' +
  'with the back light, the light through the cloth (specular and diffuse transmission, open gaps).';
const pat = $('pattern');
for (const name of Object.keys(DATA.weaves)) pat.add(new Option(name, name));
pat.value = params.pattern;
pat.addEventListener('change', () => { params.pattern = pat.value; applyParams(); });
$('mode').addEventListener('change', () => setMode($('mode').value));
if (DATA.photo) {
  const img = new Image();
  img.src = DATA.photo;
  await img.decode();
  photoTex.image = img;
  photoTex.flipY = false;
  photoTex.colorSpace = THREE.NoColorSpace;
  photoTex.needsUpdate = true;
  const split = $('split');
  split.addEventListener('input', () => { state.split = Number(split.value); display.uniforms.uSplit.value = state.split; restart(); });
  $('photoToggle').addEventListener('click', () => {
    state.split = state.split > 0 ? 0 : Number(split.value) || 0.5;
    $('photoToggle').classList.toggle('on', state.split > 0);
    display.uniforms.uSplit.value = state.split;
    restart();
  });
}
buildViewControls();
buildFabricControls();
applyParams();
setBackLight(url.get('back') === '1' || (SC.sample.shape !== 'cylinder' && SC.light.position_mm[2] < 0));
window.addEventListener('resize', () => { if (state.mode !== 'rig' && !url.get('w')) setMode(state.mode); });

window.woven = {
  THREE,
  // Render `frames` frames of `spp` samples (without waiting for the screen).
  render({ frames = state.frames, spp = state.spp } = {}) {
    state.frames = frames, state.spp = spp;
    restart();
    while (state.frame < state.frames) renderFrame();
    gl.finish();
    status(`${state.frame} / ${state.frames} frames, ${state.frame * state.spp} samples per pixel`);
    return { frames: state.frame, spp: state.spp, valid: state.valid };
  },
  snapshot: () => renderer.domElement.toDataURL('image/png'),
  // Frames per second of the progressive render over ms milliseconds, each
  // frame finished by the GPU before the next starts.
  fps(ms = 3000) {
    const px = new Uint8Array(4);
    let n = 0;
    const t0 = performance.now();
    while (performance.now() - t0 < ms) {
      renderFrame();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
      n++;
      if (state.frame >= 1e6) restart();
    }
    const dbg = gl.getExtension('WEBGL_debug_renderer_info');
    return { fps: (n * 1000) / (performance.now() - t0), frames: n, spp: state.spp, size: state.size,
             renderer: gl.getParameter(dbg ? dbg.UNMASKED_RENDERER_WEBGL : gl.RENDERER) };
  },
  // The current camera, light and display, to reproduce the view elsewhere.
  view: () => ({
    camera: { position: camera.position.toArray(), target: state.controls ? state.controls.target.toArray() : null,
              up: camera.up.toArray(), fov: camera.fov, aspect: camera.aspect },
    light: { position: fabricUniforms.uLightPos.value.toArray(), intensity: fabricUniforms.uLightI.value },
    exposure: display.uniforms.uExposure.value, size: state.size, mode: state.mode,
    backdrop: display.uniforms.uBackdrop.value, back: state.back,
  }),
  setParam(key, value) { setP(params, key, value); applyParams(); return problems(params); },
  setMode,
  setBackLight,
  problems: () => problems(params),
};
status('ready');
requestAnimationFrame(loop);
