/* Automatic choice of the weave pattern (wv_fabricnet_predict_pattern) on a held-out
 * synthetic set or on real photos.
 *   pattern MODEL SCENE [--per-pattern N] [--seed S] [--spp N] [--w-pixel W] [--target-spp N] [--oracle]
 *     N prior draws per pattern (wv_dataset_sample_params with dataset seed S, default 2022;
 *     the default models were trained on seed 1), rendered in SCENE at --target-spp (default:
 *     the scene's spp) and quantised to 8 bits like a photo; prints the confusion matrix
 *     (rows: true pattern, columns: chosen). --oracle also chooses from the true continuous
 *     parameters instead of the network's (is a miss the criterion's or the network's?).
 *   pattern MODEL SCENE --real DIR
 *     every .png file in DIR as a photo in SCENE: the chosen pattern and the five losses.
 * --spp, --w-pixel: wv_pattern_opts (defaults WV_PATTERN_SPP, WV_PATTERN_W_PIXEL); the synthetic
 * mode also reports the accuracy the same renders give with other pixel weights.
 * Prints progress on stderr and one JSON object on the last line of stdout. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/photo.h"
#include "woven/render.h"

static void die(const wv_error *e) {
  fprintf(stderr, "pattern bench: %s\n", e->msg);
  exit(1);
}

static void quantise8(wv_image *img) {
  size_t n = (size_t)img->w * img->h * img->c;
  for (size_t i = 0; i < n; i++) {
    float v = img->data[i] < 0 ? 0 : img->data[i] > 1 ? 1 : img->data[i];
    img->data[i] = floorf(v * 255.0f + 0.5f) / 255.0f;
  }
}

static void print_losses(FILE *f, const wv_pattern_choice *c) {
  fprintf(f, "{");
  for (int i = 0; i < WV_NET_PATTERNS; i++)
    fprintf(f, "%s\"%s\": [%.6f, %.6f]", i ? ", " : "", wv_net_pattern(i), c->gram[i], c->pixel[i]);
  fprintf(f, "}");
}

/* The same renders judged with other weights of the pixel term: how many are right. */
#define NW 6
static const double W_PIXEL[NW] = {0, 0.1, 0.2, 0.5, 1, 2};
static void tally_weights(const wv_pattern_choice *c, int truth, int *right) {
  for (int w = 0; w < NW; w++) {
    int best = 0;
    for (int i = 1; i < WV_NET_PATTERNS; i++)
      if (c->gram[i] + W_PIXEL[w] * c->pixel[i] < c->gram[best] + W_PIXEL[w] * c->pixel[best]) best = i;
    right[w] += best == truth;
  }
}

static void print_by_weight(const char *key, const int *right, int total) {
  printf(", \"%s\": {", key);
  for (int w = 0; w < NW; w++) printf("%s\"%g\": %.4f", w ? ", " : "", W_PIXEL[w], (double)right[w] / total);
  printf("}");
}

static void print_matrix(const char *key, int m[WV_NET_PATTERNS][WV_NET_PATTERNS]) {
  printf(", \"%s\": {", key);
  for (int t = 0; t < WV_NET_PATTERNS; t++) {
    printf("%s\"%s\": [", t ? ", " : "", wv_net_pattern(t));
    for (int c = 0; c < WV_NET_PATTERNS; c++) printf("%s%d", c ? ", " : "", m[t][c]);
    printf("]");
  }
  printf("}");
}

static void stderr_matrix(const char *title, int m[WV_NET_PATTERNS][WV_NET_PATTERNS]) {
  fprintf(stderr, "%s (rows: truth, columns: chosen)\n%-8s", title, "");
  for (int c = 0; c < WV_NET_PATTERNS; c++) fprintf(stderr, " %8s", wv_net_pattern(c));
  fprintf(stderr, "\n");
  for (int t = 0; t < WV_NET_PATTERNS; t++) {
    fprintf(stderr, "%-8s", wv_net_pattern(t));
    for (int c = 0; c < WV_NET_PATTERNS; c++) fprintf(stderr, " %8d", m[t][c]);
    fprintf(stderr, "\n");
  }
}

static int run_real(const wv_fabricnet *net, wv_descriptor *d, const wv_scene *s, const char *dir,
                    const wv_pattern_opts *po) {
  char names[64][256];
  int n = bench_list_png(dir, names);
  if (n < 0) {
    fprintf(stderr, "pattern bench: cannot open %s\n", dir);
    return 1;
  }
  printf("{\"mode\": \"real\", \"scene\": \"%s\", \"spp\": %d, \"photos\": [", s->name, po->spp);
  for (int i = 0; i < n; i++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[i]);
    wv_error e = {0};
    wv_image photo = {0};
    wv_crop crop = {0, 0, 0, 0};
    float y[WV_NET_OUT];
    wv_pattern_choice c;
    if (wv_photo_load(path, s, &crop, &photo, NULL, &e) ||
        wv_fabricnet_predict_pattern(net, d, s, &photo, po, y, &c, &e))
      die(&e);
    fprintf(stderr, "%s: %s, ", names[i], wv_net_pattern(c.best));
    print_losses(stderr, &c);
    fprintf(stderr, " (%.2f s)\n", c.seconds);
    printf("%s{\"photo\": \"%s\", \"chosen\": \"%s\", \"seconds\": %.3f, \"gram_and_pixel_loss\": ", i ? ", " : "", names[i],
           wv_net_pattern(c.best), c.seconds);
    print_losses(stdout, &c);
    printf("}");
    wv_image_free(&photo);
  }
  printf("]}\n");
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: pattern MODEL SCENE [--per-pattern N] [--seed S] [--spp N] [--w-pixel W] [--target-spp N]\n"
                    "                     [--oracle]\n"
                    "       pattern MODEL SCENE --real DIR [--spp N]\n");
    return 1;
  }
  const char *mpath = argv[1], *real = NULL;
  int per = 10, target_spp = 0, oracle = 0;
  uint64_t seed = 2022;
  wv_pattern_opts po;
  wv_pattern_opts_default(&po);
  for (int i = 3; i < argc; i++) {
    if (!strcmp(argv[i], "--per-pattern") && i + 1 < argc) per = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--seed") && i + 1 < argc) seed = strtoull(argv[++i], NULL, 10);
    else if (!strcmp(argv[i], "--spp") && i + 1 < argc) po.spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--w-pixel") && i + 1 < argc) po.w_pixel = atof(argv[++i]);
    else if (!strcmp(argv[i], "--target-spp") && i + 1 < argc) target_spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--real") && i + 1 < argc) real = argv[++i];
    else if (!strcmp(argv[i], "--oracle")) oracle = 1;
    else {
      fprintf(stderr, "pattern bench: unknown argument '%s'\n", argv[i]);
      return 1;
    }
  }
  wv_error e = {0};
  wv_dataset_info info;
  memset(&info, 0, sizeof info);
  if (wv_scene_load(argv[2], &info.scene, &e)) die(&e);
  const wv_scene *s = &info.scene;
  wv_fabricnet net;
  wv_descriptor *d;
  if (wv_fabricnet_load(mpath, &net, &e) || wv_descriptor_create("default", NULL, &d, &e) ||
      wv_fabricnet_check(&net, mpath, wv_descriptor_name(d), wv_descriptor_size(d), s, &e))
    die(&e);
  if (real) {
    int rc = run_real(&net, d, s, real, &po);
    wv_descriptor_free(d);
    wv_fabricnet_free(&net);
    return rc;
  }
  info.seed = seed, info.per_pattern = per;
  int conf[WV_NET_PATTERNS][WV_NET_PATTERNS] = {{0}}, conf_oracle[WV_NET_PATTERNS][WV_NET_PATTERNS] = {{0}};
  int right = 0, right_oracle = 0, total = WV_NET_PATTERNS * per;
  int right_w[NW] = {0}, right_w_oracle[NW] = {0};
  double *secs = malloc(sizeof(double) * (size_t)total), margin_sum = 0;
  float *gram = malloc(sizeof(float) * wv_descriptor_size(d));
  wv_render_opts ro = {target_spp, 0, NULL, NULL, NULL};
  for (int k = 0; k < total; k++) {
    wv_params truth;
    wv_image photo = {0};
    if (wv_dataset_sample_params(&info, k, &truth, &e) || wv_render(s, &truth, &ro, &photo, NULL, &e)) die(&e);
    quantise8(&photo);
    float y[WV_NET_OUT];
    wv_pattern_choice c;
    if (wv_fabricnet_predict_pattern(&net, d, s, &photo, &po, y, &c, &e)) die(&e);
    int t = k % WV_NET_PATTERNS;
    conf[t][c.best]++, right += c.best == t;
    tally_weights(&c, t, right_w);
    secs[k] = c.seconds;
    double second = INFINITY;
    for (int i = 0; i < WV_NET_PATTERNS; i++)
      if (i != c.best && c.loss[i] < second) second = c.loss[i];
    margin_sum += second / c.loss[c.best] - 1;
    char name[64];
    wv_dataset_sample_name(&info, k, name, sizeof name);
    fprintf(stderr, "%-10s -> %-8s ", name, wv_net_pattern(c.best));
    print_losses(stderr, &c);
    if (oracle) {
      /* the true continuous parameters, through the same mapping */
      float yt[WV_NET_OUT];
      wv_pattern_choice co;
      wv_fabricnet_targets(&truth, yt);
      if (wv_descriptor_forward(d, &photo, gram, &e) ||
          wv_fabricnet_choose_pattern(&net, d, s, &photo, gram, yt, &po, &co, &e))
        die(&e);
      conf_oracle[t][co.best]++, right_oracle += co.best == t;
      tally_weights(&co, t, right_w_oracle);
      fprintf(stderr, "  oracle -> %s", wv_net_pattern(co.best));
    }
    fprintf(stderr, " (%.2f s)\n", c.seconds);
    wv_image_free(&photo);
  }
  stderr_matrix("network estimate", conf);
  if (oracle) stderr_matrix("true continuous parameters", conf_oracle);
  printf("{\"mode\": \"synthetic\", \"model\": \"%s\", \"scene\": \"%s\", \"seed\": %llu, \"per_pattern\": %d, "
         "\"target_spp\": %d, \"spp\": %d, \"w_pixel\": %g, \"accuracy\": %.4f, \"choice_seconds_median\": %.3f, "
         "\"mean_relative_margin\": %.4f",
         mpath, s->name, (unsigned long long)seed, per, target_spp ? target_spp : s->spp, po.spp, po.w_pixel,
         (double)right / total, bench_median(secs, total), margin_sum / total);
  printf(", \"patterns\": [");
  for (int i = 0; i < WV_NET_PATTERNS; i++) printf("%s\"%s\"", i ? ", " : "", wv_net_pattern(i));
  printf("]");
  print_matrix("confusion", conf);
  print_by_weight("accuracy_by_w_pixel", right_w, total);
  if (oracle) {
    printf(", \"accuracy_oracle\": %.4f", (double)right_oracle / total);
    print_matrix("confusion_oracle", conf_oracle);
    print_by_weight("accuracy_oracle_by_w_pixel", right_w_oracle, total);
  }
  printf("}\n");
  free(secs), free(gram);
  wv_descriptor_free(d);
  wv_fabricnet_free(&net);
  return 0;
}
