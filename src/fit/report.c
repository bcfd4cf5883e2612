#include "woven/report.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/base64.h"
#include "woven/io.h"

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
  sb_printf(&b, "<p>SSIM against the photo (luminance, Wang et al. 2004, 11x11 Gaussian window): "
                "%s %.4f &rarr; fit %.4f. %d iterations, descriptor <code>%s</code>.</p>\n",
            r->start_label, r->ssim_start, r->ssim_fit, r->iters, r->descriptor);
  if (r->timing)
    sb_printf(&b, "<p>Time: %.1f s in all (render %.1f s, gradient %.1f s, descriptor %.1f s, discrete search %.1f s, registration %.1f s).</p>\n",
              r->timing->total, r->timing->render, r->timing->gradient, r->timing->descriptor, r->timing->discrete,
              r->timing->registration);
  const wv_pattern_choice *pc = r->pattern_choice;
  if (pc) {
    sb_printf(&b, "<p>Pattern chosen automatically: <b>%s</b>, the smallest texture (Gram) loss against the photo "
                  "when the network's estimate is rendered with each built-in pattern (%d spp):</p>\n<table><tr>",
              wv_net_pattern(pc->best), pc->spp);
    for (int i = 0; i < WV_NET_PATTERNS; i++) sb_printf(&b, "<th>%s</th>", wv_net_pattern(i));
    sb_printf(&b, "</tr>\n<tr>");
    for (int i = 0; i < WV_NET_PATTERNS; i++)
      sb_printf(&b, i == pc->best ? "<td><b>%.6f</b></td>" : "<td>%.6f</td>", pc->loss[i]);
    sb_printf(&b, "</tr></table>\n");
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
