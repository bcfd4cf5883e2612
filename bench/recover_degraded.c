/* Recovery study of the capture on synthetic targets made like the real photos of the flat45
 * rig: yarns 1 to 2.5 pixels apart, irregular cloths, and what a camera does to a photo.
 *   recover_degraded [--per-family N] [--first I] [--family NAME[,NAME...]] [--seed S]
 *                    [--degrade on|off] [--iters N] [--iter-spp N] [--iter-scale N]
 *                    [--w-struct X] [--lr X] [--threads N] [--jobs N] [--model M] [--save DIR]
 *                    [--shot-max A]
 * Targets: for each family (plain, basket, twill, satin; --family: those listed) draws I ..
 * I+N-1 (default 0 .. 7). Draw i of a family takes its built-in 3 i mod n (n built-ins in
 * wv_weave_builtin_name order: the first draws cover both orientations of the asymmetric
 * ones), a prior draw of it (wv_params_sample_prior) with its yarns set 1 to 2.5 pixels apart
 * (warp and weft drawn apart, uniform in pixels; the densities follow from the scene's
 * camera: flat45's 204 yarns/inch at one pixel) and its noise level drawn uniformly over
 * 0..10; every second draw is two-coloured (a dark blue warp, a near-white weft). Every
 * target depends on the seed, its family and its draw only, so runs over parts of the list
 * (--family, --first, --per-family) add up to the whole.
 * Degradations (--degrade on, the default), each with its own strength drawn from the
 * target's seed, applied in a camera's order to the render's linear radiance: a small
 * rotation (+-2 degrees) and a mild radial lens distortion (+-2% at the corners) in one
 * bilinear resampling (the view enlarged by a few percent so that no pixel samples outside
 * the render: the photo's densities are the drawn ones times the zoom, which the line and the
 * JSON compare the fit's with), a camera blur (Gaussian, sigma 0.5..1.5 px), sensor noise (variance
 * a x + b on the exposed signal x; a from 0.0003 up to 0.003, or up to --shot-max: a grainier
 * photo), then the scene's response, 8 bits and a JPEG round trip (libjpeg-turbo, quality
 * 75..95). --degrade off: the render quantised to 8 bits.
 * Each target is captured as `woven capture` captures a photo (the network's estimate, the
 * pattern choice, the fit) and measured by SSIM (per RGB channel, averaged) against the
 * ceiling: the true parameters rendered with the fit's noise seed instead of the target's,
 * through the same rotation, distortion and blur (what a capture can model) but without the
 * noise, the 8 bits and the JPEG. Also the target's blurred-copy SSIM (woven capture's
 * ssim_rgb_blurred_photo) and whether the fit scores below it, and the camera blur the
 * capture measured before its first iteration and the one it fitted, against the target's
 * (camera_blur per target; camera_blur_error_px, the mean absolute errors, overall).
 * --jobs N captures N targets at once in N processes (each with --threads render threads;
 * give both, e.g. --jobs 2 --threads 1). Prints one line per target as it finishes, then one
 * JSON object on the last line: per target, per family and overall. --save DIR writes each
 * target as DIR/<family>_<draw>_<pattern>.png (an existing directory), its true parameters
 * as <family>_<draw>_truth.json and the capture's as <family>_<draw>_fit.json. */
#define _DEFAULT_SOURCE /* fork, pipe, poll, M_PI */
#define RECOVER_NAME "recover_degraded"
#include "recover_common.h"

#include <errno.h>
#include <jansson.h>
#include <omp.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/nn.h"

#define NFAM 4
static const char *const FAMILIES[NFAM] = {"plain", "basket", "twill", "satin"};

/* The target's draw. */
#define SPACING_LO 1.0 /* yarn spacing in pixels, as the photos show it (scenes/flat45.json) */
#define SPACING_HI 2.5
#define NOISE_LEVEL_MAX 10 /* the parameter's whole range */
/* The degradations' strengths, uniform between these. */
#define DEG_ROTATION 2.0          /* degrees, either way */
#define DEG_LENS 0.02             /* k of the radial distortion, either way */
#define DEG_BLUR_LO 0.5           /* camera blur sigma, pixels */
#define DEG_BLUR_HI 1.5
#define DEG_SHOT_LO 3e-4          /* noise variance a x + b: a */
#define DEG_SHOT_HI 3e-3
#define DEG_READ_HI 2e-5          /* ... b from 0 */
#define DEG_JPEG_LO 75            /* JPEG quality */
#define DEG_JPEG_HI 95

typedef struct {
  double rotation_deg, lens_k, blur_px, noise_a, noise_b;
  double zoom; /* the view's enlargement (degrade_geometry): the photo's yarns lie 1 / zoom times
                * further apart than the drawn spacing, its densities zoom times the drawn ones */
  int jpeg_quality;
} degradation;

/* One target's draw and what its capture gave; written whole through a pipe by a job. */
typedef struct {
  int index, fam, draw, two_colour, noise_level, fit_noise_level, family_right, below_blurred_copy;
  char pattern[16], chosen[16], family_kind[20];
  int fam_pattern[NFAM], fam_order[NFAM];
  double fam_score[NFAM];
  double density[2], spacing_px[2], fit_density[2];
  double ssim_fit, ssim_ceiling, ratio, wsc_fit, wsc_ceiling, ssim_blurred_copy, seconds;
  double blur_start, blur_fit; /* the capture's camera blur: measured at the start, fitted (px) */
  degradation deg;
} result;

typedef struct {
  int degrade;
  uint64_t seed;
  double ypi_one_px; /* yarns per inch of yarns one pixel apart at the image centre */
  const char *save;  /* a directory for the targets (PNG), or NULL */
  double shot_hi;    /* the shot noise's a is drawn over DEG_SHOT_LO .. shot_hi */
} plan;

static double uni(uint64_t seed, uint64_t k, double lo, double hi) {
  return lo + (hi - lo) * wv_u01d(wv_hash2(seed, k, 0x756e69));
}

static void draw_degradation(uint64_t seed, double shot_hi, degradation *d) {
  d->rotation_deg = uni(seed, 1, -DEG_ROTATION, DEG_ROTATION);
  d->lens_k = uni(seed, 2, -DEG_LENS, DEG_LENS);
  d->blur_px = uni(seed, 3, DEG_BLUR_LO, DEG_BLUR_HI);
  d->noise_a = uni(seed, 4, DEG_SHOT_LO, shot_hi);
  d->noise_b = uni(seed, 5, 0, DEG_READ_HI);
  d->jpeg_quality = DEG_JPEG_LO + (int)floor(uni(seed, 6, 0, DEG_JPEG_HI - DEG_JPEG_LO + 1 - 1e-9));
}

/* Where output pixel (x, y) of a w x h image looks in the input: turned by the rotation about
 * the centre, its radius r (in half-diagonals) seen at r (1 + k r^2), and drawn toward the
 * centre by zoom. */
static void geometry_map(double x, double y, int w, int h, double c, double s, double k, double zoom, double *u,
                         double *v) {
  double half = 0.5 * sqrt((double)w * w + (double)h * h);
  double a = (x + 0.5 - 0.5 * w) / half, b = (y + 0.5 - 0.5 * h) / half, f = 1 + k * (a * a + b * b);
  a *= f, b *= f;
  *u = zoom * (c * a - s * b) * half + 0.5 * w - 0.5;
  *v = zoom * (s * a + c * b) * half + 0.5 * h - 0.5;
}

/* A small rotation and a radial lens distortion in one bilinear resampling (two would blur
 * yarns a pixel apart twice); the view is enlarged just enough (a few percent) that every
 * pixel samples inside the input, so no edge is smeared or invented. */
static double geometry_zoom(int w, int h, double rotation_deg, double k) {
  double c = cos(rotation_deg * M_PI / 180), s = sin(rotation_deg * M_PI / 180), zoom = 1, u, v;
  for (int t = 0; t < 2 * (w + h); t++) { /* the border's pixels; the map keeps the inside within them */
    int x = t < w ? t : t < 2 * w ? t - w : t < 2 * w + h ? 0 : w - 1;
    int y = t < w ? 0 : t < 2 * w ? h - 1 : t < 2 * w + h ? t - 2 * w : t - 2 * w - h;
    geometry_map(x, y, w, h, c, s, k, 1, &u, &v);
    double du = fabs(u - 0.5 * (w - 1)), dv = fabs(v - 0.5 * (h - 1));
    if (du > 1e-9 && 0.5 * (w - 1) / du < zoom) zoom = 0.5 * (w - 1) / du;
    if (dv > 1e-9 && 0.5 * (h - 1) / dv < zoom) zoom = 0.5 * (h - 1) / dv;
  }
  return zoom;
}

static wv_status degrade_geometry(const wv_image *in, double rotation_deg, double k, wv_image *out, wv_error *err) {
  int w = in->w, h = in->h, nc = in->c;
  double c = cos(rotation_deg * M_PI / 180), s = sin(rotation_deg * M_PI / 180), u, v;
  double zoom = geometry_zoom(w, h, rotation_deg, k);
  wv_status st = wv_image_alloc(out, w, h, nc, err);
  if (st) return st;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      geometry_map(x, y, w, h, c, s, k, zoom, &u, &v);
      bench_bilinear(in, u, v, wv_image_px(out, x, y)); /* holding (u, v) inside: rounding only */
    }
  return WV_OK;
}

/* Sensor noise on the exposed linear signal x = exposure * radiance: Gaussian of variance
 * a x + b (shot noise grows with the signal, read noise does not); in place. */
static void degrade_noise(wv_image *radiance, double exposure, double a, double b, uint64_t seed) {
  wv_rng r;
  wv_rng_seed(&r, seed);
  double ex = exposure > 0 ? exposure : 1;
  size_t n = (size_t)radiance->w * radiance->h * radiance->c;
  for (size_t i = 0; i < n; i++) {
    double x = ex * radiance->data[i];
    x += sqrt(a * (x > 0 ? x : 0) + b) * wv_rng_normal(&r);
    radiance->data[i] = (float)((x > 0 ? x : 0) / ex);
  }
}

/* What the camera records of a render's radiance: geometry and blur; with photo also the
 * sensor noise, then the scene's response, 8 bits and the JPEG round trip. */
static void camera(const wv_scene *s, const wv_image *radiance, const degradation *d, uint64_t noise_seed, int photo,
                   wv_image *out) {
  wv_error err = {0};
  wv_image warped, blurred, cap;
  if (degrade_geometry(radiance, d->rotation_deg, d->lens_k, &warped, &err) ||
      wv_image_blur(&warped, d->blur_px, &blurred, &err))
    die(&err);
  wv_image_free(&warped);
  if (photo) degrade_noise(&blurred, s->exposure, d->noise_a, d->noise_b, noise_seed);
  if (wv_image_alloc(&cap, blurred.w, blurred.h, 3, &err)) die(&err);
  wv_scene_response(s, &blurred, &cap);
  wv_image_free(&blurred);
  if (!photo) {
    *out = cap;
    return;
  }
  wv_image_quantise8(&cap);
  if (wv_image_jpeg_roundtrip(&cap, d->jpeg_quality, out, &err)) die(&err);
  wv_image_free(&cap);
}

/* A render of p in s through the camera (or, without degradations, as the scene records it). */
static void shoot(const study *st, const plan *pl, const wv_params *p, const degradation *d, uint64_t noise_seed,
                  int photo, wv_image *out) {
  wv_render_opts ro = {.threads = st->o.threads};
  wv_image img, rad;
  wv_error err = {0};
  if (wv_render(st->s, p, &ro, &img, pl->degrade ? &rad : NULL, &err)) die(&err);
  if (!pl->degrade) {
    if (photo) wv_image_quantise8(&img);
    *out = img;
    return;
  }
  wv_image_free(&img);
  camera(st->s, &rad, d, noise_seed, photo, out);
  wv_image_free(&rad);
}

/* The family's built-ins in wv_weave_builtin_name order; returns how many. */
static int members(int fam, int *idx) {
  int n = 0;
  for (int i = 0; i < wv_weave_builtin_count(); i++)
    if (!strcmp(wv_weave_family(wv_weave_builtin_name(i)), FAMILIES[fam])) idx[n++] = i;
  return n;
}

static void run_target(const study *st, const plan *pl, int index, int fam, int draw, result *r) {
  wv_error err = {0};
  memset(r, 0, sizeof *r);
  r->index = index, r->fam = fam, r->draw = draw, r->two_colour = draw % 2 == 1;
  int idx[WV_WEAVE_BUILTINS], n = members(fam, idx);
  snprintf(r->pattern, sizeof r->pattern, "%s", wv_weave_builtin_name(idx[(3 * draw) % n]));
  uint64_t ts = wv_hash4(pl->seed, (uint64_t)fam, (uint64_t)draw, 0x646567);
  wv_params target;
  if (wv_params_sample_prior(r->pattern, ts, &target, &err)) die(&err);
  for (int y = 0; y < 2; y++) {
    r->spacing_px[y] = uni(ts, 10 + (uint64_t)y, SPACING_LO, SPACING_HI);
    target.density[y] = r->density[y] = pl->ypi_one_px / r->spacing_px[y];
  }
  target.noise_level = r->noise_level = (int)fmin(floor(uni(ts, 12, 0, NOISE_LEVEL_MAX + 1)), NOISE_LEVEL_MAX);
  if (r->two_colour) two_colour(&target, ts);
  if (wv_params_validate(&target, &err)) die(&err);
  draw_degradation(wv_hash2(ts, 13, 0x646567), pl->shot_hi, &r->deg);
  r->deg.zoom = pl->degrade ? geometry_zoom(st->s->width, st->s->height, r->deg.rotation_deg, r->deg.lens_k) : 1;
  wv_image photo, ceiling;
  shoot(st, pl, &target, &r->deg, wv_hash2(ts, 14, 0x646567), 1, &photo);
  if (pl->save) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s_%d_%s.png", pl->save, FAMILIES[fam], draw, r->pattern);
    if (wv_image_write_png(path, &photo, 8, &err)) die(&err);
    snprintf(path, sizeof path, "%s/%s_%d_truth.json", pl->save, FAMILIES[fam], draw);
    if (wv_params_write(path, &target, &err)) die(&err);
  }
  capture c;
  run_capture(st, &photo, NULL, &c);
  if (pl->save) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s_%d_fit.json", pl->save, FAMILIES[fam], draw);
    if (wv_params_write(path, &c.fit, &err)) die(&err);
  }
  snprintf(r->chosen, sizeof r->chosen, "%s", c.chosen);
  r->family_right = !strcmp(wv_weave_family(c.chosen), FAMILIES[fam]);
  snprintf(r->family_kind, sizeof r->family_kind, "%s", c.families.kind);
  for (int f = 0; f < NFAM; f++)
    r->fam_pattern[f] = c.families.pattern[f], r->fam_score[f] = c.families.score[f], r->fam_order[f] = c.families.order[f];
  r->fit_density[0] = c.fit.density[0], r->fit_density[1] = c.fit.density[1], r->fit_noise_level = c.fit.noise_level;
  r->blur_start = c.blur_start, r->blur_fit = c.fit_scene.psf_sigma;
  double wsc[2];
  measure(&c.fit_scene, &c.fit, &photo, st->o.threads, &r->ssim_fit, NULL, wsc, 0, NULL);
  r->wsc_fit = wsc[0];
  /* the ceiling: the truth with the fit's noise seed, through what a capture can model */
  wv_params oracle = target;
  oracle.seed = c.fit.seed;
  shoot(st, pl, &oracle, &r->deg, 0, 0, &ceiling);
  measure_image(&ceiling, &photo, &r->ssim_ceiling, NULL, wsc, 0, NULL);
  r->wsc_ceiling = wsc[0];
  r->ratio = r->ssim_fit / r->ssim_ceiling;
  if (wv_blurred_copy_ssim(&photo, WV_BLURRED_COPY_SIGMA, &r->ssim_blurred_copy, &err)) die(&err);
  r->below_blurred_copy = r->ssim_fit < r->ssim_blurred_copy;
  r->seconds = c.seconds;
  wv_image_free(&photo), wv_image_free(&ceiling);
}

static void print_line(const plan *pl, const result *r) {
  printf("%-7s %d %-12s%s -> %-12s %-5s SSIM fit %.4f ceiling %.4f (%.3f)  blurred copy %.4f%s  "
         "spacing %.2f/%.2f px density fit / photo %.3f/%.3f Q %d -> %d",
         FAMILIES[r->fam], r->draw, r->pattern, r->two_colour ? " two-colour" : "", r->chosen,
         r->family_right ? "ok" : "WRONG", r->ssim_fit, r->ssim_ceiling, r->ratio, r->ssim_blurred_copy,
         r->below_blurred_copy ? " (fit below)" : "", r->spacing_px[0], r->spacing_px[1],
         r->fit_density[0] / (r->density[0] * r->deg.zoom), r->fit_density[1] / (r->density[1] * r->deg.zoom),
         r->noise_level, r->fit_noise_level);
  if (pl->degrade)
    printf("  rot %+.2f lens %+.3f blur %.2f (start %.2f, fit %.2f) noise %.1e/%.1e jpeg %d", r->deg.rotation_deg,
           r->deg.lens_k, r->deg.blur_px, r->blur_start, r->blur_fit, r->deg.noise_a, r->deg.noise_b,
           r->deg.jpeg_quality);
  printf("  %.1f s\n", r->seconds);
  fflush(stdout);
}

static json_t *target_json(const plan *pl, const result *r) {
  json_t *fs = json_object();
  for (int k = 0; k < NFAM; k++) { /* best first */
    int f = r->fam_order[k];
    if (r->fam_pattern[f] >= 0)
      json_object_set_new(fs, FAMILIES[f], json_pack("{s:s,s:f}", "pattern", wv_weave_builtin_name(r->fam_pattern[f]),
                                                     "score", r->fam_score[f]));
  }
  json_t *o = json_pack("{s:s,s:i,s:s,s:b,s:s,s:s,s:b,s:f,s:f,s:f,s:f,s:f,s:f,s:b,s:o,s:s}", "family",
                        FAMILIES[r->fam], "draw", r->draw, "pattern", r->pattern, "two_colour", r->two_colour,
                        "chosen", r->chosen, "family_chosen", wv_weave_family(r->chosen), "family_right",
                        r->family_right, "ssim_fit", r->ssim_fit, "ssim_ceiling", r->ssim_ceiling, "ratio", r->ratio,
                        "wsc_fit", r->wsc_fit, "wsc_ceiling", r->wsc_ceiling, "ssim_blurred_copy", r->ssim_blurred_copy,
                        "below_blurred_copy", r->below_blurred_copy, "family_scores", fs, "family_score_kind",
                        r->family_kind);
  json_object_set_new(o, "truth", json_pack("{s:[f,f],s:[f,f],s:[f,f],s:i}", "density", r->density[0],
                                            r->density[1], "density_in_photo", r->density[0] * r->deg.zoom,
                                            r->density[1] * r->deg.zoom, "spacing_px", r->spacing_px[0],
                                            r->spacing_px[1], "noise_level", r->noise_level));
  json_object_set_new(o, "fit_density", json_pack("[f,f]", r->fit_density[0], r->fit_density[1]));
  json_object_set_new(o, "fit_noise_level", json_integer(r->fit_noise_level));
  json_object_set_new(o, "camera_blur", json_pack("{s:f,s:f}", "start", r->blur_start, "fit", r->blur_fit));
  json_object_set_new(o, "degradation",
                      pl->degrade ? json_pack("{s:f,s:f,s:f,s:f,s:f,s:f,s:i}", "rotation_deg", r->deg.rotation_deg,
                                              "zoom", r->deg.zoom,
                                              "lens_k", r->deg.lens_k, "blur_px", r->deg.blur_px, "noise_a",
                                              r->deg.noise_a, "noise_b", r->deg.noise_b, "jpeg_quality",
                                              r->deg.jpeg_quality)
                                  : json_null());
  json_object_set_new(o, "capture_s", json_real(r->seconds));
  return o;
}

/* The study's own copy of the model, descriptor and options (each job loads its own). */
typedef struct {
  study st;
  wv_scene scene;
  wv_fabricnet net;
} job_state;

static void job_open(job_state *js, const wv_scene *s, const wv_fit_opts *o, const char *model) {
  wv_error err = {0};
  js->scene = *s;
  js->st.s = &js->scene, js->st.o = *o, js->st.orient = 1, js->st.refine = 1;
  if (wv_descriptor_create_default(&js->st.d, &err)) die(&err);
  char mpath[4096];
  if (model) snprintf(mpath, sizeof mpath, "%s", model);
  else snprintf(mpath, sizeof mpath, "%s/models/fabricnet-%s.bin", WOVEN_SOURCE_DIR, s->name);
  if (wv_fabricnet_load(mpath, &js->net, &err) ||
      wv_fabricnet_check(&js->net, mpath, wv_descriptor_name(js->st.d), wv_descriptor_size(js->st.d), s, &err))
    die(&err);
  js->st.net = &js->net;
}

static void job_close(job_state *js) {
  wv_fabricnet_free(&js->net);
  wv_descriptor_free(js->st.d);
}

static int read_full(int fd, void *buf, size_t n) {
  size_t got = 0;
  while (got < n) {
    ssize_t k = read(fd, (char *)buf + got, n - got);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return got == 0 ? 0 : -1;
    got += (size_t)k;
  }
  return 1;
}

/* The targets over jobs processes, forked before any OpenMP team exists in this one; each
 * result arrives whole (one write of less than PIPE_BUF bytes). Returns the number received. */
static int run_jobs(const wv_scene *s, const wv_fit_opts *o, const char *model, const plan *pl, int jobs,
                    const int (*targets)[2], int nt, result *res) {
  int fds[64], alive = 0, got = 0;
  pid_t pids[64];
  fflush(stdout), fflush(stderr);
  for (int j = 0; j < jobs; j++) {
    int p[2];
    if (pipe(p)) {
      perror(RECOVER_NAME ": pipe");
      exit(1);
    }
    pid_t pid = fork();
    if (pid < 0) {
      perror(RECOVER_NAME ": fork");
      exit(1);
    }
    if (pid == 0) {
      close(p[0]);
      for (int k = 0; k < j; k++) close(fds[k]);
      if (o->threads > 0) omp_set_num_threads(o->threads);
      job_state js;
      job_open(&js, s, o, model);
      for (int t = j; t < nt; t += jobs) {
        result r;
        run_target(&js.st, pl, t, targets[t][0], targets[t][1], &r);
        if (write(p[1], &r, sizeof r) != (ssize_t)sizeof r) _exit(1);
      }
      job_close(&js);
      _exit(0);
    }
    close(p[1]);
    fds[j] = p[0], pids[j] = pid, alive++;
  }
  struct pollfd pf[64];
  while (alive > 0) {
    int np = 0, map[64];
    for (int j = 0; j < jobs; j++)
      if (fds[j] >= 0) pf[np].fd = fds[j], pf[np].events = POLLIN, map[np++] = j;
    if (poll(pf, (nfds_t)np, -1) < 0) {
      if (errno == EINTR) continue;
      perror(RECOVER_NAME ": poll");
      exit(1);
    }
    for (int k = 0; k < np; k++) {
      if (!(pf[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      result r;
      int rc = read_full(pf[k].fd, &r, sizeof r);
      if (rc == 1 && r.index >= 0 && r.index < nt) {
        res[r.index] = r, got++;
        print_line(pl, &r);
      } else {
        close(pf[k].fd);
        fds[map[k]] = -1, alive--;
      }
    }
  }
  int failed = 0;
  for (int j = 0; j < jobs; j++) {
    int status;
    if (waitpid(pids[j], &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status)) failed = 1;
  }
  if (failed) {
    fprintf(stderr, "%s: a job failed (its message is above)\n", RECOVER_NAME);
    exit(1);
  }
  return got;
}

/* yarns per inch of yarns one pixel apart at the image centre of a plane seen square on */
static double ypi_one_px(const wv_scene *s) {
  double d = 0;
  for (int k = 0; k < 3; k++) d += (s->cam_pos[k] - s->cam_look_at[k]) * (s->cam_pos[k] - s->cam_look_at[k]);
  double mm_per_px = 2 * sqrt(d) * tan(0.5 * s->vfov_deg * M_PI / 180) / s->height * s->mm_per_unit;
  return 25.4 / mm_per_px;
}

static int usage(void) {
  fprintf(stderr, "usage: recover_degraded [--per-family N] [--first I] [--family NAME[,NAME...]] [--seed S]\n"
                  "                        [--degrade on|off] [--iters N] [--iter-spp N] [--iter-scale N]\n"
                  "                        [--w-struct X] [--lr X] [--threads N] [--jobs N] [--model M]\n"
                  "                        [--save DIR] [--shot-max A]\n");
  return 1;
}

int main(int argc, char **argv) {
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  int per = 8, first = 0, jobs = 1, fam_on[NFAM] = {1, 1, 1, 1};
  plan pl = {.degrade = 1, .seed = 1, .shot_hi = DEG_SHOT_HI};
  const char *model = NULL;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!v) return usage();
    i++;
    if (!strcmp(a, "--per-family")) per = atoi(v);
    else if (!strcmp(a, "--first")) first = atoi(v);
    else if (!strcmp(a, "--seed")) pl.seed = strtoull(v, NULL, 10);
    else if (!strcmp(a, "--iters")) o.iters = atoi(v);
    else if (!strcmp(a, "--iter-spp")) o.iter_spp = atoi(v);
    else if (!strcmp(a, "--iter-scale")) o.iter_scale = atoi(v);
    else if (!strcmp(a, "--w-struct")) o.w_struct = atof(v);
    else if (!strcmp(a, "--lr")) o.lr = atof(v);
    else if (!strcmp(a, "--threads")) o.threads = atoi(v);
    else if (!strcmp(a, "--jobs")) jobs = atoi(v);
    else if (!strcmp(a, "--model")) model = v;
    else if (!strcmp(a, "--save")) pl.save = v;
    else if (!strcmp(a, "--shot-max")) pl.shot_hi = atof(v);
    else if (!strcmp(a, "--degrade")) {
      if (strcmp(v, "on") && strcmp(v, "off")) return usage();
      pl.degrade = !strcmp(v, "on");
    } else if (!strcmp(a, "--family")) {
      char buf[256];
      snprintf(buf, sizeof buf, "%s", v);
      for (int f = 0; f < NFAM; f++) fam_on[f] = 0;
      for (char *t = strtok(buf, ","); t; t = strtok(NULL, ",")) {
        int f = 0;
        while (f < NFAM && strcmp(t, FAMILIES[f])) f++;
        if (f == NFAM) {
          fprintf(stderr, "recover_degraded: '%s' is not a family (plain, basket, twill, satin)\n", t);
          return 1;
        }
        fam_on[f] = 1;
      }
    } else {
      return usage();
    }
  }
  if (per < 1 || first < 0 || o.iters < 0 || jobs < 1 || jobs > 64 || o.threads < 0 ||
      !(pl.shot_hi >= DEG_SHOT_LO && pl.shot_hi <= 0.1)) {
    fprintf(stderr, "recover_degraded: --per-family at least 1, --first and --iters not negative, --jobs 1..64, "
                    "--shot-max 3e-4..0.1\n");
    return 1;
  }
  wv_error err = {0};
  if (wv_fit_opts_validate(&o, &err)) die(&err);
  wv_scene s;
  if (wv_scene_load("flat45", &s, &err)) die(&err);
  pl.ypi_one_px = ypi_one_px(&s);
  int (*targets)[2] = malloc(sizeof *targets * NFAM * (size_t)per), nt = 0;
  result *res = calloc((size_t)NFAM * (size_t)per, sizeof *res);
  if (!targets || !res) return 1;
  for (int f = 0; f < NFAM; f++)
    for (int i = first; i < first + per && fam_on[f]; i++) targets[nt][0] = f, targets[nt][1] = i, nt++;
  if (jobs > nt) jobs = nt;
  if (jobs > 1) {
    if (run_jobs(&s, &o, model, &pl, jobs, (const int(*)[2])targets, nt, res) != nt) {
      fprintf(stderr, "recover_degraded: a job ended early\n");
      return 1;
    }
  } else {
    job_state js;
    job_open(&js, &s, &o, model);
    for (int t = 0; t < nt; t++) {
      run_target(&js.st, &pl, t, targets[t][0], targets[t][1], &res[t]);
      print_line(&pl, &res[t]);
    }
    job_close(&js);
  }
  /* per family and overall */
  json_t *list = json_array(), *fams = json_object();
  int right = 0;
  double sum = 0, lo = INFINITY, blur_err[2] = {0, 0}; /* mean |camera blur - the target's|: start, fit */
  for (int t = 0; t < nt; t++) {
    json_array_append_new(list, target_json(&pl, &res[t]));
    right += res[t].family_right, sum += res[t].ratio, lo = fmin(lo, res[t].ratio);
    blur_err[0] += fabs(res[t].blur_start - res[t].deg.blur_px) / nt;
    blur_err[1] += fabs(res[t].blur_fit - res[t].deg.blur_px) / nt;
  }
  for (int f = 0; f < NFAM; f++) {
    int n = 0, fr = 0;
    double fs = 0, fl = INFINITY;
    for (int t = 0; t < nt; t++)
      if (res[t].fam == f) n++, fr += res[t].family_right, fs += res[t].ratio, fl = fmin(fl, res[t].ratio);
    if (n)
      json_object_set_new(fams, FAMILIES[f], json_pack("{s:i,s:f,s:f,s:f}", "targets", n, "family_right",
                                                       (double)fr / n, "mean_ratio", fs / n, "min_ratio", fl));
  }
  json_t *out = json_pack("{s:s,s:s,s:I,s:b,s:f,s:i,s:i,s:i,s:i,s:i,s:f,s:f,s:i,s:f,s:f,s:f,s:o,s:o}", "mode", "degraded",
                          "scene", s.name, "seed", (json_int_t)pl.seed, "degrade", pl.degrade, "shot_max",
                          pl.shot_hi, "per_family", per, "first", first, "iters", o.iters, "iter_spp", o.iter_spp, "iter_scale", o.iter_scale,
                          "w_struct", o.w_struct, "lr", o.lr, "targets", nt, "family_right_pct", 100.0 * right / nt,
                          "mean_ratio", sum / nt, "min_ratio", lo, "families", fams, "per_target", list);
  if (pl.degrade)
    json_object_set_new(out, "camera_blur_error_px", json_pack("{s:f,s:f}", "start", blur_err[0], "fit", blur_err[1]));
  char *text = json_dumps(out, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(6));
  json_decref(out);
  if (!text) return 1;
  printf("%s\n", text);
  free(text);
  free(targets), free(res);
  return 0;
}
