/* woven: capture scenes: the presets, JSON reading and writing, and the one
 * validation every scene passes (ranges of every value). */
#include "woven/scene.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_json.h"
#include "io/json_file.h"
#include "util/json.h"
#include "woven/io.h"

/* The presets. scenes/cylinder.json, scenes/flat45.json and scenes/flat45-back.json hold the same
 * text (a test checks they agree). */
static const char *PRESET_CYLINDER =
    "{\n"
    "  \"name\": \"cylinder\",\n"
    "  \"comment\": \"The paper's rig (Fig. 6): fabric on a horizontal cylinder, phone camera 250 mm from the axis, flash 60 mm above the camera.\",\n"
    "  \"image\": {\"width\": 800, \"height\": 300, \"spp\": 64},\n"
    "  \"camera\": {\"position_mm\": [0, 0, 250], \"look_at_mm\": [0, 0, 0], \"up\": [0, 1, 0], \"vfov_deg\": 16.89},\n"
    "  \"sample\": {\"shape\": \"cylinder\", \"radius_mm\": 35, \"warp\": \"along_axis\", \"offset_mm\": [0, 0]},\n"
    "  \"light\": {\"position_mm\": [0, 60, 250], \"intensity\": 150000},\n"
    "  \"response\": {\"exposure\": 1, \"clip\": 1, \"encoding\": \"srgb\"},\n"
    "  \"falloff\": {\"type\": \"gaussian\", \"sigma_px\": 450}\n"
    "}\n";

static const char *PRESET_FLAT45 =
    "{\n"
    "  \"name\": \"flat45\",\n"
    "  \"comment\": \"Flat sample seen from above, light at 45 degrees toward the top of the image (the photos of shared/data/real-flat). The photos show yarns 1 to 2.5 pixels apart (0.019..0.038 units), so one unit stands for 8 mm of fabric: 85..170 yarns per inch.\",\n"
    "  \"image\": {\"width\": 512, \"height\": 512, \"spp\": 64},\n"
    "  \"camera\": {\"position_mm\": [0, 0, 8], \"look_at_mm\": [0, 0, 0], \"up\": [0, 1, 0], \"vfov_deg\": 53},\n"
    "  \"sample\": {\"shape\": \"plane\", \"rotation_deg\": 0, \"offset_mm\": [0, 0], \"mm_per_unit\": 8},\n"
    "  \"light\": {\"position_mm\": [0, 8, 8], \"intensity\": 300},\n"
    "  \"response\": {\"exposure\": 1, \"clip\": 1, \"encoding\": \"gamma\", \"gamma\": 2.2},\n"
    "  \"falloff\": {\"type\": \"gaussian\", \"sigma_px\": 450}\n"
    "}\n";

static const char *PRESET_FLAT45_BACK =
    "{\n"
    "  \"name\": \"flat45-back\",\n"
    "  \"comment\": \"The flat45 camera, sample and response with the front light off and a point light of the same intensity behind the cloth, on the camera's axis 9 units below it (the transmission photos *_T.png of shared/data/real-flat). The light seen straight through a gap between yarns is out of focus: 8 times a Gaussian of sigma 20 px centred on the image.\",\n"
    "  \"image\": {\"width\": 512, \"height\": 512, \"spp\": 64},\n"
    "  \"camera\": {\"position_mm\": [0, 0, 8], \"look_at_mm\": [0, 0, 0], \"up\": [0, 1, 0], \"vfov_deg\": 53},\n"
    "  \"sample\": {\"shape\": \"plane\", \"rotation_deg\": 0, \"offset_mm\": [0, 0], \"mm_per_unit\": 8},\n"
    "  \"light\": {\"position_mm\": [0, 0, -9], \"intensity\": 300},\n"
    "  \"response\": {\"exposure\": 1, \"clip\": 1, \"encoding\": \"gamma\", \"gamma\": 2.2,\n"
    "               \"gap_glow\": {\"radiance\": 8, \"sigma_px\": 20}},\n"
    "  \"falloff\": {\"type\": \"gaussian\", \"sigma_px\": 450}\n"
    "}\n";

/* Numbers are read as any finite value (WV_JSON_FINITE): the ranges are wv_scene_validate's,
 * which also checks scenes made in code. */

static const char *const K_RESPONSE[] = {"exposure", "clip", "encoding", "gamma", "psf_sigma_px", "gap_glow", NULL};
static const char *const K_RESPONSE_NO_PSF[] = {"exposure", "clip", "encoding", "gamma", NULL};
static const char *const K_FALLOFF[] = {"type", "sigma_px", NULL};
static const char *const K_GLOW[] = {"radiance", "sigma_px", NULL};

wv_status wv_scene_read_response(json_t *root, int psf, wv_scene *s, wv_error *err) {
  static const wv_json_enum enc[] = {{"srgb", WV_ENC_SRGB}, {"gamma", WV_ENC_GAMMA}, {"linear", WV_ENC_LINEAR}, {0}};
  static const wv_json_enum type[] = {{"gaussian", 1}, {"none", 0}, {0}};
  json_t *o;
  int e = WV_ENC_SRGB;
  wv_status st;
  s->exposure = 1, s->clip = 1, s->gamma = 2.2, s->psf_sigma = 0, s->falloff = 0, s->falloff_sigma = 0;
  s->glow_radiance = 0, s->glow_sigma = 0;
  if ((st = wv_json_object(root, NULL, "response", psf ? K_RESPONSE : K_RESPONSE_NO_PSF, 0, &o, err)) ||
      (st = wv_json_number(o, "response", "exposure", WV_JSON_FINITE, 0, &s->exposure, err)) ||
      (st = wv_json_number(o, "response", "clip", WV_JSON_FINITE, 0, &s->clip, err)) ||
      (st = wv_json_number(o, "response", "gamma", WV_JSON_FINITE, 0, &s->gamma, err)) ||
      (st = wv_json_number(o, "response", "psf_sigma_px", WV_JSON_FINITE, 0, &s->psf_sigma, err)) ||
      (st = wv_json_enum_of(o, "response", "encoding", enc, 0, &e, err)))
    return st;
  s->encoding = (wv_encoding)e;
  json_t *g;
  if (psf && (st = wv_json_object(o, "response", "gap_glow", K_GLOW, 0, &g, err))) return st;
  if (psf && g &&
      ((st = wv_json_number(g, "response.gap_glow", "radiance", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->glow_radiance,
                            err)) ||
       (st = wv_json_number(g, "response.gap_glow", "sigma_px", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->glow_sigma,
                            err))))
    return st;
  if ((st = wv_json_object(root, NULL, "falloff", K_FALLOFF, 0, &o, err))) return st;
  if (o && (st = wv_json_enum_of(o, "falloff", "type", type, WV_JSON_REQUIRED, &s->falloff, err))) return st;
  if (s->falloff &&
      (st = wv_json_number(o, "falloff", "sigma_px", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->falloff_sigma, err)))
    return st;
  return WV_OK;
}

static wv_status parse_root(json_t *r, wv_scene *s, wv_error *err) {
  static const char *const top[] = {"name",  "comment",  "image",   "camera", "sample",
                                    "light", "response", "falloff", NULL};
  static const char *const k_img[] = {"width", "height", "spp", NULL};
  static const char *const k_cam[] = {"position_mm", "look_at_mm", "up", "vfov_deg", NULL};
  static const char *const k_smp[] = {"shape",     "radius_mm",   "warp",       "rotation_deg", "skew_deg",
                                      "offset_mm", "mm_per_unit", "distortion", NULL};
  static const char *const k_dis[] = {"extent_mm", "x", "y", NULL};
  static const char *const k_lig[] = {"position_mm", "intensity", NULL};
  static const wv_json_enum shapes[] = {{"cylinder", WV_SHAPE_CYLINDER}, {"plane", WV_SHAPE_PLANE}, {0}};
  static const wv_json_enum warps[] = {{"along_axis", 1}, {"around_axis", 0}, {0}};
  wv_status st;
  json_t *o;
  memset(s, 0, sizeof *s);
  if ((st = wv_json_only_keys(r, "", top, err))) return st;
  json_t *nm = json_object_get(r, "name");
  snprintf(s->name, sizeof s->name, "%s", json_is_string(nm) ? json_string_value(nm) : "custom");
  /* a name cut to fit ends on a whole UTF-8 character, so that it can be written back */
  size_t nl = strlen(s->name);
  if (nl == sizeof s->name - 1) {
    while (nl > 0 && ((unsigned char)s->name[nl - 1] & 0xC0) == 0x80) nl--;
    if (nl > 0 && (unsigned char)s->name[nl - 1] >= 0xC0) nl--;
    s->name[nl] = '\0';
  }

  s->spp = 64;
  if ((st = wv_json_object(r, NULL, "image", k_img, WV_JSON_REQUIRED, &o, err)) ||
      (st = wv_json_int(o, "image", "width", 1, WV_SCENE_MAX_SIDE, WV_JSON_REQUIRED, &s->width, err)) ||
      (st = wv_json_int(o, "image", "height", 1, WV_SCENE_MAX_SIDE, WV_JSON_REQUIRED, &s->height, err)) ||
      (st = wv_json_int(o, "image", "spp", 1, WV_SCENE_MAX_SPP, 0, &s->spp, err)))
    return st;

  s->cam_up[1] = 1;
  if ((st = wv_json_object(r, NULL, "camera", k_cam, WV_JSON_REQUIRED, &o, err)) ||
      (st = wv_json_numbers(o, "camera", "position_mm", 3, WV_JSON_FINITE, WV_JSON_REQUIRED, s->cam_pos, err)) ||
      (st = wv_json_numbers(o, "camera", "look_at_mm", 3, WV_JSON_FINITE, WV_JSON_REQUIRED, s->cam_look_at, err)) ||
      (st = wv_json_numbers(o, "camera", "up", 3, WV_JSON_FINITE, 0, s->cam_up, err)) ||
      (st = wv_json_number(o, "camera", "vfov_deg", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->vfov_deg, err)))
    return st;

  int shape = 0;
  if ((st = wv_json_object(r, NULL, "sample", k_smp, WV_JSON_REQUIRED, &o, err)) ||
      (st = wv_json_enum_of(o, "sample", "shape", shapes, WV_JSON_REQUIRED, &shape, err)))
    return st;
  s->shape = (wv_shape_type)shape;
  if (s->shape == WV_SHAPE_CYLINDER) {
    if (json_object_get(o, "skew_deg"))
      return wv_fail(err, WV_ERR_INVALID, "'sample.skew_deg' applies to a plane, not a cylinder");
    if (json_object_get(o, "distortion"))
      return wv_fail(err, WV_ERR_INVALID, "'sample.distortion' applies to a plane, not a cylinder");
    s->warp_along_axis = 1;
    if ((st = wv_json_number(o, "sample", "radius_mm", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->radius, err)) ||
        (st = wv_json_enum_of(o, "sample", "warp", warps, 0, &s->warp_along_axis, err)))
      return st;
  } else {
    json_t *d;
    if ((st = wv_json_number(o, "sample", "rotation_deg", WV_JSON_FINITE, 0, &s->rotation_deg, err)) ||
        (st = wv_json_number(o, "sample", "skew_deg", WV_JSON_FINITE, 0, &s->skew_deg, err)) ||
        (st = wv_json_object(o, "sample", "distortion", k_dis, 0, &d, err)))
      return st;
    if (d && ((st = wv_json_number(d, "sample.distortion", "extent_mm", WV_JSON_FINITE, WV_JSON_REQUIRED,
                                   &s->distort_extent_mm, err)) ||
              (st = wv_json_numbers(d, "sample.distortion", "x", WV_DISTORT_TERMS, WV_JSON_FINITE, WV_JSON_REQUIRED,
                                    s->distort[0], err)) ||
              (st = wv_json_numbers(d, "sample.distortion", "y", WV_DISTORT_TERMS, WV_JSON_FINITE, WV_JSON_REQUIRED,
                                    s->distort[1], err))))
      return st;
  }
  s->mm_per_unit = 1;
  if ((st = wv_json_numbers(o, "sample", "offset_mm", 2, WV_JSON_FINITE, 0, s->fabric_offset, err)) ||
      (st = wv_json_number(o, "sample", "mm_per_unit", WV_JSON_FINITE, 0, &s->mm_per_unit, err)))
    return st;

  if ((st = wv_json_object(r, NULL, "light", k_lig, WV_JSON_REQUIRED, &o, err)) ||
      (st = wv_json_numbers(o, "light", "position_mm", 3, WV_JSON_FINITE, WV_JSON_REQUIRED, s->light_pos, err)) ||
      (st = wv_json_number(o, "light", "intensity", WV_JSON_FINITE, WV_JSON_REQUIRED, &s->light_intensity, err)))
    return st;

  if ((st = wv_scene_read_response(r, 1, s, err))) return st;
  return wv_scene_validate(s, err);
}

/* v[0..n-1] within -lim..lim; the message names 'key[i]'. */
static wv_status check_vec(const double *v, int n, const char *key, double lim, wv_error *err) {
  char a[32], b[32], c[32];
  for (int i = 0; i < n; i++)
    if (!(v[i] >= -lim && v[i] <= lim))
      return wv_fail(err, WV_ERR_INVALID, "'%s[%d]' = %s is outside %s..%s", key, i, wv_num_str(v[i], a),
                     wv_num_str(-lim, b), wv_num_str(lim, c));
  return WV_OK;
}

wv_status wv_scene_check_response(const wv_scene *s, wv_error *err) {
  char a[32];
  if (!(s->exposure > 0 && s->exposure <= 1e6))
    return wv_fail(err, WV_ERR_INVALID, "'response.exposure' = %s must be in (0, 1000000]", wv_num_str(s->exposure, a));
  if (!(s->clip >= -1e6 && s->clip <= 1e6))
    return wv_fail(err, WV_ERR_INVALID, "'response.clip' = %s is outside -1000000..1000000", wv_num_str(s->clip, a));
  if (s->encoding == WV_ENC_GAMMA && !(s->gamma > 0.1 && s->gamma < 10))
    return wv_fail(err, WV_ERR_INVALID, "'response.gamma' = %s is outside (0.1, 10)", wv_num_str(s->gamma, a));
  if (!(s->psf_sigma >= 0 && s->psf_sigma <= WV_PSF_MAX_SIGMA))
    return wv_fail(err, WV_ERR_INVALID, "'response.psf_sigma_px' = %s is outside 0..%g", wv_num_str(s->psf_sigma, a),
                   WV_PSF_MAX_SIGMA);
  if (!(s->glow_radiance >= 0 && s->glow_radiance <= WV_SCENE_MAX_GLOW))
    return wv_fail(err, WV_ERR_INVALID, "'response.gap_glow.radiance' = %s is outside 0..%g",
                   wv_num_str(s->glow_radiance, a), WV_SCENE_MAX_GLOW);
  if (s->glow_radiance > 0 && !(s->glow_sigma > 0 && s->glow_sigma <= 1e9))
    return wv_fail(err, WV_ERR_INVALID, "'response.gap_glow.sigma_px' = %s must be in (0, 1e+09]",
                   wv_num_str(s->glow_sigma, a));
  if (s->falloff && !(s->falloff_sigma > 0 && s->falloff_sigma <= 1e9))
    return wv_fail(err, WV_ERR_INVALID, "'falloff.sigma_px' = %s must be in (0, 1e+09]",
                   wv_num_str(s->falloff_sigma, a));
  return WV_OK;
}

wv_status wv_scene_validate(const wv_scene *s, wv_error *err) {
  char a[32];
  wv_status st;
  if (s->width < 1 || s->width > WV_SCENE_MAX_SIDE || s->height < 1 || s->height > WV_SCENE_MAX_SIDE)
    return wv_fail(err, WV_ERR_INVALID, "'image' size %d x %d is outside 1..%d per side", s->width, s->height,
                   WV_SCENE_MAX_SIDE);
  if (s->spp < 1 || s->spp > WV_SCENE_MAX_SPP)
    return wv_fail(err, WV_ERR_INVALID, "'image.spp' = %d is outside 1..%d", s->spp, WV_SCENE_MAX_SPP);
  if ((long long)s->width * s->height * s->spp > WV_SCENE_MAX_SAMPLES)
    return wv_fail(err, WV_ERR_NOMEM, "'image': %d x %d pixels x %d spp is too many samples (limit %lld)",
                   s->width, s->height, s->spp, (long long)WV_SCENE_MAX_SAMPLES);
  /* Magnitudes first: the geometric checks below are meaningless on absurd values. */
  if ((st = check_vec(s->cam_pos, 3, "camera.position_mm", WV_SCENE_MAX_MM, err)) ||
      (st = check_vec(s->cam_look_at, 3, "camera.look_at_mm", WV_SCENE_MAX_MM, err)) ||
      (st = check_vec(s->cam_up, 3, "camera.up", WV_SCENE_MAX_MM, err)) ||
      (st = check_vec(s->light_pos, 3, "light.position_mm", WV_SCENE_MAX_MM, err)) ||
      (st = check_vec(s->fabric_offset, 2, "sample.offset_mm", WV_SCENE_MAX_OFFSET_MM, err)))
    return st;
  if (!(s->vfov_deg > 0.01 && s->vfov_deg < 179))
    return wv_fail(err, WV_ERR_INVALID, "'camera.vfov_deg' = %s is outside (0.01, 179)", wv_num_str(s->vfov_deg, a));
  double f[3], l2 = 0, c2 = 0;
  for (int i = 0; i < 3; i++) f[i] = s->cam_look_at[i] - s->cam_pos[i], l2 += f[i] * f[i];
  if (!(l2 > 1e-12)) return wv_fail(err, WV_ERR_INVALID, "'camera.look_at_mm' equals 'camera.position_mm'");
  double cr[3] = {f[1] * s->cam_up[2] - f[2] * s->cam_up[1], f[2] * s->cam_up[0] - f[0] * s->cam_up[2],
                  f[0] * s->cam_up[1] - f[1] * s->cam_up[0]};
  for (int i = 0; i < 3; i++) c2 += cr[i] * cr[i];
  if (!(c2 > 1e-12 * l2)) return wv_fail(err, WV_ERR_INVALID, "'camera.up' is parallel to the view direction (or zero)");
  if (s->shape == WV_SHAPE_CYLINDER && !(s->radius > 0 && s->radius < 1e6))
    return wv_fail(err, WV_ERR_INVALID, "'sample.radius_mm' = %s must be in (0, 1000000)", wv_num_str(s->radius, a));
  if (s->shape == WV_SHAPE_PLANE && !(s->rotation_deg >= -360 && s->rotation_deg <= 360))
    return wv_fail(err, WV_ERR_INVALID, "'sample.rotation_deg' = %s is outside -360..360",
                   wv_num_str(s->rotation_deg, a));
  if (s->shape == WV_SHAPE_PLANE && !(s->skew_deg >= -WV_SCENE_MAX_SKEW && s->skew_deg <= WV_SCENE_MAX_SKEW))
    return wv_fail(err, WV_ERR_INVALID, "'sample.skew_deg' = %s is outside -%g..%g", wv_num_str(s->skew_deg, a),
                   WV_SCENE_MAX_SKEW, WV_SCENE_MAX_SKEW);
  if (wv_scene_distorted(s)) {
    if (s->shape != WV_SHAPE_PLANE)
      return wv_fail(err, WV_ERR_INVALID, "'sample.distortion' applies to a plane, not a cylinder");
    if (!(s->distort_extent_mm > 1e-6 && s->distort_extent_mm < WV_SCENE_MAX_MM))
      return wv_fail(err, WV_ERR_INVALID, "'sample.distortion.extent_mm' = %s must be in (1e-06, %g)",
                     wv_num_str(s->distort_extent_mm, a), WV_SCENE_MAX_MM);
    if ((st = check_vec(s->distort[0], WV_DISTORT_TERMS, "sample.distortion.x", WV_SCENE_MAX_OFFSET_MM, err)) ||
        (st = check_vec(s->distort[1], WV_DISTORT_TERMS, "sample.distortion.y", WV_SCENE_MAX_OFFSET_MM, err)))
      return st;
  }
  if (!(s->mm_per_unit > 1e-6 && s->mm_per_unit < 1e6))
    return wv_fail(err, WV_ERR_INVALID, "'sample.mm_per_unit' = %s must be in (1e-06, 1000000)",
                   wv_num_str(s->mm_per_unit, a));
  if (!(s->light_intensity >= 0 && s->light_intensity <= 1e15))
    return wv_fail(err, WV_ERR_INVALID, "'light.intensity' = %s is outside 0..1e+15", wv_num_str(s->light_intensity, a));
  return wv_scene_check_response(s, err);
}

int wv_scene_transmits(const wv_scene *s) { return s->shape == WV_SHAPE_PLANE && s->light_pos[2] < 0; }

void wv_scene_downscale(const wv_scene *s, int scale, wv_scene *out) {
  *out = *s;
  if (scale <= 1) return;
  out->width = s->width / scale, out->height = s->height / scale;
  /* what is measured in pixels shrinks with them */
  out->falloff_sigma = s->falloff_sigma / scale;
  out->psf_sigma = s->psf_sigma / scale;
  out->glow_sigma = s->glow_sigma / scale;
}

int wv_scene_distorted(const wv_scene *s) {
  for (int k = 0; k < 2; k++)
    for (int t = 0; t < WV_DISTORT_TERMS; t++)
      if (s->distort[k][t] != 0) return 1;
  return 0;
}

void wv_scene_distortion_at(const wv_scene *s, double x, double y, double d[2]) {
  d[0] = d[1] = 0;
  if (s->shape != WV_SHAPE_PLANE || !wv_scene_distorted(s)) return;
  double t[WV_DISTORT_TERMS], k = s->mm_per_unit / s->distort_extent_mm;
  WV_DISTORT_EVAL(x * k, y * k, t);
  for (int i = 0; i < WV_DISTORT_TERMS; i++) d[0] += s->distort[0][i] * t[i], d[1] += s->distort[1][i] * t[i];
}

/* parse_root, then root freed; messages start with source. */
static wv_status from_root(json_t *root, const char *source, wv_scene *s, wv_error *err) {
  wv_status st = parse_root(root, s, err);
  json_decref(root);
  if (st) wv_error_prefix(err, "%s", source);
  return st;
}

wv_status wv_scene_parse(const char *text, const char *source, wv_scene *s, wv_error *err) {
  json_t *root;
  wv_status st = wv_json_parse_object(text, source, &root, err);
  return st ? st : from_root(root, source, s, err);
}

wv_status wv_scene_read(const char *path, wv_scene *s, wv_error *err) {
  json_t *root;
  wv_status st = wv_json_load_object(path, &root, err);
  return st ? st : from_root(root, path, s, err);
}

wv_status wv_scene_preset(const char *name, wv_scene *s, wv_error *err) {
  if (!strcmp(name, "cylinder")) return wv_scene_parse(PRESET_CYLINDER, "preset cylinder", s, err);
  if (!strcmp(name, "flat45")) return wv_scene_parse(PRESET_FLAT45, "preset flat45", s, err);
  if (!strcmp(name, "flat45-back")) return wv_scene_parse(PRESET_FLAT45_BACK, "preset flat45-back", s, err);
  return wv_fail(err, WV_ERR_INVALID, "unknown scene preset '%s' (expected cylinder, flat45 or flat45-back)", name);
}

wv_status wv_scene_load(const char *name_or_path, wv_scene *s, wv_error *err) {
  if (!strcmp(name_or_path, "cylinder") || !strcmp(name_or_path, "flat45") || !strcmp(name_or_path, "flat45-back"))
    return wv_scene_preset(name_or_path, s, err);
  return wv_scene_read(name_or_path, s, err);
}

char *wv_scene_to_json(const wv_scene *s) {
  static const char *enc[] = {"linear", "srgb", "gamma"};
  json_t *o = json_object();
  json_object_set_new(o, "name", json_string(s->name));
  json_object_set_new(o, "image", json_pack("{s:i,s:i,s:i}", "width", s->width, "height", s->height, "spp", s->spp));
  json_object_set_new(o, "camera", json_pack("{s:[f,f,f],s:[f,f,f],s:[f,f,f],s:f}", "position_mm", s->cam_pos[0],
                                             s->cam_pos[1], s->cam_pos[2], "look_at_mm", s->cam_look_at[0],
                                             s->cam_look_at[1], s->cam_look_at[2], "up", s->cam_up[0], s->cam_up[1],
                                             s->cam_up[2], "vfov_deg", s->vfov_deg));
  if (s->shape == WV_SHAPE_CYLINDER)
    json_object_set_new(o, "sample", json_pack("{s:s,s:f,s:s,s:[f,f],s:f}", "shape", "cylinder", "radius_mm",
                                               s->radius, "warp", s->warp_along_axis ? "along_axis" : "around_axis",
                                               "offset_mm", s->fabric_offset[0], s->fabric_offset[1], "mm_per_unit",
                                               s->mm_per_unit));
  else {
    json_object_set_new(o, "sample", json_pack("{s:s,s:f,s:[f,f],s:f}", "shape", "plane", "rotation_deg",
                                               s->rotation_deg, "offset_mm", s->fabric_offset[0],
                                               s->fabric_offset[1], "mm_per_unit", s->mm_per_unit));
    if (s->skew_deg != 0) /* written only when set: square cloth keeps its text */
      json_object_set_new(json_object_get(o, "sample"), "skew_deg", json_real(s->skew_deg));
    if (wv_scene_distorted(s)) {
      json_t *d = json_object(), *c[2] = {json_array(), json_array()};
      for (int k = 0; k < 2; k++)
        for (int t = 0; t < WV_DISTORT_TERMS; t++) json_array_append_new(c[k], json_real(s->distort[k][t]));
      json_object_set_new(d, "extent_mm", json_real(s->distort_extent_mm));
      json_object_set_new(d, "x", c[0]);
      json_object_set_new(d, "y", c[1]);
      json_object_set_new(json_object_get(o, "sample"), "distortion", d);
    }
  }
  json_object_set_new(o, "light", json_pack("{s:[f,f,f],s:f}", "position_mm", s->light_pos[0], s->light_pos[1],
                                            s->light_pos[2], "intensity", s->light_intensity));
  json_object_set_new(o, "response", json_pack("{s:f,s:f,s:s,s:f}", "exposure", s->exposure, "clip", s->clip,
                                               "encoding", enc[s->encoding], "gamma", s->gamma));
  if (s->psf_sigma > 0) /* written only when set: scenes without a blur keep their text */
    json_object_set_new(json_object_get(o, "response"), "psf_sigma_px", json_real(s->psf_sigma));
  if (s->glow_radiance > 0) /* likewise */
    json_object_set_new(json_object_get(o, "response"), "gap_glow",
                        json_pack("{s:f,s:f}", "radiance", s->glow_radiance, "sigma_px", s->glow_sigma));
  if (s->falloff)
    json_object_set_new(o, "falloff", json_pack("{s:s,s:f}", "type", "gaussian", "sigma_px", s->falloff_sigma));
  else
    json_object_set_new(o, "falloff", json_pack("{s:s}", "type", "none"));
  char *out = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
  json_decref(o);
  return out;
}
