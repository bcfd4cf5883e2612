/* Equirectangular environment maps: lookup, importance sampling by luminance
 * times sin(theta) (piecewise constant over pixels, so the pdf and the lookup
 * agree exactly), and the built-in environments generated in code. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/colour.h"
#include "woven/emitters.h"

#define PI_F 3.14159265358979f
#define PI 3.14159265358979323846

void wv_envmap_free(wv_envmap *e) {
  if (!e) return;
  free(e->rgb), free(e->cdf_row), free(e->cdf_col);
  memset(e, 0, sizeof *e);
}

size_t wv_envmap_bytes(int w, int h) {
  if (w < 0 || h < 0) return (size_t)-1;
  return ((size_t)w * h * 3 + (size_t)(h + 1) + (size_t)h * (w + 1)) * sizeof(float) + (size_t)(h + 1) * sizeof(double);
}

wv_status wv_envmap_init(wv_envmap *e, const wv_image *img, double strength, double rot_deg, const char *name,
                         wv_error *err) {
  memset(e, 0, sizeof *e);
  if (!img || img->c != 3 || img->w < 2 || img->h < 1)
    return wv_fail(err, WV_ERR_FORMAT, "%s: an environment map must be an RGB image of at least 2 x 1", name);
  if (!(strength >= 0 && isfinite(strength)) || !isfinite(rot_deg))
    return wv_fail(err, WV_ERR_INVALID, "%s: strength must be >= 0 and rotation finite", name);
  int w = img->w, h = img->h;
  e->w = w, e->h = h;
  e->rgb = malloc((size_t)w * h * 3 * sizeof(float));
  e->cdf_row = malloc((size_t)(h + 1) * sizeof(float));
  e->cdf_col = malloc((size_t)h * (w + 1) * sizeof(float));
  if (!e->rgb || !e->cdf_row || !e->cdf_col) {
    wv_envmap_free(e);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for the environment's tables", name);
  }
  for (size_t i = 0; i < (size_t)w * h * 3; i++) {
    float v = img->data[i];
    if (!isfinite(v) || v < 0) {
      wv_envmap_free(e);
      return wv_fail(err, WV_ERR_FORMAT, "%s: pixel %zu has a negative, NaN or infinite value", name, i / 3);
    }
    e->rgb[i] = (float)(v * strength);
    /* after the scaling: a finite value times the strength can overflow */
    if (!(e->rgb[i] <= WV_ENV_MAX_RADIANCE)) {
      wv_envmap_free(e);
      return wv_fail(err, WV_ERR_FORMAT, "%s: pixel %zu's radiance %g times the strength %g is above %g", name, i / 3,
                     (double)v, strength, WV_ENV_MAX_RADIANCE);
    }
  }
  double total = 0;
  e->cdf_row[0] = 0;
  double *row = malloc(sizeof(double) * (size_t)(h + 1));
  if (!row) {
    wv_envmap_free(e);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", name);
  }
  row[0] = 0;
  for (int y = 0; y < h; y++) {
    double s = sin(PI * (y + 0.5) / h), acc = 0;
    float *cdf = e->cdf_col + (size_t)y * (w + 1);
    cdf[0] = 0;
    for (int x = 0; x < w; x++) {
      const float *c = e->rgb + ((size_t)y * w + x) * 3;
      acc += wv_luminance_f(c[0], c[1], c[2]) * s;
      cdf[x + 1] = (float)acc;
    }
    for (int x = 1; x <= w; x++) cdf[x] = acc > 0 ? (float)(cdf[x] / acc) : (float)x / w;
    cdf[w] = 1.0f;
    total += acc;
    row[y + 1] = total;
  }
  for (int y = 0; y <= h; y++) e->cdf_row[y] = total > 0 ? (float)(row[y] / total) : (float)y / h;
  e->cdf_row[h] = 1.0f;
  free(row);
  e->total = total;
  double r = rot_deg * PI / 180.0;
  e->rot_c = (float)cos(r), e->rot_s = (float)sin(r);
  return WV_OK;
}

/* World direction -> pixel of the map (turned by -rotation about +y). */
static void to_pixel(const wv_envmap *e, const float d[3], int *x, int *y, float *sin_t) {
  float mx = e->rot_c * d[0] - e->rot_s * d[2], mz = e->rot_s * d[0] + e->rot_c * d[2];
  float cy = d[1] < -1.0f ? -1.0f : d[1] > 1.0f ? 1.0f : d[1];
  float theta = acosf(cy), phi = atan2f(mx, -mz);
  int ix = (int)((phi + PI_F) / (2 * PI_F) * e->w), iy = (int)(theta / PI_F * e->h);
  *x = ix < 0 ? 0 : ix >= e->w ? e->w - 1 : ix;
  *y = iy < 0 ? 0 : iy >= e->h ? e->h - 1 : iy;
  *sin_t = sqrtf(1.0f - cy * cy);
}

void wv_envmap_eval(const wv_envmap *e, const float d[3], float rgb[3]) {
  int x, y;
  float s;
  to_pixel(e, d, &x, &y, &s);
  const float *c = e->rgb + ((size_t)y * e->w + x) * 3;
  rgb[0] = c[0], rgb[1] = c[1], rgb[2] = c[2];
}

static float pixel_prob(const wv_envmap *e, int x, int y) {
  const float *row = e->cdf_col + (size_t)y * (e->w + 1);
  return (e->cdf_row[y + 1] - e->cdf_row[y]) * (row[x + 1] - row[x]);
}

float wv_envmap_pdf(const wv_envmap *e, const float d[3]) {
  if (!(e->total > 0)) return 0.0f;
  int x, y;
  float s;
  to_pixel(e, d, &x, &y, &s);
  if (s <= 0.0f) return 0.0f;
  return pixel_prob(e, x, y) * (float)e->w * (float)e->h / (2.0f * PI_F * PI_F * s);
}

/* Index i with cdf[i] <= u < cdf[i + 1] among n intervals (skipping empty ones). */
static int find(const float *cdf, int n, float u) {
  int lo = 0, hi = n;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (cdf[mid] <= u) lo = mid;
    else hi = mid;
  }
  return lo;
}

float wv_envmap_sample(const wv_envmap *e, float u1, float u2, float d[3], float rgb[3]) {
  if (!(e->total > 0)) {
    d[0] = 0, d[1] = 1, d[2] = 0, rgb[0] = rgb[1] = rgb[2] = 0;
    return 0.0f;
  }
  int y = find(e->cdf_row, e->h, u1);
  const float *row = e->cdf_col + (size_t)y * (e->w + 1);
  int x = find(row, e->w, u2);
  /* where inside the pixel: the leftover of each uniform number, rescaled */
  float fy = (u1 - e->cdf_row[y]) / (e->cdf_row[y + 1] - e->cdf_row[y]);
  float fx = (u2 - row[x]) / (row[x + 1] - row[x]);
  fy = fy < 0 ? 0 : fy > 0.999999f ? 0.999999f : fy;
  fx = fx < 0 ? 0 : fx > 0.999999f ? 0.999999f : fx;
  float theta = PI_F * (y + fy) / e->h, phi = 2 * PI_F * (x + fx) / e->w - PI_F;
  float st = sinf(theta), mx = st * sinf(phi), my = cosf(theta), mz = -st * cosf(phi);
  d[0] = e->rot_c * mx + e->rot_s * mz, d[1] = my, d[2] = -e->rot_s * mx + e->rot_c * mz;
  /* radiance and pdf where d looks up (not the drawn pixel): rounding at a pixel's
   * edge can move d to its neighbour, and the estimator must use the values of d */
  wv_envmap_eval(e, d, rgb);
  return wv_envmap_pdf(e, d);
}

/* ---- built-in environments ---- */

static double smoothstep(double a, double b, double x) {
  double t = (x - a) / (b - a);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return t * t * (3 - 2 * t);
}

/* A soft box: a rectangle of angular half-size (hw, hh) degrees around the
 * direction (azimuth az, elevation el), edges softened over 'soft' degrees. */
static double softbox(const double d[3], double az, double el, double hw, double hh, double soft) {
  double a = az * PI / 180, b = el * PI / 180;
  double c[3] = {cos(b) * sin(a), sin(b), -cos(b) * cos(a)};            /* the box's centre */
  double right[3] = {cos(a), 0, sin(a)};                                /* horizontal across it */
  double up[3] = {-sin(b) * sin(a), cos(b), sin(b) * cos(a)};            /* c x right, up the box */
  double dc = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
  if (dc <= 0) return 0;
  double x = atan2(d[0] * right[0] + d[1] * right[1] + d[2] * right[2], dc) * 180 / PI;
  double y = atan2(d[0] * up[0] + d[1] * up[1] + d[2] * up[2], dc) * 180 / PI;
  return (1 - smoothstep(hw - soft, hw, fabs(x))) * (1 - smoothstep(hh - soft, hh, fabs(y)));
}

static void studio(const double d[3], float out[3]) {
  /* a dim room (a soft vertical gradient, darker floor) lit by a large warm key box
   * in front-left, a cool fill in front-right, a rim box behind and a faint top light */
  double g = d[1] > 0 ? 0.04 + 0.05 * d[1] : 0.03 + 0.02 * (1 + d[1]);
  double key = softbox(d, -135, 30, 24, 18, 6), fill = softbox(d, 120, 15, 18, 12, 5);
  double rim = softbox(d, 15, 35, 12, 22, 4), top = softbox(d, 180, 75, 30, 30, 10);
  const double kc[3] = {7.0, 6.5, 5.8}, fc[3] = {1.2, 1.35, 1.6}, rc[3] = {4.0, 4.0, 4.0}, tc[3] = {0.6, 0.6, 0.6};
  for (int i = 0; i < 3; i++) out[i] = (float)(g + key * kc[i] + fill * fc[i] + rim * rc[i] + top * tc[i]);
}

static void sky(const double d[3], float out[3]) {
  const double sun_az = -30 * PI / 180, sun_el = 40 * PI / 180;
  double s[3] = {cos(sun_el) * sin(sun_az), sin(sun_el), -cos(sun_el) * cos(sun_az)};
  double cs = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
  double sun = smoothstep(cos(1.6 * PI / 180), cos(1.2 * PI / 180), cs); /* 1 inside 1.2 deg, 0 beyond 1.6 */
  double glow = pow(cs > 0 ? cs : 0, 64) * 0.8;
  if (d[1] >= 0) {
    double t = pow(1 - d[1], 4); /* 0 at the zenith, 1 at the horizon */
    const double zen[3] = {0.12, 0.25, 0.65}, hor[3] = {0.75, 0.82, 0.95};
    for (int i = 0; i < 3; i++) out[i] = (float)(zen[i] + (hor[i] - zen[i]) * t + glow + 2000 * sun);
  } else {
    double t = 1 - pow(1 + d[1], 8);
    const double gnd[3] = {0.09, 0.08, 0.06}, hor[3] = {0.30, 0.30, 0.30};
    for (int i = 0; i < 3; i++) out[i] = (float)(hor[i] + (gnd[i] - hor[i]) * t);
  }
}

int wv_env_is_builtin(const char *name) {
  return !strcmp(name, "studio") || !strcmp(name, "sky") || !strcmp(name, "white");
}

wv_status wv_env_builtin(const char *name, int width, wv_image *out, wv_error *err) {
  if (!wv_env_is_builtin(name))
    return wv_fail(err, WV_ERR_INVALID, "unknown built-in environment '%s' (expected studio, sky or white)", name);
  if (width < 16 || width > 8192)
    return wv_fail(err, WV_ERR_INVALID, "environment width %d is outside 16..8192", width);
  int h = width / 2;
  wv_status st = wv_image_alloc(out, width, h, 3, err);
  if (st) return st;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < width; x++) {
      float *px = wv_image_px(out, x, y);
      if (name[0] == 'w') {
        px[0] = px[1] = px[2] = 1.0f;
        continue;
      }
      /* at the pixel's centre: the soft edges span several pixels */
      double th = PI * (y + 0.5) / h, ph = 2 * PI * (x + 0.5) / width - PI;
      double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
      float acc[3];
      if (name[1] == 't') studio(d, acc);
      else sky(d, acc);
      px[0] = acc[0], px[1] = acc[1], px[2] = acc[2];
    }
  return WV_OK;
}
