/* woven: the weave pattern FabricNet does not predict, chosen over the whole built-in
 * library (src/net/pattern.c).
 * The 21 outputs do not depend on the pattern; only the parameters built from them
 * (wv_fabricnet_params) do. The choice (docs/analysis.md):
 *   1. The weave analysis of the photo (analysis.h): the lattice of its spectral peaks,
 *      explained for every built-in by densities and an orientation.
 *   2. If there is a lattice: the family (plain, basket, twill, satin) whose best built-in
 *      has the best mean of lattice score and ranking score (below) wins (a basket and a
 *      plain weave at half its densities share the better of their two lattice scores:
 *      wv_weave_builtin_twin); families within o->family_tie of it are contenders,
 *      decided by the loss criterion below (each with its best-ranked pattern). Within the
 *      family every built-in is rendered with the network's estimate and its own lattice
 *      densities in the centre window at a low spp and scored by how well its spectral peaks
 *      match the photo's (wv_lattice_rank; with o->prob, mixed with the network's class
 *      probabilities); patterns within o->tie of the best score are decided by the loss
 *      criterion. The chosen pattern starts with its lattice densities.
 *   3. Without a lattice (a flat card, sand, noise), the network's choice: the most
 *      probable class when o->prob is given, else the loss criterion over every built-in.
 *      The network's choice starts from its chosen pattern's weak lattice densities (a score
 *      above 0, below WV_LATTICE_MIN_SCORE) when their render's spectral peaks match the
 *      photo's better than the network's densities do (wv_lattice_match).
 * The loss criterion renders a candidate's parameters over the whole scene image at a low
 * spp and compares it with the photo by the fit's loss terms: the Gram loss L_g = mean
 * |Gram(photo) - Gram(render)| plus w_pixel times the pixel loss L_c = mean |down(photo) -
 * down(render)| (16 x 8 area averages); the smallest wins. Gram matrices are not rotation
 * invariant, so a pattern and its 90-degree variant give different losses. */
#ifndef WOVEN_PATTERN_H
#define WOVEN_PATTERN_H

#include "woven/analysis.h"
#include "woven/error.h"
#include "woven/fabricnet.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"
#include "woven/weave.h"

struct wv_descriptor;
#define WV_PATTERN_SPP 4       /* as the fit iterates; 16 helps twill vs satin at 2-3x the cost (docs/fabricnet.md) */
#define WV_PATTERN_W_PIXEL 0.2 /* the fit's w2 */
#define WV_PATTERN_TIE 0.05    /* ranking scores this close to the best go to the loss criterion, and so do
                                * the family's render matches better than the best-scored one's by more */
#define WV_PATTERN_FAMILY_TIE 0.0 /* families this close to the best go to the loss criterion too; 0: the
                                  * lattice and render match alone decide the family (fewer wrong
                                  * families on synthetic targets, docs/analysis.md) */
typedef struct {
  int spp;        /* samples per pixel of each candidate's render; 0: WV_PATTERN_SPP */
  int threads;    /* render threads; 0: OpenMP default */
  double w_pixel; /* weight of L_c in the criterion (the fit's w2 is 0.2) */
  int lattice;    /* 1: use the weave analysis (default); 0: the loss criterion over every built-in */
  double tie;     /* WV_PATTERN_TIE; 0: the best ranking score alone decides */
  double family_tie; /* WV_PATTERN_FAMILY_TIE; 0: the best lattice's family */
  /* Optional: the network's probability of each canonical built-in (WV_WEAVE_BUILTINS
   * values, wv_weave_builtin_name order; FabricNet's pattern head), NULL when the model has
   * none. Used as wv_rank_opts.prob (weight w_prob) and, without a lattice, as the choice. */
  const float *prob;
  double w_prob;  /* 0.25 */
  double psf_sigma; /* camera blur of the candidates' renders: -1 (default) the scene's, else measured
                     * from the photo on the network's estimate (wv_psf_estimate); >= 0 this sigma */
  int orient;     /* 1 (default): on a plane scene, each candidate is rendered, and the chosen one
                   * fitted, with its lattice's rotation and skew (wv_pattern_choice_scene) */
  int refine;     /* 1 (default): the chosen pattern's lattice is refined over the whole image
                   * (wv_lattice_refine) */
} wv_pattern_opts;
void wv_pattern_opts_default(wv_pattern_opts *o);
typedef struct {
  int best;                 /* the chosen pattern, an index for wv_weave_builtin_name */
  const char *method;       /* "lattice" (the lattice and the ranking alone), "lattice+loss" (a tie of
                             * families or patterns broken by the loss criterion), "loss" (no lattice:
                             * the loss criterion), "network" (no lattice: the network's most probable
                             * class) */
  int family_contenders;    /* with a lattice: how many families the loss criterion chose among (1: none) */
  wv_lattice lattice;       /* the weave analysis (lattice.found: the photo showed one) */
  wv_lattice_ranking ranking; /* with a lattice: each built-in's render against the photo */
  int evaluated[WV_WEAVE_BUILTINS]; /* the loss criterion ran for this candidate */
  double loss[WV_WEAVE_BUILTINS];   /* its criterion, gram + w_pixel pixel */
  double gram[WV_WEAVE_BUILTINS];   /* its L_g */
  double pixel[WV_WEAVE_BUILTINS];  /* its L_c */
  int has_prob;                     /* the network's pattern head gave probabilities: */
  double prob[WV_WEAVE_BUILTINS];   /* ... each built-in's */
  wv_params params[WV_WEAVE_BUILTINS]; /* each candidate: the network's estimate with the pattern
                                        * (and, with a lattice, its lattice densities) */
  int spp;                  /* what the loss criterion's renders used */
  double w_pixel;           /* what the criterion used */
  double seconds;           /* analysis, renders and descriptor passes */
  double psf_sigma;         /* the camera blur the candidates were rendered with */
  int orient;               /* the candidates carry their lattice's orientation (wv_pattern_opts) */
  /* Without a lattice, by the network, and with photo peaks that the chosen pattern's
   * lattice explains a little (its score above 0, below WV_LATTICE_MIN_SCORE): the spectral
   * peak match (wv_lattice_match) of the network's densities and of that lattice's was
   * compared (start_compared), and the start took the lattice's when it matched better
   * (lattice_densities). */
  int start_compared, lattice_densities;
  double start_match[2]; /* the network's densities, the lattice's */
  /* Without a lattice, by the network, with photo peaks: the chosen pattern's lattice refined
   * from the start's densities with the cloth square (wv_lattice_refine_from) was tried
   * (start_refine_tried); it moved (start_refine_moved); and the start took its densities and
   * the scene its orientation (start_refined) when its render's peaks matched the photo's no
   * worse than the start's (refine_match: the start's, the refined; 0 unless it moved). With
   * a lattice and the network's probabilities: the same, refined from the network's
   * densities, against the chosen lattice's start with its orientation, and taken only when
   * it matched strictly better (unrefined: the network's densities). */
  int start_refine_tried, start_refine_moved, start_refined;
  wv_lattice_fit start_fit; /* the refined geometry */
  double refine_match[2];
  double unrefined[2];      /* the start's densities before the refinement */
} wv_pattern_choice;
/* The scene in which candidate i of c is rendered and fitted: s, with the rotation and
 * skew of the refined start (start_refined) for the chosen candidate, or else of its
 * lattice when the lattice was found, added when c->orient (a plane scene). out may be s. */
void wv_pattern_choice_scene(const wv_pattern_choice *c, const wv_scene *s, int i, wv_scene *out);
/* The loss criterion of candidate i of a choice made for this photo (a no-op when known). */
wv_status wv_pattern_loss(struct wv_descriptor *d, const wv_scene *s, const wv_image *photo, const float *gram_photo,
                          const wv_pattern_opts *o, int i, wv_pattern_choice *c, wv_error *err);
/* The decision of step 2 from a choice whose lattice was found and ranked: the chosen
 * pattern, or -1 - i when it needs the loss criterion of candidate i, not yet evaluated.
 * contenders (may be NULL): how many families were within family_tie. */
int wv_pattern_decide(const wv_pattern_choice *c, double family_tie, double tie, int *contenders);
/* How each family (plain, basket, twill, satin: wv_weave_family's names, in that order) stood
 * in the choice c, runner-ups included: its best candidate and that candidate's score. With
 * a lattice, step 2's family score: the best mean of lattice score (a basket and its plain
 * twin sharing theirs) and ranking score over the family's built-ins, and the built-in that
 * has it (kind "lattice+ranking", higher is better; within the chosen family the pattern
 * itself goes by the ranking score alone, so it may be another). Without a lattice, by the
 * choice's method: "network" each family's most probable built-in and its probability
 * (kind "probability", higher is better); "loss" the built-in with the smallest loss
 * criterion and that loss (kind "loss", lower is better). pattern[f] -1: the family had no
 * scored candidate (then score is 0). */
#define WV_PATTERN_FAMILIES 4
typedef struct {
  const char *kind;                   /* "lattice+ranking", "probability", "loss" or "none" */
  int higher_is_better;
  const char *family[WV_PATTERN_FAMILIES];
  int pattern[WV_PATTERN_FAMILIES];   /* an index for wv_weave_builtin_name, or -1 */
  double score[WV_PATTERN_FAMILIES];
  int order[WV_PATTERN_FAMILIES];     /* the families, best first (unscored ones last) */
} wv_pattern_families;
void wv_pattern_family_scores(const wv_pattern_choice *c, wv_pattern_families *out);
/* y: the network's normalised outputs; photo: the scene's capture image; gram_photo: its raw
 * descriptor features (before preprocessing). o may be NULL (defaults). */
wv_status wv_fabricnet_choose_pattern(const wv_fabricnet *n, struct wv_descriptor *d, const wv_scene *s,
                                      const wv_image *photo, const float *gram_photo, const float *y,
                                      const wv_pattern_opts *o, wv_pattern_choice *out, wv_error *err);
/* The whole estimate without a pattern: one descriptor pass over the photo serves both the
 * network (y, 21 normalised outputs) and the choice. The result is out->params[out->best]. */
wv_status wv_fabricnet_predict_pattern(const wv_fabricnet *n, struct wv_descriptor *d, const wv_scene *s,
                                       const wv_image *photo, const wv_pattern_opts *o, float *y,
                                       wv_pattern_choice *out, wv_error *err);
/* {"chosen", "family", "method", "criterion", "spp", "w_pixel", "seconds", "lattice": {...},
 * "ranking": {...}, "loss", "gram_loss", "pixel_loss"}, the last three {pattern: value} over
 * the candidates the loss criterion evaluated; one line (malloc'ed, caller frees; NULL when
 * out of memory). docs/analysis.md lists the fields. */
char *wv_pattern_choice_to_json(const wv_pattern_choice *c);

#endif
