/* The sensor side of a capture scene: the camera rig (pinhole camera, the
 * sample's shape, the point light) with its ray tracing in scalar and 8-wide
 * form (sensor/trace_impl.h), each pixel's footprint on the fabric, and the
 * sensor response with its adjoint (sensor/response_impl.h), written once for
 * float and double. Internal to the library. */
#ifndef WOVEN_SENSOR_H
#define WOVEN_SENSOR_H

#include <math.h>

#include "kernel/kernel.h"
#include "shape/shape.h"
#include "util/colour.h"
#include "woven/scene.h"

/* The scene's geometry prepared for tracing. */
typedef struct {
  int width, height;
  float cpos[3], fwd[3], right[3], up[3];
  float tan_half, aspect;
  wv_shape shape;
  float lpos[3], lint;
  int transmit;       /* the light is behind the sample (wv_scene_transmits): light through the cloth */
  float glow, glow_sigma; /* the gap glow (wv_scene.glow_radiance, glow_sigma; 0: none) */
  const struct wv_footprint_s *cache; /* per-pixel footprints made once (wv_footprints) or NULL */
} wv_camera_rig;

void wv_rig_prepare(const wv_scene *s, wv_camera_rig *rig);

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "sensor/trace_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_8
#include "kernel/lane_begin.h"
#include "sensor/trace_impl.h"
#include "kernel/lane_end.h"

/* A pixel's footprint on the fabric. A pixel spans ~1e-3 rad seen from the
 * light and the camera, so light and view directions are taken at the pixel
 * centre while the fabric position (what changes across yarns) is per sample:
 * bilinear in the four corners, used when all four and the centre hit the
 * sample (exact for the plane up to perspective, and within 1e-6 of a pixel on
 * the cylinder away from its silhouette). Other pixels trace every sample. */
typedef struct wv_footprint_s {
  int fast;           /* 1: use corners and dirs; 0: trace every sample */
  float fx[4], fy[4]; /* corners (0,0), (1,0), (0,1), (1,1) */
  wv_dirs_f dirs;
} wv_footprint;

void wv_footprint_prepare(const wv_camera_rig *rig, int px, int py, wv_footprint *fp);

/* ---- sensor response ---- */
/* The response's powers: in float and double, one value by the vector functions of
 * util/vmath.h, so that a value's response is the same alone and in a row
 * (wv_respond_n). */
float wv_power_f(float x, float e);
double wv_power_d(double x, double e);
/* The power of a linear value in d encode / d linear (0: the slope is constant). */
double wv_slope_exponent(const wv_scene *s);
/* d encode / d linear in double of a linear value x under encoding enc (gamma: the
 * scene's), given p = x^wv_slope_exponent (0 for x <= 0, where encode is clamped to 0). */
static inline double wv_encode_slope_pow(wv_encoding enc, double gamma, double x, double p) {
  if (x <= 0.0) return 0.0;
  switch (enc) {
    case WV_ENC_SRGB: return wv_srgb_encode_slope_pow(x, p);
    case WV_ENC_GAMMA: return p / gamma;
    default: return 1.0;
  }
}
/* d encode / d linear in double (0 for linear <= 0, where encode is clamped to 0). */
double wv_encode_slope(const wv_scene *s, double linear);
/* exp(-d^2 / sigma^2), d the distance in pixels of pixel (x, y)'s centre from the centre
 * of a w x h image: the form of the falloff mask and of the gap glow. */
double wv_pixel_gaussian(int w, int h, int x, int y, double sigma);
/* The camera blur (wv_psf_apply) streamed by rows: K, its transpose or its derivative by
 * sigma applied to an image that load delivers row by row (row y's w * c values) and
 * store takes back row by row, bands of rows on parallel threads, with no image-sized
 * buffer. store may be called from several threads at once, once for each row. The
 * values are wv_psf_apply's and wv_psf_apply_dsigma's, bit for bit. sigma <= 0: K is
 * the identity and dK zero. */
typedef enum { WV_PSF_K, WV_PSF_KT, WV_PSF_DK } wv_psf_op;
typedef struct {
  wv_psf_op op;
  double sigma;
  int w, h, c;
  int threads; /* 0: OpenMP's default */
  void (*load)(void *ctx, int y, double *row);
  void (*store)(void *ctx, int y, const double *row);
  void *ctx;
} wv_psf_stream;
wv_status wv_psf_run(const wv_psf_stream *ps, wv_error *err);
/* The falloff mask at pixel (x, y) of the scene's full image (1 without falloff). */
double wv_response_mask(const wv_scene *s, int x, int y);
/* The gap glow's radiance at pixel (x, y) of the rig's full image per unit of open area
 * (the fraction of the pixel's samples whose line of sight crosses an open gap); 0
 * without a glow or with the light in front. */
float wv_gap_glow(const wv_camera_rig *rig, int x, int y);

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "sensor/response_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_D
#include "kernel/lane_begin.h"
#include "sensor/response_impl.h"
#include "kernel/lane_end.h"

/* The response of n pixels of c channels each (interleaved): cap[i] = wv_respond_f of
 * rad[i] with the mask of its pixel (mask[k], or 1 with mask NULL) and, with slope,
 * slope[i] its slope; the powers taken many at once. */
void wv_respond_n(const wv_scene *s, const double *mask, int n, int c, const float *rad, float *cap, double *slope);
/* The falloff masks of n pixels of row y from column x0 (wv_response_mask). */
void wv_response_mask_row(const wv_scene *s, int x0, int y, int n, double *mask);

#endif
