// woven viewer: from accumulated radiance to the screen. In the capture rig it
// is the scene's sensor response, mirrored from src/scene/response.c (exposure,
// clip, encoding, Gaussian falloff mask about the image centre); in the studio
// an exposure, a clip at 1 and sRGB encoding over a grey backdrop (black with the
// key light alone, as woven scene shows nothing where no light is). With the
// light through the cloth the fabric pass's alpha is the cloth's cover: the rig
// adds the light seen through the open gaps (the scene's gap glow, radiance
// uGlow exp(-d^2 / uGlowSigma^2) per open area, wv_gap_glow), the studio its
// backdrop. The left part
// of the picture (uSplit) may show the photo instead.
precision highp float;
in vec2 vUv;
out vec4 outColor;
uniform sampler2D uAcc;
uniform float uInvFrames;
uniform bool uRig;
uniform float uExposure, uClip, uGamma, uSigma;
uniform int uEncoding;        // 0 linear, 1 sRGB, 2 gamma (wv_encoding)
uniform bool uFalloff;
uniform float uGlow, uGlowSigma; // rig: the gap glow (uGlow 0: none)
uniform bool uBackdrop;       // studio: the grey backdrop behind the fabric
uniform vec2 uSize;           // image size in pixels
uniform sampler2D uPhoto;
uniform float uSplit;         // fraction of the width showing the photo

float encode(float x) { // wv_encode
  if (x <= 0.0) return 0.0;
  if (uEncoding == 1) return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
  if (uEncoding == 2) return pow(x, 1.0 / uGamma);
  return x;
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 a = texelFetch(uAcc, p, 0) * uInvFrames;
  vec3 c;
  if (uRig) {
    vec3 rad = a.rgb;
    if (uGlow > 0.0) {
      vec2 d = gl_FragCoord.xy - 0.5 * uSize;
      rad += uGlow * exp(-dot(d, d) / (uGlowSigma * uGlowSigma)) * (1.0 - a.a);
    }
    vec3 v = rad * uExposure;
    if (uClip > 0.0) v = min(v, vec3(uClip));
    float m = 1.0;
    if (uFalloff) { // pixel centres: gl_FragCoord is x + 0.5 (and mirrored in y, which the mask does not mind)
      vec2 d = gl_FragCoord.xy - 0.5 * uSize;
      m = exp(-dot(d, d) / (uSigma * uSigma));
    }
    c = m * vec3(encode(v.r), encode(v.g), encode(v.b));
  } else {
    vec3 v = min(a.rgb * uExposure, vec3(1.0));
    vec3 fab = vec3(encode(v.r), encode(v.g), encode(v.b));
    vec3 bg = uBackdrop ? mix(vec3(0.16), vec3(0.30), vUv.y) : vec3(0.0);
    c = fab + (1.0 - clamp(a.a, 0.0, 1.0)) * bg; // fab: the cloth's light times its cover
  }
  if (vUv.x < uSplit) c = texture(uPhoto, vec2(vUv.x, 1.0 - vUv.y)).rgb;
  outColor = vec4(c, 1.0);
}
