/* woven: choosing the weave pattern FabricNet does not predict, over the whole built-in
 * library: the weave analysis of the photo ranks the built-ins by their own renders'
 * spectral peaks, the fit's loss criterion breaks near ties and decides when the photo
 * shows no weave lattice. */
#include <jansson.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/imgops.h"
#include "woven/loss.h"
#include "woven/pattern.h"
#include "woven/render.h"

void wv_pattern_opts_default(wv_pattern_opts *o) {
  memset(o, 0, sizeof *o);
  o->spp = WV_PATTERN_SPP;
  o->threads = 0;
  o->w_pixel = WV_PATTERN_W_PIXEL;
  o->lattice = 1;
  o->tie = WV_PATTERN_TIE;
  o->family_tie = WV_PATTERN_FAMILY_TIE;
  o->prob = NULL;
  o->w_prob = 0.25;
  o->psf_sigma = -1;
  o->orient = 1;
  o->refine = 1;
}

/* The loss criterion of candidate i: its parameters rendered over the whole image at sc's
 * spp, through the fit's image loss (Gram and pixel terms, the criterion's own pixel weight). */
static wv_status loss_of(wv_image_loss *loss, const wv_scene *sc, const wv_pattern_opts *o, int i,
                         wv_pattern_choice *out, wv_error *err) {
  wv_render_opts ro = {.spp = sc->spp, .threads = o->threads};
  wv_image img = {0};
  wv_scene si;
  wv_pattern_choice_scene(out, sc, i, &si);
  /* the same render seed for every candidate: the losses then differ by the pattern, not the noise draw */
  wv_status st = wv_render(&si, &out->params[i], &ro, &img, NULL, err);
  wv_loss_terms t;
  if (!st) st = wv_image_loss_eval(loss, &img, &t, NULL, err);
  wv_image_free(&img);
  if (st) return st;
  out->gram[i] = t.gram, out->pixel[i] = t.pixel;
  out->loss[i] = t.total;
  out->evaluated[i] = 1;
  return WV_OK;
}

static wv_status criterion_create(const wv_image *photo, wv_descriptor *d, const float *gram_photo,
                                  const wv_pattern_opts *o, wv_image_loss **loss, wv_error *err) {
  wv_loss_weights lw = {.w_pixel = o->w_pixel, .down_w = WV_LOSS_DOWN_W, .down_h = WV_LOSS_DOWN_H};
  return wv_image_loss_create(photo, d, gram_photo, &lw, loss, err);
}

wv_status wv_pattern_loss(wv_descriptor *d, const wv_scene *s, const wv_image *photo, const float *gram_photo,
                          const wv_pattern_opts *o, int i, wv_pattern_choice *c, wv_error *err) {
  if (c->evaluated[i]) return WV_OK;
  wv_scene sc = *s;
  sc.spp = c->spp;
  wv_image_loss *loss = NULL;
  wv_status st = criterion_create(photo, d, gram_photo, o, &loss, err);
  if (!st) st = loss_of(loss, &sc, o, i, c, err);
  wv_image_loss_free(loss);
  return st;
}

void wv_pattern_choice_scene(const wv_pattern_choice *c, const wv_scene *s, int i, wv_scene *out) {
  wv_params unused;
  wv_scene in = *s;
  *out = in;
  if (c->orient && c->start_refined && i == c->best)
    wv_lattice_fit_apply(&c->start_fit, &c->params[i], &in, 1, &unused, out);
  else if (c->orient && c->lattice.found)
    wv_lattice_candidate(&c->lattice, i, &c->params[i], &in, 1, &unused, out);
}

static const char *const FAMILY[WV_PATTERN_FAMILIES] = {"plain", "basket", "twill", "satin"};

static int family_index(int i) {
  int f = 0;
  while (f < WV_PATTERN_FAMILIES - 1 && strcmp(wv_weave_family(wv_weave_builtin_name(i)), FAMILY[f])) f++;
  return f;
}

/* Each built-in's lattice score as the family step weighs it (term). A built-in whose
 * yarns lie in groups (a basket) and its twin that weaves as the groups (plain) describe
 * one cloth seen through a blur when the first's densities are the groups' times the twin's
 * (wv_weave_builtin_twin). Their lattices share the points of the colour checks; they
 * differ at the twin's yarn frequency, which the groups' shading shows and the grouped
 * lattice does not hold, and at the grouped one's own yarn frequency, which the blur takes
 * out: which scores higher tells the camera's blur, not the weave. Each then takes the
 * better of the two, and their renders and the network decide. */
static void lattice_terms(const wv_lattice *l, double *term) {
  int nb = wv_weave_builtin_count(), g[2];
  for (int i = 0; i < nb; i++) term[i] = l->fit[i].score;
  for (int k = 0; k < nb; k++) { /* k: a grouped built-in */
    int twin = wv_weave_builtin_twin(k, g), same = twin >= 0;
    for (int d = 0; d < 2 && same; d++) {
      double a = l->fit[k].density[d], b = g[d] * l->fit[twin].density[d]; /* 0: not fitted */
      same = a > 0 && b > 0 && fabs(log(a / b)) < WV_LATTICE_NEAR;
    }
    if (same) term[k] = term[twin] = fmax(l->fit[k].score, l->fit[twin].score);
  }
}

/* Step 2's family score: the best mean of lattice term (lattice_terms) and ranking score over
 * the family's built-ins (ff) and the built-in that has it (arg, may be NULL), and the
 * family's best-ranked built-in (rep); -1 for a family without any. */
static void lattice_families(const wv_pattern_choice *c, double *ff, int *rep, int *arg) {
  const wv_lattice *l = &c->lattice;
  const wv_lattice_ranking *r = &c->ranking;
  double term[WV_WEAVE_BUILTINS];
  lattice_terms(l, term);
  for (int f = 0; f < WV_PATTERN_FAMILIES; f++) ff[f] = -1, rep[f] = -1;
  for (int k = 0; k < wv_weave_builtin_count(); k++) {
    int i = r->order[k], f = family_index(i);
    double v = 0.5 * (term[i] + r->score[i]);
    if (v > ff[f]) {
      ff[f] = v;
      if (arg) arg[f] = i;
    }
    if (rep[f] < 0) rep[f] = i;
  }
}

void wv_pattern_family_scores(const wv_pattern_choice *c, wv_pattern_families *out) {
  int prob = !c->lattice.found && c->method && !strcmp(c->method, "network");
  int loss = !c->lattice.found && c->method && !strcmp(c->method, "loss");
  out->kind = c->lattice.found ? "lattice+ranking" : prob ? "probability" : loss ? "loss" : "none";
  out->higher_is_better = !loss;
  for (int f = 0; f < WV_PATTERN_FAMILIES; f++) out->family[f] = FAMILY[f], out->pattern[f] = -1, out->score[f] = 0;
  if (c->lattice.found) {
    int rep[WV_PATTERN_FAMILIES];
    lattice_families(c, out->score, rep, out->pattern);
  } else if (prob || loss) {
    /* each family's most probable built-in, or the one with the smallest loss criterion */
    for (int i = 0; i < wv_weave_builtin_count(); i++) {
      int f = family_index(i);
      if (loss && !c->evaluated[i]) continue;
      double v = prob ? c->prob[i] : c->loss[i];
      if (out->pattern[f] < 0 || (prob ? v > out->score[f] : v < out->score[f])) out->pattern[f] = i, out->score[f] = v;
    }
  }
  for (int f = 0; f < WV_PATTERN_FAMILIES; f++) {
    if (out->pattern[f] < 0) out->score[f] = 0;
    out->order[f] = f;
  }
  /* best first, families without a candidate last (an insertion sort of four) */
  for (int a = 1; a < WV_PATTERN_FAMILIES; a++)
    for (int b = a; b > 0; b--) {
      int fa = out->order[b - 1], fb = out->order[b];
      int swap = out->pattern[fa] < 0   ? out->pattern[fb] >= 0
                 : out->pattern[fb] < 0 ? 0
                 : out->higher_is_better ? out->score[fb] > out->score[fa]
                                         : out->score[fb] < out->score[fa];
      if (!swap) break;
      out->order[b - 1] = fb, out->order[b] = fa;
    }
}

int wv_pattern_decide(const wv_pattern_choice *c, double family_tie, double tie, int *contenders) {
  const wv_lattice_ranking *r = &c->ranking;
  int nb = wv_weave_builtin_count();
  /* 1. The family: the best by the mean of lattice term (lattice_terms) and ranking score
   * (the lattice cannot tell a plain weave from a basket at twice its densities; their
   * renders differ, and so do the network's probabilities,
   * which the ranking score holds: on a two-colour plain weave the render match alone
   * prefers the basket, whose colour checks look the same), or the loss criterion among
   * the contenders, each represented by its best-ranked pattern. */
  double ff[WV_PATTERN_FAMILIES];
  int rep[WV_PATTERN_FAMILIES], fam = 0, n = 0;
  lattice_families(c, ff, rep, NULL);
  for (int f = 1; f < 4; f++)
    if (ff[f] > ff[fam]) fam = f;
  int best_f = -1;
  for (int f = 0; f < 4; f++)
    if (rep[f] >= 0 && ff[f] >= ff[fam] - family_tie) {
      n++;
      if (best_f >= 0 && (!c->evaluated[rep[f]] || !c->evaluated[rep[best_f]]))
        return -1 - (c->evaluated[rep[f]] ? rep[best_f] : rep[f]);
      if (best_f < 0 || c->loss[rep[f]] < c->loss[rep[best_f]]) best_f = f;
    }
  if (contenders) *contenders = n;
  if (n > 1) fam = best_f;
  /* 2. The pattern within it: the best ranking score; near ties by the loss criterion, and
   * so is any built-in whose render matches the photo's peaks better than that one's by more
   * than tie: the network's probability in the score must not carry, alone, a pattern whose
   * render shows the photo's weave far worse. */
  int best = rep[fam];
  for (int k = 0; k < nb; k++) {
    int i = r->order[k];
    if (i == rep[fam] || family_index(i) != fam) continue;
    int near = r->score[i] >= r->score[rep[fam]] - tie, matches = tie > 0 && r->match[i] > r->match[rep[fam]] + tie;
    if (!near && !matches) continue;
    if (!c->evaluated[i] || !c->evaluated[best]) return -1 - (c->evaluated[i] ? best : i);
    if (c->loss[i] < c->loss[best]) best = i;
  }
  return best;
}

/* The chosen built-in b's lattice climbed from densities `from` (wv_lattice_refine_from)
 * with its orientation, against the start `start` rendered in `start_scene` (its peak match
 * `known`, or NULL to measure it): the refined start replaces out->params[b]
 * (start_refined) when its render's peaks match the photo's better, or no worse unless
 * strict. Fills the choice's start_refine_tried, start_refine_moved, start_fit,
 * refine_match and unrefined. */
static wv_status climb_start(const wv_scene *s, const wv_image *photo, int b, const double from[2],
                             const wv_scene *start_scene, const wv_params *start, const double *known, int strict,
                             int spp, int threads, wv_pattern_choice *out, wv_error *err) {
  int moved = 0;
  out->unrefined[0] = from[0], out->unrefined[1] = from[1];
  wv_status st = wv_lattice_refine_from(s, photo, b, from, &out->start_fit, &moved, err);
  out->start_refine_tried = !st, out->start_refine_moved = moved;
  if (st || !moved) return st;
  wv_params pr;
  wv_scene sr;
  wv_lattice_fit_apply(&out->start_fit, &out->params[b], s, 1, &pr, &sr);
  if (known) out->refine_match[0] = *known;
  else st = wv_lattice_match(start_scene, &out->lattice, start, spp, threads, &out->refine_match[0], err);
  if (!st) st = wv_lattice_match(&sr, &out->lattice, &pr, spp, threads, &out->refine_match[1], err);
  double m0 = out->refine_match[0], m1 = out->refine_match[1];
  if (!st && (strict ? m1 > m0 : m1 >= m0)) out->params[b] = pr, out->start_refined = 1;
  return st;
}

wv_status wv_fabricnet_choose_pattern(const wv_fabricnet *n, wv_descriptor *d, const wv_scene *s,
                                      const wv_image *photo, const float *gram_photo, const float *y,
                                      const wv_pattern_opts *o, wv_pattern_choice *out, wv_error *err) {
  memset(out, 0, sizeof *out);
  wv_pattern_opts def;
  wv_pattern_opts_default(&def);
  if (!o) o = &def;
  size_t ng = wv_descriptor_size(d);
  if (ng != (size_t)n->n_in)
    return wv_fail(err, WV_ERR_INVALID, "descriptor gives %zu features, the model takes %d", ng, n->n_in);
  if (photo->w != s->width || photo->h != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                   s->width, s->height);
  double t0 = omp_get_wtime();
  int nb = wv_weave_builtin_count();
  wv_scene sc = *s;
  sc.spp = o->spp > 0 ? o->spp : WV_PATTERN_SPP;
  out->spp = sc.spp, out->w_pixel = o->w_pixel, out->orient = o->orient;
  if (o->prob) {
    out->has_prob = 1;
    for (int i = 0; i < nb; i++) out->prob[i] = o->prob[i];
  }
  wv_status st = WV_OK;
  for (int i = 0; i < nb && !st; i++) st = wv_fabricnet_params(n, y, wv_weave_builtin_name(i), &out->params[i], err);
  out->lattice.best = -1;
  /* the candidates are rendered through the camera's blur, as the fit will render them:
   * without it a render's spectrum keeps a flat envelope the photo's does not have */
  wv_scene sb = *s;
  if (o->psf_sigma >= 0) sb.psf_sigma = o->psf_sigma;
  else if (!st && !(s->psf_sigma > 0)) st = wv_psf_estimate(s, photo, &out->params[0], o->threads, &sb.psf_sigma, NULL, err);
  sc.psf_sigma = out->psf_sigma = sb.psf_sigma;
  s = &sb;
  if (!st && o->lattice) st = wv_lattice_analyse(s, photo, &out->lattice, err);
  wv_image_loss *loss = NULL;
  if (!st) st = criterion_create(photo, d, gram_photo, o, &loss, err);
#define LOSS(i) (out->evaluated[i] ? WV_OK : loss_of(loss, &sc, o, (i), out, err))
  if (!st && out->lattice.found) {
    const wv_lattice *l = &out->lattice;
    wv_rank_opts ro;
    wv_rank_opts_default(&ro);
    ro.spp = sc.spp, ro.threads = o->threads, ro.prob = o->prob, ro.w_prob = o->w_prob, ro.rotate = o->orient;
    /* the estimate's colours with pattern 0; wv_lattice_rank sets each candidate's pattern */
    st = wv_lattice_rank(s, photo, l, &out->params[0], &ro, &out->ranking, err);
    for (int i = 0; i < nb && !st; i++) { /* every candidate starts from its lattice densities */
      wv_scene unused;
      wv_params p = out->params[i];
      wv_lattice_candidate(l, i, &p, s, 0, &out->params[i], &unused);
    }
    /* the decision asks for the losses it needs, one at a time */
    int b = 0;
    while (!st && (b = wv_pattern_decide(out, o->family_tie, o->tie, &out->family_contenders)) < 0) st = LOSS(-1 - b);
    if (!st) {
      out->best = b;
      /* the chosen lattice, refined over the whole image, gives the start its densities */
      if (o->refine && !(st = wv_lattice_refine(s, photo, &out->lattice, b, err))) {
        wv_scene unused;
        wv_params p = out->params[b];
        wv_lattice_candidate(&out->lattice, b, &p, s, 0, &out->params[b], &unused);
      }
      /* A lattice found by its harmonics' recall can be weak and lie a few percent off, out
       * of the registration's reach: the network's densities, the chosen pattern's lattice
       * climbed from them, give the start when their render's peaks match the photo's
       * better (docs/analysis.md, "The start's geometry without a lattice") */
      if (!st && o->prob && o->orient) {
        wv_params net, pl;
        wv_scene sl;
        wv_lattice_candidate(&out->lattice, b, &out->params[b], s, 1, &pl, &sl);
        st = wv_fabricnet_params(n, y, wv_weave_builtin_name(b), &net, err);
        if (!st) st = climb_start(s, photo, b, net.density, &sl, &pl, NULL, 1, sc.spp, o->threads, out, err);
      }
      int used = 0;
      for (int i = 0; i < nb; i++) used += out->evaluated[i];
      out->method = used ? "lattice+loss" : "lattice";
    }
  } else if (!st && o->prob) {
    for (int i = 1; i < nb; i++)
      if (o->prob[i] > o->prob[out->best]) out->best = i;
    out->method = "network";
    /* A lattice too weak to count as a weave's often still holds the yarn spacings, where the
     * network's densities can miss a dense cloth by far: the start takes the chosen pattern's
     * lattice densities when their render's spectral peaks match the photo's better. */
    int b = out->best;
    if (!st && o->lattice && out->lattice.n_peaks > 0 && out->lattice.fit[b].score > 0) {
      wv_params lat;
      wv_scene unused;
      wv_lattice_candidate(&out->lattice, b, &out->params[b], s, 0, &lat, &unused);
      st = wv_lattice_match(s, &out->lattice, &out->params[b], sc.spp, o->threads, &out->start_match[0], err);
      if (!st) st = wv_lattice_match(s, &out->lattice, &lat, sc.spp, o->threads, &out->start_match[1], err);
      out->start_compared = !st;
      if (!st && out->start_match[1] > out->start_match[0]) out->params[b] = lat, out->lattice_densities = 1;
    }
    /* The photo's peaks fix the yarns' spacings and the cloth's orientation far more finely
     * than the network or a weak lattice: a start 2% off drifts by several yarns across a
     * photo a few hundred yarns wide, out of the registration's reach. The chosen pattern's
     * lattice, climbed from the start's densities, gives both when its render's peaks match
     * the photo's no worse. */
    if (!st && o->lattice && o->orient && out->lattice.n_peaks > 0) {
      /* the start's match is known when the weak lattice's densities were compared */
      const double *known = out->start_compared ? &out->start_match[out->lattice_densities] : NULL;
      wv_params start = out->params[b];
      st = climb_start(s, photo, b, start.density, s, &start, known, 0, sc.spp, o->threads, out, err);
    }
  } else if (!st) {
    for (int i = 0; i < nb && !st; i++) {
      st = LOSS(i);
      if (!st && out->loss[i] < out->loss[out->best]) out->best = i;
    }
    out->method = "loss";
  }
#undef LOSS
  wv_image_loss_free(loss);
  out->seconds = omp_get_wtime() - t0;
  return st;
}

wv_status wv_fabricnet_predict_pattern(const wv_fabricnet *n, wv_descriptor *d, const wv_scene *s,
                                       const wv_image *photo, const wv_pattern_opts *o, float *y,
                                       wv_pattern_choice *out, wv_error *err) {
  size_t ng = wv_descriptor_size(d);
  if (ng != (size_t)n->n_in)
    return wv_fail(err, WV_ERR_INVALID, "descriptor gives %zu features, the model takes %d", ng, n->n_in);
  float *gram = malloc(sizeof(float) * ng * 2);
  if (!gram) return wv_fail(err, WV_ERR_NOMEM, "out of memory for Gram vectors");
  float *feat = gram + ng, probs[WV_NET_CLASSES];
  wv_status st = wv_descriptor_forward(d, photo, gram, err);
  if (!st) {
    /* the network preprocesses its input in place; the choice needs the raw Gram */
    memcpy(feat, gram, sizeof(float) * ng);
    st = wv_fabricnet_predict_features(n, feat, y, probs, err);
  }
  /* the pattern head's probabilities join the choice unless the caller gave its own; a
   * model without a head (format 1) gives none, and the loss decides in their place */
  wv_pattern_opts oc;
  if (o) oc = *o;
  else wv_pattern_opts_default(&oc);
  if (!oc.prob && n->n_cls == wv_weave_builtin_count()) oc.prob = probs;
  if (!st) st = wv_fabricnet_choose_pattern(n, d, s, photo, gram, y, &oc, out, err);
  free(gram);
  return st;
}

static json_t *per_candidate(const wv_pattern_choice *c, const double *v) {
  json_t *o = json_object();
  for (int i = 0; i < wv_weave_builtin_count(); i++)
    if (c->evaluated[i]) json_object_set_new(o, wv_weave_builtin_name(i), json_real(v[i]));
  return o;
}

char *wv_pattern_choice_to_json(const wv_pattern_choice *c) {
  static const char *CRITERION =
      "the built-ins ranked by how well the spectral peaks of their render (the network's estimate with each "
      "pattern's lattice densities) match the photo's, mixed with the network's pattern probabilities when it has "
      "them; near ties, and patterns of the chosen family whose render matches the photo's peaks better by more than the "
      "tie, decided by the smallest gram + w_pixel * pixel loss; a photo without a weave lattice by the network's most "
      "probable pattern, or by that loss when the network gives no probabilities";
  char *lj = wv_lattice_to_json(&c->lattice, c->lattice.found ? &c->ranking : NULL);
  json_t *lat = lj ? json_loads(lj, 0, NULL) : NULL;
  free(lj);
  const char *name = wv_weave_builtin_name(c->best);
  json_t *o = lat ? json_pack("{s:s,s:s,s:s,s:s,s:i,s:f,s:f,s:o,s:o,s:o,s:o}", "chosen", name, "family",
                              wv_weave_family(name), "method", c->method ? c->method : "", "criterion", CRITERION,
                              "spp", c->spp, "w_pixel", c->w_pixel, "seconds", c->seconds, "lattice", lat, "loss",
                              per_candidate(c, c->loss), "gram_loss", per_candidate(c, c->gram), "pixel_loss",
                              per_candidate(c, c->pixel))
                  : NULL;
  if (o) json_object_set_new(o, "camera_blur_px", json_real(c->psf_sigma));
  if (o && c->has_prob) {
    json_t *pr = json_object();
    for (int i = 0; i < wv_weave_builtin_count(); i++)
      json_object_set_new(pr, wv_weave_builtin_name(i), json_real(c->prob[i]));
    json_object_set_new(o, "network_probability", pr);
  }
  if (o && c->start_compared) /* the start's densities: the network's or a weak lattice's */
    json_object_set_new(o, "start_densities",
                        json_pack("{s:s,s:f,s:f}", "from", c->lattice_densities ? "lattice" : "network",
                                  "match_network", c->start_match[0], "match_lattice", c->start_match[1]));
  if (o && c->start_refine_tried) { /* the start's geometry: refined from the photo's peaks, or as estimated */
    const wv_lattice_fit *f = &c->start_fit;
    json_object_set_new(o, "start_refinement",
                        json_pack("{s:b,s:b,s:[f,f],s:[f,f],s:f,s:f,s:f,s:f}", "moved", c->start_refine_moved, "kept",
                                  c->start_refined, "from", c->unrefined[0], c->unrefined[1], "density",
                                  f->density[0], f->density[1], "angle_deg", f->angle_deg, "skew_deg", f->skew_deg,
                                  "match_start", c->refine_match[0], "match_refined", c->refine_match[1]));
  }
  char *s = o ? json_dumps(o, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(6)) : NULL;
  json_decref(o);
  return s;
}
