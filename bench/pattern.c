/* Automatic choice of the weave pattern over the built-in library
 * (wv_fabricnet_predict_pattern) on synthetic targets or on real photos.
 *   pattern MODEL SCENE [--per-pattern N] [--seed S] [--spp N] [--target-spp N] [--tie T]
 *                       [--family-tie T] [--blur SIGMA] [--noise SIGMA] [--no-lattice]
 *     N prior draws of every canonical built-in (wv_params_sample_prior, seeds from S), rendered
 *     in SCENE at --target-spp (default: the scene's spp), optionally blurred (Gaussian, sigma
 *     in pixels) and given Gaussian noise (sigma in 8-bit levels / 255) as a camera would, and
 *     quantised to 8 bits. Reports how often the chosen pattern, its family and (for twills)
 *     its direction are right, the density error when the pattern is right, the families'
 *     confusion matrix, what the lattice alone and the render ranking alone would have chosen,
 *     and the choice replayed with other margins of the family and pattern ties (the loss
 *     criterion deciding near ties; wv_pattern_decide).
 *   pattern MODEL SCENE --real DIR [--views]
 *     every .png file in DIR as a photo in SCENE: the weave analysis and the chosen pattern.
 *     With --views also of other views of each photo that show the same weave (mirrored left to
 *     right, moved half a pixel, enlarged 1.15 and 1.3 times about the centre, turned by +-3
 *     degrees; all but the mirror resampled bilinearly): which family
 *     each view gets, and how many views keep the photo's own view's family; for photos whose
 *     file name starts with their family (plain, basket, twill, satin), how often each view's
 *     family is right, and two ways to decide from all views: a vote of their families (ties
 *     to the photo's own view's), and the family with the largest sum of the network's
 *     probabilities over the views that keep a twill's direction (all but the mirrored),
 *     beside the network's most probable family on the photo as it is.
 * Prints progress on stderr and one JSON object on the last line of stdout. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "util/hash.h"
#include "woven/descriptor.h"
#include "woven/metrics.h"
#include "woven/pattern.h"
#include "woven/photo.h"
#include "woven/render.h"

static void die(const wv_error *e) {
  fprintf(stderr, "pattern bench: %s\n", e->msg);
  exit(1);
}

/* Blur, noise and 8-bit quantisation: what a camera adds to a render. */
static void camera(wv_image *img, double blur, double noise, uint64_t seed) {
  wv_error e = {0};
  if (blur > 0) {
    wv_image b;
    if (wv_image_blur(img, blur, &b, &e)) die(&e);
    wv_image_free(img);
    *img = b;
  }
  size_t n = (size_t)img->w * img->h * img->c;
  for (size_t i = 0; i < n; i++) {
    double v = img->data[i];
    if (noise > 0) { /* Box-Muller from two hashes of (seed, sample) */
      double u1 = wv_u01d(wv_hash2(seed, 2 * i, 17)), u2 = wv_u01d(wv_hash2(seed, 2 * i + 1, 17));
      v += noise / 255.0 * sqrt(-2 * log(u1 + 1e-300)) * cos(2 * 3.14159265358979323846 * u2);
    }
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    img->data[i] = (float)(floor(v * 255.0 + 0.5) / 255.0);
  }
}

static const char *const FAMILIES[4] = {"plain", "basket", "twill", "satin"};

static int fam_index(const char *name) {
  for (int i = 0; i < 4; i++)
    if (!strcmp(wv_weave_family(name), FAMILIES[i])) return i;
  return 0;
}

/* 1 S, -1 Z, 0 not a twill */
static int twill_dir(const char *name) {
  const char *c = wv_weave_canonical(name);
  if (!c || strcmp(wv_weave_family(c), "twill")) return 0;
  return strchr(c, 'z') ? -1 : 1;
}

/* Views of a photo that show the same weave: as it is, mirrored left to right (a twill's S
 * becomes a Z; the light stays at the top, as the rig has it), moved half a pixel in x and y
 * (the bilinear resampling's own blur and nothing else: the other resampled views have it too),
 * enlarged about the centre (the yarns more pixels apart), turned about the centre. */
#define NVIEW 7
static const char *const VIEW_NAME[NVIEW] = {"as is",     "mirrored",  "moved half a pixel", "enlarged 1.15",
                                             "enlarged 1.3", "turned +3", "turned -3"};
static const double VIEW_ZOOM[NVIEW] = {1, 1, 1, 1.15, 1.3, 1, 1}, VIEW_TURN[NVIEW] = {0, 0, 0, 0, 0, 3, -3},
                    VIEW_SHIFT[NVIEW] = {0, 0, 0.5, 0, 0, 0, 0};

/* Output pixel (x, y) samples the input bilinearly at the centre plus the turned offset over
 * the zoom; a turned view is enlarged just enough (cos + |sin|) that no pixel samples outside. */
static void make_view(const wv_image *in, int v, wv_image *out) {
  wv_error e = {0};
  int w = in->w, h = in->h, nc = in->c;
  double a = VIEW_TURN[v] * 3.14159265358979323846 / 180, c = cos(a), s = sin(a);
  double zoom = fmax(VIEW_ZOOM[v], c + fabs(s));
  if (wv_image_alloc(out, w, h, nc, &e)) die(&e);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double dx = x - 0.5 * (w - 1), dy = y - 0.5 * (h - 1);
      if (v == 1) dx = -dx;
      double u = (c * dx - s * dy) / zoom + 0.5 * (w - 1) + VIEW_SHIFT[v],
             t = (s * dx + c * dy) / zoom + 0.5 * (h - 1) + VIEW_SHIFT[v];
      bench_bilinear(in, u, t, wv_image_px(out, x, y));
    }
}

/* The index in FAMILIES of the family a file name starts with, or -1. */
static int named_family(const char *name) {
  for (int i = 0; i < 4; i++)
    if (!strncmp(name, FAMILIES[i], strlen(FAMILIES[i]))) return i;
  return -1;
}

static int run_real(const wv_fabricnet *net, wv_descriptor *d, const wv_scene *s, const char *dir,
                    const wv_pattern_opts *po, int views) {
  char names[64][256];
  int n = bench_list_png(dir, names);
  if (n < 0) {
    fprintf(stderr, "pattern bench: cannot open %s\n", dir);
    return 1;
  }
  int nv = views ? NVIEW : 1, kept = 0, named = 0, named_right = 0, view_right[NVIEW] = {0}, photos_named = 0,
      vote_right = 0, net_sum_right = 0, net_own_right = 0;
  printf("{\"mode\": \"real\", \"scene\": \"%s\", \"spp\": %d, \"photos\": [", s->name, po->spp);
  for (int i = 0; i < n; i++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[i]);
    wv_error e = {0};
    wv_image photo = {0};
    wv_crop crop = {0, 0, 0, 0};
    if (wv_photo_load(path, s, &crop, &photo, NULL, &e)) die(&e);
    int want = named_family(names[i]), votes[4] = {0}, own = 0, net_own = -1;
    double net_sum[4] = {0};
    printf("%s{\"photo\": \"%s\", \"views\": [", i ? ", " : "", names[i]);
    for (int v = 0; v < nv; v++) {
      float y[WV_NET_OUT];
      wv_pattern_choice c;
      wv_image img = {0};
      if (v) make_view(&photo, v, &img);
      if (wv_fabricnet_predict_pattern(net, d, s, v ? &img : &photo, po, y, &c, &e)) die(&e);
      wv_image_free(&img);
      const char *chosen = wv_weave_builtin_name(c.best), *fam = wv_weave_family(chosen);
      int f = fam_index(chosen);
      if (!v) own = f;
      else kept += f == own;
      if (want >= 0) named++, named_right += f == want, view_right[v] += f == want;
      votes[f]++;
      if (c.has_prob) {
        int top = 0;
        for (int b = 0; b < wv_weave_builtin_count(); b++) {
          if (v != 1) net_sum[fam_index(wv_weave_builtin_name(b))] += c.prob[b];
          if (c.prob[b] > c.prob[top]) top = b;
        }
        if (!v) net_own = fam_index(wv_weave_builtin_name(top));
      }
      fprintf(stderr, "%s, %s: %s (%s, %s), %.2f s\n", names[i], VIEW_NAME[v], chosen, fam, c.method, c.seconds);
      char *cj = wv_pattern_choice_to_json(&c);
      printf("%s{\"view\": \"%s\", \"family\": \"%s\", \"choice\": %s}", v ? ", " : "", VIEW_NAME[v], fam,
             cj ? cj : "null");
      free(cj);
    }
    printf("]}");
    wv_image_free(&photo);
    if (want >= 0 && views) {
      int vote = own, net = 0;
      for (int f = 0; f < 4; f++) {
        if (votes[f] > votes[vote]) vote = f;
        if (net_sum[f] > net_sum[net]) net = f;
      }
      photos_named++;
      vote_right += vote == want;
      net_sum_right += net_sum[net] > 0 && net == want;
      net_own_right += net_own == want;
    }
  }
  printf("], \"family_as_named\": [%d, %d]", named_right, named);
  if (named) fprintf(stderr, "family as the file name has it: %d of %d\n", named_right, named);
  if (views) {
    printf(", \"views_keeping_the_family\": [%d, %d]", kept, n * (nv - 1));
    fprintf(stderr, "views keeping the photo's own family: %d of %d\n", kept, n * (nv - 1));
  }
  if (views && photos_named) {
    printf(", \"named_right_per_view\": {");
    for (int v = 0; v < NVIEW; v++) {
      printf("%s\"%s\": %d", v ? ", " : "", VIEW_NAME[v], view_right[v]);
      fprintf(stderr, "%s %s %d", v ? "," : "family right per view of the named photos:", VIEW_NAME[v], view_right[v]);
    }
    printf("}, \"named_photos\": %d, \"vote_right\": %d, \"network_sum_right\": %d, \"network_own_right\": %d",
           photos_named, vote_right, net_sum_right, net_own_right);
    fprintf(stderr, " (of %d); the views' vote %d, the network's family sums over the views %d, the network on the "
                    "photo as it is %d\n",
            photos_named, vote_right, net_sum_right, net_own_right);
  }
  printf("}\n");
  return 0;
}

/* Margins the same runs are replayed with (every candidate's loss is computed): family
 * ties x pattern ties. */
#define NF 4
#define NT 4
static const double FTIES[NF] = {0, 0.05, 0.1, 0.2}, TIES[NT] = {0, 0.02, 0.05, 0.1};

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: pattern MODEL SCENE [--per-pattern N] [--seed S] [--spp N] [--target-spp N] [--tie T]\n"
                    "                           [--family-tie T] [--blur SIGMA] [--noise SIGMA] [--no-lattice]\n"
                    "       pattern MODEL SCENE --real DIR [--spp N] [--views]\n");
    return 1;
  }
  const char *mpath = argv[1], *real = NULL;
  int per = 2, target_spp = 0, views = 0;
  double blur = 0, noise = 0;
  uint64_t seed = 2022;
  wv_pattern_opts po;
  wv_pattern_opts_default(&po);
  for (int i = 3; i < argc; i++) {
    if (!strcmp(argv[i], "--per-pattern") && i + 1 < argc) per = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--seed") && i + 1 < argc) seed = strtoull(argv[++i], NULL, 10);
    else if (!strcmp(argv[i], "--spp") && i + 1 < argc) po.spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--tie") && i + 1 < argc) po.tie = atof(argv[++i]);
    else if (!strcmp(argv[i], "--family-tie") && i + 1 < argc) po.family_tie = atof(argv[++i]);
    else if (!strcmp(argv[i], "--target-spp") && i + 1 < argc) target_spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--blur") && i + 1 < argc) blur = atof(argv[++i]);
    else if (!strcmp(argv[i], "--noise") && i + 1 < argc) noise = atof(argv[++i]);
    else if (!strcmp(argv[i], "--real") && i + 1 < argc) real = argv[++i];
    else if (!strcmp(argv[i], "--no-lattice")) po.lattice = 0;
    else if (!strcmp(argv[i], "--views")) views = 1;
    else {
      fprintf(stderr, "pattern bench: unknown argument '%s'\n", argv[i]);
      return 1;
    }
  }
  if (views && !real) {
    fprintf(stderr, "pattern bench: --views needs --real DIR (the views are of photos)\n");
    return 1;
  }
  wv_error e = {0};
  wv_scene s;
  if (wv_scene_load(argv[2], &s, &e)) die(&e);
  wv_fabricnet net;
  wv_descriptor *d;
  if (wv_fabricnet_load(mpath, &net, &e) || wv_descriptor_create("default", NULL, &d, &e) ||
      wv_fabricnet_check(&net, mpath, wv_descriptor_name(d), wv_descriptor_size(d), &s, &e))
    die(&e);
  if (real) {
    int rc = run_real(&net, d, &s, real, &po, views);
    wv_descriptor_free(d);
    wv_fabricnet_free(&net);
    return rc;
  }
  /* The loss criterion runs for every candidate so that the choice under each pair of
   * margins can be replayed (wv_pattern_decide); the reported choice uses the options. */
  int nb = wv_weave_builtin_count(), total = nb * per;
  int right = 0, fam_right = 0, dir_right = 0, dir_total = 0, lat_fam = 0, rank_fam = 0, found = 0;
  int tie_right[NF][NT] = {{0}}, tie_fam[NF][NT] = {{0}}, conf[4][4] = {{0}};
  float *gram = malloc(sizeof(float) * wv_descriptor_size(d));
  double dens_err = 0;
  int dens_n = 0;
  double *secs = malloc(sizeof(double) * (size_t)total);
  wv_render_opts ro = {.spp = target_spp};
  for (int k = 0; k < total; k++) {
    int t = k % nb;
    const char *tname = wv_weave_builtin_name(t);
    wv_params truth;
    wv_image photo = {0};
    if (wv_params_sample_prior(tname, wv_hash4(seed, (uint64_t)t, (uint64_t)(k / nb), 7), &truth, &e) ||
        wv_render(&s, &truth, &ro, &photo, NULL, &e))
      die(&e);
    camera(&photo, blur, noise, wv_hash4(seed, (uint64_t)k, 3, 5));
    float y[WV_NET_OUT];
    wv_pattern_choice c;
    if (wv_fabricnet_predict_pattern(&net, d, &s, &photo, &po, y, &c, &e)) die(&e);
    /* the choice with the requested margin, and with every other one, from the same scores */
    int chosen = c.best;
    if (c.lattice.found) {
      if (wv_descriptor_forward(d, &photo, gram, &e)) die(&e);
      for (int i = 0; i < nb; i++)
        if (wv_pattern_loss(d, &s, &photo, gram, &po, i, &c, &e)) die(&e);
      for (int f = 0; f < NF; f++)
        for (int m = 0; m < NT; m++) {
          int b = wv_pattern_decide(&c, FTIES[f], TIES[m], NULL);
          tie_right[f][m] += b == t, tie_fam[f][m] += fam_index(wv_weave_builtin_name(b)) == fam_index(tname);
        }
      found++;
      lat_fam += fam_index(wv_weave_builtin_name(c.lattice.best)) == fam_index(tname);
      rank_fam += fam_index(wv_weave_builtin_name(c.ranking.best)) == fam_index(tname);
    }
    const char *cname = wv_weave_builtin_name(chosen);
    right += chosen == t;
    fam_right += fam_index(cname) == fam_index(tname);
    conf[fam_index(tname)][fam_index(cname)]++;
    if (twill_dir(tname)) {
      dir_total++;
      dir_right += twill_dir(cname) == twill_dir(tname);
    }
    if (chosen == t && c.lattice.found)
      for (int y2 = 0; y2 < 2; y2++, dens_n++)
        dens_err += fabs(c.lattice.fit[t].density[y2] - truth.density[y2]) / truth.density[y2];
    secs[k] = c.seconds;
    fprintf(stderr, "%-12s %6.1f/%6.1f -> %-12s (%s) lattice %s %6.1f/%6.1f (%.2f s)\n", tname, truth.density[0],
            truth.density[1], cname, c.method, c.lattice.found ? wv_weave_builtin_name(c.lattice.best) : "none",
            c.lattice.found ? c.lattice.fit[t].density[0] : 0.0, c.lattice.found ? c.lattice.fit[t].density[1] : 0.0,
            c.seconds);
    wv_image_free(&photo);
  }
  fprintf(stderr, "families (rows: truth, columns: chosen)\n%-8s", "");
  for (int j = 0; j < 4; j++) fprintf(stderr, " %7s", FAMILIES[j]);
  fprintf(stderr, "\n");
  for (int i = 0; i < 4; i++) {
    fprintf(stderr, "%-8s", FAMILIES[i]);
    for (int j = 0; j < 4; j++) fprintf(stderr, " %7d", conf[i][j]);
    fprintf(stderr, "\n");
  }
  printf("{\"mode\": \"synthetic\", \"model\": \"%s\", \"scene\": \"%s\", \"seed\": %llu, \"per_pattern\": %d, "
         "\"targets\": %d, \"target_spp\": %d, \"blur\": %g, \"noise\": %g, \"spp\": %d, \"tie\": %g, \"family_tie\": %g, "
         "\"pattern_right\": %.4f, \"family_right\": %.4f, \"twill_direction_right\": %.4f, "
         "\"lattice_found\": %.4f, \"family_right_lattice_alone\": %.4f, \"family_right_ranking_alone\": %.4f, "
         "\"density_rel_error_when_right\": %.4f, \"choice_seconds_median\": %.3f, \"by_margins\": {",
         mpath, s.name, (unsigned long long)seed, per, total, target_spp ? target_spp : s.spp, blur, noise, po.spp, po.tie, po.family_tie,
         (double)right / total, (double)fam_right / total, dir_total ? (double)dir_right / dir_total : 0.0,
         (double)found / total, found ? (double)lat_fam / found : 0.0, found ? (double)rank_fam / found : 0.0,
         dens_n ? dens_err / dens_n : 0.0, bench_median(secs, total));
  for (int f = 0; f < NF; f++)
    for (int m = 0; m < NT; m++)
      printf("%s\"family %g, pattern %g\": {\"pattern\": %.4f, \"family\": %.4f}", f || m ? ", " : "", FTIES[f],
             TIES[m], found ? (double)tie_right[f][m] / found : 0.0, found ? (double)tie_fam[f][m] / found : 0.0);
  printf("}");
  printf(", \"family_confusion\": {");
  for (int i = 0; i < 4; i++) {
    printf("%s\"%s\": [", i ? ", " : "", FAMILIES[i]);
    for (int j = 0; j < 4; j++) printf("%s%d", j ? ", " : "", conf[i][j]);
    printf("]");
  }
  printf("}}\n");
  free(secs), free(gram);
  wv_descriptor_free(d);
  wv_fabricnet_free(&net);
  return 0;
}
