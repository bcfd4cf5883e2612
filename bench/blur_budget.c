/* What a re-render can gain over a photo's blurred copy: SSIM (per RGB channel) against the
 * photo of images made from the photo and from a render of it.
 *   blur_budget PHOTO RENDER [PHOTO RENDER ...]
 * For each pair (same size, at least 32 x 32):
 *   photo_blur      the photo blurred by sigma 1, 2, 4 px (4 px: woven capture's
 *                   ssim_rgb_blurred_photo);
 *   render_blur     the render as it is and blurred by sigma 1, 2, 4 px;
 *   photo_low_render_detail  the photo's own blur (sigma 2 px) plus the render's detail (the
 *                   render minus its own blur) times 0, 0.5, 1: what the render's detail adds
 *                   to the photo's own shading;
 *   periodic_share  the share of the photo's detail power (luminance minus its sigma 4 px
 *                   blur) in its spectral peaks (wv_detail_periodic);
 *   periodic_oracle the photo's sigma 4 px blur plus those peaks of its own detail, per
 *                   channel: a periodic texture exactly in register with the photo, on the
 *                   photo's own shading.
 * Prints one line per pair, then one JSON object on the last line. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "woven/image.h"
#include "woven/io.h"
#include "woven/metrics.h"
#include "wsc_quadrants.h"

static void die(const wv_error *e) {
  fprintf(stderr, "blur_budget: %s\n", e->msg);
  exit(1);
}

static double ssim_rgb(const wv_image *a, const wv_image *b) {
  wv_error e = {0};
  double s;
  if (wv_ssim(a, b, WV_SSIM_RGB, &s, &e)) die(&e);
  return s;
}

static double wsc(const wv_image *a, const wv_image *b) {
  wv_error e = {0};
  double v;
  if (wv_wsc(a, b, &v, &e)) die(&e);
  return v;
}

static wv_image blurred(const wv_image *in, double sigma) {
  wv_error e = {0};
  wv_image out;
  if (wv_image_blur(in, sigma, &out, &e)) die(&e);
  return out;
}

/* low + k (img - img_low); img_low NULL: low + k img */
static wv_image plus_detail(const wv_image *low, const wv_image *img, const wv_image *img_low, double k) {
  wv_error e = {0};
  wv_image out;
  if (wv_image_alloc(&out, low->w, low->h, low->c, &e)) die(&e);
  size_t n = (size_t)low->w * low->h * low->c;
  for (size_t i = 0; i < n; i++)
    out.data[i] = (float)(low->data[i] + k * (img->data[i] - (img_low ? img_low->data[i] : 0.0f)));
  return out;
}

int main(int argc, char **argv) {
  if (argc < 3 || (argc - 1) % 2) {
    fprintf(stderr, "usage: blur_budget PHOTO RENDER [PHOTO RENDER ...]\n");
    return 2;
  }
  static const double SIG[3] = {1, 2, 4}, K[3] = {0, 0.5, 1};
  json_t *list = json_array();
  for (int a = 1; a + 1 < argc; a += 2) {
    wv_error e = {0};
    wv_image photo = {0}, render = {0};
    if (wv_image_read(argv[a], &photo, NULL, &e) || wv_image_read(argv[a + 1], &render, NULL, &e)) die(&e);
    if (photo.w != render.w || photo.h != render.h || photo.c != 3 || render.c != 3 || photo.w < 32 || photo.h < 32) {
      fprintf(stderr, "blur_budget: %s and %s must be RGB images of one size, at least 32 x 32\n", argv[a],
              argv[a + 1]);
      return 1;
    }
    double pb[3], rb[4], pl[3];
    rb[0] = ssim_rgb(&render, &photo);
    for (int k = 0; k < 3; k++) {
      wv_image b = blurred(&photo, SIG[k]), r = blurred(&render, SIG[k]);
      pb[k] = ssim_rgb(&b, &photo), rb[k + 1] = ssim_rgb(&r, &photo);
      wv_image_free(&b), wv_image_free(&r);
    }
    wv_image p2 = blurred(&photo, 2), r2 = blurred(&render, 2), p4 = blurred(&photo, 4);
    for (int k = 0; k < 3; k++) {
      wv_image m = plus_detail(&p2, &render, &r2, K[k]);
      pl[k] = ssim_rgb(&m, &photo);
      wv_image_free(&m);
    }
    double share;
    wv_image per;
    if (wv_detail_periodic(&photo, 4, &share, &per, &e)) die(&e);
    wv_image oracle = plus_detail(&p4, &per, NULL, 1);
    wv_image_free(&per);
    double so = ssim_rgb(&oracle, &photo), w[4] = {wsc(&render, &photo), wsc(&p4, &photo), wsc(&oracle, &photo), 0};
    if (bench_wsc_quadrants(&photo, 0, &w[3], &e)) die(&e);
    printf("%s vs %s: photo blurred by 1 / 2 / 4 px %.4f / %.4f / %.4f; render as it is %.4f, blurred %.4f / %.4f / "
           "%.4f; photo's 2 px blur + render detail x 0 / 0.5 / 1 %.4f / %.4f / %.4f; periodic share %.3f, oracle "
           "%.4f; WSC render %.3f, photo's 4 px blur %.3f, oracle %.3f, photo's quadrants %.3f\n",
           argv[a], argv[a + 1], pb[0], pb[1], pb[2], rb[0], rb[1], rb[2], rb[3], pl[0], pl[1], pl[2], share, so, w[0],
           w[1], w[2], w[3]);
    json_array_append_new(
        list, json_pack("{s:s,s:s,s:[f,f,f],s:[f,f,f,f],s:[f,f,f],s:f,s:f,s:[f,f,f,f]}", "photo", argv[a], "render",
                        argv[a + 1],
                        "photo_blur_1_2_4", pb[0], pb[1], pb[2], "render_blur_0_1_2_4", rb[0], rb[1], rb[2], rb[3],
                        "photo_low_render_detail_0_05_1", pl[0], pl[1], pl[2], "periodic_share", share,
                        "periodic_oracle", so, "wsc_render_blur4_oracle_quadrants", w[0], w[1], w[2], w[3]));
    wv_image_free(&p2), wv_image_free(&r2), wv_image_free(&p4), wv_image_free(&oracle);
    wv_image_free(&photo), wv_image_free(&render);
  }
  json_t *root = json_pack("{s:o}", "pairs", list);
  char *text = json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(6));
  json_decref(root);
  if (!text) return 1;
  printf("%s\n", text);
  free(text);
  return 0;
}
