/* woven: refine fabric parameters from a photo by differentiable rendering
 * (paper section 4.3, SPEC section 7).
 *   L = L_g + w1 L_p + w2 L_c + w3 L_s + w4 L_k
 *   L_g = mean |Gram(photo) - Gram(render)|        (the texture descriptor)
 *   L_p = sum over warp, weft of (beta - mu)^2 / (2 sigma^2)   (pattern prior)
 *   L_c = mean |down(photo) - down(render)|        (area average to 16 x 8)
 *   L_s = the weave's log power spectrum in the yarn band (phase-invariant structure;
 *         include/woven/loss.h)
 *   L_k = how the colour of the pixel-scale detail varies (include/woven/loss.h)
 * Adam on the continuous parameters (normalised to [0,1] by their ranges, kept
 * inside them), the twist included (we have its gradient); every few iterations
 * a random step of a discrete parameter (noise level Q, warp or weft density) is
 * kept only if the loss drops. */
#ifndef WOVEN_FIT_H
#define WOVEN_FIT_H

#include <stdint.h>

#include "woven/descriptor.h"
#include "woven/error.h"
#include "woven/image.h"
#include "woven/nn.h"
#include "woven/params.h"
#include "woven/scene.h"

typedef struct {
  int iters;          /* 200 */
  double lr;          /* Adam learning rate in normalised units: 0.02 */
  double w_prior;     /* w1 = 0.0005 */
  double w_pixel;     /* w2 = 0.2 */
  double w_struct;    /* w3 = WV_FIT_W_STRUCT (0: no structure term) */
  double w_colour;    /* w4 = WV_FIT_W_COLOUR (0: no detail-colour term) */
  int colour_split;   /* 1 (default): before the first iteration, try starts that split warp and weft colours */
  int down_w, down_h; /* 16 x 8 */
  int discrete_every; /* 5 (0: no discrete search) */
  int density_steps;  /* 1: the discrete search steps the densities too (1); 0: the noise level
                       * alone (a capture whose weave analysis measured the densities) */
  int iter_scale;     /* iterate on the image downscaled by this factor (1) */
  int iter_spp;       /* samples per pixel while iterating (4) */
  uint64_t seed;      /* random steps of the discrete search */
  int threads;        /* 0: all cores */
  int checkpoint_every; /* 10 */
  int align_radius;   /* density alignment: search +-this many yarns/inch (230: the whole range; 0 = off) */
  int register_radius; /* registration: whole-yarn grid +-this many yarns/inch around the fit (6; 0 = off) */
  int distort_degree;  /* the cloth's distortion after the registration, a plane scene's: the
                        * polynomial's degree (3; 0 = off; wv_fit_distort) */
  double psf_sigma;   /* camera blur in pixels: WV_FIT_PSF_AUTO (-1, the default) measures it from the
                       * photo (wv_psf_estimate) unless the scene gives one; >= 0: this sigma */
  int psf_fit;        /* 1: a measured blur is then fitted with the parameters, by its gradient (1);
                       * 0: it stays as measured. A given blur is never fitted. */
  int schedule;       /* 1: a first stage iterates on the centre window of 1/WV_FIT_WINDOW_DIV of
                       * each side (when the fit holds it) for at most WV_FIT_WINDOW_SHARE of the
                       * iterations, the second on the whole image; 0 (default): one stage, the whole image */
  int noise_sweep;    /* 1: when the iterations end, every noise level 0..10 is rendered and the one with
                       * the lowest loss kept (1); 0: the noise level moves by the discrete steps alone */
  int width_sweep;    /* a photo pair: 1: the yarn width (the open gaps) is set before the first iteration to
                       * the open area the back-lit photo's gap glow measures (wv_open_area_measure), or, in a
                       * back-lit scene without a glow, searched on the pair's loss when the iterations end,
                       * after the noise sweep (1); 0: it stays at its start */
  int forward_sweep;  /* a photo pair: 1: whether the back-lit photo shows a forward band, and its width over
                       * WV_FIT_FORWARD_WIDTHS, is searched before the transmission colours' start and, where
                       * none is found, after it (1); 0: the band stays as it starts */
  int patience;       /* the stopping rule (wv_fit_converged): a stage ends when its smoothed loss has not
                       * fallen by WV_FIT_MIN_GAIN in this many iterations, and the last stage ends the
                       * iterations (WV_FIT_PATIENCE; 0: every stage runs to its limit, `iters` in all) */
} wv_fit_opts;

void wv_fit_opts_default(wv_fit_opts *o);
#define WV_FIT_PSF_AUTO -1.0
#define WV_FIT_W_STRUCT 0.0 /* the structure term's weight: off by default (docs/fit.md: why) */
#define WV_FIT_W_COLOUR 0.1   /* the detail-colour term's weight (docs/fit.md: how it was chosen) */

/* The schedule (docs/fit.md, "Schedule and stopping rule"). */
#define WV_FIT_WINDOW_DIV 2      /* the first stage's window: this fraction of each side */
#define WV_FIT_WINDOW_SHARE 0.3  /* ... for at most this share of the iterations */
#define WV_FIT_SMOOTH 5          /* the smoothed loss: the mean of this many consecutive losses */
#define WV_FIT_MIN_GAIN 0.01     /* a relative fall of the smoothed loss that counts as progress */
#define WV_FIT_PATIENCE 10       /* the default patience (0: every iteration runs; docs/measurements.md) */
#define WV_FIT_LR_T_SCALE 3      /* a back-lit photo fitted alone: the transmission colours' learning
                                  * rate, this times lr (docs/fit.md) */
#define WV_FIT_T_SHARE 0.25      /* a pair: the share of the iterations left to the transmission
                                  * colours, and the most they take (docs/fit.md, "Photo pairs") */
#define WV_FIT_T_STEP0 0.1       /* a pair: the transmission colours' first step, in units of their
                                  * range, along the steepest descent (a larger one is cut back) */
#define WV_FIT_T_PROBE 20        /* a pair: steps of the colours' descent from each of their two best
                                  * starts before one is chosen (docs/fit.md, "Photo pairs") */
#define WV_FIT_FORWARD_WIDTHS {0.1, 0.2, 0.4, 0.8} /* a pair: the forward band's widths searched, the
                                  * prior's range in steps of two (docs/fit.md, "Photo pairs") */

/* Ranges of the options (the command line and checkpoints are held to them). */
#define WV_FIT_MAX_ITERS 100000
#define WV_FIT_MAX_ITER_SCALE 16
#define WV_FIT_MAX_ALIGN_RADIUS 230
#define WV_FIT_MAX_REGISTER_RADIUS 50
/* Every option within its range (iter_spp 1..WV_SCENE_MAX_SPP, down_w and down_h
 * 1..1024, ...); the message names the option. */
wv_status wv_fit_opts_validate(const wv_fit_opts *o, wv_error *err);

/* The smallest scene image a fit accepts (SSIM needs 11 x 11 windows; the
 * descriptor and the 16 x 8 pixel loss need a little more). */
#define WV_FIT_MIN_SIDE 32

/* Can the scene be fitted with descriptor d (NULL: not checked) and these options?
 * The image must be at least WV_FIT_MIN_SIDE and the descriptor's minimum per
 * side, and so must the image at the iteration scale (and hold the pixel loss's
 * down_w x down_h). Checked by wv_fit_run; call it before writing anything. */
wv_status wv_fit_check_sizes(const wv_scene *s, const wv_descriptor *d, const wv_fit_opts *o, wv_error *err);

/* One iteration's record. */
typedef struct {
  int iter;
  double loss, gram, prior, pixel, structure, colour;
  int discrete_tried, discrete_kept;
  double loss_t; /* a pair: the transmission photo's part of loss (0 for one photo) */
  int t_alone;   /* a pair's iteration on the transmission photo alone (loss = loss_t): its colours
                  * the only parameters stepped */
} wv_fit_record;

/* Time spent, seconds. */
typedef struct {
  double render, gradient, descriptor, discrete, registration, distortion, total;
} wv_fit_timing;

/* The stopping rule on the iterations from .. to - 1 of log (one stage): S_j, the mean of
 * the WV_FIT_SMOOTH losses ending at j (all within the stage), has not fallen in the last
 * `patience` iterations: the least S_j there is not below (1 - WV_FIT_MIN_GAIN) times the
 * least S_j before them. Once the range holds a pair's iterations on the transmission photo
 * alone (t_alone), the rule reads those alone, on loss_t; otherwise a log that holds both
 * photos' losses judges them apart (loss - loss_t and loss_t): both must have stopped
 * falling. Needs at least patience + WV_FIT_SMOOTH iterations; 0 when patience <= 0. It
 * reads the losses alone, so a resumed fit stops where a straight one does. */
int wv_fit_converged(const wv_fit_record *log, int from, int to, int patience);

/* Everything needed to continue a fit: parameters, Adam moments, RNG, history. */
typedef struct {
  wv_params start, params;
  int iter; /* iterations done */
  int aligned; /* the density alignment after the last iteration is done */
  int colour_split; /* the start's colours: 0 as given, 1..4 split (darker on the warp: 1, 3; weft: 2, 4; 3, 4 twice
                     * as far), 5 both the start's mean */
  double align_ssim_before, align_ssim_after; /* its criterion at the start and end */
  double align_wsc_before, align_wsc_after; /* the whole image's WSC without and with the densities it found
                                             * (kept only if it does not fall; -2: not measured) */
  int registered; /* the registration after the alignment is done */
  double offset_mm[2]; /* fabric offset found by the registration (added to the scene's) */
  int psf_done;        /* the camera blur is settled (measured, or given): */
  double psf_sigma;    /* ... its sigma in pixels of the scene's image (0: none) */
  double psf_start;    /* ... as measured before the first iteration (psf_sigma moves when fitted) */
  int psf_fit;         /* ... it is fitted with the parameters (measured, not 0, and opts.psf_fit) */
  float psf_m, psf_v;  /* its Adam moments */
  double reg_ncc_before, reg_ncc_after;   /* correlation with the photo at zero shift, whole image */
  double reg_ssim_before, reg_ssim_after; /* SSIM of the whole image (RGB) at the iteration spp */
  int reg_renders[4];  /* renders of the last registration per window: 64, 128, 256 px, the whole image */
  int distorted;       /* the distortion after the registration is done */
  double distort_extent_mm, distort[2][WV_DISTORT_TERMS]; /* found (added to the scene's; wv_scene) */
  double dist_ssim_before, dist_ssim_after; /* SSIM of the whole image (RGB, 16 spp) */
  int open_measured;   /* a pair: the open area was measured on the back-lit photo's gap glow ... */
  double open_photo;   /* ... as this (wv_open_area_measure), and the yarn width set to match it */
  /* A pair's back-lit photo as its own view of the cloth (docs/fit.md, "Photo pairs"): taken
   * after the cloth was turned to the light, it is seldom at the front-lit photo's distance
   * and angle, laid the same way or at the same phase. */
  int t_related;       /* its own view was measured: its weave compared with the front-lit photo's
                        * (wv_weave_relate), */
  int t_found;         /* ... the two weaves relate, by */
  double t_scale, t_rotation_deg; /* ... this scale and rotation (1, 0: one camera's view) */
  int t_registered, t_distorted;  /* its own registration and distortion are done: */
  double t_density_ratio[2];      /* the densities it shows over the parameters' (1: the same), */
  double t_offset_mm[2];          /* its fabric offset, */
  double t_distort_extent_mm, t_distort[2][WV_DISTORT_TERMS]; /* its distortion (from the front-lit
                                   * photo's when the weaves do not relate: one camera's view then) */
  double t_reg_ssim_before, t_reg_ssim_after, t_dist_ssim_before, t_dist_ssim_after; /* its SSIM per RGB
                                   * channel before and after each (the registration's at the iteration spp) */
  float adam_m[WV_P_COUNT], adam_v[WV_P_COUNT]; /* wv_nn_adam's moments */
  wv_nn_lbfgs t_qn; /* a pair's transmission colours: their quasi-Newton memory (docs/fit.md, "Photo pairs") */
  uint64_t rng;
  wv_fit_record *log; /* iter entries */
  int log_cap;
  wv_fit_timing timing;
  int pair; /* the fit is a pair's (wv_fit_run_pair with a transmission photo): its iterations on
             * the reflection photo are followed by those on the transmission colours */
} wv_fit_state;

wv_status wv_fit_state_init(wv_fit_state *st, const wv_params *start, const wv_fit_opts *o, wv_error *err);

/* The schedule's stage after st->iter iterations, replayed from the log (wv_fit_converged
 * on each stage): 0 the window's stage, 1 the whole image's (with o->schedule 0 the only one is
 * 1), 2 the iterations are over (o->iters reached, or the last stage converged; a pair's
 * last stage is over when its iterations on the transmission photo have converged). *from
 * (may be NULL): the first iteration of the stage (when over, of the last one). */
int wv_fit_stage(const wv_fit_state *st, const wv_fit_opts *o, int *from);
/* The iterations are over: wv_fit_stage is 2. */
int wv_fit_finished(const wv_fit_state *st, const wv_fit_opts *o);
void wv_fit_state_free(wv_fit_state *st);

/* Called after every iteration (may be NULL); return nonzero to stop early. */
typedef int (*wv_fit_callback)(void *user, const wv_fit_state *st, const wv_fit_opts *o);

/* Runs iterations st->iter .. o->iters - 1 against photo (the scene's size, as
 * wv_photo_load gives it), or fewer when the stopping rule ends them (wv_fit_stage), then
 * the density alignment: the Gram loss cannot see
 * where yarns are, only what they look like, so a density a few yarns/inch off
 * costs it nothing while it shifts every yarn in the picture. After the last
 * iteration the warp and weft densities are searched, one at a time, on the
 * integer grid within +-align_radius for the best SSIM against the photo in a
 * centre window (a criterion that does see yarn positions). */
wv_status wv_fit_run(wv_fit_state *st, const wv_scene *s, const wv_image *photo, wv_descriptor *d,
                     const wv_fit_opts *o, wv_fit_callback cb, void *user, wv_error *err);
/* wv_fit_run on a photo pair (docs/fit.md, "Photo pairs"): the reflection photo in s and the
 * transmission photo photo_t in s_t, its back-lit counterpart (same camera, same cloth). The
 * iterations fit the reflection photo alone, as wv_fit_run does, until its stopping rule or
 * (1 - WV_FIT_T_SHARE) of the iterations; then the transmission photo alone, stepping only the
 * transmission colours (which the reflection photo does not see), until its own rule,
 * WV_FIT_T_SHARE of the iterations or the iteration limit. The colour split, noise sweep,
 * alignment, registration and distortion read the reflection photo alone; the back-lit photo
 * then gets its own view. s_t or photo_t NULL: wv_fit_run. */
wv_status wv_fit_run_pair(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_scene *s_t,
                          const wv_image *photo_t, wv_descriptor *d, const wv_fit_opts *o, wv_fit_callback cb,
                          void *user, wv_error *err);

/* Registration (after the alignment, flat and cylinder scenes alike): a real photo's
 * weave has a phase (where the yarns start) and a density known only to a few
 * yarns/inch, and SSIM compares pixels, so a render that looks right but is a
 * quarter of a rib out of step scores like noise. The score is the phase
 * correlation with the photo (the maximum over shifts of the normalised
 * cross-correlation of high-passed luminance, via FFT). The densities are searched
 * over the whole range in a small centre window, refined in larger windows and
 * finally on the whole image to 0.1 yarns/inch (docs/fit.md); the best shift
 * becomes a fabric offset. Kept only if the whole image's SSIM per RGB channel rises
 * (luminance alone misses yarns that differ in hue more than in brightness) and the
 * correlation at zero shift reaches 0.2. */
wv_status wv_fit_register(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                          wv_error *err);

/* The cloth's distortion (after the registration, a plane scene only): a real cloth is not
 * laid perfectly straight, so a render in register at the image centre drifts out of it
 * toward the edges, by whole yarns on some photos, and SSIM counts every yarn out of step.
 * For the N_FREQ weave frequencies the photo and the render share most, the local phase of
 * each (its demodulated detail, low-passed) in the photo against the render says how far
 * the render's fabric must move there; the frequency's fabric frequency comes from two
 * renders moved by 0.01 mm. A polynomial displacement of the fabric coordinates (degree
 * o->distort_degree, wv_scene.distort) is fitted to those phases by Gauss-Newton, degree
 * by degree, and estimated again from its own render; kept only as far as it raises the
 * whole image's SSIM per RGB channel. The fit's parameters do not change; the displacement
 * goes to the fit's scene (wv_fit_scene). docs/fit.md. */
wv_status wv_fit_distort(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                         wv_error *err);

/* The camera blur of photo (the scene's size): the sigma in 0..WV_PSF_RANGE pixels, in
 * steps of WV_PSF_RANGE / WV_PSF_STEPS, whose Gaussian blur of p's render (at WV_PSF_SPP)
 * has the weave spectrum (centre 256 x 256 pixels, wv_weave_spectrum) most correlated
 * with the photo's: the least 1 - WSC (returned in distance, may be NULL). Photos under
 * WV_PSF_MIN_SIDE pixels: 0. */
#define WV_PSF_RANGE 2.0
#define WV_PSF_STEPS 20
#define WV_PSF_SPP 16
#define WV_PSF_MIN_SIDE 64
wv_status wv_psf_estimate(const wv_scene *s, const wv_image *photo, const wv_params *p, int threads,
                          double *sigma, double *distance, wv_error *err);

/* The scene the fit's parameters are meant for: s with the registration's offset and
 * the camera blur the fit settled on. */
void wv_fit_scene(const wv_fit_state *st, const wv_scene *s, wv_scene *out);

/* A pair's back-lit scene and parameters as the fit settled them: s_t with the back-lit
 * photo's own view and the camera blur (when the two photos' weaves relate, t_found, its scale
 * as a narrower or wider field of view and its rotation added to the sample's; its offset and
 * distortion), and p with the densities that photo shows (t_density_ratio). Before that view
 * is measured (t_related 0): wv_fit_scene's, the front-lit photo's offset and distortion. */
void wv_fit_scene_t(const wv_fit_state *st, const wv_scene *s_t, wv_scene *out);
void wv_fit_params_t(const wv_fit_state *st, const wv_params *p, wv_params *out);

/* Loss terms of params against photo at the scene's own resolution and spp. */
wv_status wv_fit_loss(const wv_scene *s, const wv_image *photo, wv_descriptor *d, const wv_params *p,
                      const wv_fit_opts *o, wv_fit_record *out, wv_error *err);

/* Checkpoints (JSON, written atomically): the state and the options. Reading checks
 * every value (options as wv_fit_opts_validate, iteration count against the log,
 * RNG state as 16 hex digits, registration offset within WV_SCENE_MAX_OFFSET_MM,
 * finite Adam moments, ...); messages name the file and the key. */
wv_status wv_fit_checkpoint_write(const char *path, const wv_fit_state *st, const wv_fit_opts *o,
                                  const char *descriptor_name, wv_error *err);
wv_status wv_fit_checkpoint_read(const char *path, wv_fit_state *st, wv_fit_opts *o, char *descriptor_name,
                                 size_t name_cap, wv_error *err);

/* The beta prior of SPEC section 7 for a pattern (plain, twill, satin; the 90
 * variants and custom patterns use their base / the plain prior). */
void wv_fit_beta_prior(const char *pattern, double *mu, double *sigma);

#endif
