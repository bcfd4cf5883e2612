/* woven: the fit (include/woven/fit.h): Adam on the continuous parameters against the
 * weighted image losses of include/woven/loss.h, the random discrete steps, the colour
 * split of the start and the density alignment. */
#include "woven/fit.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "util/colour.h"
#include "util/hash.h"
#include "fit/fit_internal.h"
#include "woven/analysis.h"
#include "woven/grad.h"
#include "woven/imgops.h"
#include "woven/loss.h"
#include "woven/metrics.h"
#include "woven/nn.h"
#include "woven/render.h"

/* The colour split's rule of coverage: a share of warp cells this far from a half (the
 * built-ins give 0, 1/6, 1/4, 3/10 or 3/8) lets the weave decide which yarn type wears
 * which colour, when the two ways round, rendered, differ by this much in how far their
 * share of dark pixels lies from the photo's; start colours whose luminances differ by
 * less than this fraction of their sum count as one colour. */
#define SPLIT_WEAVE_MIN 0.08
#define SPLIT_SHARE_GAP 0.05
#define SPLIT_LUM_SAME 0.05

static double sq(double x) { return x * x; }

wv_status wv_fit_check_sizes(const wv_scene *s, const wv_descriptor *d, const wv_fit_opts *o, wv_error *err) {
  int need = d ? wv_descriptor_min_side(d) : 0, scale = o->iter_scale > 0 ? o->iter_scale : 1;
  need = need > WV_FIT_MIN_SIDE ? need : WV_FIT_MIN_SIDE;
  if (s->width < need || s->height < need)
    return wv_fail(err, WV_ERR_INVALID, "the scene's image (%d x %d) is too small for a fit (at least %d x %d%s%s)",
                   s->width, s->height, need, need, d ? " for descriptor " : "", d ? wv_descriptor_name(d) : "");
  int w = s->width / scale, h = s->height / scale, dmin = d ? wv_descriptor_min_side(d) : 0;
  if (w < dmin || h < dmin || w < o->down_w || h < o->down_h)
    return wv_fail(err, WV_ERR_INVALID,
                   "iterating at 1/%d scale makes the scene's %d x %d image %d x %d, too small for the fit (at "
                   "least %d x %d); use a smaller --iter-scale",
                   scale, s->width, s->height, w, h, dmin > o->down_w ? dmin : o->down_w,
                   dmin > o->down_h ? dmin : o->down_h);
  return WV_OK;
}

void wv_fit_beta_prior(const char *pattern, double *mu, double *sigma) {
  if (!strncmp(pattern, "twill", 5)) *mu = 1.0, *sigma = 0.5;
  else if (!strncmp(pattern, "satin", 5)) *mu = 0.1, *sigma = 0.5;
  else *mu = 1.0, *sigma = 1.0;
}

/* The rule on one photo's losses: part 0 the reflection photo's, 1 the transmission photo's. */
static int stalled(const wv_fit_record *log, int first, int to, int patience, int part) {
  double before = INFINITY, recent = INFINITY;
  for (int j = first; j < to; j++) {
    double m = 0;
    for (int k = j - WV_FIT_SMOOTH + 1; k <= j; k++) m += part ? log[k].loss_t : log[k].loss - log[k].loss_t;
    m /= WV_FIT_SMOOTH;
    if (j < to - patience) before = m < before ? m : before;
    else recent = m < recent ? m : recent;
  }
  return !(recent < (1 - WV_FIT_MIN_GAIN) * before);
}

/* A pair's first iteration on the transmission photo alone in from .. to - 1, else to. */
static int t_phase(const wv_fit_record *log, int from, int to) {
  for (int j = from; j < to; j++)
    if (log[j].t_alone) return j;
  return to;
}

int wv_fit_converged(const wv_fit_record *log, int from, int to, int patience) {
  int tf = t_phase(log, from, to);
  if (tf < to) from = tf; /* the transmission colours' iterations: their own loss, from their first */
  int first = from + WV_FIT_SMOOTH - 1; /* the first iteration with a whole window in the stage */
  if (patience <= 0 || to - patience <= first) return 0;
  if (tf < to) return stalled(log, first, to, patience, 1);
  return stalled(log, first, to, patience, 0) && stalled(log, first, to, patience, 1);
}

/* The last iteration (exclusive) the stage may reach. */
static int stage_limit(const wv_fit_opts *o, int stage) {
  return stage == 0 ? (int)(o->iters * WV_FIT_WINDOW_SHARE) : o->iters;
}

/* A pair's iteration `done` (the stage's from `from`) is on the transmission photo alone: its
 * iterations have begun, or the reflection photo's have converged or reached their share. */
static int t_next(const wv_fit_record *log, const wv_fit_opts *o, int pair, int stage, int from, int done) {
  if (!pair || stage != 1) return 0;
  return t_phase(log, from, done) < done || done >= (int)(o->iters * (1 - WV_FIT_T_SHARE)) ||
         wv_fit_converged(log, from, done, o->patience);
}

/* A pair's iterations on the transmission photo alone in from .. done - 1 have reached
 * their share of the iterations, WV_FIT_T_SHARE. */
static int t_spent(const wv_fit_record *log, const wv_fit_opts *o, int pair, int stage, int from, int done) {
  int tf = t_phase(log, from, done);
  return pair && stage == 1 && tf < done && done - tf >= (int)(o->iters * WV_FIT_T_SHARE);
}

/* The stage after iteration `done` (iterations from .. done - 1 in the stage so far): the
 * next one when the stage reached its limit or converged (a pair's last stage: its
 * iterations on the transmission photo converged or reached their share). */
static int stage_after(const wv_fit_record *log, const wv_fit_opts *o, int pair, int stage, int *from, int done) {
  while (stage < 2 && (done >= stage_limit(o, stage) || t_spent(log, o, pair, stage, *from, done) ||
                       ((!pair || stage == 0 || t_phase(log, *from, done) < done) &&
                        wv_fit_converged(log, *from, done, o->patience))))
    if (++stage < 2) *from = done;
  return stage;
}

int wv_fit_stage(const wv_fit_state *st, const wv_fit_opts *o, int *from) {
  int f = 0, stage = stage_after(st->log, o, st->pair, o->schedule ? 0 : 1, &f, 0);
  for (int i = 1; i <= st->iter && stage < 2; i++) stage = stage_after(st->log, o, st->pair, stage, &f, i);
  if (from) *from = f;
  return stage;
}

int wv_fit_finished(const wv_fit_state *st, const wv_fit_opts *o) { return wv_fit_stage(st, o, NULL) == 2; }

/* What stays fixed during a fit: the target at the iteration resolution. */
typedef struct {
  wv_scene scene;
  wv_image photo;
  wv_image render, dcap;
  wv_image_loss *loss; /* the photo's side of every image loss term */
  const wv_fit_opts *o;
  wv_fit_timing *timing;
  wv_footprints *fp; /* the iteration scene's camera geometry, made once */
  wv_fit_opts wopts; /* a window's options (o points here) */
  int no_prior;      /* the pattern prior is left out (the second photo of a pair: counted once) */
  wv_grad_record *record; /* the last gradient render's, its memory reused by the next */
} fit_ctx;

static void ctx_free(fit_ctx *c) {
  wv_image_free(&c->photo), wv_image_free(&c->render), wv_image_free(&c->dcap);
  wv_image_loss_free(c->loss);
  wv_footprints_free(c->fp);
  wv_record_free(c->record);
}

static wv_status ctx_init(fit_ctx *c, const wv_scene *s, const wv_image *photo, wv_descriptor *d, int scale,
                          int spp, const wv_fit_opts *o, wv_fit_timing *timing, wv_error *err) {
  wv_fit_opts keep = c->wopts; /* o may point to it */
  memset(c, 0, sizeof *c);
  c->wopts = keep;
  c->o = o == &c->wopts ? &c->wopts : o, c->timing = timing;
  wv_fit_opts so = *o;
  so.iter_scale = scale;
  wv_status st = wv_fit_check_sizes(s, d, &so, err);
  if (st) return st;
  wv_scene_downscale(s, scale, &c->scene);
  if (spp > 0) c->scene.spp = spp;
  if (photo->w != s->width || photo->h != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                   s->width, s->height);
  if (c->scene.width == photo->w && c->scene.height == photo->h) {
    if ((st = wv_image_alloc(&c->photo, photo->w, photo->h, 3, err))) return st;
    memcpy(c->photo.data, photo->data, sizeof(float) * 3 * (size_t)photo->w * photo->h);
  } else if ((st = wv_image_downsample(photo, c->scene.width, c->scene.height, &c->photo, err))) {
    return st;
  }
  wv_loss_weights lw = {.w_pixel = o->w_pixel, .w_struct = o->w_struct, .down_w = o->down_w, .down_h = o->down_h,
                        .w_colour = o->w_colour};
  if ((st = wv_image_loss_create(&c->photo, d, NULL, &lw, &c->loss, err))) return st;
  if ((st = wv_image_alloc(&c->dcap, c->scene.width, c->scene.height, 3, err))) return st;
  return wv_footprints_create(&c->scene, o->threads, &c->fp, err);
}

/* Loss of p; with grad != NULL also dL/dtheta (file units), and with dpsf != NULL
 * dL/dsigma of the iteration scene's camera blur (its pixels). */
static wv_status evaluate(fit_ctx *c, const wv_params *p, wv_fit_record *rec, double grad[WV_P_COUNT],
                          double *dpsf, wv_error *err) {
  const wv_fit_opts *o = c->o;
  wv_render_opts ro = {.spp = c->scene.spp, .threads = o->threads, .footprints = c->fp};
  double t0 = omp_get_wtime();
  wv_image_free(&c->render);
  /* With a gradient wanted, render once and keep each pixel's derivative sums:
   * the adjoint depends on the render, so it is applied afterwards. */
  wv_status st = grad ? wv_render_record_into(&c->scene, p, &ro, NULL, &c->render, &c->record, err)
                      : wv_render(&c->scene, p, &ro, &c->render, NULL, err);
  if (st) return st;
  double t1 = omp_get_wtime();
  c->timing->render += t1 - t0;
  /* the image terms (and with a gradient wanted, dL/dcapture) */
  wv_loss_terms lt;
  if ((st = wv_image_loss_eval(c->loss, &c->render, &lt, grad ? &c->dcap : NULL, err))) return st;
  /* L_p on beta */
  double mu, sg;
  wv_fit_beta_prior(p->pattern, &mu, &sg);
  double lp = 0;
  for (int y = 0; y < 2; y++) lp += (p->heightfield[y] - mu) * (p->heightfield[y] - mu) / (2 * sg * sg);
  rec->gram = lt.gram, rec->pixel = lt.pixel, rec->prior = lp, rec->structure = lt.structure, rec->colour = lt.colour;
  double wp = c->no_prior ? 0.0 : o->w_prior;
  rec->loss = lt.total + wp * lp;
  double t3 = omp_get_wtime();
  c->timing->descriptor += t3 - t1;
  if (!grad) return WV_OK;
  st = wv_record_grad(c->record, &c->dcap, grad, NULL, err);
  if (!st && dpsf) st = wv_record_grad_psf(c->record, &c->dcap, dpsf, err);
  if (st) return st;
  c->timing->gradient += omp_get_wtime() - t3;
  grad[WV_P_BETA_WARP] += wp * (p->heightfield[WV_WARP] - mu) / (sg * sg);
  grad[WV_P_BETA_WEFT] += wp * (p->heightfield[WV_WEFT] - mu) / (sg * sg);
  return WV_OK;
}

/* The loss of p on a pair's transmission photo and, with grad, its transmission colours'
 * gradient, from the back-lit radiance as a linear function of them (wv_trans_basis, made
 * here at the first call: the rest of the parameters stays while the colours are fitted). */
static wv_status evaluate_t(fit_ctx *c, wv_trans_basis **tb, const wv_params *p, wv_fit_record *rec,
                            double grad[WV_P_COUNT], wv_error *err) {
  double t0 = omp_get_wtime();
  wv_status st = WV_OK;
  if (!*tb) {
    wv_render_opts ro = {.spp = c->scene.spp, .threads = c->o->threads, .footprints = c->fp};
    st = wv_trans_basis_create(&c->scene, p, &ro, tb, err);
    c->timing->render += omp_get_wtime() - t0;
    if (st) return st;
    t0 = omp_get_wtime();
  }
  wv_image_free(&c->render);
  wv_loss_terms lt;
  if ((st = wv_trans_basis_capture(*tb, p, &c->render, err)) ||
      (st = wv_image_loss_eval(c->loss, &c->render, &lt, grad ? &c->dcap : NULL, err)))
    return st;
  rec->gram = lt.gram, rec->pixel = lt.pixel, rec->prior = 0, rec->structure = lt.structure, rec->colour = lt.colour;
  rec->loss = lt.total;
  double t1 = omp_get_wtime();
  c->timing->descriptor += t1 - t0;
  if (!grad) return WV_OK;
  st = wv_trans_basis_grad(*tb, &c->dcap, grad, err);
  c->timing->gradient += omp_get_wtime() - t1;
  return st;
}

/* The transmission colours' gradient at the point evaluate_t evaluated last, without it: the
 * loss's descriptor pass is not run again (wv_image_loss_grad). */
static wv_status evaluate_t_grad(fit_ctx *c, wv_trans_basis *tb, double grad[WV_P_COUNT], wv_error *err) {
  double t0 = omp_get_wtime();
  wv_status st = wv_image_loss_grad(c->loss, &c->render, &c->dcap, err);
  double t1 = omp_get_wtime();
  c->timing->descriptor += t1 - t0;
  if (!st) st = wv_trans_basis_grad(tb, &c->dcap, grad, err);
  c->timing->gradient += omp_get_wtime() - t1;
  return st;
}

static wv_status colours_step(fit_ctx *c, wv_trans_basis **tb, wv_params *p, wv_nn_lbfgs *qn,
                              const wv_fit_record *rec, const double g[WV_P_COUNT], wv_params *next,
                              wv_fit_record *next_rec, double next_g[WV_P_COUNT], int *have_next, wv_error *err);

/* steps of the colours' descent (colours_step) from p with a fresh memory qn over the first n
 * colours; p moves, *loss is where it ends. */
static wv_status colours_descend(fit_ctx *c, wv_trans_basis **tb, wv_params *p, int n, int steps, wv_nn_lbfgs *qn,
                                 double *loss, wv_error *err) {
  wv_nn_lbfgs_reset(qn, n);
  wv_fit_record rec = {0};
  double g[WV_P_COUNT] = {0};
  wv_status rc = evaluate_t(c, tb, p, &rec, g, err);
  for (int k = 0; !rc && k < steps; k++) {
    wv_params next;
    wv_fit_record nr;
    double ng[WV_P_COUNT];
    int have = 0;
    if ((rc = colours_step(c, tb, p, qn, &rec, g, &next, &nr, ng, &have, err))) break;
    rec = nr;
    memcpy(g, ng, sizeof g);
  }
  *loss = rec.loss;
  return rc;
}

/* Whether the back-lit photo shows a forward band, and its width. At each width of
 * WV_FIT_FORWARD_WIDTHS the basis's band images are made again (wv_trans_basis_forward_width:
 * two renders) and k_f alone matched to the photo's brightness (wv_trans_basis_match, WV_TRANS_MATCH_FORWARD) with the other colours as
 * they are; the width of the lowest back-lit loss is kept with its basis and k_f if that loss
 * is below the colours' own. Run before the colours' start (colours_start), whose candidates
 * then hold k_f and whose iterations move it too; where it finds no band there, once more
 * after the start, against the colours the start chose (the iterations' memory grown to k_f).
 * Without a band k_f stays 0 and the iterations move the other colours alone, as before the
 * band. Before the candidates: with the band only after them, a synthetic basket whose
 * back-lit photo shows a band came back with its warp and weft colours exchanged (its back-lit
 * re-render at 0.57 of its ceiling against 0.99); only before them, a synthetic twill's band was
 * not found against the start's colours (0.88 against 0.98; docs/measurements.md, "The forward
 * band"). The width has no gradient in the colours' iterations, which keep the geometry. */
static wv_status forward_sweep(fit_ctx *c, wv_trans_basis **tb, wv_fit_state *st, wv_error *err) {
  static const double widths[] = WV_FIT_FORWARD_WIDTHS;
  enum { NW = sizeof widths / sizeof widths[0] };
  wv_fit_record rec = {0};
  wv_status rc = evaluate_t(c, tb, &st->params, &rec, NULL, err);
  double best = rec.loss, start_w = st->params.forward_width;
  wv_params best_p = st->params;
  wv_render_opts ro = {.spp = c->scene.spp, .threads = c->o->threads, .footprints = c->fp};
  for (int k = 0; k < NW && !rc; k++) {
    wv_params m = st->params;
    m.forward_width = widths[k];
    if (!(rc = wv_trans_basis_forward_width(*tb, &m, &ro, err)) &&
        !(rc = wv_trans_basis_match(*tb, &c->photo, c->o->down_w, c->o->down_h, WV_TRANS_MATCH_FORWARD, &m, NULL, err)) &&
        !(rc = evaluate_t(c, tb, &m, &rec, NULL, err)) && rec.loss < best)
      best = rec.loss, best_p = m;
  }
  if (rc) return rc;
  st->params = best_p;
  if (!wv_params_has_forward_band(&best_p)) st->params.forward_width = start_w; /* no band: the width as it was */
  return wv_trans_basis_forward_width(*tb, &st->params, &ro, err); /* the basis's band at that width */
}

/* The transmission colours' start, before their first iteration. The candidates: the colours
 * as they are, and those matched to the back-lit photo's brightness (wv_trans_basis_match):
 * free; with the split of the light between the yarn types kept, the start's, its mirror's,
 * or the reflection colours' (k_t following k_d and k_st following k_s: each yarn type's light
 * coloured by the yarn as the front-lit photo shows it). The two with the lowest back-lit loss
 * each take WV_FIT_T_PROBE steps of the descent, and the lower end is kept. Adam's steps from
 * the start took about 50 iterations to reach that brightness; the match alone, free, can split
 * the light wrongly, and the split kept can leave it too bright; a start's loss alone can
 * choose a basin whose end is higher (docs/measurements.md, "The back-lit photo's colours
 * alone", "The yarn underneath"). The first n_free colours move: k_f too when all of them, as
 * when the start has a forward band. */
static wv_status colours_start(fit_ctx *c, wv_trans_basis **tb, wv_fit_state *st, int n_free, wv_error *err) {
  enum { CANDS = 5 };
  wv_params cand[CANDS];
  double loss[CANDS];
  wv_fit_record rec = {0};
  cand[0] = st->params;
  wv_status rc = evaluate_t(c, tb, &cand[0], &rec, NULL, err);
  loss[0] = rec.loss;
  for (int k = 1; !rc && k < CANDS; k++) {
    wv_trans_match mode = k == 1 ? WV_TRANS_MATCH_FREE : WV_TRANS_MATCH_SPLIT;
    wv_params m = st->params;
    if (k == 3) /* the mirror: the start's way round is that of the reflection colours before the colour split */
      for (int ch = 0; ch < 3; ch++) {
        double t = m.transmission[0][ch], u = m.transmission_specular[0][ch], f = m.transmission_forward[0][ch];
        m.transmission[0][ch] = m.transmission[1][ch], m.transmission[1][ch] = t;
        m.transmission_specular[0][ch] = m.transmission_specular[1][ch], m.transmission_specular[1][ch] = u;
        m.transmission_forward[0][ch] = m.transmission_forward[1][ch], m.transmission_forward[1][ch] = f;
      }
    if (k == 4)
      for (int y = 0; y < 2; y++)
        for (int ch = 0; ch < 3; ch++)
          m.transmission[y][ch] = m.diffuse[y][ch], m.transmission_specular[y][ch] = m.specular[y][ch];
    if ((rc = wv_trans_basis_match(*tb, &c->photo, c->o->down_w, c->o->down_h, mode, &m, NULL, err)) ||
        (rc = evaluate_t(c, tb, &m, &rec, NULL, err)))
      break;
    cand[k] = m, loss[k] = rec.loss;
  }
  if (rc) return rc;
  int a = 0, b = -1; /* the lowest two, the earlier on a tie */
  for (int k = 1; k < CANDS; k++)
    if (loss[k] < loss[a]) b = a, a = k;
    else if (b < 0 || loss[k] < loss[b]) b = k;
  double ea, eb;
  wv_nn_lbfgs qa, qb;
  if ((rc = colours_descend(c, tb, &cand[a], n_free, WV_FIT_T_PROBE, &qa, &ea, err)) ||
      (rc = colours_descend(c, tb, &cand[b], n_free, WV_FIT_T_PROBE, &qb, &eb, err)))
    return rc;
  /* the iterations go on from the chosen end, with its memory */
  st->params = eb < ea ? cand[b] : cand[a];
  st->t_qn = eb < ea ? qb : qa;
  return WV_OK;
}

/* One step of the transmission colours from *p (loss rec->loss, gradient g): along the
 * quasi-Newton direction of the memory qn in normalised coordinates, the box [0, 1] holding each,
 * the first of the steps 1, 1/4, 1/16, 1/64 along it that lowers the loss (no more is asked of
 * it: where a colour and its partner sit at 0 the response's slope has no bound, and a rule
 * that trusts the slope's prediction turns down every step);
 * with no curvature seen yet, the first step moves the farthest colour by WV_FIT_T_STEP0. The
 * accepted trial, evaluated with its gradient, is handed back for the next iteration. None
 * accepted: the colours stay, and the next step starts again from the steepest descent; when
 * that was the steepest descent, the colours stay until the stopping rule ends their
 * iterations, at no further cost. Adam's fixed step length took about 30
 * iterations to carry satin1's colours to the photo's detail colour (docs/measurements.md,
 * "The colours' steps"). */
static wv_status colours_step(fit_ctx *c, wv_trans_basis **tb, wv_params *p, wv_nn_lbfgs *qn,
                              const wv_fit_record *rec, const double g[WV_P_COUNT], wv_params *next,
                              wv_fit_record *next_rec, double next_g[WV_P_COUNT], int *have_next, wv_error *err) {
  enum { NMAX = WV_P_COUNT - WV_P_REFLECT_COUNT };
  const int N = qn->n; /* the colours that move: the first N (docs/fit.md, "Photo pairs") */
  double x[NMAX], gx[NMAX], dir[NMAX], lo[NMAX], span[NMAX];
  for (int i = 0; i < N; i++) {
    double hi;
    wv_param_range(WV_P_REFLECT_COUNT + i, &lo[i], &hi);
    span[i] = hi - lo[i];
    x[i] = (wv_param_get(p, WV_P_REFLECT_COUNT + i) - lo[i]) / span[i];
    gx[i] = isfinite(g[WV_P_REFLECT_COUNT + i]) ? g[WV_P_REFLECT_COUNT + i] * span[i] : 0;
  }
  *have_next = 0;
  double alpha = 1;
  int pairs = wv_nn_lbfgs_direction(qn, x, rec->loss, gx, 0, 1, dir);
  if (pairs < 0) alpha = 0; /* the steepest descent was turned down here before */
  if (pairs == 0) {
    double m = 0;
    for (int i = 0; i < N; i++) m = fabs(dir[i]) > m ? fabs(dir[i]) : m;
    alpha = m > 0 ? WV_FIT_T_STEP0 / m : 0;
  }
  for (int k = 0; k < 4 && alpha > 0; k++, alpha *= 0.25) {
    wv_params trial = *p;
    double dec = 0;
    for (int i = 0; i < N; i++) {
      double xt = x[i] + alpha * dir[i];
      xt = xt < 0 ? 0 : xt > 1 ? 1 : xt;
      dec += gx[i] * (xt - x[i]);
      wv_param_set(&trial, WV_P_REFLECT_COUNT + i, lo[i] + xt * span[i]);
    }
    if (!(dec < 0)) break; /* the box leaves no descent along it */
    wv_fit_record tr = {0};
    double tg[WV_P_COUNT] = {0};
    /* the value first: most trials turned down cost half an evaluation with the gradient */
    wv_status rc = evaluate_t(c, tb, &trial, &tr, NULL, err);
    if (rc) return rc;
    if (tr.loss < rec->loss) {
      if ((rc = evaluate_t_grad(c, *tb, tg, err))) return rc;
      *p = trial;
      *next = trial, *next_rec = tr, *have_next = 1;
      memcpy(next_g, tg, sizeof tg);
      return WV_OK;
    }
  }
  if (pairs >= 0) wv_nn_lbfgs_reject(qn);
  *next = *p, *next_rec = *rec, *have_next = 1; /* the same point again */
  memcpy(next_g, g, sizeof(double) * WV_P_COUNT);
  return WV_OK;
}

wv_status wv_fit_loss(const wv_scene *s, const wv_image *photo, wv_descriptor *d, const wv_params *p,
                      const wv_fit_opts *o, wv_fit_record *out, wv_error *err) {
  fit_ctx c;
  wv_fit_timing t = {0};
  wv_status st = ctx_init(&c, s, photo, d, 1, 0, o, &t, err);
  if (!st) st = evaluate(&c, p, out, NULL, NULL, err);
  ctx_free(&c);
  return st;
}

/* The parameters and their gradient in normalised coordinates z = (theta - lo) / (hi - lo). */
static void param_z(const wv_params *p, const double g[WV_P_COUNT], float z[WV_P_COUNT], float gz[WV_P_COUNT]) {
  for (int i = 0; i < WV_P_COUNT; i++) {
    double lo, hi;
    wv_param_range(i, &lo, &hi);
    double gi = g[i] * (hi - lo);
    gz[i] = isfinite(gi) ? (float)gi : 0.0f;
    z[i] = (float)((wv_param_get(p, i) - lo) / (hi - lo));
  }
}

/* Parameters from .. to - 1 from z; the others keep their values exactly. */
static void param_set_z(wv_params *p, const float z[WV_P_COUNT], int from, int to) {
  for (int i = from; i < to; i++) {
    double lo, hi;
    wv_param_range(i, &lo, &hi);
    wv_param_set(p, i, lo + z[i] * (hi - lo));
  }
}

/* The loss of p on both photos of a pair: the reflection photo's (c) and the transmission
 * photo's (ct), the prior counted once. */
static wv_status pair_loss(fit_ctx *c, fit_ctx *ct, const wv_params *p, double *loss, wv_error *err) {
  wv_fit_record r = {0}, rt = {0};
  wv_status rc = evaluate(c, p, &r, NULL, NULL, err);
  if (!rc) rc = evaluate(ct, p, &rt, NULL, NULL, err);
  *loss = r.loss + rt.loss;
  return rc;
}

static uint64_t next_rand(uint64_t *state) {
  *state += 0x9e3779b97f4a7c15ULL;
  return wv_mix64(*state);
}

/* One random step of a discrete parameter (SPEC section 7 schedule). Returns 0
 * when the step would leave the range (nothing to try). */
static int discrete_step(wv_params *p, uint64_t *rng, int iter, int iters, int density_steps) {
  uint64_t r = next_rand(rng);
  int which = (int)(r % 3), sign = (r >> 8) & 1 ? 1 : -1;
  if (which && !density_steps) return 0; /* the same draws either way: only what is tried differs */
  double frac = (double)iter / (iters > 0 ? iters : 1);
  double dstep = frac < 0.5 ? 10 : frac < 0.75 ? 5 : 2;
  if (which == 0) {
    int q = p->noise_level + sign;
    if (q < 0 || q > 10) return 0;
    p->noise_level = q;
  } else {
    double *dens = &p->density[which - 1];
    double v = *dens + sign * dstep;
    if (v < WV_DENSITY_MIN || v > WV_DENSITY_MAX) return 0;
    *dens = v;
  }
  return 1;
}

static wv_status align_densities(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                                 wv_error *err) {
  int w = s->width < 160 ? s->width : 160, h = s->height < 80 ? s->height : 80;
  w -= (s->width - w) % 2, h -= (s->height - h) % 2; /* keep the window centred on whole pixels */
  wv_scene win;
  wv_scene_centre_window(s, w, h, &win);
  win.spp = o->iter_spp;
  wv_image ref;
  wv_status rc = wv_image_centre_crop(photo, w, h, &ref, err);
  if (rc) return rc;
  wv_footprints *fp = NULL;
  if ((rc = wv_footprints_create(&win, o->threads, &fp, err))) {
    wv_image_free(&ref);
    return rc;
  }
  wv_render_opts ro = {.spp = win.spp, .threads = o->threads, .footprints = fp};
  /* Coordinate search: one density at a time over +-R with the other fixed, until
   * a full round changes nothing (each density alone already moves the SSIM). */
  wv_params cur = st->params;
  for (int y = 0; y < 2; y++) cur.density[y] = floor(cur.density[y] + 0.5);
  const double d0[2] = {cur.density[0], cur.density[1]}; /* where the search starts */
  double best = -2, before = -2;
  wv_image img;
  if (!(rc = wv_render(&win, &cur, &ro, &img, NULL, err))) {
    rc = wv_ssim(&ref, &img, WV_SSIM_LUMA, &before, err);
    wv_image_free(&img);
  }
  best = before;
  /* A window this small is rendered faster one per thread than split across them (the
   * render does not depend on the thread count); the scores are compared in order after. */
  int nthreads = o->threads > 0 ? o->threads : omp_get_max_threads();
  double *score = rc ? NULL : malloc(sizeof(double) * (2 * (size_t)o->align_radius + 1));
  if (!rc && !score) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the density alignment");
  wv_render_opts ro1 = ro;
  ro1.threads = 1;
  int unchanged = 0;
  for (int pass = 0; pass < 6 && unchanged < 2 && !rc; pass++) {
    int y = pass & 1;
    int R = pass < 2 ? o->align_radius : (o->align_radius < 5 ? o->align_radius : 5); /* later rounds refine */
    double centre = cur.density[y], best_d = centre;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads)
    for (int k = -R; k <= R; k++) {
      wv_params trial = cur;
      trial.density[y] = centre + k;
      score[k + R] = -3;
      if (k == 0 || trial.density[y] < WV_DENSITY_MIN || trial.density[y] > WV_DENSITY_MAX) continue; /* k = 0 is best already */
      wv_error e = {0};
      wv_image im;
      wv_status r = wv_render(&win, &trial, &ro1, &im, NULL, &e);
      if (!r) {
        r = wv_ssim(&ref, &im, WV_SSIM_LUMA, &score[k + R], &e);
        wv_image_free(&im);
      }
      if (r) {
#pragma omp critical(wv_align_error)
        if (!rc) {
          rc = r;
          if (err) *err = e;
        }
      }
    }
    for (int k = -R; k <= R && !rc; k++)
      if (score[k + R] > best) best = score[k + R], best_d = centre + k;
    unchanged = best_d == centre ? unchanged + 1 : 0;
    cur.density[y] = best_d;
  }
  free(score);
  wv_image_free(&ref);
  wv_footprints_free(fp);
  if (rc) return rc;
  /* The window's SSIM rewards a weave in phase with the photo's, and a cloth too fine to
   * show any weave over one out of phase: a search over the whole range can land on such
   * a density (an alias several times the photo's). The weave's spectrum does not depend
   * on the phase, so new densities are kept only if the whole image's weave-spectrum
   * correlation with the photo does not fall. */
  st->align_wsc_before = st->align_wsc_after = -2;
  if (cur.density[0] != d0[0] || cur.density[1] != d0[1]) {
    wv_scene whole = *s;
    whole.spp = o->iter_spp;
    wv_render_opts rw = {.spp = whole.spp, .threads = o->threads};
    wv_params start = cur;
    start.density[0] = d0[0], start.density[1] = d0[1];
    const wv_params *cand[2] = {&start, &cur};
    double wsc[2] = {-2, -2};
    for (int k = 0; k < 2 && !rc; k++) {
      if ((rc = wv_render(&whole, cand[k], &rw, &img, NULL, err))) break;
      if (wv_wsc(photo, &img, &wsc[k], NULL)) wsc[k] = -2; /* too small to measure: no check */
      wv_image_free(&img);
    }
    if (rc) return rc;
    st->align_wsc_before = wsc[0], st->align_wsc_after = wsc[1];
    if (wsc[1] < wsc[0]) cur.density[0] = d0[0], cur.density[1] = d0[1], best = before;
  }
  st->params.density[0] = cur.density[0], st->params.density[1] = cur.density[1];
  st->align_ssim_before = before, st->align_ssim_after = best;
  st->aligned = 1;
  return WV_OK;
}

/* An image's two colours as ratios to their neighbourhood's mean colour (linear values,
 * so illumination and the falloff cancel): 2-means over every pixel, r[0] the darker
 * cluster, *dark_share the share of pixels in it. Returns 0 when the image has no colour
 * detail to split. */
static int colour_clusters(const wv_scene *s, const wv_image *ph, double r[2][3], double *dark_share, wv_error *err) {
  size_t n = (size_t)ph->w * ph->h;
  wv_image lin = {0}, mean = {0};
  if (wv_image_alloc(&lin, ph->w, ph->h, 3, err)) return 0;
  for (size_t i = 0; i < 3 * n; i++) lin.data[i] = wv_decode(s, ph->data[i]);
  if (wv_image_blur(&lin, 4.0, &mean, err)) {
    wv_image_free(&lin);
    return 0;
  }
  for (size_t i = 0; i < 3 * n; i++) lin.data[i] /= mean.data[i] + 1e-4f;
  wv_image_free(&mean);
  /* start: the pixels below and above the mean luminance ratio */
  double cen[2][3] = {{0}}, cnt[2] = {0};
  for (size_t i = 0; i < n; i++) {
    const float *v = lin.data + 3 * i;
    int k = wv_luminance_d(v[0], v[1], v[2]) > 1.0;
    for (int ch = 0; ch < 3; ch++) cen[k][ch] += v[ch];
    cnt[k]++;
  }
  for (int it = 0; it < 10; it++) {
    for (int k = 0; k < 2; k++)
      for (int ch = 0; ch < 3; ch++) cen[k][ch] = cnt[k] > 0 ? cen[k][ch] / cnt[k] : 1.0;
    double acc[2][3] = {{0}}, nk[2] = {0};
    for (size_t i = 0; i < n; i++) {
      const float *v = lin.data + 3 * i;
      double d0 = 0, d1 = 0;
      for (int ch = 0; ch < 3; ch++) d0 += (v[ch] - cen[0][ch]) * (v[ch] - cen[0][ch]), d1 += (v[ch] - cen[1][ch]) * (v[ch] - cen[1][ch]);
      int k = d1 < d0;
      for (int ch = 0; ch < 3; ch++) acc[k][ch] += v[ch];
      nk[k]++;
    }
    memcpy(cen, acc, sizeof cen), memcpy(cnt, nk, sizeof cnt);
  }
  wv_image_free(&lin);
  for (int k = 0; k < 2; k++)
    for (int ch = 0; ch < 3; ch++) r[k][ch] = cnt[k] > 0 ? cen[k][ch] / cnt[k] : 1.0;
  double l0 = wv_luminance_d(r[0][0], r[0][1], r[0][2]);
  double l1 = wv_luminance_d(r[1][0], r[1][1], r[1][2]);
  *dark_share = cnt[0] / (cnt[0] + cnt[1] > 0 ? cnt[0] + cnt[1] : 1);
  if (l0 > l1) {
    for (int ch = 0; ch < 3; ch++) {
      double t = r[0][ch];
      r[0][ch] = r[1][ch], r[1][ch] = t;
    }
    *dark_share = 1 - *dark_share;
  }
  return cnt[0] > 0 && cnt[1] > 0 && fabs(l1 - l0) > 1e-3;
}

/* A start that splits warp and weft colours. A start with one diffuse colour for both
 * yarn types is a symmetric point the gradient does not leave (both colours move
 * alike), while a two-colour photo needs them apart. Candidates: the photo's two local
 * colours (colour_clusters), once and twice as far apart (yarns of one or two pixels
 * mix them), on the warp and the weft each way round, scaled to the start's mean
 * diffuse colour; and both yarns given that mean (a one-colour cloth, where the start
 * split the hues: per-channel detail the photo lacks). The candidate with the lowest
 * loss (the start included) is kept.
 * The loss sees yarns of one or two pixels at no phase (its pixel term is downsampled),
 * so it cannot tell which yarn type wears which colour. The weave can when one yarn type
 * covers more of the cloth than the other (a 2/1 twill, a satin): the way round whose
 * render has a share of dark pixels nearer the photo's is kept (the renders carry the
 * yarns' shading, which moves that share away from the weave's coverage), and a start
 * with the colours the other way round is not. Where both cover half (plain, basket, 2/2
 * twills), the swap is a shift of the weave when the two densities are equal, which the
 * registration after the fit finds; with other densities it is not, and the photo in
 * register decides: the way round whose render, in phase with the photo, has the higher
 * SSIM (docs/fit.md). */
static wv_status colour_split(fit_ctx *c, wv_fit_state *st, const wv_scene *s, const wv_image *photo,
                              const wv_fit_opts *o, wv_error *err) {
  double r[2][3], dark_share = 0.5;
  wv_fit_record base = {0};
  wv_status rc = evaluate(c, &st->params, &base, NULL, NULL, err);
  if (rc || !colour_clusters(&c->scene, &c->photo, r, &dark_share, err)) return rc;
  wv_weave w;
  double warp_share = 0.5;
  if (!wv_params_weave(&st->params, &w, NULL)) {
    int n = 0;
    for (int i = 0; i < w.rows; i++)
      for (int j = 0; j < w.cols; j++) n += w.p[i][j] != 0;
    warp_share = (double)n / (w.rows * w.cols);
  }
  wv_params cand_p[6];
  double cand_loss[6], lo, hi, gap[2] = {0, 0};
  for (int cand = 1; cand <= 5; cand++) {
    double alpha = cand <= 2 ? 1.0 : cand <= 4 ? 2.0 : 0.0; /* 5: both the mean colour */
    int dark = (cand & 1) ? WV_WARP : WV_WEFT;              /* the yarn type given the darker colour */
    wv_params *p = &cand_p[cand];
    *p = st->params;
    for (int ch = 0; ch < 3; ch++) {
      double m = 0.5 * (st->params.diffuse[WV_WARP][ch] + st->params.diffuse[WV_WEFT][ch]);
      for (int k = 0; k < 2; k++) {
        int y = k == 0 ? dark : 1 - dark, id = y == WV_WARP ? WV_P_KD_WARP_R + ch : WV_P_KD_WEFT_R + ch;
        wv_param_range(id, &lo, &hi);
        double v = m * (1 + alpha * (r[k][ch] - 1));
        p->diffuse[y][ch] = v < lo ? lo : v > hi ? hi : v;
      }
    }
    cand_loss[cand] = INFINITY;
  }
  /* the yarn type the darker colour must go on, or -1: either */
  int need = -1;
  if (fabs(warp_share - 0.5) >= SPLIT_WEAVE_MIN) {
    for (int cand = 1; cand <= 2 && !rc; cand++) {
      wv_fit_record rec = {0};
      double rr[2][3], share = 0.5;
      if ((rc = evaluate(c, &cand_p[cand], &rec, NULL, NULL, err))) break;
      cand_loss[cand] = rec.loss;
      if (colour_clusters(&c->scene, &c->render, rr, &share, err)) {
        /* the render's clusters matched to the photo's by colour: yarns that differ in hue
         * more than in brightness can order them the other way by luminance */
        double same = 0, swapped = 0;
        for (int ch = 0; ch < 3; ch++)
          same += sq(rr[0][ch] - r[0][ch]) + sq(rr[1][ch] - r[1][ch]),
              swapped += sq(rr[0][ch] - r[1][ch]) + sq(rr[1][ch] - r[0][ch]);
        if (swapped < same) share = 1 - share;
      }
      gap[cand - 1] = fabs(share - dark_share);
    }
    if (!rc && fabs(gap[0] - gap[1]) >= SPLIT_SHARE_GAP) need = gap[0] < gap[1] ? WV_WARP : WV_WEFT;
  }
  double lum[2];
  for (int y = 0; y < 2; y++)
    lum[y] = wv_luminance_d(st->params.diffuse[y][0], st->params.diffuse[y][1], st->params.diffuse[y][2]);
  int start_dark = lum[WV_WARP] < lum[WV_WEFT] ? WV_WARP : WV_WEFT;
  int start_ok = need < 0 || start_dark == need || fabs(lum[0] - lum[1]) < SPLIT_LUM_SAME * (lum[0] + lum[1]);
  double best = start_ok ? base.loss : INFINITY;
  int choice = 0;
  wv_params best_p = st->params;
  for (int cand = 1; cand <= 5 && !rc; cand++) {
    int dark = (cand & 1) ? WV_WARP : WV_WEFT;
    if (cand <= 4 && need >= 0 && dark != need) continue;
    if (cand_loss[cand] == INFINITY) {
      wv_fit_record rec = {0};
      if ((rc = evaluate(c, &cand_p[cand], &rec, NULL, NULL, err))) break;
      cand_loss[cand] = rec.loss;
    }
    if (cand_loss[cand] < best) best = cand_loss[cand], choice = cand, best_p = cand_p[cand];
  }
  if (!rc && fabs(warp_share - 0.5) < SPLIT_WEAVE_MIN && choice >= 1 && choice <= 4 && o->register_radius > 0) {
    /* A split won and each yarn type covers half: the photo in register tells the way
     * round. The loss's choice is registered (its densities near the start's and its phase,
     * as after the fit), the other way round put in phase at those densities, and the
     * higher SSIM per RGB channel kept (the loss's choice on a tie). */
    int other = choice + ((choice & 1) ? 1 : -1);
    wv_fit_state t = *st;
    t.params = cand_p[choice];
    double ssim_other = 0;
    if (!(rc = wv_fit_register_near(&t, s, photo, o, err))) {
      wv_params m = cand_p[other];
      m.density[0] = t.params.density[0], m.density[1] = t.params.density[1];
      rc = wv_fit_register_phase(&t, s, photo, &m, o, &ssim_other, err);
    }
    if (!rc && ssim_other > t.reg_ssim_after) choice = other, best_p = cand_p[other];
  }
  st->params = best_p;
  st->colour_split = choice;
  return rc;
}

/* The noise level by exhaustion: the loss of every level 0..10 with the other parameters as
 * they are, the lowest kept (the current level on a tie). The level scales each yarn
 * segment's height by its own random factor, so a cloth's irregularity shows only in
 * statistics that one random step of +-1, judged by one noisy loss, rarely climbs far
 * along; the renders share their samples, so the losses differ by the level alone. */
static wv_status noise_sweep(fit_ctx *c, wv_fit_state *st, wv_error *err) {
  double best = INFINITY;
  int best_q = st->params.noise_level;
  for (int q = 0; q <= 10; q++) {
    wv_params trial = st->params;
    trial.noise_level = q;
    wv_fit_record rec = {0};
    wv_status rc = evaluate(c, &trial, &rec, NULL, NULL, err); /* geometry: the reflection photo's */
    if (rc) return rc;
    if (rec.loss < best || (rec.loss == best && q == st->params.noise_level)) best = rec.loss, best_q = q;
  }
  st->params.noise_level = best_q;
  return WV_OK;
}

/* A photo pair's yarn width by search (width_sweep): the open gaps it leaves, (1 - width)^2
 * of the cloth, show in the transmission photo as light straight through, and the width
 * has no gradient (a gap's edge is a step). The pair's loss at the width as it is, at 1,
 * 0.9 .. 0.5, then at steps of 0.05, 0.025 and 0.0125 either side of the best; the lowest
 * kept (the width as it was on a tie). */
static wv_status width_sweep(fit_ctx *c, fit_ctx *ct, wv_fit_state *st, wv_error *err) {
  double lo, hi, best = INFINITY, best_w = st->params.yarn_width;
  wv_param_range_width(&lo, &hi);
  double grid[6] = {1.0, 0.9, 0.8, 0.7, 0.6, 0.5};
  for (int k = -1; k < 6 + 6; k++) {
    double w = k < 0 ? st->params.yarn_width : k < 6 ? grid[k] : best_w + (k % 2 ? 1 : -1) * 0.1 / (1 << ((k - 6) / 2 + 1));
    /* the width as it is was the first tried: its loss would only tie */
    if (w < lo || w > hi || (k >= 0 && w == st->params.yarn_width)) continue;
    wv_params trial = st->params;
    trial.yarn_width = w;
    double loss;
    wv_status rc = pair_loss(c, ct, &trial, &loss, err);
    if (rc) return rc;
    if (loss < best) best = loss, best_w = w;
  }
  st->params.yarn_width = best_w;
  return WV_OK;
}

/* The first stage's window: the centre of the scene, 1/WV_FIT_WINDOW_DIV of each side, the
 * same pixels as the whole image there; the whole image when the window would be too small
 * for the fit. */
static void stage_window(const wv_scene *s, const wv_descriptor *d, const wv_fit_opts *o, int *w, int *h) {
  *w = s->width / WV_FIT_WINDOW_DIV, *h = s->height / WV_FIT_WINDOW_DIV;
  *w -= (s->width - *w) % 2, *h -= (s->height - *h) % 2; /* centred on whole pixels */
  wv_scene win;
  wv_scene_centre_window(s, *w, *h, &win);
  if (wv_fit_check_sizes(&win, d, o, NULL)) *w = s->width, *h = s->height;
}

/* The context of a stage: 0 the centre window, 1 the whole image. */
static wv_status stage_ctx(fit_ctx *c, int stage, const wv_scene *s, const wv_image *photo, wv_descriptor *d,
                           const wv_fit_opts *o, wv_fit_timing *timing, wv_error *err) {
  int w = s->width, h = s->height;
  if (stage == 0) stage_window(s, d, o, &w, &h);
  if (w == s->width && h == s->height) return ctx_init(c, s, photo, d, o->iter_scale, o->iter_spp, o, timing, err);
  wv_scene win;
  wv_image pw;
  wv_scene_centre_window(s, w, h, &win);
  wv_status rc = wv_image_centre_crop(photo, w, h, &pw, err);
  if (rc) return rc;
  /* the pixel term's cells as large as the whole image's (there they are the centre cells):
   * smaller ones would fit the window's light to a detail the whole image's term ignores */
  c->wopts = *o;
  c->wopts.down_w = (o->down_w * w + s->width / 2) / s->width;
  c->wopts.down_h = (o->down_h * h + s->height / 2) / s->height;
  if (c->wopts.down_w < 1) c->wopts.down_w = 1;
  if (c->wopts.down_h < 1) c->wopts.down_h = 1;
  rc = ctx_init(c, &win, &pw, d, o->iter_scale, o->iter_spp, &c->wopts, timing, err);
  wv_image_free(&pw);
  return rc;
}

/* A pair's back-lit photo as its own view of the cloth, after the iterations (which compare
 * the two photos' textures, not where their yarns lie): its scale and rotation against the
 * front-lit photo from their weaves (wv_weave_relate), then its own registration (the
 * densities it shows, near the fit's, and its phase) and distortion, on a copy of the state
 * whose offset and distortion are the back-lit photo's: from none when the weaves relate (another
 * view), from the front-lit photo's when they do not (taken as one camera's view). The
 * parameters do not change. Measured after the iterations rather than before them: with the
 * scale in the back-lit scene from the start, the transmission colours of a pair came out 17%
 * too bright (docs/measurements.md, "The back-lit photo's own view"). */
static wv_status own_view_t(wv_fit_state *st, const wv_scene *s_t, const wv_image *photo, const wv_image *photo_t,
                            const wv_fit_opts *o, wv_error *err) {
  wv_status rc = WV_OK;
  double ta = omp_get_wtime();
  if (!st->t_related) {
    wv_weave_relation rel;
    if ((rc = wv_weave_relate(photo, photo_t, &rel, err))) return rc;
    st->t_found = rel.found;
    st->t_scale = rel.scale, st->t_rotation_deg = rel.rotation_deg;
    if (!rel.found) {
      st->t_offset_mm[0] = st->offset_mm[0], st->t_offset_mm[1] = st->offset_mm[1];
      st->t_distort_extent_mm = st->distort_extent_mm;
      memcpy(st->t_distort, st->distort, sizeof st->t_distort);
    }
    st->t_related = 1;
  }
  wv_fit_state v = *st; /* shares st's log, which neither step reads */
  wv_scene base = *s_t; /* the scale and rotation go in the scene; the offset and distortion in v */
  wv_fit_state sr = {.t_related = 1, .t_found = st->t_found, .t_scale = st->t_scale, .t_rotation_deg = st->t_rotation_deg};
  wv_fit_scene_t(&sr, s_t, &base);
  wv_fit_params_t(st, &st->params, &v.params);
  v.offset_mm[0] = st->t_offset_mm[0], v.offset_mm[1] = st->t_offset_mm[1];
  v.distort_extent_mm = st->t_distort_extent_mm;
  memcpy(v.distort, st->t_distort, sizeof v.distort);
  if (!st->t_registered && o->register_radius == 0) st->t_registered = 1; /* off, as for the front-lit photo */
  if (!st->t_distorted && o->distort_degree == 0) st->t_distorted = 1;
  /* near the fit's densities: the scale already carries the front-lit photo's to the back-lit one's */
  if (!st->t_registered && !(rc = wv_fit_register_view(&v, &base, photo_t, o, err))) {
    st->t_registered = 1;
    for (int k = 0; k < 2; k++) st->t_density_ratio[k] = v.params.density[k] / st->params.density[k];
    st->t_offset_mm[0] = v.offset_mm[0], st->t_offset_mm[1] = v.offset_mm[1];
    st->t_reg_ssim_before = v.reg_ssim_before, st->t_reg_ssim_after = v.reg_ssim_after;
  }
  st->timing.registration += omp_get_wtime() - ta;
  st->timing.total += omp_get_wtime() - ta;
  ta = omp_get_wtime();
  if (!rc && !st->t_distorted && !(rc = wv_fit_distort(&v, &base, photo_t, o, err))) {
    st->t_distorted = 1;
    st->t_offset_mm[0] = v.offset_mm[0], st->t_offset_mm[1] = v.offset_mm[1];
    st->t_distort_extent_mm = v.distort_extent_mm;
    memcpy(st->t_distort, v.distort, sizeof st->t_distort);
    st->t_dist_ssim_before = v.dist_ssim_before, st->t_dist_ssim_after = v.dist_ssim_after;
  }
  st->timing.distortion += omp_get_wtime() - ta;
  st->timing.total += omp_get_wtime() - ta;
  return rc;
}

wv_status wv_fit_run(wv_fit_state *st, const wv_scene *s, const wv_image *photo, wv_descriptor *d,
                     const wv_fit_opts *o, wv_fit_callback cb, void *user, wv_error *err) {
  return wv_fit_run_pair(st, s, photo, NULL, NULL, d, o, cb, user, err);
}

wv_status wv_fit_run_pair(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_scene *s_t,
                          const wv_image *photo_t, wv_descriptor *d, const wv_fit_opts *o, wv_fit_callback cb,
                          void *user, wv_error *err) {
  int pair = s_t && photo_t;
  st->pair = pair;
  wv_status vs = wv_fit_opts_validate(o, err);
  if (vs) return vs;
  if (o->iters > st->log_cap) {
    wv_fit_record *nl = realloc(st->log, sizeof *nl * (size_t)o->iters);
    if (!nl) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the fit log");
    st->log = nl, st->log_cap = o->iters;
  }
  int from = 0, stage = wv_fit_stage(st, o, &from);
  if (stage < 2) /* more iterations: align again after them */
    st->aligned = st->registered = st->distorted = st->t_registered = st->t_distorted = 0;
  /* One context per stage (the coarse one and the full one), each made once: the photo's
   * side of the loss and the camera geometry do not change between iterations. */
  fit_ctx cx[2], ct[2]; /* ct: the transmission photo's, for a pair */
  wv_trans_basis *tb = NULL; /* the transmission colours' iterations: the back-lit capture as their function */
  int made[2] = {0, 0}, made_t[2] = {0, 0};
  wv_params t_cache_p; /* the colours' last accepted trial, evaluated: the next iteration's point */
  wv_fit_record t_cache_rec;
  double t_cache_g[WV_P_COUNT];
  int t_cached = 0;
  double scale = o->iter_scale;
  memset(cx, 0, sizeof cx);
  memset(ct, 0, sizeof ct);
  double t_start = omp_get_wtime();
  wv_status rc = wv_fit_check_sizes(s, d, o, err);
  if (!rc && (photo->w != s->width || photo->h != s->height))
    rc = wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                 s->width, s->height);
  if (!rc && pair) rc = wv_fit_check_sizes(s_t, d, o, err);
  if (!rc && pair && (photo_t->w != s_t->width || photo_t->h != s_t->height))
    rc = wv_fail(err, WV_ERR_INVALID, "the transmission photo is %d x %d but its scene renders %d x %d", photo_t->w,
                 photo_t->h, s_t->width, s_t->height);
  if (!rc && !st->psf_done) {
    /* the camera blur: given by the options or the scene, else measured on the start */
    double tp = omp_get_wtime();
    st->psf_sigma = o->psf_sigma >= 0 ? o->psf_sigma : s->psf_sigma;
    if (o->psf_sigma < 0 && !(s->psf_sigma > 0)) {
      wv_scene se;
      wv_fit_scene(st, s, &se);
      rc = wv_psf_estimate(&se, photo, &st->params, o->threads, &st->psf_sigma, NULL, err);
    }
    st->psf_done = !rc;
    st->psf_start = st->psf_sigma;
    /* a measured blur is fitted with the parameters (a given one, or none measured, stays) */
    st->psf_fit = o->psf_fit && o->psf_sigma < 0 && !(s->psf_sigma > 0) && st->psf_sigma > 0;
    st->timing.discrete += omp_get_wtime() - tp;
  }
  wv_scene sb; /* the scene with the fit's camera blur */
  wv_fit_scene(st, s, &sb);
  if (!rc && st->iter == 0 && pair && o->width_sweep && o->iters > 0 && s_t->glow_radiance > 0) {
    /* the open area as the back-lit photo's gap glow shows it: its loss alone rejects the gaps
     * while the rest of the fit is off (docs/fit.md, "Photo pairs") */
    double td = omp_get_wtime();
    wv_open_area oa;
    if (!(rc = wv_open_area_measure(s_t, photo_t, &oa, err)) && oa.found) {
      double lo, hi, open = oa.open_area > 0 ? oa.open_area : 0;
      wv_param_range_width(&lo, &hi);
      double w = 1 - sqrt(open);
      st->params.yarn_width = w < lo ? lo : w > hi ? hi : w;
      st->open_measured = 1, st->open_photo = oa.open_area;
    }
    st->timing.discrete += omp_get_wtime() - td;
  }
  if (!rc && st->iter == 0 && o->colour_split && o->iters > 0) {
    /* at the full iteration scale: the split reads the colours of single yarns. After a pair's
     * open area: the gaps change which way round the colours render closer to the photo
     * (docs/measurements.md, "The colour split after the open area") */
    double td = omp_get_wtime();
    wv_fit_timing saved = st->timing;
    if (!(rc = stage_ctx(&cx[1], 1, s, photo, d, o, &st->timing, err))) {
      made[1] = 1;
      cx[1].scene.psf_sigma = sb.psf_sigma / scale;
      rc = colour_split(&cx[1], st, s, photo, o, err);
    }
    st->timing.render = saved.render, st->timing.descriptor = saved.descriptor; /* counted as a discrete step */
    st->timing.discrete += omp_get_wtime() - td;
  }
  while (!rc && stage < 2) {
    int k = stage > 0;
    fit_ctx *c = &cx[k];
    if (!made[k]) {
      if ((rc = stage_ctx(c, k, s, photo, d, o, &st->timing, err))) break;
      made[k] = 1;
    }
    c->scene.psf_sigma = (st->psf_done ? st->psf_sigma : s->psf_sigma) / scale;
    fit_ctx *tc = NULL;
    if (pair) { /* the same camera: the same blur */
      tc = &ct[k];
      if (!made_t[k]) {
        if ((rc = stage_ctx(tc, k, s_t, photo_t, d, o, &st->timing, err))) break;
        made_t[k] = 1, tc->no_prior = 1;
      }
      tc->scene.psf_sigma = c->scene.psf_sigma;
    }
    int t_alone = t_next(st->log, o, pair, stage, from, st->iter);
    wv_fit_record rec = {0};
    rec.iter = st->iter;
    double g[WV_P_COUNT] = {0};
    double dpsf = 0;
    float z[WV_P_COUNT], gz[WV_P_COUNT];
    if (t_alone) {
      /* the transmission colours on the transmission photo: nothing else is stepped, so the
       * reflection photo, which does not see them, is not rendered */
      if (t_phase(st->log, from, st->iter) == st->iter) {
        /* k_f moves if the start has a band or a search adds one: before the candidates, which
         * then hold it, or else after them, against the colours they chose */
        int band = wv_params_has_forward_band(&st->params);
        if (!band && o->forward_sweep) {
          if ((rc = forward_sweep(tc, &tb, st, err))) break;
          band = wv_params_has_forward_band(&st->params);
        }
        int n_free = band ? WV_P_COUNT - WV_P_REFLECT_COUNT : WV_P_KF_WARP_R - WV_P_REFLECT_COUNT;
        if ((rc = colours_start(tc, &tb, st, n_free, err))) break;
        if (!band && o->forward_sweep) {
          if ((rc = forward_sweep(tc, &tb, st, err))) break;
          if (wv_params_has_forward_band(&st->params)) wv_nn_lbfgs_grow(&st->t_qn, WV_P_COUNT - WV_P_REFLECT_COUNT);
        }
      }
      int same = t_cached; /* the last step's trial, evaluated, is where the colours are */
      for (int i = WV_P_REFLECT_COUNT; i < WV_P_COUNT && same; i++)
        same = wv_param_get(&t_cache_p, i) == wv_param_get(&st->params, i);
      if (same) {
        rec = t_cache_rec, rec.iter = st->iter;
        memcpy(g, t_cache_g, sizeof g);
      } else if ((rc = evaluate_t(tc, &tb, &st->params, &rec, g, err))) {
        break;
      }
      rec.loss_t = rec.loss, rec.t_alone = 1;
      if ((rc = colours_step(tc, &tb, &st->params, &st->t_qn, &rec, g, &t_cache_p, &t_cache_rec, t_cache_g, &t_cached,
                              err)))
        break;
    } else {
      if ((rc = evaluate(c, &st->params, &rec, g, st->psf_fit ? &dpsf : NULL, err))) break;
      int t = st->iter + 1;
      /* Discrete search: a random step is kept only if it lowers the loss. It is compared with
       * this iteration's render (the parameters the gradient was taken at), so it costs one
       * forward render; the continuous parameters then take their Adam step from there (the
       * discrete ones are not among them). */
      if (o->discrete_every > 0 && t % o->discrete_every == 0) {
        double td = omp_get_wtime();
        wv_fit_timing saved = st->timing;
        wv_params trial = st->params;
        if (discrete_step(&trial, &st->rng, st->iter, o->iters, o->density_steps)) {
          wv_fit_record alt = {0};
          if ((rc = evaluate(c, &trial, &alt, NULL, NULL, err))) break;
          rec.discrete_tried = 1;
          if (alt.loss < rec.loss) {
            st->params = trial;
            rec.discrete_kept = 1;
          }
        }
        /* account the search as its own item, not as render/descriptor time */
        double spent = omp_get_wtime() - td;
        st->timing.render = saved.render, st->timing.descriptor = saved.descriptor;
        st->timing.discrete += spent;
      }
      /* Adam in normalised coordinates z = (theta - lo) / (hi - lo), projected onto [0, 1];
       * z is remade from the parameters every step, so a resumed fit repeats this exactly. */
      param_z(&st->params, g, z, gz);
      wv_nn_adam adam = {.n = WV_P_REFLECT_COUNT, .lr = (float)o->lr, .beta1 = 0.9f, .beta2 = 0.999f, .eps = 1e-8f,
                         .weight_decay = 0.0f, .t = st->iter, .m = st->adam_m, .v = st->adam_v};
      wv_nn_adam_step_box(&adam, z, gz, 0.0f, 1.0f);
      /* a back-lit scene fitted alone shows the transmission colours too: they step with the
       * rest, WV_FIT_LR_T_SCALE times as far (docs/fit.md, "Photo pairs") */
      if (wv_scene_transmits(s)) {
        wv_nn_adam adam_t = adam;
        adam_t.t = st->iter;
        adam_t.n = WV_P_COUNT - WV_P_REFLECT_COUNT, adam_t.lr = (float)(o->lr * WV_FIT_LR_T_SCALE);
        adam_t.m = st->adam_m + WV_P_REFLECT_COUNT, adam_t.v = st->adam_v + WV_P_REFLECT_COUNT;
        wv_nn_adam_step_box(&adam_t, z + WV_P_REFLECT_COUNT, gz + WV_P_REFLECT_COUNT, 0.0f, 1.0f);
      }
      param_set_z(&st->params, z, 0, wv_scene_transmits(s) ? WV_P_COUNT : WV_P_REFLECT_COUNT);
      if (st->psf_fit) {
        /* the camera blur, by the same Adam on z = sigma / WV_PSF_RANGE: a measured blur
         * and the parameters trade contrast, so they settle together */
        float zs = (float)(st->psf_sigma / WV_PSF_RANGE), gs = (float)(dpsf / scale * WV_PSF_RANGE);
        if (!isfinite(gs)) gs = 0.0f;
        wv_nn_adam a1 = {.n = 1, .lr = (float)o->lr, .beta1 = 0.9f, .beta2 = 0.999f, .eps = 1e-8f,
                         .weight_decay = 0.0f, .t = st->iter, .m = &st->psf_m, .v = &st->psf_v};
        wv_nn_adam_step_box(&a1, &zs, &gs, 0.0f, 1.0f);
        st->psf_sigma = zs * WV_PSF_RANGE;
      }
    }
    st->log[st->iter] = rec;
    st->iter++;
    stage = stage_after(st->log, o, pair, stage, &from, st->iter);
    int r_over = stage == 2 ? !t_alone : t_next(st->log, o, pair, stage, from, st->iter) && !t_alone;
    if (r_over || (stage == 2 && pair)) {
      /* the reflection photo's iterations are over: the noise level, before the transmission
       * colours' iterations fit what it renders; a pair's yarn width when they are over. Before
       * the checkpoint that records it. */
      double td = omp_get_wtime();
      wv_fit_timing saved = st->timing;
      c->scene.psf_sigma = (st->psf_done ? st->psf_sigma : s->psf_sigma) / scale;
      if (tc) tc->scene.psf_sigma = c->scene.psf_sigma;
      if (r_over && o->noise_sweep && (rc = noise_sweep(c, st, err))) break;
      if (stage == 2 && pair && o->width_sweep && !st->open_measured && (rc = width_sweep(c, tc, st, err))) break;
      st->timing.render = saved.render, st->timing.descriptor = saved.descriptor;
      st->timing.discrete += omp_get_wtime() - td;
    }
    st->timing.total += omp_get_wtime() - t_start;
    t_start = omp_get_wtime();
    if (cb && cb(user, st, o)) break;
  }
  wv_trans_basis_free(tb);
  for (int k = 0; k < 2; k++) {
    if (made[k]) ctx_free(&cx[k]);
    if (made_t[k]) ctx_free(&ct[k]);
  }
  wv_fit_scene(st, s, &sb); /* the blur as fitted; the offset as given (the alignment comes before the registration) */
  sb.fabric_offset[0] = s->fabric_offset[0], sb.fabric_offset[1] = s->fabric_offset[1];
  int over = !rc && stage == 2;
  if (over && !st->aligned && o->align_radius > 0) {
    double ta = omp_get_wtime();
    rc = align_densities(st, &sb, photo, o, err);
    st->timing.discrete += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  if (!rc && over && !st->registered && o->register_radius > 0) {
    double ta = omp_get_wtime();
    rc = wv_fit_register(st, s, photo, o, err);
    st->timing.registration += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  if (!rc && over && !st->distorted && o->distort_degree > 0) {
    double ta = omp_get_wtime();
    rc = wv_fit_distort(st, s, photo, o, err);
    st->timing.distortion += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  if (!rc && over && pair && (!st->t_related || !st->t_registered || !st->t_distorted))
    rc = own_view_t(st, s_t, photo, photo_t, o, err);
  return rc;
}
