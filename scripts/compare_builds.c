/* Output comparison between two builds of the library (see compare_builds.sh).
 *   compare_builds dump DIR   renders a fixed set of cases with the library it
 *                             is linked to and writes each result to DIR/<case>.bin
 *   compare_builds diff A B   compares two such directories value by value:
 *                             bit-identical, or the largest relative difference
 * Uses only the public API, so it builds against older versions too. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/brdf.h"
#include "woven/grad.h"
#include "woven/maps.h"
#include "woven/render.h"

static const char *dir;

static void put(const char *name, const void *data, size_t bytes) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s.bin", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(data, 1, bytes, f) != bytes) {
    fprintf(stderr, "cannot write %s\n", path);
    exit(1);
  }
  fclose(f);
}

static void check(wv_status st, const wv_error *err) {
  if (st) {
    fprintf(stderr, "error: %s\n", err->msg);
    exit(1);
  }
}

static uint64_t rng = 12345;
static double rnd(void) {
  rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

static void params_for(int k, wv_params *p) {
  static const char *pats[] = {"twill", "satin90", "plain", "satin", "twill90"};
  wv_error err = {0};
  check(wv_params_default(pats[k % 5], p, &err), &err);
  if (k >= 2) { /* noise, gaps, glints, twist */
    p->noise_level = 3 + k;
    p->yarn_width = 0.85;
    p->twist_deg = -20 + 7 * k;
    p->specular_noise = 1;
    p->seed = 7 + k;
  }
}

static void dump(void) {
  wv_error err = {0};
  /* forward renders: capture and radiance at several spp (every packing of samples) */
  static const struct {
    const char *scene;
    int pat, spp;
  } fw[] = {{"cylinder", 0, 64}, {"cylinder", 0, 4}, {"cylinder", 2, 1},  {"cylinder", 3, 3},
            {"cylinder", 4, 20}, {"cylinder", 2, 8}, {"flat45", 1, 4},   {"flat45", 3, 64},
            {"flat45", 2, 5},    {"flat45", 4, 16}, {"cylinder", 3, 12}, {"flat45", 0, 2}};
  for (size_t i = 0; i < sizeof fw / sizeof fw[0]; i++) {
    wv_scene s;
    wv_params p;
    check(wv_scene_preset(fw[i].scene, &s, &err), &err);
    params_for(fw[i].pat, &p);
    wv_render_opts o = {fw[i].spp, 0, NULL, NULL, NULL};
    wv_image cap, rad;
    check(wv_render(&s, &p, &o, &cap, &rad, &err), &err);
    char name[128];
    snprintf(name, sizeof name, "render_%s_%d_spp%d_capture", fw[i].scene, fw[i].pat, fw[i].spp);
    put(name, cap.data, sizeof(float) * 3 * cap.w * cap.h);
    snprintf(name, sizeof name, "render_%s_%d_spp%d_radiance", fw[i].scene, fw[i].pat, fw[i].spp);
    put(name, rad.data, sizeof(float) * 3 * rad.w * rad.h);
    wv_image_free(&cap), wv_image_free(&rad);
  }
  /* gradients (float production path; double on a window), with their captures */
  static const struct {
    const char *scene;
    int pat, spp, dbl;
  } gr[] = {{"cylinder", 0, 4, 0}, {"cylinder", 3, 64, 0}, {"flat45", 1, 4, 0},
            {"flat45", 2, 20, 0},  {"cylinder", 2, 8, 1},  {"flat45", 4, 12, 1}};
  for (size_t i = 0; i < sizeof gr / sizeof gr[0]; i++) {
    wv_scene s;
    wv_params p;
    check(wv_scene_preset(gr[i].scene, &s, &err), &err);
    params_for(gr[i].pat, &p);
    wv_grad_opts g = {0, 0, 0, 0, gr[i].dbl};
    if (gr[i].dbl) g.x0 = s.width / 2 - 40, g.y0 = s.height / 2 - 20, g.width = 80, g.height = 40;
    int w = g.width ? g.width : s.width, h = g.height ? g.height : s.height;
    wv_image dc, cap;
    check(wv_image_alloc(&dc, w, h, 3, &err), &err);
    for (int k = 0; k < w * h * 3; k++) dc.data[k] = (float)(2 * rnd() - 1);
    wv_render_opts o = {gr[i].spp, 0, NULL, NULL, NULL};
    double grad[WV_P_COUNT + 1];
    check(wv_render_grad_ex(&s, &p, &o, &g, &dc, grad, &grad[WV_P_COUNT], &cap, &err), &err);
    char name[128];
    snprintf(name, sizeof name, "grad_%s_%d_spp%d_%s", gr[i].scene, gr[i].pat, gr[i].spp, gr[i].dbl ? "double" : "float");
    put(name, grad, sizeof grad);
    snprintf(name, sizeof name, "grad_%s_%d_spp%d_%s_capture", gr[i].scene, gr[i].pat, gr[i].spp,
             gr[i].dbl ? "double" : "float");
    put(name, cap.data, sizeof(float) * 3 * w * h);
    wv_image_free(&dc), wv_image_free(&cap);
  }
  /* maps */
  for (int k = 0; k < 5; k += 2) {
    wv_params p;
    params_for(k, &p);
    wv_maps m;
    check(wv_maps_generate(&p, 192, &m, &err), &err);
    const wv_image *all[] = {&m.normal, &m.tangent, &m.yarn_id, &m.height};
    static const char *names[] = {"normal", "tangent", "yarn_id", "height"};
    for (int j = 0; j < 4; j++) {
      char name[128];
      snprintf(name, sizeof name, "maps_%d_%s", k, names[j]);
      put(name, all[j]->data, sizeof(float) * 3 * all[j]->w * all[j]->h);
    }
    wv_maps_free(&m);
  }
  /* the public BRDF functions */
  float vals[4000];
  int n = 0;
  for (int i = 0; i < 1000; i++) {
    float t[3], wi[3], wo[3], wm[3] = {0, 0, 1};
    for (int k = 0; k < 3; k++) t[k] = (float)(2 * rnd() - 1), wi[k] = (float)(2 * rnd() - 1), wo[k] = (float)(2 * rnd() - 1);
    wi[2] = fabsf(wi[2]), wo[2] = fabsf(wo[2]);
    float lt = sqrtf(wv_dot3(t, t)), li = sqrtf(wv_dot3(wi, wi)), lo = sqrtf(wv_dot3(wo, wo));
    for (int k = 0; k < 3; k++) t[k] /= lt, wi[k] /= li, wo[k] /= lo;
    float alpha = (float)(0.02 + rnd()), thick = (float)(0.5 + 3 * rnd()), w = (float)rnd();
    vals[n++] = wv_brdf_specular(t, alpha, thick, wi, wo, wm);
    vals[n++] = wv_brdf_diffuse_cos(t, w, wi, wm);
    vals[n++] = wv_sggx_sigma(t, alpha, wi);
    vals[n++] = wv_sggx_D(t, alpha, wo);
  }
  put("brdf", vals, sizeof(float) * n);
}

static void *slurp(const char *path, size_t *n) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  void *buf = malloc((size_t)len + 1);
  if (fread(buf, 1, (size_t)len, f) != (size_t)len) len = 0;
  fclose(f);
  *n = (size_t)len;
  return buf;
}

static int diff(const char *a, const char *b) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "ls %s | sort", a);
  FILE *ls = popen(cmd, "r");
  char name[512];
  int differ = 0;
  while (fgets(name, sizeof name, ls)) {
    name[strcspn(name, "\n")] = 0;
    char pa[1024], pb[1024];
    snprintf(pa, sizeof pa, "%s/%s", a, name), snprintf(pb, sizeof pb, "%s/%s", b, name);
    size_t na, nb;
    unsigned char *da = slurp(pa, &na), *db = slurp(pb, &nb);
    if (!db || na != nb) {
      printf("%-44s missing or of another size\n", name);
      differ = 1;
    } else if (!memcmp(da, db, na)) {
      printf("%-44s bit-identical (%zu bytes)\n", name, na);
    } else {
      int dbl = strncmp(name, "grad_", 5) == 0 && !strstr(name, "capture");
      size_t cnt = dbl ? na / 8 : na / 4, ndiff = 0;
      double worst = 0, worst_abs = 0, scale = 0;
      for (size_t i = 0; i < cnt; i++) {
        double x = dbl ? ((double *)da)[i] : ((float *)da)[i], y = dbl ? ((double *)db)[i] : ((float *)db)[i];
        scale = fmax(scale, fabs(x));
        if (x == y) continue;
        ndiff++;
        double r = fabs(x - y) / fmax(fabs(x), fabs(y));
        worst = fmax(worst, r), worst_abs = fmax(worst_abs, fabs(x - y));
      }
      printf("%-44s %zu of %zu values differ: max relative %.2e, max absolute %.2e (largest value %.3g)\n", name,
             ndiff, cnt, worst, worst_abs, scale);
      differ = 1;
    }
    free(da), free(db);
  }
  pclose(ls);
  return differ;
}

int main(int argc, char **argv) {
  if (argc == 3 && !strcmp(argv[1], "dump")) {
    dir = argv[2];
    dump();
    return 0;
  }
  if (argc == 4 && !strcmp(argv[1], "diff")) return diff(argv[2], argv[3]) ? 2 : 0;
  fprintf(stderr, "usage: compare_builds dump DIR | diff DIR_A DIR_B\n");
  return 1;
}
