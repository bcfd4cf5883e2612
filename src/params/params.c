/* woven: fabric parameters: priors, ranges (SPEC section 5), validation, JSON. */
#include "woven/params.h"

#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/hash.h"
#include "io/json_file.h"
#include "util/json.h"
#include "woven/io.h"


/* Ranges of SPEC section 5. */
typedef struct {
  const char *key;
  double lo, hi;
} range;
static const range R_DENSITY = {"density", WV_DENSITY_MIN, WV_DENSITY_MAX};
static const range R_BETA = {"heightfield", 0, 2};
static const range R_KD = {"diffuse", 0, 1};
static const range R_KS = {"specular", 0, 1};
static const range R_KT = {"transmission", 0, 1};
static const range R_KST = {"transmission_specular", 0, 1};
static const range R_KF = {"transmission_forward", 0, 1};
static const range R_FWIDTH = {"forward_width", 0.05, 1};
static const range R_ALPHA = {"roughness", 0.01, 1};
static const range R_TWIST = {"twist_deg", -60, 60};
static const range R_UMAX = {"inclination_deg", 5, 70};
static const range R_BLEND = {"diffuse_blend", 0, 1};
static const range R_THICK = {"thickness", 0.01, 100};
static const range R_WIDTH = {"yarn_width", 0.1, 1};

wv_status wv_params_default(const char *pattern, wv_params *p, wv_error *err) {
  memset(p, 0, sizeof *p);
  if (!wv_weave_is_builtin(pattern))
    return wv_fail(err, WV_ERR_INVALID, "no prior for pattern '%s'", pattern);
  snprintf(p->pattern, sizeof p->pattern, "%s", pattern);
  int rot = strstr(pattern, "90") != NULL;
  int wa = rot ? WV_WEFT : WV_WARP, we = rot ? WV_WARP : WV_WEFT;
  const char *fam = wv_weave_family(pattern);
  /* A Z twill is the mirror image of its S twill, as is a 90-degree variant. */
  int mirror = rot ^ (!strcmp(fam, "twill") && strchr(wv_weave_canonical(pattern), 'z') != NULL);
  /* Centres of the dataset priors (SPEC section 5); basket takes plain's. */
  if (!strcmp(fam, "plain") || !strcmp(fam, "basket")) {
    p->density[wa] = p->density[we] = 100;
    p->heightfield[wa] = p->heightfield[we] = 1.1;
    p->roughness[wa] = p->roughness[we] = 0.25;
    p->inclination_deg = 22.5;
    p->twist_deg = 0;
  } else if (!strcmp(fam, "twill")) {
    p->density[wa] = 140, p->density[we] = 85;
    p->heightfield[wa] = p->heightfield[we] = 1.5;
    p->roughness[wa] = p->roughness[we] = 0.745;
    p->inclination_deg = 30;
    p->twist_deg = -30;
  } else {
    p->density[wa] = 185, p->density[we] = 100;
    p->heightfield[wa] = p->heightfield[we] = 0.6;
    p->roughness[wa] = 0.745, p->roughness[we] = 0.265;
    p->inclination_deg = 47.5;
    p->twist_deg = 0;
  }
  if (mirror) p->twist_deg = -p->twist_deg;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) {
      p->diffuse[y][c] = 0.5;
      p->specular[y][c] = 0.5;
    }
  wv_params_transmission_default(p);
  p->diffuse_blend = 0.5;
  p->noise_level = 2;
  p->thickness = 2.0;
  p->yarn_width = 1.0;
  p->seed = 1;
  p->specular_noise = 1;
  return WV_OK;
}

void wv_params_transmission_default(wv_params *p) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      p->transmission[y][c] = 0.5 * p->diffuse[y][c], p->transmission_specular[y][c] = p->specular[y][c],
      p->transmission_forward[y][c] = 0;
  p->forward_width = 0.2;
}

int wv_params_has_forward_band(const wv_params *p) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      if (p->transmission_forward[y][c] != 0) return 1;
  return 0;
}

static wv_status check(const range *r, const char *sub, double v, wv_error *err) {
  char a[32], b[32], c[32];
  if (!isfinite(v) || v < r->lo || v > r->hi)
    return wv_fail(err, WV_ERR_INVALID, "'%s%s%s' = %s is outside %s..%s", r->key, sub ? "." : "",
                   sub ? sub : "", wv_num_str(v, a), wv_num_str(r->lo, b), wv_num_str(r->hi, c));
  return WV_OK;
}

wv_status wv_params_weave(const wv_params *p, wv_weave *w, wv_error *err) {
  if (!strcmp(p->pattern, "custom")) {
    const char *rows[WV_WEAVE_MAX];
    for (int i = 0; i < p->custom_rows && i < WV_WEAVE_MAX; i++) rows[i] = p->custom[i];
    wv_status st = wv_weave_from_rows(rows, p->custom_rows, w, err);
    if (st) wv_error_prefix(err, "'weave'");
    return st;
  }
  return wv_weave_builtin(p->pattern, w, err);
}

wv_status wv_params_validate(const wv_params *p, wv_error *err) {
  static const char *yn[2] = {"warp", "weft"};
  wv_weave w;
  wv_status st = wv_params_weave(p, &w, err);
  if (st) return st;
  for (int y = 0; y < 2; y++) {
    if ((st = check(&R_DENSITY, yn[y], p->density[y], err))) return st;
    if ((st = check(&R_BETA, yn[y], p->heightfield[y], err))) return st;
    if ((st = check(&R_ALPHA, yn[y], p->roughness[y], err))) return st;
    for (int c = 0; c < 3; c++) {
      if ((st = check(&R_KD, yn[y], p->diffuse[y][c], err))) return st;
      if ((st = check(&R_KS, yn[y], p->specular[y][c], err))) return st;
      if ((st = check(&R_KT, yn[y], p->transmission[y][c], err))) return st;
      if ((st = check(&R_KST, yn[y], p->transmission_specular[y][c], err))) return st;
      if ((st = check(&R_KF, yn[y], p->transmission_forward[y][c], err))) return st;
    }
  }
  if ((st = check(&R_TWIST, NULL, p->twist_deg, err))) return st;
  if ((st = check(&R_UMAX, NULL, p->inclination_deg, err))) return st;
  if ((st = check(&R_BLEND, NULL, p->diffuse_blend, err))) return st;
  if ((st = check(&R_THICK, NULL, p->thickness, err))) return st;
  if ((st = check(&R_WIDTH, NULL, p->yarn_width, err))) return st;
  if ((st = check(&R_FWIDTH, NULL, p->forward_width, err))) return st;
  if (p->noise_level < 0 || p->noise_level > 10)
    return wv_fail(err, WV_ERR_INVALID, "'noise_level' = %d is outside 0..10", p->noise_level);
  return WV_OK;
}

/* ---- JSON reading: every key known, every value typed, messages name the key. ---- */

static const char *const YARNS[] = {"warp", "weft", NULL};

/* root[key] as {"warp": .., "weft": ..}, n numbers each (n = 3: an RGB array, or one
 * number for grey). Absent keys keep the defaults; the ranges are wv_params_validate's,
 * which also checks parameters made in code. */
static wv_status get_pair(json_t *root, const char *key, int n, double *warp, double *weft, wv_error *err) {
  double *out[2] = {warp, weft};
  json_t *o;
  wv_status st = wv_json_object(root, NULL, key, YARNS, 0, &o, err);
  for (int y = 0; y < 2 && !st; y++)
    st = n == 1 ? wv_json_number(o, key, YARNS[y], WV_JSON_FINITE, 0, out[y], err)
                : wv_json_numbers(o, key, YARNS[y], n, WV_JSON_FINITE, WV_JSON_ONE_FOR_ALL, out[y], err);
  return st;
}

static const char *const KNOWN_KEYS[] = {
    "version",   "pattern",      "weave",         "density",         "heightfield",     "diffuse",
    "specular",  "transmission", "transmission_specular", "transmission_forward", "forward_width", "roughness",
    "twist_deg", "inclination_deg",
    "diffuse_blend", "noise_level", "thickness",  "yarn_width",      "seed",            "specular_noise",
    "comment",   NULL};

static wv_status parse_root(json_t *root, wv_params *p, wv_error *err) {
  const char *name = NULL;
  int version = 1;
  wv_status st;
  if ((st = wv_json_only_keys(root, NULL, KNOWN_KEYS, err)) ||
      (st = wv_json_int(root, NULL, "version", 1, WV_PARAMS_VERSION, 0, &version, err)) ||
      (st = wv_json_string(root, NULL, "pattern", WV_JSON_REQUIRED, &name, err)))
    return st;
  if (!strcmp(name, "custom")) {
    wv_params_default("plain", p, err);
    snprintf(p->pattern, sizeof p->pattern, "custom");
    json_t *wv = json_object_get(root, "weave");
    if (!json_is_array(wv) || json_array_size(wv) < 1 || json_array_size(wv) > WV_WEAVE_MAX)
      return wv_fail(err, WV_ERR_INVALID, "'weave' must be an array of 1..%d strings of 0/1 for a custom pattern",
                     WV_WEAVE_MAX);
    p->custom_rows = (int)json_array_size(wv);
    for (int i = 0; i < p->custom_rows; i++) {
      json_t *row = json_array_get(wv, i);
      if (!json_is_string(row) || strlen(json_string_value(row)) > WV_WEAVE_MAX)
        return wv_fail(err, WV_ERR_INVALID, "'weave[%d]' must be a string of at most %d characters 0/1", i,
                       WV_WEAVE_MAX);
      snprintf(p->custom[i], sizeof p->custom[i], "%s", json_string_value(row));
    }
  } else {
    if (!wv_weave_is_builtin(name))
      return wv_fail(err, WV_ERR_INVALID,
                     "'pattern': unknown pattern '%s' (expected plain, twill, satin, twill90, satin90 or custom)", name);
    if (json_object_get(root, "weave"))
      return wv_fail(err, WV_ERR_INVALID, "'weave' is only allowed with \"pattern\": \"custom\"");
    wv_params_default(name, p, err);
  }
  long long seed = p->seed;
  if ((st = get_pair(root, "density", 1, &p->density[0], &p->density[1], err)) ||
      (st = get_pair(root, "heightfield", 1, &p->heightfield[0], &p->heightfield[1], err)) ||
      (st = get_pair(root, "roughness", 1, &p->roughness[0], &p->roughness[1], err)) ||
      (st = get_pair(root, "diffuse", 3, p->diffuse[0], p->diffuse[1], err)) ||
      (st = get_pair(root, "specular", 3, p->specular[0], p->specular[1], err)) ||
      (st = get_pair(root, "transmission", 3, p->transmission[0], p->transmission[1], err)) ||
      (st = get_pair(root, "transmission_specular", 3, p->transmission_specular[0], p->transmission_specular[1],
                     err)) ||
      (st = get_pair(root, "transmission_forward", 3, p->transmission_forward[0], p->transmission_forward[1],
                     err)) ||
      (st = wv_json_number(root, NULL, "forward_width", WV_JSON_FINITE, 0, &p->forward_width, err)) ||
      (st = wv_json_number(root, NULL, "twist_deg", WV_JSON_FINITE, 0, &p->twist_deg, err)) ||
      (st = wv_json_number(root, NULL, "inclination_deg", WV_JSON_FINITE, 0, &p->inclination_deg, err)) ||
      (st = wv_json_number(root, NULL, "diffuse_blend", WV_JSON_FINITE, 0, &p->diffuse_blend, err)) ||
      (st = wv_json_number(root, NULL, "thickness", WV_JSON_FINITE, 0, &p->thickness, err)) ||
      (st = wv_json_number(root, NULL, "yarn_width", WV_JSON_FINITE, 0, &p->yarn_width, err)) ||
      (st = wv_json_int(root, NULL, "noise_level", 0, 10, 0, &p->noise_level, err)) ||
      (st = wv_json_integer(root, NULL, "seed", LLONG_MIN, LLONG_MAX, 0, &seed, err)) ||
      (st = wv_json_bool(root, NULL, "specular_noise", 0, &p->specular_noise, err)))
    return st;
  p->seed = (int64_t)seed;
  /* a file without a key (every version 1 file; versions 1 and 2 for k_st; 1 to 3 for k_f and
   * its width): its default, from the albedos read above; a value the file gives is kept */
  int has_kt = json_object_get(root, "transmission") != NULL;
  int has_kst = json_object_get(root, "transmission_specular") != NULL;
  int has_kf = json_object_get(root, "transmission_forward") != NULL;
  int has_fw = json_object_get(root, "forward_width") != NULL;
  if (!has_kt || !has_kst || !has_kf || !has_fw) {
    wv_params given = *p;
    wv_params_transmission_default(p);
    if (has_kt) memcpy(p->transmission, given.transmission, sizeof p->transmission);
    if (has_kst) memcpy(p->transmission_specular, given.transmission_specular, sizeof p->transmission_specular);
    if (has_kf) memcpy(p->transmission_forward, given.transmission_forward, sizeof p->transmission_forward);
    if (has_fw) p->forward_width = given.forward_width;
  }
  return wv_params_validate(p, err);
}

/* parse_root, then root freed; messages start with source. */
static wv_status from_root(json_t *root, const char *source, wv_params *p, wv_error *err) {
  wv_status st = parse_root(root, p, err);
  json_decref(root);
  if (st) wv_error_prefix(err, "%s", source);
  return st;
}

wv_status wv_params_parse(const char *text, const char *source, wv_params *p, wv_error *err) {
  json_t *root;
  wv_status st = wv_json_parse_object(text, source, &root, err);
  return st ? st : from_root(root, source, p, err);
}

wv_status wv_params_read(const char *path, wv_params *p, wv_error *err) {
  json_t *root;
  wv_status st = wv_json_load_object(path, &root, err);
  return st ? st : from_root(root, path, p, err);
}

static json_t *rgb(const double v[3]) {
  return json_pack("[f,f,f]", v[0], v[1], v[2]);
}

char *wv_params_to_json(const wv_params *p) {
  json_t *o = json_object();
  json_object_set_new(o, "version", json_integer(WV_PARAMS_VERSION));
  json_object_set_new(o, "pattern", json_string(p->pattern));
  if (!strcmp(p->pattern, "custom")) {
    json_t *a = json_array();
    for (int i = 0; i < p->custom_rows; i++) json_array_append_new(a, json_string(p->custom[i]));
    json_object_set_new(o, "weave", a);
  }
  json_object_set_new(o, "density", json_pack("{s:f,s:f}", "warp", p->density[0], "weft", p->density[1]));
  json_object_set_new(o, "heightfield",
                      json_pack("{s:f,s:f}", "warp", p->heightfield[0], "weft", p->heightfield[1]));
  json_object_set_new(o, "diffuse", json_pack("{s:o,s:o}", "warp", rgb(p->diffuse[0]), "weft", rgb(p->diffuse[1])));
  json_object_set_new(o, "specular",
                      json_pack("{s:o,s:o}", "warp", rgb(p->specular[0]), "weft", rgb(p->specular[1])));
  json_object_set_new(o, "transmission",
                      json_pack("{s:o,s:o}", "warp", rgb(p->transmission[0]), "weft", rgb(p->transmission[1])));
  json_object_set_new(o, "transmission_specular", json_pack("{s:o,s:o}", "warp", rgb(p->transmission_specular[0]),
                                                            "weft", rgb(p->transmission_specular[1])));
  json_object_set_new(o, "transmission_forward", json_pack("{s:o,s:o}", "warp", rgb(p->transmission_forward[0]),
                                                           "weft", rgb(p->transmission_forward[1])));
  json_object_set_new(o, "forward_width", json_real(p->forward_width));
  json_object_set_new(o, "roughness", json_pack("{s:f,s:f}", "warp", p->roughness[0], "weft", p->roughness[1]));
  json_object_set_new(o, "twist_deg", json_real(p->twist_deg));
  json_object_set_new(o, "inclination_deg", json_real(p->inclination_deg));
  json_object_set_new(o, "diffuse_blend", json_real(p->diffuse_blend));
  json_object_set_new(o, "noise_level", json_integer(p->noise_level));
  json_object_set_new(o, "thickness", json_real(p->thickness));
  json_object_set_new(o, "yarn_width", json_real(p->yarn_width));
  json_object_set_new(o, "seed", json_integer(p->seed));
  json_object_set_new(o, "specular_noise", json_boolean(p->specular_noise));
  /* 17 significant digits: the file reads back to the same doubles. */
  char *s = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
  json_decref(o);
  return s;
}

wv_status wv_params_write(const char *path, const wv_params *p, wv_error *err) {
  wv_status st = wv_params_validate(p, err);
  if (st) return st;
  char *s = wv_params_to_json(p);
  if (!s) return wv_fail(err, WV_ERR_NOMEM, "%s: cannot format parameters", path);
  size_t n = strlen(s);
  char *t = realloc(s, n + 2);
  if (!t) {
    free(s);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  }
  t[n] = '\n', t[n + 1] = 0;
  st = wv_write_file_atomic(path, t, n + 1, err);
  free(t);
  return st;
}

static double *param_slot(wv_params *p, int id) {
  if (id <= WV_P_BETA_WEFT) return &p->heightfield[id - WV_P_BETA_WARP];
  if (id <= WV_P_KD_WEFT_B) return &p->diffuse[(id - WV_P_KD_WARP_R) / 3][(id - WV_P_KD_WARP_R) % 3];
  if (id <= WV_P_KS_WEFT_B) return &p->specular[(id - WV_P_KS_WARP_R) / 3][(id - WV_P_KS_WARP_R) % 3];
  if (id <= WV_P_ALPHA_WEFT) return &p->roughness[id - WV_P_ALPHA_WARP];
  if (id == WV_P_UMAX_DEG) return &p->inclination_deg;
  if (id == WV_P_BLEND) return &p->diffuse_blend;
  if (id == WV_P_TWIST_DEG) return &p->twist_deg;
  if (id <= WV_P_KT_WEFT_B) return &p->transmission[(id - WV_P_KT_WARP_R) / 3][(id - WV_P_KT_WARP_R) % 3];
  if (id <= WV_P_KST_WEFT_B)
    return &p->transmission_specular[(id - WV_P_KST_WARP_R) / 3][(id - WV_P_KST_WARP_R) % 3];
  return &p->transmission_forward[(id - WV_P_KF_WARP_R) / 3][(id - WV_P_KF_WARP_R) % 3];
}

double wv_param_get(const wv_params *p, int id) { return *param_slot((wv_params *)p, id); }
void wv_param_set(wv_params *p, int id, double v) { *param_slot(p, id) = v; }

void wv_param_range_width(double *lo, double *hi) {
  *lo = R_WIDTH.lo, *hi = R_WIDTH.hi;
}

void wv_param_range_forward_width(double *lo, double *hi) {
  *lo = R_FWIDTH.lo, *hi = R_FWIDTH.hi;
}

void wv_param_range(int id, double *lo, double *hi) {
  const range *r = id <= WV_P_BETA_WEFT ? &R_BETA
                   : id <= WV_P_KD_WEFT_B ? &R_KD
                   : id <= WV_P_KS_WEFT_B ? &R_KS
                   : id <= WV_P_ALPHA_WEFT ? &R_ALPHA
                   : id == WV_P_UMAX_DEG ? &R_UMAX
                   : id == WV_P_BLEND ? &R_BLEND
                   : id == WV_P_TWIST_DEG ? &R_TWIST
                   : id <= WV_P_KT_WEFT_B ? &R_KT
                   : id <= WV_P_KST_WEFT_B ? &R_KST
                                           : &R_KF;
  *lo = r->lo, *hi = r->hi;
}

const char *wv_param_name(int id) {
  static const char *names[WV_P_COUNT] = {
      "heightfield.warp", "heightfield.weft", "diffuse.warp[0]", "diffuse.warp[1]", "diffuse.warp[2]",
      "diffuse.weft[0]",  "diffuse.weft[1]",  "diffuse.weft[2]", "specular.warp[0]", "specular.warp[1]",
      "specular.warp[2]", "specular.weft[0]", "specular.weft[1]", "specular.weft[2]", "roughness.warp",
      "roughness.weft",   "inclination_deg",  "diffuse_blend",   "twist_deg",       "transmission.warp[0]",
      "transmission.warp[1]", "transmission.warp[2]", "transmission.weft[0]", "transmission.weft[1]",
      "transmission.weft[2]", "transmission_specular.warp[0]", "transmission_specular.warp[1]",
      "transmission_specular.warp[2]", "transmission_specular.weft[0]", "transmission_specular.weft[1]",
      "transmission_specular.weft[2]", "transmission_forward.warp[0]", "transmission_forward.warp[1]",
      "transmission_forward.warp[2]", "transmission_forward.weft[0]", "transmission_forward.weft[1]",
      "transmission_forward.weft[2]"};
  return id >= 0 && id < WV_P_COUNT ? names[id] : "?";
}

static double uni(uint64_t *st, double lo, double hi) {
  *st += 0x9e3779b97f4a7c15ULL;
  return lo + (hi - lo) * wv_u01d(wv_mix64(*st));
}

wv_status wv_params_sample_prior(const char *pattern, uint64_t seed, wv_params *p, wv_error *err) {
  wv_status st = wv_params_default(pattern, p, err);
  if (st) return st;
  uint64_t r = wv_mix64(seed ^ 0x7072696f72ULL);
  int rot = strstr(pattern, "90") != NULL;
  int wa = rot ? WV_WEFT : WV_WARP, we = rot ? WV_WARP : WV_WEFT; /* the base pattern's warp and weft */
  const char *fam = wv_weave_family(pattern);
  double dlo[2], dhi[2], blo, bhi, alo[2], ahi[2], ulo, uhi;
  if (!strcmp(fam, "plain") || !strcmp(fam, "basket")) {
    dlo[0] = dlo[1] = 60, dhi[0] = dhi[1] = 140, blo = 0.2, bhi = 2;
    alo[0] = alo[1] = 0.01, ahi[0] = ahi[1] = 0.49, ulo = 15, uhi = 30;
  } else if (!strcmp(fam, "twill")) {
    dlo[0] = 80, dhi[0] = 200, dlo[1] = 50, dhi[1] = 120, blo = 1, bhi = 2;
    alo[0] = alo[1] = 0.49, ahi[0] = ahi[1] = 1, ulo = 20, uhi = 40;
  } else {
    dlo[0] = 120, dhi[0] = 250, dlo[1] = 60, dhi[1] = 140, blo = 0.2, bhi = 1;
    alo[0] = 0.49, ahi[0] = 1, alo[1] = 0.04, ahi[1] = 0.49, ulo = 30, uhi = 65;
  }
  int role[2] = {wa, we};
  for (int k = 0; k < 2; k++) { /* k: the base pattern's warp (0) and weft (1) */
    int y = role[k];
    p->density[y] = floor(uni(&r, dlo[k], dhi[k]) + 0.5);
    p->heightfield[y] = uni(&r, blo, bhi);
    p->roughness[y] = uni(&r, alo[k], ahi[k]);
  }
  /* Diffuse: uniform per channel; 10% grey; the weft repeats the warp colour 30% of the time. */
  for (int y = 0; y < 2; y++) {
    int grey = uni(&r, 0, 1) < 0.1;
    for (int c = 0; c < 3; c++) p->diffuse[y][c] = uni(&r, 0, 1);
    if (grey) p->diffuse[y][1] = p->diffuse[y][2] = p->diffuse[y][0];
  }
  if (uni(&r, 0, 1) < 0.3)
    for (int c = 0; c < 3; c++) p->diffuse[WV_WEFT][c] = p->diffuse[WV_WARP][c];
  /* Specular: the diffuse colour raised to a random power in (0, 1): a whiter tint. */
  for (int y = 0; y < 2; y++) {
    double g = uni(&r, 0, 1);
    for (int c = 0; c < 3; c++) p->specular[y][c] = pow(p->diffuse[y][c], g);
  }
  p->inclination_deg = uni(&r, ulo, uhi);
  p->diffuse_blend = uni(&r, 0, 1);
  int q = (int)floor(uni(&r, 0, 6));
  p->noise_level = q > 5 ? 5 : q;
  p->seed = (int64_t)(wv_mix64(r + 1) >> 33);
  /* Transmission: the diffuse colour times a factor uniform in 0.1..0.9 per yarn type (mean
   * 1/2: the default), from a stream of its own so that every draw above is as before. */
  uint64_t rt = wv_mix64(seed ^ 0x7472616e73ULL);
  for (int y = 0; y < 2; y++) {
    double f = uni(&rt, 0.1, 0.9);
    for (int c = 0; c < 3; c++) p->transmission[y][c] = f * p->diffuse[y][c];
  }
  /* Specular transmission: the specular colour times a factor uniform in 0.1..1 per yarn type,
   * from a third stream (the draws above stay as they were). */
  uint64_t rs = wv_mix64(seed ^ 0x7370656374ULL);
  for (int y = 0; y < 2; y++) {
    double f = uni(&rs, 0.1, 1.0);
    for (int c = 0; c < 3; c++) p->transmission_specular[y][c] = f * p->specular[y][c];
  }
  /* The forward band: k_f the transmission colour times a factor uniform in 0..1 per yarn type,
   * its width log-uniform in 0.1..0.8, from a fourth stream. */
  uint64_t rf = wv_mix64(seed ^ 0x666f7277ULL);
  for (int y = 0; y < 2; y++) {
    double f = uni(&rf, 0.0, 1.0);
    for (int c = 0; c < 3; c++) p->transmission_forward[y][c] = f * p->transmission[y][c];
  }
  p->forward_width = 0.1 * pow(8.0, uni(&rf, 0, 1));
  return wv_params_validate(p, err);
}
