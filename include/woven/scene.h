/* woven: capture scenes (SPEC section 6): the sample's shape, a pinhole camera,
 * a point light, the image size and sampling, and the sensor response
 * (clipping, colour encoding, falloff mask). Read from JSON; see scenes/. */
#ifndef WOVEN_SCENE_H
#define WOVEN_SCENE_H

#include "woven/error.h"
#include "woven/image.h"

typedef enum { WV_SHAPE_CYLINDER = 0, WV_SHAPE_PLANE = 1 } wv_shape_type;
typedef enum { WV_ENC_LINEAR = 0, WV_ENC_SRGB = 1, WV_ENC_GAMMA = 2 } wv_encoding;

#define WV_DISTORT_TERMS 9 /* cubic, without the constant (sample.offset_mm) */

typedef struct {
  char name[64];
  int width, height, spp;
  /* Camera: pinhole at position looking at look_at; vfov is the full vertical angle. */
  double cam_pos[3], cam_look_at[3], cam_up[3], vfov_deg;
  /* Sample: a cylinder of radius around the world x axis, or the plane z = 0. */
  wv_shape_type shape;
  double radius;        /* cylinder, mm */
  int warp_along_axis;  /* cylinder: 1 = warp along the axis (default), 0 = around it */
  double rotation_deg;  /* plane: angle of the fabric x axis from world x */
  double skew_deg;      /* plane: cloth out of square: the warp yarns turn by rotation - skew / 2,
                         * the weft yarns by rotation + skew / 2 (WV_SCENE_MAX_SKEW) */
  double fabric_offset[2]; /* shift of the pattern on the sample, mm */
  /* plane: cloth not laid straight, a smooth displacement of the fabric coordinates (mm)
   * added to the offset: distort[k][t] times term t of (a, b) = (x, y) * mm_per_unit /
   * distort_extent_mm, (x, y) the point on the plane; terms a, b, a^2, ab, b^2, a^3, a^2 b,
   * a b^2, b^3 (WV_DISTORT_TERMS); k = 0 fabric x, 1 fabric y. All 0: none. */
  double distort_extent_mm;
  double distort[2][WV_DISTORT_TERMS];
  double mm_per_unit;      /* fabric millimetres per scene unit (1 when the scene is in mm) */
  /* Point light. */
  double light_pos[3], light_intensity;
  /* Sensor response, applied in this order: exposure, clip, encode, falloff mask. */
  double exposure;
  double clip;          /* <= 0: no clipping */
  wv_encoding encoding;
  double gamma;         /* for WV_ENC_GAMMA: encoded = linear^(1/gamma) */
  int falloff;          /* 1 = Gaussian mask exp(-d^2/sigma^2), d in pixels from the centre */
  double falloff_sigma;
  double psf_sigma;     /* camera blur: Gaussian point-spread function of this sigma in pixels on
                         * the radiance, before exposure (0: none; docs/scenes.md) */
  /* The light seen straight through the gaps between yarns, out of focus (a light behind a
   * plane sample): wherever a sample's line of sight crosses an open gap it adds a radiance of
   * glow_radiance * exp(-d^2 / glow_sigma^2), d in pixels from the image centre (the falloff
   * mask's form). 0: none. */
  double glow_radiance, glow_sigma;
} wv_scene;

/* Limits on what a scene may request (memory and time guards). */
#define WV_SCENE_MAX_SIDE 16384
#define WV_SCENE_MAX_SPP 4096
#define WV_SCENE_MAX_SAMPLES (1LL << 34)
#define WV_SCENE_MAX_MM 1e6        /* |coordinate| of the camera, look-at, up and light: 1 km */
#define WV_SCENE_MAX_SKEW 15.0 /* |sample.skew_deg|, degrees */
#define WV_SCENE_MAX_OFFSET_MM 1e4 /* |sample.offset_mm|: any offset is equivalent to one within a weave repeat */
#define WV_SCENE_MAX_GLOW 1e6      /* response.gap_glow.radiance */

wv_status wv_scene_parse(const char *json, const char *source, wv_scene *s, wv_error *err);
wv_status wv_scene_read(const char *path, wv_scene *s, wv_error *err);
wv_status wv_scene_validate(const wv_scene *s, wv_error *err);
/* The presets, built in (identical to scenes/cylinder.json, scenes/flat45.json and
 * scenes/flat45-back.json). */
wv_status wv_scene_preset(const char *name, wv_scene *s, wv_error *err);
/* "cylinder" / "flat45" / "flat45-back" name a preset; anything else is read as a file. */
wv_status wv_scene_load(const char *name_or_path, wv_scene *s, wv_error *err);
char *wv_scene_to_json(const wv_scene *s);
/* The displacement (mm) of s's distortion at plane point (x, y) (scene units); 0 without one. */
void wv_scene_distortion_at(const wv_scene *s, double x, double y, double d[2]);
/* The distortion's terms at (a, b) (see wv_scene.distort), for any arithmetic type (the
 * renderer's 8-wide lanes too). */
#define WV_DISTORT_EVAL(a, b, t)                                                    \
  ((t)[0] = (a), (t)[1] = (b), (t)[2] = (a) * (a), (t)[3] = (a) * (b), (t)[4] = (b) * (b), \
   (t)[5] = (t)[2] * (a), (t)[6] = (t)[2] * (b), (t)[7] = (t)[3] * (b), (t)[8] = (t)[4] * (b))
/* 1 when s has a distortion (a nonzero term). */
int wv_scene_distorted(const wv_scene *s);
/* 1 when the scene renders light through the cloth: a plane sample with the light behind
 * it (light z < 0, the camera in front). The light is then on the far side of every point,
 * and the fabric transmits (docs/model.md); otherwise it reflects. */
int wv_scene_transmits(const wv_scene *s);
/* s seen by the same camera on an image scale times smaller (width / scale x height / scale,
 * rounded down): what the scene measures in pixels (the falloff, the camera blur, the gap
 * glow) divided by scale. scale <= 1: a copy. */
void wv_scene_downscale(const wv_scene *s, int scale, wv_scene *out);

/* Sensor response: capture = mask * encode(clip(exposure * radiance)). In place allowed.
 * (Its adjoint is applied inside the gradient renderer, woven/grad.h.) The camera blur is
 * not part of it: wv_scene_capture applies both. */
void wv_scene_response(const wv_scene *s, const wv_image *radiance, wv_image *capture);
/* What the camera makes of the radiance reaching it: the blur (wv_psf_apply with
 * s->psf_sigma), then wv_scene_response. capture must be allocated like radiance. */
wv_status wv_scene_capture(const wv_scene *s, const wv_image *radiance, wv_image *capture, wv_error *err);
#define WV_PSF_MAX_SIGMA 8.0 /* pixels */
/* The camera blur: a separable Gaussian of sigma pixels (truncated at 3 sigma, weights
 * summing to 1, edges clamped), on w x h images of c interleaved channels; adjoint != 0
 * applies its transpose (for the gradient). in and out must differ. sigma <= 0 copies. */
wv_status wv_psf_apply(double sigma, int w, int h, int c, const double *in, double *out, int adjoint,
                       wv_error *err);
/* Its derivative by sigma applied to in: out = (dK/dsigma) in (0 at sigma <= 0). */
wv_status wv_psf_apply_dsigma(double sigma, int w, int h, int c, const double *in, double *out, wv_error *err);
/* Encoding of one value and its inverse (used to decode photos). */
float wv_encode(const wv_scene *s, float linear);
float wv_decode(const wv_scene *s, float encoded);

#endif
