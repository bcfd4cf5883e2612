/* The flat C interface of woven/ffi.h: strings, numbers and caller-owned buffers in,
 * statuses and messages out, over the public API only (the Python package's way in). */
#include "woven/ffi.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/capture.h"
#include "woven/emitters.h"
#include "woven/error.h"
#include "woven/grad.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/metrics.h"
#include "woven/nn.h"
#include "woven/params.h"
#include "woven/render.h"
#include "woven/scene.h"

struct wv_ffi_record {
  wv_grad_record *rec;
  int w, h; /* of the capture it was made with */
  size_t n;
};

/* The message out to the caller's buffer; returns the status. */
static int finish(wv_status st, const wv_error *e, char *err, size_t err_len) {
  if (err && err_len) {
    const char *msg = st ? (e->msg[0] ? e->msg : "failed") : "";
    snprintf(err, err_len, "%s", msg);
  }
  return (int)st;
}

static int is_json_text(const char *s) {
  while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
  return *s == '{';
}

/* params as JSON text or a path, then theta over its continuous parameters. */
static wv_status load_params(const char *params, const double *theta, wv_params *p, wv_error *e) {
  if (!params) return wv_fail(e, WV_ERR_INVALID, "no parameters given");
  wv_status st = is_json_text(params) ? wv_params_parse(params, "parameters", p, e) : wv_params_read(params, p, e);
  if (st || !theta) return st;
  for (int i = 0; i < WV_P_COUNT; i++) {
    double lo, hi;
    wv_param_range(i, &lo, &hi);
    if (!isfinite(theta[i])) return wv_fail(e, WV_ERR_INVALID, "parameter '%s' is not finite", wv_param_name(i));
    if (theta[i] < lo || theta[i] > hi)
      return wv_fail(e, WV_ERR_INVALID, "parameter '%s' = %.17g is outside %g..%g", wv_param_name(i), theta[i], lo,
                     hi);
    wv_param_set(p, i, theta[i]);
  }
  return wv_params_validate(p, e);
}

static wv_status load_scene(const char *scene, wv_scene *s, wv_error *e) {
  if (!scene) return wv_fail(e, WV_ERR_INVALID, "no scene given");
  return is_json_text(scene) ? wv_scene_parse(scene, "scene", s, e) : wv_scene_load(scene, s, e);
}

static wv_status check_len(size_t n, size_t want, const char *what, wv_error *e) {
  if (n != want) return wv_fail(e, WV_ERR_INVALID, "%s: buffer of %zu floats, expected %zu", what, n, want);
  return WV_OK;
}

static wv_status copy_json(char *json, char *out, size_t out_len, wv_error *e) {
  if (!json) return wv_fail(e, WV_ERR_NOMEM, "out of memory");
  size_t len = strlen(json);
  wv_status st = WV_OK;
  if (!out || len + 1 > out_len)
    st = wv_fail(e, WV_ERR_INVALID, "output buffer of %zu bytes, %zu needed", out_len, len + 1);
  else
    memcpy(out, json, len + 1);
  free(json);
  return st;
}

int wv_ffi_version(void) { return WV_FFI_VERSION; }
int wv_ffi_param_count(void) { return WV_P_COUNT; }
const char *wv_ffi_param_name(int id) { return id >= 0 && id < WV_P_COUNT ? wv_param_name(id) : NULL; }

int wv_ffi_param_range(int id, double *lo, double *hi) {
  if (id < 0 || id >= WV_P_COUNT || !lo || !hi) return WV_ERR_INVALID;
  wv_param_range(id, lo, hi);
  return WV_OK;
}

int wv_ffi_params_json(const char *params, const double *theta, char *out, size_t out_len, char *err,
                       size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_status st = load_params(params, theta, &p, &e);
  if (!st) st = copy_json(wv_params_to_json(&p), out, out_len, &e);
  return finish(st, &e, err, err_len);
}

int wv_ffi_params_default(const char *pattern, char *out, size_t out_len, char *err, size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_status st = pattern ? wv_params_default(pattern, &p, &e) : wv_fail(&e, WV_ERR_INVALID, "no pattern given");
  if (!st) st = copy_json(wv_params_to_json(&p), out, out_len, &e);
  return finish(st, &e, err, err_len);
}

int wv_ffi_params_vector(const char *params, double *theta, char *err, size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_status st = theta ? load_params(params, NULL, &p, &e) : wv_fail(&e, WV_ERR_INVALID, "no output vector");
  if (!st)
    for (int i = 0; i < WV_P_COUNT; i++) theta[i] = wv_param_get(&p, i);
  return finish(st, &e, err, err_len);
}

int wv_ffi_scene_info(const char *scene, int *width, int *height, int *spp, double *exposure, char *err,
                      size_t err_len) {
  wv_error e = {0};
  wv_scene s;
  wv_status st = load_scene(scene, &s, &e);
  if (!st) {
    if (width) *width = s.width;
    if (height) *height = s.height;
    if (spp) *spp = s.spp;
    if (exposure) *exposure = s.exposure;
  }
  return finish(st, &e, err, err_len);
}

int wv_ffi_scene_capture(const char *scene, const float *radiance, int w, int h, float *capture, size_t n,
                         char *err, size_t err_len) {
  wv_error e = {0};
  wv_scene s;
  wv_status st = load_scene(scene, &s, &e);
  if (!st && (!radiance || !capture)) st = wv_fail(&e, WV_ERR_INVALID, "no image given");
  if (!st && (w != s.width || h != s.height))
    st = wv_fail(&e, WV_ERR_INVALID, "image of %d x %d, the scene's is %d x %d", w, h, s.width, s.height);
  if (!st) st = check_len(n, (size_t)w * h * 3, "capture", &e);
  wv_image rad = {0}, cap = {0};
  if (!st) st = wv_image_alloc(&rad, w, h, 3, &e);
  if (!st) st = wv_image_alloc(&cap, w, h, 3, &e);
  if (!st) {
    memcpy(rad.data, radiance, n * sizeof(float));
    st = wv_scene_capture(&s, &rad, &cap, &e);
  }
  if (!st) memcpy(capture, cap.data, n * sizeof(float));
  wv_image_free(&rad);
  wv_image_free(&cap);
  return finish(st, &e, err, err_len);
}

/* Parameters and scene of a render, with the seed applied. */
static wv_status setup(const char *params, const double *theta, const char *scene, int spp, long long seed,
                       int threads, wv_params *p, wv_scene *s, wv_error *e) {
  wv_status st = load_params(params, theta, p, e);
  if (!st) st = load_scene(scene, s, e);
  if (st) return st;
  if (spp < 0 || spp > WV_SCENE_MAX_SPP) return wv_fail(e, WV_ERR_INVALID, "spp %d is outside 0..%d", spp, WV_SCENE_MAX_SPP);
  if (threads < 0 || threads > 1024) return wv_fail(e, WV_ERR_INVALID, "threads %d is outside 0..1024", threads);
  if (seed > INT64_MAX / 2) return wv_fail(e, WV_ERR_INVALID, "seed %lld is too large", seed);
  if (seed >= 0) p->seed = seed;
  return WV_OK;
}

int wv_ffi_render(const char *params, const double *theta, const char *scene, int spp, long long seed,
                  int threads, float *capture, float *radiance, size_t n, char *err, size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_scene s;
  wv_status st = setup(params, theta, scene, spp, seed, threads, &p, &s, &e);
  if (!st) st = check_len(n, (size_t)s.width * s.height * 3, "render", &e);
  if (st) return finish(st, &e, err, err_len);
  wv_render_opts opt = {.spp = spp, .threads = threads};
  wv_image cap = {0}, rad = {0};
  st = wv_render(&s, &p, &opt, &cap, radiance ? &rad : NULL, &e);
  if (!st) {
    if (capture) memcpy(capture, cap.data, n * sizeof(float));
    /* as the CLI's EXR: the scene's exposure, no clip, encoding or mask */
    if (radiance)
      for (size_t i = 0; i < n; i++) radiance[i] = rad.data[i] * (float)s.exposure;
  }
  wv_image_free(&cap);
  wv_image_free(&rad);
  return finish(st, &e, err, err_len);
}

int wv_ffi_render_record(const char *params, const double *theta, const char *scene, int spp, long long seed,
                         int threads, int double_precision, const int *window, float *capture, size_t n,
                         wv_ffi_record **rec, char *err, size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_scene s;
  if (rec) *rec = NULL;
  wv_status st = rec ? setup(params, theta, scene, spp, seed, threads, &p, &s, &e)
                     : wv_fail(&e, WV_ERR_INVALID, "no record pointer");
  if (st) return finish(st, &e, err, err_len);
  wv_grad_opts g = {0, 0, 0, 0, double_precision != 0};
  if (window) g.x0 = window[0], g.y0 = window[1], g.width = window[2], g.height = window[3];
  int whole = !g.width && !g.height, w = whole ? s.width : g.width, h = whole ? s.height : g.height;
  /* the library checks that the window lies inside the image */
  if (w < 1 || h < 1) st = wv_fail(&e, WV_ERR_INVALID, "window of %d x %d pixels", w, h);
  if (!st) st = check_len(n, (size_t)w * h * 3, "render", &e);
  if (st) return finish(st, &e, err, err_len);
  wv_render_opts opt = {.spp = spp, .threads = threads};
  wv_image cap = {0};
  wv_ffi_record *r = calloc(1, sizeof *r);
  if (!r) return finish(wv_fail(&e, WV_ERR_NOMEM, "out of memory"), &e, err, err_len);
  st = wv_render_record(&s, &p, &opt, &g, &cap, &r->rec, &e);
  if (!st && capture) memcpy(capture, cap.data, n * sizeof(float));
  wv_image_free(&cap);
  if (st) {
    free(r);
    return finish(st, &e, err, err_len);
  }
  r->w = w, r->h = h, r->n = n;
  *rec = r;
  return finish(st, &e, err, err_len);
}

int wv_ffi_record_grad(const wv_ffi_record *rec, const float *dcapture, size_t n, double *grad, double *dot,
                       char *err, size_t err_len) {
  wv_error e = {0};
  wv_status st = WV_OK;
  if (!rec || !rec->rec || !dcapture || !grad) st = wv_fail(&e, WV_ERR_INVALID, "record, adjoint and gradient are required");
  if (!st) st = check_len(n, rec->n, "dL/dcapture", &e);
  for (size_t i = 0; !st && i < n; i++)
    if (!isfinite(dcapture[i])) st = wv_fail(&e, WV_ERR_INVALID, "dL/dcapture is not finite at value %zu", i);
  if (st) return finish(st, &e, err, err_len);
  /* the image only borrows the caller's floats */
  wv_image d = {rec->w, rec->h, 3, (float *)dcapture};
  st = wv_record_grad(rec->rec, &d, grad, dot, &e);
  return finish(st, &e, err, err_len);
}

void wv_ffi_record_free(wv_ffi_record *rec) {
  if (!rec) return;
  wv_record_free(rec->rec);
  free(rec);
}

static const char *const MAP_NAMES[WV_FFI_MAP_COUNT] = {"normal",   "tangent",   "yarn_id",      "height", "diffuse",
                                                        "specular", "roughness", "transmission", "open"};
const char *wv_ffi_map_name(int i) { return i >= 0 && i < WV_FFI_MAP_COUNT ? MAP_NAMES[i] : NULL; }

int wv_ffi_maps(const char *params, int size, float *out, size_t n, double *tile_mm, double *height_max,
                char *err, size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_status st = load_params(params, NULL, &p, &e);
  if (!st && (size < 1 || size > 8192)) st = wv_fail(&e, WV_ERR_INVALID, "map size %d is outside 1..8192", size);
  size_t one = (size_t)size * size * 3;
  if (!st) st = check_len(n, one * WV_FFI_MAP_COUNT, "maps", &e);
  if (!st && !out) st = wv_fail(&e, WV_ERR_INVALID, "no output buffer");
  if (st) return finish(st, &e, err, err_len);
  wv_maps m;
  if ((st = wv_maps_generate(&p, size, &m, &e))) return finish(st, &e, err, err_len);
  const wv_image *all[WV_FFI_MAP_COUNT] = {&m.normal,   &m.tangent,   &m.yarn_id,      &m.height, &m.diffuse,
                                           &m.specular, &m.roughness, &m.transmission, &m.open};
  for (int k = 0; k < WV_FFI_MAP_COUNT; k++) {
    const wv_image *im = all[k];
    float *dst = out + one * k;
    for (size_t i = 0; i < (size_t)size * size; i++)
      for (int c = 0; c < 3; c++) dst[i * 3 + c] = im->data[i * im->c + (im->c == 1 ? 0 : c)];
  }
  if (tile_mm) tile_mm[0] = m.tile_mm[0], tile_mm[1] = m.tile_mm[1];
  if (height_max) *height_max = m.height_max;
  wv_maps_free(&m);
  return finish(st, &e, err, err_len);
}

int wv_ffi_maps_write(const char *params, int size, const char *dir, const char *format, char *err,
                      size_t err_len) {
  wv_error e = {0};
  wv_params p;
  wv_status st = load_params(params, NULL, &p, &e);
  if (!st && (size < 1 || size > 8192)) st = wv_fail(&e, WV_ERR_INVALID, "map size %d is outside 1..8192", size);
  if (!st && (!dir || !format)) st = wv_fail(&e, WV_ERR_INVALID, "a directory and a format are required");
  if (st) return finish(st, &e, err, err_len);
  wv_maps m;
  if ((st = wv_maps_generate(&p, size, &m, &e))) return finish(st, &e, err, err_len);
  st = wv_maps_write(&m, dir, format, &e);
  wv_maps_free(&m);
  return finish(st, &e, err, err_len);
}

int wv_ffi_image_size(const char *path, int *w, int *h, char *err, size_t err_len) {
  wv_error e = {0};
  wv_image im = {0};
  wv_status st = path ? wv_image_read(path, &im, NULL, &e) : wv_fail(&e, WV_ERR_INVALID, "no path given");
  if (!st) {
    if (w) *w = im.w;
    if (h) *h = im.h;
  }
  wv_image_free(&im);
  return finish(st, &e, err, err_len);
}

int wv_ffi_image_read(const char *path, float *out, size_t n, char *err, size_t err_len) {
  wv_error e = {0};
  wv_image im = {0};
  wv_status st = path ? wv_image_read(path, &im, NULL, &e) : wv_fail(&e, WV_ERR_INVALID, "no path given");
  if (!st) st = check_len(n, (size_t)im.w * im.h * 3, path, &e);
  if (!st && out) memcpy(out, im.data, n * sizeof(float));
  wv_image_free(&im);
  return finish(st, &e, err, err_len);
}

int wv_ffi_image_write(const char *path, const float *data, int w, int h, char *err, size_t err_len) {
  wv_error e = {0};
  wv_image im = {0};
  wv_status st = path && data ? WV_OK : wv_fail(&e, WV_ERR_INVALID, "a path and an image are required");
  if (!st) st = wv_image_alloc(&im, w, h, 3, &e);
  if (!st) {
    memcpy(im.data, data, (size_t)w * h * 3 * sizeof(float));
    st = wv_image_write(path, &im, &e);
  }
  wv_image_free(&im);
  return finish(st, &e, err, err_len);
}

int wv_ffi_compare(const float *a, const float *b, int w, int h, double blur, int rgb, double *out, char *err,
                   size_t err_len) {
  wv_error e = {0};
  wv_image im[2] = {{0}, {0}};
  wv_status st = a && b && out ? WV_OK : wv_fail(&e, WV_ERR_INVALID, "two images and an output are required");
  if (!st && !(blur >= 0 && blur <= 100)) st = wv_fail(&e, WV_ERR_INVALID, "blur %g is outside 0..100", blur);
  for (int i = 0; i < 2 && !st; i++)
    if (!(st = wv_image_alloc(&im[i], w, h, 3, &e))) memcpy(im[i].data, i ? b : a, (size_t)w * h * 3 * sizeof(float));
  for (int i = 0; i < 2 && blur > 0 && !st; i++) {
    wv_image bl;
    if (!(st = wv_image_blur(&im[i], blur, &bl, &e))) {
      wv_image_free(&im[i]);
      im[i] = bl;
    }
  }
  double ssim = 0, mae = 0, wsc = NAN, wscw = NAN;
  if (!st) st = wv_ssim(&im[0], &im[1], rgb ? WV_SSIM_RGB : WV_SSIM_LUMA, &ssim, &e);
  if (!st) st = wv_mae(&im[0], &im[1], &mae, &e);
  if (!st && w >= 32 && h >= 32) st = wv_wsc(&im[0], &im[1], &wsc, &e);
  if (!st && w >= 32 && h >= 32) st = wv_wsc_whitened(&im[0], &im[1], &wscw, &e);
  if (!st) out[0] = ssim, out[1] = wsc, out[2] = wscw, out[3] = mae;
  wv_image_free(&im[0]);
  wv_image_free(&im[1]);
  return finish(st, &e, err, err_len);
}

int wv_ffi_env_builtin(const char *name, int width, float *out, size_t n, char *err, size_t err_len) {
  wv_error e = {0};
  wv_image im = {0};
  wv_status st = name && out ? wv_env_builtin(name, width, &im, &e)
                             : wv_fail(&e, WV_ERR_INVALID, "a name and an output are required");
  if (!st) st = check_len(n, (size_t)im.w * im.h * 3, "environment", &e);
  if (!st)
    for (size_t i = 0; i < (size_t)im.w * im.h; i++)
      for (int c = 0; c < 3; c++) out[i * 3 + c] = im.data[i * im.c + (im.c == 1 ? 0 : c)];
  wv_image_free(&im);
  return finish(st, &e, err, err_len);
}

/* ---- capture ---- */

static wv_status opt_int(json_t *o, const char *key, int lo, int hi, int *out, int *given, wv_error *e) {
  json_t *v = json_object_get(o, key);
  if (!v) return WV_OK;
  if (!json_is_integer(v) || json_integer_value(v) < lo || json_integer_value(v) > hi)
    return wv_fail(e, WV_ERR_INVALID, "capture option '%s' must be an integer in %d..%d", key, lo, hi);
  *out = (int)json_integer_value(v);
  if (given) *given = 1;
  return WV_OK;
}

static wv_status opt_str(json_t *o, const char *key, const char **out, wv_error *e) {
  json_t *v = json_object_get(o, key);
  if (!v || json_is_null(v)) return WV_OK;
  if (!json_is_string(v)) return wv_fail(e, WV_ERR_INVALID, "capture option '%s' must be a string", key);
  *out = json_string_value(v);
  return WV_OK;
}

static const char *const CAPTURE_KEYS[] = {"pattern", "model", "descriptor", "weights", "drape", "crop", "iters",
                                           "iter_spp", "iter_scale", "seed", "threads", "align_radius",
                                           "register_radius", "distort_degree", "force", "transmission",
                                           "transmission_scene", "pair_model", NULL};

static wv_status capture_opts(json_t *o, wv_capture_opts *co, wv_error *e) {
  const char *key;
  json_t *v;
  json_object_foreach(o, key, v) {
    int known = 0;
    for (int i = 0; CAPTURE_KEYS[i]; i++) known |= !strcmp(key, CAPTURE_KEYS[i]);
    if (!known) return wv_fail(e, WV_ERR_INVALID, "unknown capture option '%s'", key);
  }
  wv_status st = WV_OK;
  int seed = -1, dummy = 0;
  if (!st) st = opt_str(o, "pattern", &co->estimate.pattern, e);
  if (!st) st = opt_str(o, "model", &co->estimate.model, e);
  if (!st) st = opt_str(o, "descriptor", &co->estimate.descriptor, e);
  if (!st) st = opt_str(o, "weights", &co->estimate.weights, e);
  if (!st) st = opt_str(o, "drape", &co->drape, e);
  if (!st) st = opt_str(o, "transmission", &co->photo_t, e);
  if (!st) st = opt_str(o, "transmission_scene", &co->scene_t, e);
  if (!st) st = opt_str(o, "pair_model", &co->pair_model, e);
  if (!st && !co->photo_t && (co->scene_t || co->pair_model))
    st = wv_fail(e, WV_ERR_INVALID, "capture options 'transmission_scene' and 'pair_model' need 'transmission'");
  if (!st) st = opt_int(o, "iters", 0, WV_FIT_MAX_ITERS, &co->fit.iters, &co->iters_given, e);
  if (!st) st = opt_int(o, "iter_spp", 1, WV_SCENE_MAX_SPP, &co->fit.iter_spp, NULL, e);
  if (!st) st = opt_int(o, "iter_scale", 1, WV_FIT_MAX_ITER_SCALE, &co->fit.iter_scale, NULL, e);
  if (!st) st = opt_int(o, "seed", 0, INT32_MAX, &seed, NULL, e);
  if (!st) st = opt_int(o, "threads", 0, 1024, &co->fit.threads, NULL, e);
  if (!st) st = opt_int(o, "align_radius", 0, WV_FIT_MAX_ALIGN_RADIUS, &co->fit.align_radius, &co->align_given, e);
  if (!st) st = opt_int(o, "register_radius", 0, WV_FIT_MAX_REGISTER_RADIUS, &co->fit.register_radius, &dummy, e);
  if (!st) st = opt_int(o, "distort_degree", 0, 3, &co->fit.distort_degree, &dummy, e);
  if (!st && seed >= 0) co->fit.seed = (uint64_t)seed;
  json_t *force = json_object_get(o, "force");
  if (!st && force) {
    if (!json_is_boolean(force)) return wv_fail(e, WV_ERR_INVALID, "capture option 'force' must be true or false");
    co->force = co->estimate.any_scene = json_is_true(force);
  }
  json_t *crop = json_object_get(o, "crop");
  if (!st && crop) {
    int c[4];
    if (!json_is_array(crop) || json_array_size(crop) != 4)
      return wv_fail(e, WV_ERR_INVALID, "capture option 'crop' must be [x, y, w, h]");
    for (int i = 0; i < 4; i++) {
      json_t *x = json_array_get(crop, (size_t)i);
      if (!json_is_integer(x) || json_integer_value(x) < 0 || json_integer_value(x) > WV_IMAGE_READ_MAX_SIDE)
        return wv_fail(e, WV_ERR_INVALID, "capture option 'crop' must hold non-negative integers");
      c[i] = (int)json_integer_value(x);
    }
    co->estimate.crop = (wv_crop){c[0], c[1], c[2], c[3]};
  }
  return st;
}

int wv_ffi_capture(const char *photo, const char *scene, const char *dir, const char *options, char *summary,
                   size_t summary_len, char *err, size_t err_len) {
  wv_error e = {0};
  if (!photo || !scene || !dir)
    return finish(wv_fail(&e, WV_ERR_INVALID, "a photo, a scene and a directory are required"), &e, err, err_len);
  json_error_t je;
  json_t *o = options && options[0] ? json_loads(options, 0, &je) : json_object();
  if (!o || !json_is_object(o)) {
    json_decref(o);
    return finish(wv_fail(&e, WV_ERR_INVALID, "capture options are not a JSON object"), &e, err, err_len);
  }
  wv_capture_opts co;
  memset(&co, 0, sizeof co);
  wv_fit_opts_default(&co.fit);
  co.estimate.photo = photo, co.estimate.scene = scene, co.estimate.descriptor = "default";
  co.dir = dir;
  wv_status st = capture_opts(o, &co, &e);
  if (!st) st = wv_fit_opts_validate(&co.fit, &e);
  wv_estimate est;
  wv_fit_outcome out;
  if (!st) st = wv_capture_run(&co, &est, &out, &e);
  json_decref(o);
  if (st) return finish(st, &e, err, err_len);
  char *pj = wv_params_to_json(&out.state.params);
  json_t *params = pj ? json_loads(pj, 0, &je) : NULL;
  free(pj);
  json_t *s = json_pack("{s:s,s:s,s:b,s:f,s:f,s:i,s:o}", "dir", dir, "pattern", out.state.params.pattern,
                        "pattern_chosen", est.chosen, "ssim_network", out.ssim_start, "ssim_fit", out.ssim_fit,
                        "iterations", out.state.iter, "params", params ? params : json_null());
  if (s) { /* how the re-render stands against the photo (woven capture --json's names) */
    const wv_weave_views *v = &out.views;
    json_object_set_new(s, "ssim_rgb_fit", json_real(v->ssim_rgb[1]));
    if (v->ssim_rgb_blurred > -2) {
      json_object_set_new(s, "ssim_rgb_blurred_photo", json_real(v->ssim_rgb_blurred));
      json_object_set_new(s, "below_blurred_copy", json_boolean(v->below_blurred_copy));
    }
    if (v->wsc[1] > -2) json_object_set_new(s, "wsc_fit", json_real(v->wsc[1]));
    if (v->periodic_share > -2) json_object_set_new(s, "photo_periodic_share", json_real(v->periodic_share));
    json_object_set_new(s, "blas_core", json_string(wv_nn_blas_core()));
  }
  if (s && out.pair) { /* the transmission photo against its re-render */
    json_object_set_new(s, "ssim_rgb_fit_t", json_real(out.ssim_rgb_t));
    json_object_set_new(s, "ssim_rgb_blurred_photo_t", json_real(out.ssim_rgb_blurred_t));
    json_object_set_new(s, "below_blurred_copy_t", json_boolean(out.below_blurred_copy_t));
    if (out.periodic_share_t > -2) json_object_set_new(s, "photo_periodic_share_t", json_real(out.periodic_share_t));
    json_object_set_new(s, "wsc_fit_t", json_real(out.wsc_t));
  }
  wv_fit_state_free(&out.state);
  wv_estimate_free(&est);
  if (summary && summary_len) {
    char *text = s ? json_dumps(s, JSON_COMPACT) : NULL;
    st = copy_json(text, summary, summary_len, &e);
  }
  json_decref(s);
  return finish(st, &e, err, err_len);
}
