/* What a capture hands back to a person: side-by-side and zoomed images, the loss plot,
 * the parameters left on a bound, and the self-contained HTML report. */
#include "woven/report.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/analysis.h"
#include "util/base64.h"
#include "woven/io.h"
#include "woven/metrics.h"
#include "woven/nn.h"

wv_status wv_image_hconcat(const wv_image *const *imgs, int n, int gap, wv_image *out, wv_error *err) {
  int w = 0, h = imgs[0]->h;
  for (int i = 0; i < n; i++) {
    if (imgs[i]->h != h || imgs[i]->c != 3)
      return wv_fail(err, WV_ERR_INVALID, "side-by-side images must share their height");
    w += imgs[i]->w + (i ? gap : 0);
  }
  wv_status st = wv_image_alloc(out, w, h, 3, err);
  if (st) return st;
  for (size_t k = 0; k < (size_t)w * h * 3; k++) out->data[k] = 1.0f;
  int x0 = 0;
  for (int i = 0; i < n; i++) {
    for (int y = 0; y < h; y++)
      memcpy(wv_image_px(out, x0, y), wv_image_px(imgs[i], 0, y), sizeof(float) * 3 * (size_t)imgs[i]->w);
    x0 += imgs[i]->w + gap;
  }
  return WV_OK;
}

wv_status wv_image_centre_zoom(const wv_image *img, int side, int factor, wv_image *out, wv_error *err) {
  if (side > img->w) side = img->w;
  if (side > img->h) side = img->h;
  if (side < 1 || factor < 1) return wv_fail(err, WV_ERR_INVALID, "zoom: empty crop");
  wv_status st = wv_image_alloc(out, side * factor, side * factor, 3, err);
  if (st) return st;
  int x0 = (img->w - side) / 2, y0 = (img->h - side) / 2;
  for (int y = 0; y < out->h; y++)
    for (int x = 0; x < out->w; x++) {
      const float *s = wv_image_px(img, x0 + x / factor, y0 + y / factor);
      float *d = wv_image_px(out, x, y);
      for (int c = 0; c < 3; c++) d[c] = s[img->c >= 3 ? c : 0];
    }
  return WV_OK;
}

wv_status wv_blurred_copy_ssim(const wv_image *photo, double sigma, double *ssim, wv_error *err) {
  wv_image blurred = {0};
  wv_status st = wv_image_blur(photo, sigma, &blurred, err);
  if (!st) st = wv_ssim(photo, &blurred, WV_SSIM_RGB, ssim, err);
  wv_image_free(&blurred);
  return st;
}

wv_status wv_weave_views_write(const char *dir, const wv_image *photo, const wv_image *start, const wv_image *fit,
                               wv_weave_views *v, wv_error *err) {
  const wv_image *img[3] = {photo, start, fit};
  v->wsc[0] = v->wsc[1] = v->wsc_whitened[0] = v->wsc_whitened[1] = v->ssim_rgb_blurred = -2;
  v->below_blurred_copy = 0;
  v->periodic_share = -2;
  v->zoom_png[0] = v->spectra_png[0] = 0;
  v->zoom_factor = WV_WEAVE_ZOOM;
  wv_status st = WV_OK;
  for (int i = 0; i < 2 && !st; i++) st = wv_ssim(photo, img[i + 1], WV_SSIM_RGB, &v->ssim_rgb[i], err);
  if (!st) st = wv_blurred_copy_ssim(photo, WV_BLURRED_COPY_SIGMA, &v->ssim_rgb_blurred, err);
  if (!st) v->below_blurred_copy = v->ssim_rgb[1] < v->ssim_rgb_blurred;
  if (!st && wv_detail_periodic(photo, WV_BLURRED_COPY_SIGMA, &v->periodic_share, NULL, NULL))
    v->periodic_share = -2;
  int n = photo->w < photo->h ? photo->w : photo->h;
  n = n > WV_WSC_SIZE ? WV_WSC_SIZE : n - n % 2;
  if (!st && n >= 32) {
    float *sp = malloc(sizeof(float) * (size_t)n * n * 3);
    if (!sp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave spectra");
    const float *spec[3] = {sp, sp + (size_t)n * n, sp + (size_t)n * n * 2};
    for (int i = 0; i < 3 && !st; i++)
      st = wv_weave_spectrum(img[i], (photo->w - n) / 2, (photo->h - n) / 2, n, (float *)spec[i], err);
    wv_image pic = {0};
    if (!st) {
      v->wsc[0] = wv_wsc_spectra(spec[0], spec[1], n), v->wsc[1] = wv_wsc_spectra(spec[0], spec[2], n);
      st = wv_spectrum_picture(spec, 3, n, 1, &pic, err);
    }
    /* whitened in place once the picture of the plain spectra is made */
    for (int i = 0; i < 3 && !st; i++) st = wv_spectrum_whiten(spec[i], n, WV_WSC_Z_FLOOR, WV_WSC_Z_CAP, (float *)spec[i], err);
    if (!st)
      v->wsc_whitened[0] = wv_wsc_spectra(spec[0], spec[1], n),
      v->wsc_whitened[1] = wv_wsc_spectra(spec[0], spec[2], n);
    snprintf(v->spectra_png, sizeof v->spectra_png, "%s/spectra.png", dir);
    if (!st) st = wv_image_write_png(v->spectra_png, &pic, 8, err);
    wv_image_free(&pic);
    free(sp);
  }
  /* the centre crop a person can see the yarns in: a quarter of the image, at most 96 pixels */
  v->zoom_side = (photo->w < photo->h ? photo->w : photo->h) / 4;
  if (v->zoom_side > 96) v->zoom_side = 96;
  if (!st && v->zoom_side >= 8) {
    wv_image z[3] = {{0}, {0}, {0}}, row = {0};
    for (int i = 0; i < 3 && !st; i++) st = wv_image_centre_zoom(img[i], v->zoom_side, v->zoom_factor, &z[i], err);
    const wv_image *zs[3] = {&z[0], &z[1], &z[2]};
    if (!st) st = wv_image_hconcat(zs, 3, 4, &row, err);
    snprintf(v->zoom_png, sizeof v->zoom_png, "%s/zoom.png", dir);
    if (!st) st = wv_image_write_png(v->zoom_png, &row, 8, err);
    for (int i = 0; i < 3; i++) wv_image_free(&z[i]);
    wv_image_free(&row);
  }
  if (st) v->zoom_png[0] = v->spectra_png[0] = 0;
  return st;
}

int wv_params_at_bounds(const wv_params *p, char (*lines)[96], int cap) {
  int n = 0, band = wv_params_has_forward_band(p);
  for (int i = 0; i < WV_P_COUNT && n < cap; i++) {
    if (i >= WV_P_KF_WARP_R && !band) break; /* no forward band: k_f is 0 by choice, not held there */
    double lo, hi, v = wv_param_get(p, i);
    wv_param_range(i, &lo, &hi);
    double tol = 1e-6 * (hi - lo);
    if (v <= lo + tol || v >= hi - tol)
      snprintf(lines[n++], 96, "%s = %g (%s bound)", wv_param_name(i), v, v <= lo + tol ? "lower" : "upper");
  }
  for (int y = 0; y < 2 && n < cap; y++)
    if (p->density[y] <= WV_DENSITY_MIN || p->density[y] >= WV_DENSITY_MAX)
      snprintf(lines[n++], 96, "density.%s = %g (%s bound)", y ? "weft" : "warp", p->density[y],
               p->density[y] <= WV_DENSITY_MIN ? "lower" : "upper");
  if (n < cap && (p->noise_level <= 0 || p->noise_level >= 10))
    snprintf(lines[n++], 96, "noise_level = %d (%s bound)", p->noise_level, p->noise_level <= 0 ? "lower" : "upper");
  return n;
}

/* A growing string. */
typedef struct {
  char *s;
  size_t len, cap;
  int failed;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_printf(sbuf *b, const char *fmt, ...) {
  if (b->failed) return;
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (n < 0) {
    b->failed = 1;
    return;
  }
  if (b->len + (size_t)n + 1 > b->cap) {
    size_t cap = (b->cap + (size_t)n + 1) * 2;
    char *s = realloc(b->s, cap);
    if (!s) {
      b->failed = 1;
      return;
    }
    b->s = s, b->cap = cap;
  }
  va_start(ap, fmt);
  vsnprintf(b->s + b->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  b->len += (size_t)n;
}

char *wv_loss_svg(const wv_fit_record *log, int n, const wv_fit_opts *o) {
  const int W = 640, H = 300, L = 60, R = 150, T = 20, B = 40;
  sbuf b = {0};
  sb_printf(&b, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
                "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
            W, H, W, H);
  double lo = INFINITY, hi = -INFINITY;
  for (int i = 0; i < n; i++) {
    double v[4] = {log[i].loss, log[i].gram, o->w_pixel * log[i].pixel, o->w_prior * log[i].prior};
    for (int k = 0; k < 4; k++)
      if (v[k] > 0) lo = fmin(lo, v[k]), hi = fmax(hi, v[k]);
  }
  if (n == 0 || !(lo < hi)) lo = 1e-6, hi = 1;
  double llo = floor(log10(lo)), lhi = ceil(log10(hi));
  if (lhi <= llo) lhi = llo + 1;
  double pw = W - L - R, ph = H - T - B;
  sb_printf(&b, "<rect x=\"%d\" y=\"%d\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"#888\"/>\n", L, T, pw, ph);
  for (double e = llo; e <= lhi; e += 1) {
    double y = T + ph * (1 - (e - llo) / (lhi - llo));
    sb_printf(&b, "<line x1=\"%d\" x2=\"%g\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">1e%d</text>\n",
              L, L + pw, y, y, L - 5, y + 4, (int)e);
  }
  sb_printf(&b, "<text x=\"%g\" y=\"%d\" text-anchor=\"middle\">iteration (0..%d)</text>\n", L + pw / 2, H - 10,
            n > 0 ? n - 1 : 0);
  static const char *names[4] = {"total", "Gram L_g", "pixel w2 L_c", "prior w1 L_p"};
  static const char *colours[4] = {"#000", "#1f77b4", "#d62728", "#2ca02c"};
  for (int k = 0; k < 4; k++) {
    sb_printf(&b, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"", colours[k]);
    for (int i = 0; i < n; i++) {
      double v[4] = {log[i].loss, log[i].gram, o->w_pixel * log[i].pixel, o->w_prior * log[i].prior};
      if (!(v[k] > 0)) continue;
      double x = L + pw * (n > 1 ? (double)i / (n - 1) : 0.5);
      double y = T + ph * (1 - (log10(v[k]) - llo) / (lhi - llo));
      sb_printf(&b, "%.1f,%.1f ", x, y);
    }
    sb_printf(&b, "\"/>\n<line x1=\"%g\" x2=\"%g\" y1=\"%d\" y2=\"%d\" stroke=\"%s\" stroke-width=\"2\"/>"
                  "<text x=\"%g\" y=\"%d\">%s</text>\n",
              L + pw + 10, L + pw + 30, T + 15 + 18 * k, T + 15 + 18 * k, colours[k], L + pw + 35, T + 19 + 18 * k,
              names[k]);
  }
  for (int i = 0; i < n; i++)
    if (log[i].t_alone) { /* a pair: from here the losses are the back-lit photo's */
      double x = L + pw * (n > 1 ? (double)i / (n - 1) : 0.5);
      sb_printf(&b, "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%d\" y2=\"%g\" stroke=\"#888\" stroke-dasharray=\"4 3\"/>"
                    "<text x=\"%.1f\" y=\"%d\" font-size=\"10\">back-lit photo: its colours</text>\n",
                x, x, T, T + ph, x + 3, T + 12);
      break;
    }
  sb_printf(&b, "</svg>\n");
  if (b.failed) {
    free(b.s);
    return NULL;
  }
  return b.s;
}

static void sb_base64_file(sbuf *b, const char *path, wv_status *st, wv_error *err) {
  char *data;
  size_t len;
  if ((*st = wv_read_file(path, &data, &len, err))) return;
  char *text = wv_base64(data, len);
  free(data);
  if (!text) {
    b->failed = 1;
    return;
  }
  sb_printf(b, "%s", text);
  free(text);
}

/* How sure the pattern choice was: each family's candidate and score, the best first, and
 * how far each runner-up is behind the first. */
static void family_table(sbuf *b, const wv_pattern_choice *pc) {
  wv_pattern_families fs;
  wv_pattern_family_scores(pc, &fs);
  if (!strcmp(fs.kind, "none")) return;
  const char *what = !strcmp(fs.kind, "lattice+ranking") ? "the family's score, the best mean of lattice score and "
                                                           "ranking score of its built-ins"
                     : !strcmp(fs.kind, "probability") ? "the network's probability of the family's most probable "
                                                         "built-in"
                                                       : "the smallest fit loss of the family's built-ins";
  sb_printf(b, "<p>How the families stood (%s; %s is better), the runner-ups with how far they are behind:</p>\n"
               "<table class=\"families\"><tr><th>family</th><th>candidate</th><th>score</th><th>behind</th></tr>\n",
            what, fs.higher_is_better ? "higher" : "lower");
  int top = fs.order[0];
  const char *chosen = wv_weave_family(wv_weave_builtin_name(pc->best));
  for (int k = 0; k < WV_PATTERN_FAMILIES; k++) {
    int f = fs.order[k];
    if (fs.pattern[f] < 0) continue;
    sb_printf(b, strcmp(fs.family[f], chosen) ? "<tr><td>%s</td><td>%s</td><td>%.4f</td><td>%.4f</td></tr>\n"
                   : "<tr><td><b>%s</b></td><td><b>%s</b></td><td>%.4f</td><td>%.4f</td></tr>\n",
              fs.family[f], wv_weave_builtin_name(fs.pattern[f]), fs.score[f], fabs(fs.score[top] - fs.score[f]));
  }
  sb_printf(b, "</table>\n");
}

/* The warning box of an unsure re-render, and the mark on a baseline the fit scores below. */
#define UNSURE_BOX "<p class=\"unsure\" style=\"background:#fde8e8;border:2px solid #c00;padding:0.6em\"><b>Warning: "
#define BELOW_MARK " <b style=\"color:#c00\">(the fit scores below it)</b>"

wv_status wv_report_write_html(const char *path, const wv_report *r, wv_error *err) {
  sbuf b = {0};
  wv_status st = WV_OK;
  sb_printf(&b, "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>%s</title>\n<style>"
                "body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
                "img{max-width:100%%;image-rendering:pixelated;border:1px solid #ccc}"
                "table{border-collapse:collapse}td,th{padding:2px 10px;border-bottom:1px solid #eee;text-align:right}"
                "th:first-child,td:first-child{text-align:left}figure{display:inline-block;margin:0 1em 1em 0}"
                "</style></head><body>\n<h1>%s</h1>\n",
            r->title, r->title);
  const char *files[3] = {r->photo_png, r->start_png, r->fit_png};
  const char *labels[3] = {"photo", r->start_label, "fit"};
  for (int i = 0; i < 3 && !st; i++) {
    sb_printf(&b, "<figure><img alt=\"%s\" src=\"data:image/png;base64,", labels[i]);
    sb_base64_file(&b, files[i], &st, err);
    if (i == 0) sb_printf(&b, "\"><figcaption>%s</figcaption></figure>\n", labels[i]);
    else
      sb_printf(&b, "\"><figcaption>%s: SSIM %.4f</figcaption></figure>\n", labels[i],
                i == 1 ? r->ssim_start : r->ssim_fit);
  }
  char grain[320] = "";
  if (r->weave && r->weave->periodic_share > -2)
    snprintf(grain, sizeof grain,
             " Of the photo's detail (what the blurred copy lacks), %.0f%% lies in the peaks of its spectrum, "
             "the weave; the rest is grain, which a procedural material matches in its statistics but not "
             "where it lies.",
             100 * r->weave->periodic_share);
  if (r->weave && r->weave->below_blurred_copy)
    sb_printf(&b, UNSURE_BOX "an unsure %s.</b> The fit's render scores a lower SSIM against the photo (per RGB "
                  "channel, %.4f) than the photo's own copy blurred by a Gaussian of sigma %.0f px (%.4f), a copy "
                  "that keeps no weave at all: the fit reproduces the photo less well than a blur does. Check the weave "
                  "close up%s before using these parameters.%s</p>\n",
              r->pattern_choice ? "capture" : "fit", r->weave->ssim_rgb[1], WV_BLURRED_COPY_SIGMA,
              r->weave->ssim_rgb_blurred, r->pattern_choice ? " and the families' scores below" : "", grain);
  if (r->weave && r->weave->zoom_png[0] && !st) {
    sb_printf(&b, "<h2>The weave, close up</h2>\n<figure><img alt=\"zoom\" src=\"data:image/png;base64,");
    sb_base64_file(&b, r->weave->zoom_png, &st, err);
    sb_printf(&b, "\"><figcaption>photo | %s | fit: the centre %d x %d pixels, %d times enlarged</figcaption>"
                  "</figure>\n",
              r->start_label, r->weave->zoom_side, r->weave->zoom_side, r->weave->zoom_factor);
  }
  if (r->weave && r->weave->spectra_png[0] && !st) {
    sb_printf(&b, "<figure><img alt=\"spectra\" src=\"data:image/png;base64,");
    sb_base64_file(&b, r->weave->spectra_png, &st, err);
    sb_printf(&b, "\"><figcaption>weave spectra (log power of the luminance detail, centre window, DC in the "
                  "middle): photo | %s | fit. The same weave shows the same lattice of peaks, wherever its yarns "
                  "lie.</figcaption></figure>\n",
              r->start_label);
  }
  sb_printf(&b, "<table><tr><th>against the photo</th><th>%s</th><th>fit</th></tr>\n", r->start_label);
  sb_printf(&b, "<tr><td>SSIM (luminance)</td><td>%.4f</td><td>%.4f</td></tr>\n", r->ssim_start, r->ssim_fit);
  if (r->weave)
    sb_printf(&b, "<tr><td>SSIM (per RGB channel)</td><td>%.4f</td><td>%.4f</td></tr>\n", r->weave->ssim_rgb[0],
              r->weave->ssim_rgb[1]);
  if (r->weave && r->weave->ssim_rgb_blurred > -2)
    sb_printf(&b, "<tr><td>SSIM (per RGB channel) of the photo's copy blurred by %.0f px, the baseline</td>"
                  "<td colspan=\"2\">%.4f%s</td></tr>\n",
              WV_BLURRED_COPY_SIGMA, r->weave->ssim_rgb_blurred,
              r->weave->below_blurred_copy ? BELOW_MARK : "");
  if (r->weave && r->weave->periodic_share > -2)
    sb_printf(&b, "<tr><td>the photo's detail in the peaks of its spectrum (the weave; the rest is grain)</td>"
                  "<td colspan=\"2\">%.1f%%</td></tr>\n",
              100 * r->weave->periodic_share);
  if (r->weave && r->weave->wsc[0] > -2)
    sb_printf(&b, "<tr><td>WSC (weave-spectrum correlation)</td><td>%.4f</td><td>%.4f</td></tr>\n",
              r->weave->wsc[0], r->weave->wsc[1]);
  if (r->weave && r->weave->wsc_whitened[0] > -2)
    sb_printf(&b, "<tr><td>whitened WSC (the weave's peaks alone)</td><td>%.4f</td><td>%.4f</td></tr>\n",
              r->weave->wsc_whitened[0], r->weave->wsc_whitened[1]);
  if (r->photo_t_png && !st) {
    sb_printf(&b, "</table>\n<h2>Transmission</h2>\n");
    const char *tf[2] = {r->photo_t_png, r->fit_t_png}, *tl[2] = {"transmission photo", "fit, back-lit"};
    for (int i = 0; i < 2 && !st; i++) {
      sb_printf(&b, "<figure><img alt=\"%s\" src=\"data:image/png;base64,", tl[i]);
      sb_base64_file(&b, tf[i], &st, err);
      sb_printf(&b, "\"><figcaption>%s</figcaption></figure>\n", tl[i]);
    }
    if (r->below_blurred_copy_t) {
      char grain_t[320] = "";
      if (r->periodic_share_t > -2)
        snprintf(grain_t, sizeof grain_t,
                 " Of the back-lit photo's detail, %.0f%% lies in the peaks of its spectrum, the weave; the rest "
                 "is grain, which no re-render places where the photo has it, so where the weave is a small "
                 "share the blurred copy can be a bound no parameters pass.",
                 100 * r->periodic_share_t);
      sb_printf(&b, UNSURE_BOX "the back-lit re-render is unsure.</b> It scores a lower SSIM against the "
                    "transmission photo (per RGB channel, %.4f) than the photo's own copy blurred by a Gaussian of sigma %.0f px "
                    "(%.4f).%s Compare the weave's spectrum (WSC below) before relying on the transmission "
                    "colours.</p>\n",
                r->ssim_rgb_t, WV_BLURRED_COPY_SIGMA, r->ssim_rgb_blurred_t, grain_t);
    }
    sb_printf(&b, "<table><tr><th>against the transmission photo</th><th>fit</th></tr>\n");
    sb_printf(&b, "<tr><td>SSIM (per RGB channel)</td><td>%.4f</td></tr>\n", r->ssim_rgb_t);
    if (r->ssim_rgb_blurred_t > -2)
      sb_printf(&b, "<tr><td>SSIM (per RGB channel) of the photo's copy blurred by %.0f px, the baseline</td>"
                    "<td>%.4f%s</td></tr>\n",
                WV_BLURRED_COPY_SIGMA, r->ssim_rgb_blurred_t,
                r->below_blurred_copy_t ? BELOW_MARK : "");
    if (r->periodic_share_t > -2)
      sb_printf(&b, "<tr><td>the photo's detail in the peaks of its spectrum (the weave; the rest is grain)</td>"
                    "<td>%.1f%%</td></tr>\n",
                100 * r->periodic_share_t);
    if (r->wsc_t > -2) sb_printf(&b, "<tr><td>WSC (weave-spectrum correlation)</td><td>%.4f</td></tr>\n", r->wsc_t);
    sb_printf(&b, "<tr><td colspan=\"2\">One set of parameters for both photos (docs/fit.md, \"Photo pairs\"): "
                  "the back-lit photo fitted the transmission colours, the reflection photo the rest.</td></tr>\n");
    if (r->view_t && r->view_t_related)
      sb_printf(&b, "<tr><td colspan=\"2\">The back-lit photo sees the weave %.3f times as large and turned by %+.2f "
                    "degrees against the reflection photo; the back-lit render is in that view, with its own "
                    "registration and distortion.</td></tr>\n",
                1 / r->view_t_scale, r->view_t_rotation_deg);
    else if (r->view_t)
      sb_printf(&b, "<tr><td colspan=\"2\">The back-lit photo's weave does not relate to the reflection photo's: "
                    "the back-lit render starts from the reflection photo's view, with its own registration and "
                    "distortion.</td></tr>\n");
    else
      sb_printf(&b, "<tr><td colspan=\"2\">The back-lit render uses the reflection photo's view.</td></tr>\n");
    if (r->open_measured)
      sb_printf(&b, "<tr><td>open area, measured on the back-lit photo's gap glow (the yarn width set to "
                    "match)</td><td>%.2f%%</td></tr>\n", 100 * (r->open_area > 0 ? r->open_area : 0));
    if (r->kt_start)
      sb_printf(&b, "<tr><td colspan=\"2\">The diffuse transmission colours started from the pair model %s (the "
                    "photo pair through FabricNet), the specular ones from the specular colours.</td></tr>\n",
                r->kt_start);
    else
      sb_printf(&b, "<tr><td colspan=\"2\">The transmission colours started from the prior (half the start's "
                    "diffuse colour, and its specular colour): %s.</td></tr>\n",
                r->kt_tried ? "the pair model's estimate scored a higher loss on the two photos"
                            : "there is no pair model for these scenes");
  }
  char how[96] = "measured from the photo's spectrum unless given";
  if (r->camera_blur_measured >= 0)
    snprintf(how, sizeof how, "measured from the photo's spectrum at %.2f px, then fitted with the parameters",
             r->camera_blur_measured);
  sb_printf(&b, "</table>\n<p>Both renders pass through the camera blur: a Gaussian of sigma %.2f px on the "
                "radiance (%s; docs/fit.md).</p>\n",
            r->camera_blur, how);
  if (!r->photo_t_png && !r->kt_fitted)
    sb_printf(&b, "<p>One photo, front-lit: the transmission colours (k_t, k_st) were not fitted; they are the "
                  "start's, from the prior (half the start's diffuse colour, and its specular colour). "
                  "<code>--transmission T.png</code> fits them to a back-lit photo.</p>\n");
  sb_printf(&b, "<p>SSIM: Wang et al. 2004, 11x11 Gaussian window. WSC: Pearson correlation of the log "
                "power spectra of the luminance detail of the centre 256 x 256 pixels, DC left out; 1 for the same "
                "periodic structure, about 0 for none in common. Whitened WSC: the same after each ring of the spectrum is "
                "standardised by its median and spread, which removes the blur's envelope that dominates WSC. "
                "%d iterations, descriptor <code>%s</code>, OpenBLAS kernels <code>%s</code> (another CPU's can end "
                "the fit a few thousandths away).</p>\n",
            r->iters, r->descriptor, wv_nn_blas_core());
  char bounds[WV_P_COUNT + 3][96];
  int nbounds = wv_params_at_bounds(r->fit, bounds, WV_P_COUNT + 3);
  if (nbounds) {
    sb_printf(&b, "<p>Parameters of the fit on a bound of their range (the fit wanted to push them further):</p><ul>");
    for (int i = 0; i < nbounds; i++) sb_printf(&b, "<li>%s</li>", bounds[i]);
    sb_printf(&b, "</ul>\n");
  } else {
    sb_printf(&b, "<p>No parameter of the fit ended on a bound of its range.</p>\n");
  }
  if (r->timing)
    sb_printf(&b, "<p>Time: %.1f s in all (render %.1f s, gradient %.1f s, descriptor %.1f s, discrete search %.1f s, registration %.1f s, the cloth's distortion %.1f s).</p>\n",
              r->timing->total, r->timing->render, r->timing->gradient, r->timing->descriptor, r->timing->discrete,
              r->timing->registration, r->timing->distortion);
  const wv_pattern_choice *pc = r->pattern_choice;
  if (pc) {
    const wv_lattice *l = &pc->lattice;
    const char *chosen = wv_weave_builtin_name(pc->best);
    sb_printf(&b, "<h2>Weave analysis and pattern choice</h2>\n");
    if (l->found) {
      const wv_lattice_fit *f = &l->fit[l->best];
      sb_printf(&b, "<p>The photo's weave spectrum shows %d peaks. The built-in lattice that explains them best is "
                    "<b>%s</b>: %.1f warp x %.1f weft yarns/inch (%.2f x %.2f pixels apart), turned by %.1f&deg;, "
                    "%.1f&deg; out of square, a repeat of %d yarns moving %+d per row (score %.3f).</p>\n",
                l->n_peaks, wv_weave_builtin_name(l->best), f->density[0], f->density[1], l->spacing_px[0],
                l->spacing_px[1], f->angle_deg, f->skew_deg, l->repeat, l->shear, f->score);
      sb_printf(&b, "<p>Pattern chosen: <b>%s</b> (%s family, %s). Each built-in was rendered with the network's "
                    "estimate and its own lattice densities; the match of its spectral peaks with the photo's "
                    "ranks it%s:</p>\n<table><tr><th>pattern</th><th>lattice score</th><th>densities</th>"
                    "<th>render match</th><th>render WSC</th><th>fit loss</th></tr>\n",
                chosen, wv_weave_family(chosen), pc->method,
                strcmp(pc->method, "lattice+loss") ? "" : "; near ties were decided by the fit's loss");
      for (int k = 0; k < wv_weave_builtin_count(); k++) {
        int i = pc->ranking.order[k];
        const char *fmt = i == pc->best ? "<tr><td><b>%s</b></td>" : "<tr><td>%s</td>";
        sb_printf(&b, fmt, wv_weave_builtin_name(i));
        sb_printf(&b, "<td>%.3f</td><td>%.1f / %.1f</td><td>%.3f</td><td>%.3f</td>", l->fit[i].score,
                  l->fit[i].density[0], l->fit[i].density[1], pc->ranking.match[i], pc->ranking.wsc[i]);
        if (pc->evaluated[i]) sb_printf(&b, "<td>%.6f</td></tr>\n", pc->loss[i]);
        else sb_printf(&b, "<td></td></tr>\n");
      }
      sb_printf(&b, "</table>\n");
      if (pc->start_refined)
        sb_printf(&b, "<p>The start's densities: the network's, %.1f / %.1f yarns/inch, refined from the photo's "
                      "spectral peaks to %.1f / %.1f, the cloth turned %.2f&deg; and %.2f&deg; out of square: the "
                      "render's peaks matched the photo's %.3f, against %.3f with the %s lattice's.</p>\n",
                  pc->unrefined[0], pc->unrefined[1], pc->start_fit.density[0], pc->start_fit.density[1],
                  pc->start_fit.angle_deg, pc->start_fit.skew_deg, pc->refine_match[1], pc->refine_match[0], chosen);
    } else {
      sb_printf(&b, "<p>The weave analysis found no weave lattice (%s). The pattern was chosen as the network "
                    "would: <b>%s</b> (%s family), %s.</p>\n",
                l->reason, chosen, wv_weave_family(chosen),
                !strcmp(pc->method, "network") ? "its most probable class"
                                               : "the smallest fit loss of its estimate rendered with each built-in");
      const double *d0 = pc->start_refine_tried ? pc->unrefined : pc->params[pc->best].density;
      if (pc->start_compared)
        sb_printf(&b, "<p>The start's densities: %s, %.1f / %.1f yarns/inch. The spectral peaks of the render "
                      "matched the photo's %.3f with the network's densities and %.3f with those of the weak "
                      "%s lattice (score %.3f).</p>\n",
                  pc->lattice_densities ? "the weak lattice's" : "the network's", d0[0], d0[1], pc->start_match[0],
                  pc->start_match[1], chosen, l->fit[pc->best].score);
      if (pc->start_refined)
        sb_printf(&b, "<p>Refined from the photo's spectral peaks (the %s lattice searched near those densities): "
                      "%.1f / %.1f yarns/inch, the cloth turned %.2f&deg; and %.2f&deg; out of square. The "
                      "render's peaks matched the photo's %.3f before and %.3f after.</p>\n",
                  chosen, pc->start_fit.density[0], pc->start_fit.density[1], pc->start_fit.angle_deg,
                  pc->start_fit.skew_deg, pc->refine_match[0], pc->refine_match[1]);
    }
    family_table(&b, pc);
  }
  if (r->drape_png || r->drape_note) {
    sb_printf(&b, "<h2>On a draped cloth</h2>\n");
    if (r->drape_png && !st) {
      sb_printf(&b, "<figure><img alt=\"photo\" style=\"height:384px;width:auto\" src=\"data:image/png;base64,");
      sb_base64_file(&b, r->photo_png, &st, err);
      sb_printf(&b, "\"><figcaption>photo</figcaption></figure>\n<figure><img alt=\"drape\" "
                    "style=\"image-rendering:auto\" src=\"data:image/png;base64,");
      sb_base64_file(&b, r->drape_png, &st, err);
      sb_printf(&b, "\"><figcaption>the fit on a draped cloth</figcaption></figure>\n");
    }
    if (r->drape_note) sb_printf(&b, "<p>%s</p>\n", r->drape_note);
  }
  if (r->viewer_html)
    sb_printf(&b, "<h2>Interactive viewer</h2>\n<p>The true model in WebGL: orbit, move the light, edit the "
                  "parameters, compare with the photo (<a href=\"%s\">open it alone</a>).</p>\n"
                  "<iframe src=\"%s\" style=\"width:100%%;height:640px;border:1px solid #ccc\"></iframe>\n",
              r->viewer_html, r->viewer_html);
  sb_printf(&b, "<h2>Parameters</h2>\n<table><tr><th>parameter</th><th>%s</th><th>fit</th></tr>\n", r->start_label);
  sb_printf(&b, "<tr><td>pattern</td><td>%s</td><td>%s</td></tr>\n", r->start->pattern, r->fit->pattern);
  sb_printf(&b, "<tr><td>density.warp (yarns/inch)</td><td>%.1f</td><td>%.1f</td></tr>\n", r->start->density[0],
            r->fit->density[0]);
  sb_printf(&b, "<tr><td>density.weft (yarns/inch)</td><td>%.1f</td><td>%.1f</td></tr>\n", r->start->density[1],
            r->fit->density[1]);
  for (int i = 0; i < WV_P_COUNT; i++)
    sb_printf(&b, "<tr><td>%s</td><td>%.4f</td><td>%.4f</td></tr>\n", wv_param_name(i), wv_param_get(r->start, i),
              wv_param_get(r->fit, i));
  sb_printf(&b, "<tr><td>noise_level</td><td>%d</td><td>%d</td></tr>\n</table>\n", r->start->noise_level,
            r->fit->noise_level);
  sb_printf(&b, "<h2>Loss</h2>\n%s\n</body></html>\n", r->loss_svg ? r->loss_svg : "");
  if (!st && b.failed) st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory writing the report", path);
  if (!st) st = wv_write_file_atomic(path, b.s, b.len, err);
  free(b.s);
  return st;
}
