/* woven: weave analysis of a photo (classical textile image analysis). A woven fabric is
 * a periodic texture: the power spectrum of its luminance detail (metrics.h) is a lattice
 * of peaks, the reciprocal lattice of the weave's repeat, folded into the pixel grid's
 * band where the yarns are finer than two pixels. This module
 *   1. finds the photo's spectral peaks (wv_lattice_analyse),
 *   2. explains them, for each built-in pattern, by the yarn densities (yarns per inch,
 *      through the scene's scale at the image centre) and the weave's orientation whose
 *      predicted peaks (the pattern's own Fourier coefficients, blurred by the pixel and
 *      folded at the pixel grid) best match the photo's,
 *   3. ranks the built-in patterns by how well their OWN render, with those densities in
 *      the photo's scene, shows the photo's peaks (wv_lattice_rank).
 * The best pattern's lattice gives the yarn spacings, the orientation and the repeat's
 * shear (twill direction S or Z, satin step). A photo without periodic structure (a flat
 * card, sand, noise) has no lattice: found = 0 and a reason. docs/analysis.md. */
#ifndef WOVEN_ANALYSIS_H
#define WOVEN_ANALYSIS_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"
#include "woven/weave.h"

#define WV_LATTICE_PEAKS 24     /* peaks kept, strongest first */
#define WV_LATTICE_WINDOW 256   /* the centre window analysed (the WSC window) */
#define WV_LATTICE_MIN_WINDOW 64
#define WV_LATTICE_REFINE_WINDOW 512 /* the chosen pattern's lattice is refined over this window */

/* One spectral peak, in the half plane v > 0 (or v = 0, u > 0): its mirror -(u, v) is
 * the same peak. */
typedef struct {
  double u, v; /* cycles per pixel, v downward (image rows) */
  double z;    /* prominence: robust standard deviations above its ring of the spectrum */
} wv_spectral_peak;

/* A lattice that explains the photo's peaks with a score below this is not a weave's: the
 * analysis finds none (a weaker one may still give the start its densities, pattern.h). */
#define WV_LATTICE_MIN_SCORE 0.35
/* A pattern's lattice explaining the photo's peaks. */
typedef struct {
  double density[2];  /* yarns per inch, [WV_WARP], [WV_WEFT] */
  double angle_deg;   /* the fabric's rotation, counter-clockwise, to add to the scene's */
  double skew_deg;    /* how far the yarns are out of square: the warp turns by angle - skew / 2,
                       * the weft by angle + skew / 2 (a plane scene draws it: sample.skew_deg) */
  double precision;   /* weighted share of the predicted peaks the photo shows */
  double recall;      /* share of the photo's peak prominence the prediction explains */
  double score;       /* 2 precision recall / (precision + recall), 0..1 */
} wv_lattice_fit;

typedef struct {
  int window;         /* side of the analysed centre window (pixels) */
  int found;          /* a weave lattice was found */
  char reason[160];   /* why not, when found = 0 */
  int n_peaks;
  wv_spectral_peak peaks[WV_LATTICE_PEAKS];
  double mm_per_px;   /* the scene's scale at the image centre (geometric mean of the axes) */
  wv_lattice_fit fit[WV_WEAVE_BUILTINS]; /* per canonical built-in (wv_weave_builtin_name order) */
  int best;           /* the built-in whose lattice explains the peaks best (-1: none) */
  /* The best lattice's geometry: */
  double spacing_px[2]; /* warp yarns' spacing across the image (x), weft yarns' (y), pixels */
  int repeat;         /* the repeat's size in yarns */
  int shear;          /* cells the pattern moves per row: twill +1 (S) or -1 (Z) (90-degree
                       * variants: per column), satin its step, 0 for plain and basket */
  int refined_window; /* 0, or the window over which wv_lattice_refine refined a fit */
  double seconds;
} wv_lattice;

/* Analyses the centre window of photo (the scene's capture image; at least 64 x 64). A
 * photo without a lattice is not an error: out->found = 0 with out->reason. A built-in
 * and its twin (wv_weave_builtin_twin) come back at twin densities: the weaker fit takes
 * the stronger one's lattice, scaled by the groups, with its own score there. */
wv_status wv_lattice_analyse(const wv_scene *s, const wv_image *photo, wv_lattice *out, wv_error *err);

/* Refines fit i of lat (found) over the photo's centre window of up to
 * WV_LATTICE_REFINE_WINDOW pixels, larger than the analysis's: the lattice points of a
 * render must fall within a fraction of a bin of the photo's across the whole image for
 * the two to stay in register. The densities move by less than 2% (a larger step is an
 * alias, not a refinement), the rotation and skew within their ranges; nothing changes
 * when the fit explains that window no better. A no-op for a photo no larger than the
 * analysis's window. */
wv_status wv_lattice_refine(const wv_scene *s, const wv_image *photo, wv_lattice *lat, int i, wv_error *err);

/* For a photo whose lattice was not found but whose pattern and densities were estimated
 * otherwise (FabricNet): built-in i's lattice refined from those densities with the cloth
 * square, by the lattice power over the analysis window and then over the refinement
 * window (coarse to fine: the smaller window's wider peaks reach a start a few percent
 * off). *moved = 1 and out holds the densities, rotation and skew (not the score, precision
 * or recall) when the power over the larger window rose and each density moved by less
 * than WV_LATTICE_NEAR (log ratio; a larger move is an alias or a walk among weak peaks);
 * otherwise out holds the densities given, square. */
#define WV_LATTICE_NEAR 0.05
wv_status wv_lattice_refine_from(const wv_scene *s, const wv_image *photo, int i, const double density[2],
                                 wv_lattice_fit *out, int *moved, wv_error *err);

/* The peaks of a weave spectrum (n x n, from wv_weave_spectrum) with prominence at least
 * min_z, strongest first; returns how many (at most cap). */
int wv_spectrum_peaks(const float *spectrum, int n, double min_z, wv_spectral_peak *peaks, int cap);

/* ---- ranking the built-in patterns by their own renders ---- */
#define WV_RANK_SPP 4
/* How well the spectral peaks of p's render, in the analysis window at the centre of s (as
 * given: no lattice rotation added) at spp (0: WV_RANK_SPP), match the photo's peaks in lat
 * (found or not): the ranking's peak match, 0..1 (0 when lat holds no peaks). */
wv_status wv_lattice_match(const wv_scene *s, const wv_lattice *lat, const wv_params *p, int spp, int threads,
                           double *match, wv_error *err);
typedef struct {
  int spp;      /* samples per pixel of each candidate's render (WV_RANK_SPP) */
  int threads;  /* 0: OpenMP default */
  int rotate;   /* 1: render with the lattice's rotation and skew added to a plane scene's */
  /* Optional: a probability per canonical built-in (wv_weave_builtin_count() values, e.g.
   * FabricNet's pattern head), NULL when there is none. Each candidate's score is then
   * (1 - w_prob) match + w_prob probability. */
  const float *prob;
  double w_prob;
} wv_rank_opts;
void wv_rank_opts_default(wv_rank_opts *o);

typedef struct {
  double match[WV_WEAVE_BUILTINS]; /* peak match between the candidate's render and the photo, 0..1 */
  double wsc[WV_WEAVE_BUILTINS];   /* WSC of the candidate's render against the photo */
  double wsc_whitened[WV_WEAVE_BUILTINS]; /* ... and its whitened WSC (metrics.h) */
  double score[WV_WEAVE_BUILTINS]; /* the ranking criterion (match, or mixed with prob) */
  int order[WV_WEAVE_BUILTINS];    /* candidates, best first */
  int best;
  double seconds;
} wv_lattice_ranking;

/* Renders each built-in with base's other parameters and its own lattice densities
 * (lat->fit[i]) in the centre window of s at a low spp, and scores how well the render's
 * spectral peaks match the photo's. lat must have found a lattice. */
wv_status wv_lattice_rank(const wv_scene *s, const wv_image *photo, const wv_lattice *lat, const wv_params *base,
                          const wv_rank_opts *o, wv_lattice_ranking *out, wv_error *err);

/* The parameters base with fit f's densities (clamped to the density range), and the scene
 * s with f's orientation (rotation and skew added to the scene's) when rotate and s is a
 * plane. */
void wv_lattice_fit_apply(const wv_lattice_fit *f, const wv_params *base, const wv_scene *s, int rotate, wv_params *p,
                          wv_scene *ps);
/* wv_lattice_fit_apply of lat's fit i, with built-in i as the pattern. */
void wv_lattice_candidate(const wv_lattice *lat, int i, const wv_params *base, const wv_scene *s, int rotate,
                          wv_params *p, wv_scene *ps);

/* The analysis as a JSON object text (docs/analysis.md; malloc'ed, caller frees; NULL
 * when out of memory); with a ranking (may be NULL) its scores too. */
char *wv_lattice_to_json(const wv_lattice *l, const wv_lattice_ranking *r);

/* A picture of k weave spectra side by side (n x n each, from wv_weave_spectrum), each
 * scaled to its own range and enlarged `zoom` times, 4 white pixels apart; RGB. */
wv_status wv_spectrum_picture(const float *const *spectra, int k, int n, int zoom, wv_image *out, wv_error *err);

/* The open area of a back-lit photo (the scene's size, encoded as the scene encodes), measured on
 * its gap glow: the rig adds wv_scene.glow_radiance times a Gaussian of glow_sigma pixels centred
 * on the image, times the fraction of the pixel's lines of sight that cross a gap, to the
 * radiance. Blocks of the photo's linear radiance within 5 sigma of the centre (blocks that
 * reach the clip left out) are fitted by least squares as a quadratic in x and y (the light
 * the yarns pass) plus an amplitude times the Gaussian; the amplitude over glow_radiance is
 * the open area (it may come out a little below 0 on a cloth without gaps). found = 0 when
 * the centre is clipped or too small to tell the bump from the quadratic. An error when the
 * scene has no glow or the photo is not its size. docs/analysis.md. */
typedef struct {
  int found;
  double open_area;  /* the fraction of the cloth that is open (1 - yarn_width)^2 */
  double amplitude;  /* the glow's linear radiance at the image's centre */
  int blocks, clipped; /* the blocks fitted, the blocks left out as clipped */
} wv_open_area;
wv_status wv_open_area_measure(const wv_scene *s, const wv_image *photo, wv_open_area *out, wv_error *err);

/* How a second photo of the same cloth sees its weave against a first: the two photos of a
 * pair are seldom taken at exactly the same distance and angle (the cloth is moved to put the
 * light behind it, the lens refocused). The weave spectra (wv_weave_spectrum) of both photos'
 * centre windows (the largest even square up to WV_LATTICE_REFINE_WINDOW both hold) give
 * their WV_RELATE_PEAKS strongest peaks (wv_spectrum_peaks, prominence at least WV_RELATE_MIN_Z:
 * the weaker ones are mostly folded harmonics and noise, which no scale carries over); the scale s and the
 * rotation r that carry the first's peaks onto the second's (s R(r) f) and the second's back
 * onto the first's (within WV_RELATE_TOL bins of any peak of the other) are searched over
 * WV_RELATE_SCALE_MIN..MAX and +-WV_RELATE_MAX_ROT degrees, each match weighted by the smaller
 * prominence of its two peaks. found = 0 (and scale 1, rotation 0) when fewer than
 * WV_RELATE_MIN_MATCH of the 2 WV_RELATE_PEAKS peaks match or the matched weight is under
 * WV_RELATE_MIN_SCORE of their total: a photo without a clear weave lattice (a satin's back-lit
 * streak) tells nothing, and the pair is then taken as one camera's. docs/analysis.md. */
#define WV_RELATE_PEAKS 8
#define WV_RELATE_MIN_Z 3.0
#define WV_RELATE_TOL 2.0
#define WV_RELATE_SCALE_MIN 0.75
#define WV_RELATE_SCALE_MAX 1.33
#define WV_RELATE_MAX_ROT 5.0
#define WV_RELATE_MIN_MATCH 5
#define WV_RELATE_MIN_SCORE 0.2
typedef struct {
  int found;
  double scale;        /* the second photo's spatial frequencies over the first's: its yarns lie
                        * 1 / scale times as many pixels apart */
  double rotation_deg; /* the second photo's weave turned counter-clockwise (as seen, y up) */
  double score;        /* the matched share of the peaks' prominence, 0..1 */
  int matched;         /* peaks matched */
  int window;          /* the windows' side, pixels */
} wv_weave_relation;
wv_status wv_weave_relate(const wv_image *a, const wv_image *b, wv_weave_relation *out, wv_error *err);

#endif
