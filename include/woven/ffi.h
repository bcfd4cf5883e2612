/* woven: a flat C interface for other languages (the Python package in python/ loads
 * it from libwoven.so through ctypes). Only plain C types cross it: strings, numbers
 * and caller-owned buffers; no struct layout has to be mirrored on the other side.
 *
 * Conventions of every function:
 * - The return value is a wv_status code (0 = success).
 * - err (may be NULL) receives woven's message on failure, NUL-terminated and cut to
 *   err_len bytes; on success it is set to "".
 * - "params" is a parameter file's JSON text (starting with '{') or the path of one;
 *   "scene" is JSON text, a preset name (cylinder, flat45) or a scene file's path.
 * - Images are row-major, top row first, RGB interleaved floats (3 per pixel); every
 *   output buffer comes with its length in floats, checked before anything is written.
 * - theta (may be NULL) overrides the continuous parameters: WV_FFI_PARAM_COUNT values
 *   in the order of wv_ffi_param_name (woven/params.h's wv_param_id), in the parameter
 *   file's units (angles in degrees). Values outside their range or not finite are
 *   refused with the parameter's name. */
#ifndef WOVEN_FFI_H
#define WOVEN_FFI_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define WV_FFI_VERSION 1 /* bumped when a signature below changes */
int wv_ffi_version(void);

/* ---- parameters ---- */
int wv_ffi_param_count(void);
const char *wv_ffi_param_name(int id); /* NULL outside 0..count-1 */
int wv_ffi_param_range(int id, double *lo, double *hi);
/* The parameters (with theta applied when not NULL) as woven writes them, validated. */
int wv_ffi_params_json(const char *params, const double *theta, char *out, size_t out_len, char *err,
                       size_t err_len);
/* A built-in pattern's prior mean, as JSON. */
int wv_ffi_params_default(const char *pattern, char *out, size_t out_len, char *err, size_t err_len);
/* The continuous parameters of params as a vector (theta: WV_FFI_PARAM_COUNT doubles). */
int wv_ffi_params_vector(const char *params, double *theta, char *err, size_t err_len);

/* ---- scenes ---- */
/* Image size, default spp and exposure of a capture scene (any pointer may be NULL). */
int wv_ffi_scene_info(const char *scene, int *width, int *height, int *spp, double *exposure, char *err,
                      size_t err_len);
/* What the scene's camera makes of a w x h radiance image: blur, exposure, clip,
 * encoding, falloff mask (woven/scene.h wv_scene_capture). The mask is centred on the
 * image, which must be the scene's size. */
int wv_ffi_scene_capture(const char *scene, const float *radiance, int w, int h, float *capture, size_t n,
                         char *err, size_t err_len);

/* ---- rendering (woven render) ----
 * seed < 0 keeps the parameters' noise seed; spp 0 = the scene's; threads 0 = all cores.
 * capture (may be NULL): the image the camera records (the float values the CLI's PNG
 * quantises). radiance (may be NULL): linear radiance times the scene's exposure (the
 * CLI's EXR). Each buffer holds width * height * 3 floats. */
int wv_ffi_render(const char *params, const double *theta, const char *scene, int spp, long long seed,
                  int threads, float *capture, float *radiance, size_t n, char *err, size_t err_len);

/* The differentiable render (woven/grad.h): renders the capture and keeps each pixel's
 * derivatives in a record; wv_ffi_record_grad then turns any adjoint dL/dcapture into
 * dL/dtheta. window (may be NULL): x0, y0, width, height of the part of the image to
 * render (all 0: the whole image). double_precision: shade in double (for gradient
 * checks). capture: width * height * 3 floats of the window, bitwise wv_ffi_render's
 * capture in float precision. *rec is freed with wv_ffi_record_free. */
typedef struct wv_ffi_record wv_ffi_record;
int wv_ffi_render_record(const char *params, const double *theta, const char *scene, int spp, long long seed,
                         int threads, int double_precision, const int *window, float *capture, size_t n,
                         wv_ffi_record **rec, char *err, size_t err_len);
/* grad: WV_FFI_PARAM_COUNT doubles, dL/dtheta for L = sum(dcapture * capture); dot
 * (may be NULL): that sum, accumulated in double (in double precision mode from the
 * unrounded capture). dcapture has the record's n floats and must be finite. */
int wv_ffi_record_grad(const wv_ffi_record *rec, const float *dcapture, size_t n, double *grad, double *dot,
                       char *err, size_t err_len);
void wv_ffi_record_free(wv_ffi_record *rec);

/* ---- texture maps (woven maps) ----
 * The nine maps of one weave repeat, size x size pixels each, RGB, in the order of
 * wv_ffi_map_name (normal, tangent, yarn_id, height, diffuse, specular, roughness,
 * transmission, open: woven/maps.h): out holds 9 * size * size * 3 floats. tile_mm: the
 * tile's width and height in mm. */
#define WV_FFI_MAP_COUNT 9
const char *wv_ffi_map_name(int i);
int wv_ffi_maps(const char *params, int size, float *out, size_t n, double *tile_mm, double *height_max,
                char *err, size_t err_len);
/* The maps written to a directory as `woven maps` writes them (format png, exr or both). */
int wv_ffi_maps_write(const char *params, int size, const char *dir, const char *format, char *err,
                      size_t err_len);

/* ---- images and metrics (woven compare) ---- */
int wv_ffi_image_size(const char *path, int *w, int *h, char *err, size_t err_len);
int wv_ffi_image_read(const char *path, float *out, size_t n, char *err, size_t err_len);
/* .png (8-bit, values clamped to [0,1]) or .exr (float), written atomically. */
int wv_ffi_image_write(const char *path, const float *data, int w, int h, char *err, size_t err_len);
/* out: SSIM (luma, or rgb != 0: the mean over R, G, B), WSC, whitened WSC (both NaN below
 * 32 x 32 pixels) and the mean absolute difference, of Gaussian blurs of sigma blur
 * pixels when blur > 0 (0..100). a and b are w x h RGB. */
int wv_ffi_compare(const float *a, const float *b, int w, int h, double blur, int rgb, double *out, char *err,
                   size_t err_len);

/* A built-in environment (studio, sky, white): width x width/2 RGB floats, equirectangular. */
int wv_ffi_env_builtin(const char *name, int width, float *out, size_t n, char *err, size_t err_len);

/* ---- capture (woven capture) ----
 * photo -> parameters: FabricNet's estimate, then the fit, every output written into dir
 * as `woven capture` writes it. options: JSON text (may be NULL or "{}") with any of
 * pattern, model, descriptor, weights, drape (strings), crop ([x, y, w, h]), iters,
 * iter_spp, iter_scale, seed, threads, align_radius, register_radius, distort_degree
 * (integers) and force (boolean), and for a photo pair transmission (the back-lit photo),
 * transmission_scene and pair_model (strings), meaning what the command's options mean.
 * summary (may be NULL): JSON text with the chosen pattern, SSIM of the estimate and the
 * fit, the iterations and the parameters; for a pair also ssim_rgb_fit_t,
 * ssim_rgb_blurred_photo_t and wsc_fit_t. */
int wv_ffi_capture(const char *photo, const char *scene, const char *dir, const char *options, char *summary,
                   size_t summary_len, char *err, size_t err_len);

#ifdef __cplusplus
}
#endif
#endif
