// woven's fabric model in GLSL ES 3.00: the viewer's shader of the true model.
// It mirrors the C code operation for operation (same constants, same hashes,
// same polynomial sine, cosine and exponential), so a pixel sees what the C
// renderer computes for the same fabric point and directions:
//   yarnEval      src/yarn/yarn_eval.h  wv_yarn_eval_inline, wv_yarn_frame_inline, wv_yarn_scale_inline
//   glint         src/render/render_internal.h  wv_glint (U_s from the hashed 1/8-spacing grid)
//   shadeLight    src/render/render_internal.h  wv_shade (SGGX/SpongeCake specular, blended Lambert)
//   clothAt, shadeTrans  src/kernel/kernel_impl.h  wv_yarn_locate's crossing yarn, wv_cloth_chords,
//                 wv_shade_trans (light from behind: specular and diffuse transmission, the forward
//                 band, open gaps; the band's norm uFwNorm is computed in C, src/kernel/kernel.c
//                 wv_forward_band_mean, and reaches the page from src/view/view.c)
//   hash2, mix64  src/util/hash.h (64-bit integers emulated as uvec2(high, low))
//   sinHp, cosHp, expWv  src/util/fastmath.h
// The light through the cloth is compiled only with WV_TRANSMIT defined (the
// back light on): without it the shader is the reflection model alone.
// A change to the model in C must be repeated here; the browser test
// (web/test/browser.test.mjs) compares this shader with `woven render`.
precision highp float;
precision highp int;
precision highp usampler2D;
precision highp sampler2D;

in vec3 vWorld;     // world position
in vec3 vNormal;    // mesh: interpolated normal
in vec4 vTangent;   // mesh: tangent along +u, bitangent sign in w
in vec2 vUv;        // mesh: texture coordinates
out vec4 outColor;

// Fabric (see prepareFabric in viewer.js, the mirror of wv_fabric_prepare).
uniform usampler2D uWeave;      // cell (col, row): type | len << 8 | index << 16
uniform int uRows, uCols;
uniform vec2 uSpacing;          // [warp (x), weft (y)] mm
uniform vec2 uInvSpacing, uUmaxOverSpacing, uVScale, uBeta;
uniform float uYarnWidth, uSinPsi, uCosPsi;
uniform int uNoise;             // Q
uniform uvec2 uSeed;            // (high, low) of the 64-bit seed
uniform vec3 uKd[2], uKs[2];
uniform vec2 uAlpha;
uniform float uBlend, uThickness;
uniform bool uGlints;
uniform vec2 uInvGlintCell;

// Geometry: 0 plane z = 0 (rig), 1 cylinder around x (rig), 2 mesh with UVs.
uniform int uShape;
uniform float uRadius, uRotC, uRotS, uMmPerUnit;
uniform vec2 uOffset;
uniform float uDistX[9], uDistY[9], uDistK; // plane: the cloth's distortion (wv_scene.distort), uDistK 0: none
uniform vec2 uAcross0, uAcross1; // plane: fabric x = P.xy . uAcross0, fabric y = P.xy . uAcross1 (skew)
uniform bool uWarpAlongAxis;
uniform float uUvMm;            // mesh: fabric mm per UV unit

uniform vec3 uCamPos;
uniform vec3 uLightPos;
uniform float uLightI;
// Studio: up to three rectangular soft boxes (centre, half sides, radiance) and
// a uniform ambient radiance on the diffuse lobe.
uniform int uBoxes;
uniform vec3 uBoxC[3], uBoxU[3], uBoxV[3];
uniform float uBoxL[3];
uniform vec3 uBoxN[3];          // unit normal
uniform float uBoxArea[3];
uniform float uAmbient;
// The key light's shadow map (studio; see renderShadows in viewer.js).
uniform bool uShadows;
uniform sampler2D uShadowMap;   // distance from the light / far
uniform mat4 uShadowMatrix;
uniform float uShadowInvFar, uShadowBias;
uniform float uShadowTexel;     // a texel's width per unit distance from the light

#ifdef WV_TRANSMIT
uniform vec3 uKt[2];            // transmission colours: diffuse k_t
uniform vec3 uKst[2];           // and specular k_st
uniform vec3 uKf[2];            // the forward band's colour k_f
uniform float uFwK, uFwNorm;    // 1 / (2 width^2); 1 / the band's mean (wv_forward_band_mean)
uniform vec3 uBackPos;          // studio: a point light behind the cloth (uBackI 0: none)
uniform float uBackI;
#endif

uniform int uSpp;               // samples this frame
uniform int uFrame;             // frame index of the progressive accumulation

const float PI_F = 3.14159265358979;

// ---- 64-bit hashing (src/util/hash.h) ----
uvec2 add64(uvec2 a, uvec2 b) {
  uint lo = a.y + b.y;
  return uvec2(a.x + b.x + (lo < a.y ? 1u : 0u), lo);
}
uvec2 mul32(uint a, uint b) { // full 64-bit product of two 32-bit numbers
  uint a0 = a & 0xffffu, a1 = a >> 16, b0 = b & 0xffffu, b1 = b >> 16;
  uint p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  uint mid = (p00 >> 16) + (p01 & 0xffffu) + (p10 & 0xffffu);
  return uvec2(p11 + (p01 >> 16) + (p10 >> 16) + (mid >> 16), (p00 & 0xffffu) | (mid << 16));
}
uvec2 mul64(uvec2 a, uvec2 b) {
  uvec2 p = mul32(a.y, b.y);
  p.x += a.x * b.y + a.y * b.x;
  return p;
}
uvec2 shr64(uvec2 a, int n) { return uvec2(a.x >> n, (a.y >> n) | (a.x << (32 - n))); } // 0 < n < 32
uvec2 mix64(uvec2 z) {
  z = mul64(z ^ shr64(z, 30), uvec2(0xbf58476du, 0x1ce4e5b9u));
  z = mul64(z ^ shr64(z, 27), uvec2(0x94d049bbu, 0x133111ebu));
  return z ^ shr64(z, 31);
}
uvec2 hash2(uvec2 a, uvec2 b, uvec2 seed) {
  return mix64(mix64(add64(mul64(a, uvec2(0x9e3779b9u, 0x7f4a7c15u)), seed)) ^ mul64(b, uvec2(0xc2b2ae3du, 0x27d4eb4fu)));
}
uvec2 i64(int v) { return uvec2(v < 0 ? 0xffffffffu : 0u, uint(v)); } // sign-extended, as (uint64_t)(int64_t)v
float u01(uvec2 h) { return float(h.x >> 8) * (1.0 / 16777216.0); } // top 24 bits

// ---- fast math (src/util/fastmath.h) ----
float sinHp(float x) {
  float x2 = x * x;
  return x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 +
             x2 * (1.0 / 362880.0 + x2 * (-1.0 / 39916800.0))))));
}
float cosHp(float x) {
  float x2 = x * x;
  return 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 +
         x2 * (-1.0 / 3628800.0 + x2 * (1.0 / 479001600.0))))));
}
float expWv(float x) {
  x = clamp(x, -87.0, 88.0);
  float kf = floor(x * 1.44269502 + 0.5);
  float r = (x - kf * 0.693145751953125) - kf * 1.42860677e-6;
  float p = 1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 +
            r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
  return p * intBitsToFloat((int(kf) + 127) << 23);
}

// ---- yarn geometry (src/yarn/yarn_eval.h) ----
int wrapI(int v, int n) { int r = v % n; return r < 0 ? r + n : r; }

// The last segment's noisy heightfield scaling: a pixel's samples mostly fall on
// a few segments, and the segment hash is the costliest part of a sample.
struct SegCache { ivec3 key; float beta; };

// Returns the yarn type (0 warp, 1 weft, -1 gap) and n, t in fabric tangent space.
int yarnEval(float x, float y, inout SegCache cache, out vec3 n, out vec3 t) {
  float r = -y * uInvSpacing.y, c = x * uInvSpacing.x;
  float rf = floor(r), cf = floor(c);
  int I = int(rf), J = int(cf);
  float fr = r - rf, fc = c - cf;
  uint cell = texelFetch(uWeave, ivec2(wrapI(J, uCols), wrapI(I, uRows)), 0).r;
  int type = int(cell & 0xffu), len = int((cell >> 8) & 0xffu), idx = int(cell >> 16);
  float L = float(len), k = float(idx);
  float a, l, dAcross;
  ivec3 key; // the segment: type, its column (warp) or row (weft), its first cell
  if (type == 0) {
    a = (fc - 0.5) * uSpacing.x;
    l = -((k + fr) - 0.5 * L) * uSpacing.y;
    dAcross = uSpacing.x;
    key = ivec3(0, J, I - idx);
  } else {
    a = (fr - 0.5) * uSpacing.y;
    l = ((k + fc) - 0.5 * L) * uSpacing.x;
    dAcross = uSpacing.y;
    key = ivec3(1, I, J - idx);
  }
  if (abs(a) > 0.5 * dAcross * uYarnWidth) { // gap between yarns
    n = vec3(0.0, 0.0, 1.0);
    t = vec3(0.0, 1.0, 0.0);
    return -1;
  }
  float u = l * (2.0 * (1.0 / L)) * (type == 0 ? uUmaxOverSpacing.y : uUmaxOverSpacing.x);
  float v = a * (type == 0 ? uVScale.x : uVScale.y);
  float beta = type == 0 ? uBeta.x : uBeta.y;
  if (uNoise > 0) {
    if (key != cache.key) {
      uvec2 k2 = i64(key.y);
      uvec2 seg = hash2(uvec2((k2.x << 1) | (k2.y >> 31), (k2.y << 1) | uint(key.x)), i64(key.z), uSeed);
      float xi = u01(mix64(seg ^ uvec2(0x5851f42du, 0x4c957f2du)));
      cache.key = key;
      cache.beta = max(beta * (1.0 + 0.1 * float(uNoise) * (2.0 * xi - 1.0)), 0.0);
    }
    beta = cache.beta;
  }
  float su = sinHp(u), cu = cosHp(u), sv = sinHp(v), cv = cosHp(v);
  n = vec3(sv, su * cv, cu * cv);
  t = vec3(-cv * uSinPsi, cu * uCosPsi + su * sv * uSinPsi, -su * uCosPsi + cu * sv * uSinPsi);
  // heightfield scaling (wv_yarn_scale_inline)
  vec3 ns = vec3(beta * n.x, beta * n.y, n.z);
  float ln2 = dot(ns, ns);
  if (ln2 < 1e-24) { ns = vec3(0.0, 0.0, 1.0); ln2 = 1.0; }
  n = ns * (1.0 / sqrt(ln2));
  vec3 ts = vec3(t.x, t.y, beta * t.z);
  float lt2 = dot(ts, ts);
  if (lt2 < 1e-24) { ts = vec3(0.0, 1.0, 0.0); lt2 = 1.0; }
  t = ts * (1.0 / sqrt(lt2));
  if (type == 1) { // the +y yarn frame rotated by -90 degrees about z
    n = vec3(n.y, -n.x, n.z);
    t = vec3(t.y, -t.x, t.z);
  }
  return type;
}

// U_s (wv_glint): -ln(1 - xi) at the midpoint of xi's 4096-bin cell, at most 10.
// The last cell's value is kept: where a pixel is smaller than a glint cell (an
// eighth of the yarn spacing), its samples share one and hash it once.
struct GlintCache { ivec2 cell; float us; };
float glint(float fx, float fy, inout GlintCache cache) {
  if (!uGlints) return 1.0;
  ivec2 g = ivec2(int(floor(fx * uInvGlintCell.x)), int(floor(fy * uInvGlintCell.y)));
  if (g != cache.cell) {
    uvec2 h = hash2(i64(g.x), i64(g.y), uSeed ^ uvec2(0u, 0x676c696eu));
    float xi = (float(h.x >> 20) + 0.5) / 4096.0;
    cache.cell = g;
    cache.us = min(-log(1.0 - xi), 10.0);
  }
  return cache.us;
}

// wv_shade for one light: the radiance of a fabric point with yarn frame (n, t),
// glint factor us, directions wi, wo (fabric tangent space), light = I / r^2.
vec3 shadeLight(int ty, vec3 n, vec3 t, float us, vec3 wi, vec3 wo, float light) {
  if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
  vec3 h = normalize(wi + wo);
  float mi = wi.z, mo = wo.z;
  float a = uAlpha[ty], k = 1.0 - a * a;
  float ti = dot(t, wi), to = dot(t, wo), th = dot(t, h);
  float si2 = 1.0 - k * ti * ti, so2 = 1.0 - k * to * to;
  float si = sqrt(max(si2, 0.0)), so = sqrt(max(so2, 0.0));
  float A = si / mi + so / mo;
  float q = 1.0 + (1.0 / (a * a) - 1.0) * th * th;
  float D = 1.0 / (PI_F * a * q * q);
  float spec = A > 0.0 ? D * (1.0 - expWv(-uThickness * A)) / (4.0 * mo * A) : 0.0;
  spec *= us;
  float ni = dot(wi, n);
  float diff = (uBlend * max(ni, 0.0) + (1.0 - uBlend) * mi) * (1.0 / PI_F);
  return light * (uKs[ty] * spec + uKd[ty] * diff);
}

// The cloth at a fabric point (wv_yarn_locate's crossing yarn, wv_cloth_chords):
// the type of the yarn seen from the front and passed by light from behind (the
// visible one, or beside it the crossing one; -1 in an open gap, where no yarn
// is) and the chords of the visible (lv) and the crossing (lh) yarn, in yarn
// diameters.
int clothAt(float x, float y, out float lv, out float lh) {
  float r = -y * uInvSpacing.y, c = x * uInvSpacing.x;
  int I = int(floor(r)), J = int(floor(c));
  float fr = r - floor(r), fc = c - floor(c);
  int type = int(texelFetch(uWeave, ivec2(wrapI(J, uCols), wrapI(I, uRows)), 0).r & 0xffu);
  float a = type == 0 ? (fc - 0.5) * uSpacing.x : (fr - 0.5) * uSpacing.y;
  float ah = type == 0 ? (fr - 0.5) * uSpacing.y : (fc - 0.5) * uSpacing.x;
  bool lit = !(abs(a) > 0.5 * (type == 0 ? uSpacing.x : uSpacing.y) * uYarnWidth);
  bool cov = !(abs(ah) > 0.5 * (type == 0 ? uSpacing.y : uSpacing.x) * uYarnWidth);
  float cv = cosHp(a * (type == 0 ? uVScale.x : uVScale.y)), ch = cosHp(ah * (type == 0 ? uVScale.y : uVScale.x));
  lv = lit && cv > 0.0 ? cv : 0.0;
  lh = cov && ch > 0.0 ? ch : 0.0;
  if (lit) return type;
  return cov ? 1 - type : -1;
}

// wv_shade_refl beside the visible yarn, over the crossing yarn tc: that yarn's
// diffuse lobe with the macro normal.
vec3 shadeUnder(int tc, vec3 wi, vec3 wo, float light) {
  if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
  return light * uKd[tc] * (wi.z * (1.0 / PI_F));
}

#ifdef WV_TRANSMIT
// phi(y) = (1 - e^-y) / y, its Taylor series below 0.5 (wv_phi).
float phiWv(float y) {
  if (y < 0.5)
    return 1.0 - y * (1.0 / 2.0 - y * (1.0 / 6.0 - y * (1.0 / 24.0 - y * (1.0 / 120.0 - y * (1.0 / 720.0 -
           y * (1.0 / 5040.0 - y * (1.0 / 40320.0 - y * (1.0 / 362880.0 - y * (1.0 / 3628800.0)))))))));
  return (1.0 - expWv(-y)) / y;
}

// wv_shade_trans for one light behind the cloth (wi.z < 0): the visible yarn ty
// (-1 beside it) with frame (n, t), the yarn tw the light passes, the chords.
vec3 shadeTrans(int ty, int tw, vec3 n, vec3 t, float us, float lv, float lh, vec3 wi, vec3 wo, float light) {
  if (wo.z <= 0.0) return vec3(0.0);
  float ami = -wi.z, mo = wo.z;
  float Ah = 1.0 / (1.0 + 0.5 * (uThickness * lh)), A = 1.0 / (1.0 + 0.5 * (uThickness * (lv + lh)));
  vec3 spec = vec3(0.0);
  float ni = ami; // beside the visible yarn: the macro normal
  if (ty >= 0) {
    vec3 h = normalize(wi + wo);
    float a = uAlpha[ty], k = 1.0 - a * a;
    float ti = dot(t, wi), to = dot(t, wo), th = dot(t, h);
    float si = sqrt(max(1.0 - k * ti * ti, 0.0)), so = sqrt(max(1.0 - k * to * to, 0.0));
    float pa = si / ami, pb = so / mo, tl = uThickness * lv;
    float E = tl * expWv(-tl * min(pa, pb)) * phiWv(tl * abs(pa - pb));
    float q = 1.0 + (1.0 / (a * a) - 1.0) * th * th;
    float D = 1.0 / (PI_F * a * q * q);
    spec = uKst[ty] * (us * Ah * D / (4.0 * mo) * E);
    // the yarn's underside, where the light enters: the normal mirrored along the yarn and in z
    ni = dot(wi, ty == 0 ? vec3(n.x, -n.y, -n.z) : vec3(-n.x, n.y, -n.z));
  }
  float diff = (uBlend * max(ni, 0.0) + (1.0 - uBlend) * ami) * (1.0 / PI_F) * A;
  // the forward band around the axis of the yarn the light passes, in the fabric frame
  // (warp along y, weft along x), not the yarn's local one
  float sf = 0.5 * (tw == 0 ? wi.y + wo.y : wi.x + wo.x);
  float fq = 1.0 + (sf * sf) * uFwK;
  float fwd = (ami * A * uFwNorm * 0.3183098861837907) / (fq * fq);
  return light * (spec + uKt[tw] * diff + uKf[tw] * fwd);
}
#endif

// 0 where the shadow map has a surface nearer the key light than P, else 1.
// P moves off the surface along N by 1.5 texels: a texel is flat where the
// surface slopes away from the light, and would shadow the surface itself.
float keyVisible(vec3 P, vec3 N) {
  if (!uShadows) return 1.0;
  P += N * (1.5 * uShadowTexel * distance(P, uLightPos));
  vec4 q = uShadowMatrix * vec4(P, 1.0);
  vec2 uv = q.xy / q.w * 0.5 + 0.5;
  if (q.w <= 0.0 || any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
  return distance(P, uLightPos) * uShadowInvFar > texture(uShadowMap, uv).r + uShadowBias ? 0.0 : 1.0;
}

// A per-pixel random rotation of the sample sequence (a 32-bit integer hash).
uint pcg(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}

void main() {
  // Fabric coordinates (mm) and the tangent frame at the pixel centre.
  vec3 P = vWorld, T, B, N;
  vec2 f;
  if (uShape == 0) { // plane (wv_rig_trace)
    N = vec3(0.0, 0.0, 1.0);
    T = vec3(uRotC, uRotS, 0.0);
    B = vec3(-uRotS, uRotC, 0.0);
    f = vec2(dot(P.xy, uAcross0), dot(P.xy, uAcross1)) * uMmPerUnit + uOffset;
    if (uDistK > 0.0) { // the terms a, b, a^2, ab, b^2, a^3, a^2 b, a b^2, b^3 (WV_DISTORT_EVAL)
      float a = P.x * uDistK, b = P.y * uDistK;
      float t[9] = float[9](a, b, a * a, a * b, b * b, a * a * a, a * a * b, a * b * b, b * b * b);
      for (int i = 0; i < 9; i++) f += t[i] * vec2(uDistX[i], uDistY[i]);
    }
  } else if (uShape == 1) { // cylinder around the x axis
    float sn = P.y / uRadius, cs = P.z / uRadius;
    N = vec3(0.0, sn, cs);
    float theta = atan(P.y, P.z);
    if (uWarpAlongAxis) {
      T = vec3(0.0, -cs, sn);
      B = vec3(1.0, 0.0, 0.0);
      f = vec2(-uRadius * theta * uMmPerUnit, P.x * uMmPerUnit) + uOffset;
    } else {
      T = vec3(1.0, 0.0, 0.0);
      B = vec3(0.0, cs, -sn);
      f = vec2(P.x * uMmPerUnit, uRadius * theta * uMmPerUnit) + uOffset;
    }
  } else { // mesh: u along fabric x, v down (fabric y = -v)
    N = normalize(vNormal);
    T = normalize(vTangent.xyz - N * dot(N, vTangent.xyz));
    B = cross(N, T) * vTangent.w;
    if (!gl_FrontFacing) { N = -N; B = -B; } // the back, seen as a mirror image
    f = vec2(vUv.x, -vUv.y) * uUvMm;
  }
  // The pixel's footprint on the fabric: the parallelogram of the screen-space
  // derivatives (the C renderer maps each pixel's four corners bilinearly).
  vec2 fdx = dFdx(f), fdy = dFdy(f);

  vec3 L = uLightPos - P;
  float r2 = dot(L, L);
  vec3 l = L * (1.0 / sqrt(r2));
  vec3 V = normalize(uCamPos - P);
  vec3 wi = vec3(dot(l, T), dot(l, B), dot(l, N));
  vec3 wo = vec3(dot(V, T), dot(V, B), dot(V, N));
#ifdef WV_TRANSMIT
  float light = uLightI / r2 * keyVisible(P, wi.z < 0.0 ? -N : N); // lit from behind: tested on the far side
  vec3 wib = vec3(0.0, 0.0, 1.0);
  float lightb = 0.0;
  if (uBackI > 0.0) {
    vec3 Lb = uBackPos - P;
    float rb2 = dot(Lb, Lb);
    vec3 lb = Lb * (1.0 / sqrt(rb2));
    wib = vec3(dot(lb, T), dot(lb, B), dot(lb, N));
    lightb = uBackI / rb2;
  }
  float open = 0.0; // samples whose line of sight crosses an open gap
#else
  float light = uLightI / r2 * keyVisible(P, N);
#endif

  // Samples: the R2 low-discrepancy sequence (Roberts 2018) continued across
  // frames, rotated per pixel (Cranley-Patterson).
  uvec2 pix = uvec2(gl_FragCoord.xy);
  uint ph = pcg(pix.x * 73856093u ^ pcg(pix.y * 19349663u));
  vec2 rot = vec2(float(ph >> 8) * (1.0 / 16777216.0), float(pcg(ph) >> 8) * (1.0 / 16777216.0));
  vec3 sum = vec3(0.0);
  SegCache cache = SegCache(ivec3(-1, 0x7fffffff, 0), 0.0);
  GlintCache gcache = GlintCache(ivec2(0x7fffffff, -0x7fffffff), 1.0); // a cell no position reaches
  for (int s = 0; s < uSpp; s++) {
    float g = float(uFrame * uSpp + s);
    vec2 xi = fract(rot + g * vec2(0.7548776662466927, 0.5698402909980532));
    vec2 fs = f + fdx * (xi.x - 0.5) + fdy * (xi.y - 0.5);
    vec3 yn, yt;
    int ty = yarnEval(fs.x, fs.y, cache, yn, yt);
    float lv = 0.0, lh = 0.0;
#ifdef WV_TRANSMIT
    int tw = clothAt(fs.x, fs.y, lv, lh); // the yarn seen: the visible one, or beside it the crossing one
    if (tw < 0) { open += 1.0; continue; } // an open gap: what is behind shows (display.frag)
    float us = ty >= 0 ? glint(fs.x, fs.y, gcache) : 1.0;
    sum += wi.z < 0.0 ? shadeTrans(ty, tw, yn, yt, us, lv, lh, wi, wo, light)
                      : (ty >= 0 ? shadeLight(ty, yn, yt, us, wi, wo, light) : shadeUnder(tw, wi, wo, light));
    if (lightb > 0.0)
      sum += wib.z < 0.0 ? shadeTrans(ty, tw, yn, yt, us, lv, lh, wib, wo, lightb)
                         : (ty >= 0 ? shadeLight(ty, yn, yt, us, wib, wo, lightb) : shadeUnder(tw, wib, wo, lightb));
#else
    int tw = ty >= 0 ? ty : clothAt(fs.x, fs.y, lv, lh);
    if (tw < 0) continue; // an open gap: nothing reflects
    float us = ty >= 0 ? glint(fs.x, fs.y, gcache) : 1.0;
    sum += ty >= 0 ? shadeLight(ty, yn, yt, us, wi, wo, light) : shadeUnder(tw, wi, wo, light);
#endif
    for (int b = 0; b < uBoxes; b++) { // one point of each soft box per sample
      vec2 e = fract(rot.yx + g * vec2(0.5698402909980532, 0.7548776662466927) + 0.37 * float(b + 1)) * 2.0 - 1.0;
      vec3 q = uBoxC[b] + e.x * uBoxU[b] + e.y * uBoxV[b];
      vec3 Lb = q - P;
      float rb2 = dot(Lb, Lb);
      vec3 lb = Lb * (1.0 / sqrt(rb2));
      float cosb = abs(dot(lb, uBoxN[b])); // two-sided emitter
      vec3 wib = vec3(dot(lb, T), dot(lb, B), dot(lb, N));
      float lb2 = uBoxL[b] * uBoxArea[b] * cosb / rb2;
      sum += ty >= 0 ? shadeLight(ty, yn, yt, us, wib, wo, lb2) : shadeUnder(tw, wib, wo, lb2);
    }
    if (uAmbient > 0.0 && wo.z > 0.0) // uniform sky on the diffuse lobe: its exact cosine integral (yn the macro normal beside a yarn)
      sum += uAmbient * uKd[tw] * (uBlend * 0.5 * (1.0 + yn.z) + (1.0 - uBlend));
  }
#ifdef WV_TRANSMIT
  outColor = vec4(sum / float(uSpp), 1.0 - open / float(uSpp)); // alpha: the cloth's cover
#else
  outColor = vec4(sum / float(uSpp), 1.0);
#endif
}
