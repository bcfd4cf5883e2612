/* woven: the differentiable renderer (paper section 4.3). Gradients of a scalar
 * loss L(capture) with respect to every continuous fabric parameter, given the
 * adjoint image dL/dcapture. Exact derivatives of the renderer as implemented
 * (forward mode over the few non-linear parameters, closed form; no finite
 * differences), with the same sample positions and noise as wv_render, so the
 * capture it returns is the image wv_render gives. See docs/gradients.md. */
#ifndef WOVEN_GRAD_H
#define WOVEN_GRAD_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/render.h"
#include "woven/scene.h"

/* Extra controls; a zeroed struct (or NULL) means: the whole image, float. */
typedef struct {
  /* Render only this window of the scene's image (pixel x0..x0+width-1,
   * y0..y0+height-1); the falloff mask stays centred on the full image.
   * width = height = 0: the whole image. */
  int x0, y0, width, height;
  /* 1: evaluate the shading and its derivatives in double precision (about 1.3x
   * slower; for gradient checks, where float rounding swamps finite differences).
   * The capture is then the double result rounded to float, not wv_render's. */
  int double_precision;
} wv_grad_opts;

/* Render the capture and the gradient of L in one pass.
 * dcapture: dL/dcapture, the size of the render (3 channels).
 * grad[i]: dL/dtheta_i for theta = wv_param_get(p, i), in the parameter file's
 *   units (angles per degree). Densities, Q, thickness and width have none.
 * capture_out (optional, allocated here): the capture image, equal to wv_render's. */
wv_status wv_render_grad(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                         const wv_image *dcapture, double grad[WV_P_COUNT], wv_image *capture_out,
                         wv_error *err);

/* As wv_render_grad with a window and precision (g may be NULL). dot (optional):
 * the sum over the window of dcapture * capture, accumulated in double: the
 * linear loss whose exact gradient grad is (what a finite-difference check needs). */
wv_status wv_render_grad_ex(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                            const wv_grad_opts *g, const wv_image *dcapture, double grad[WV_P_COUNT],
                            double *dot, wv_image *capture_out, wv_error *err);

/* Render first, differentiate later: for losses whose adjoint depends on the
 * capture itself (L1, Gram matrices), which is every loss of the fit. The render
 * keeps each pixel's derivative sums (about 200 bytes a pixel); wv_record_grad
 * then costs one cheap pass over them and may be called with any number of
 * adjoints. Same results as wv_render_grad_ex, bit for bit. */
typedef struct wv_grad_record wv_grad_record;
wv_status wv_render_record(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                           const wv_grad_opts *g, wv_image *capture, wv_grad_record **rec, wv_error *err);
/* As wv_render_record, into *rec: NULL (a record is made) or a record from an earlier
 * call, whose memory is reused (grown for a larger image), so that a loop rendering a
 * record every iteration (the fit) does not map and fault in fresh pages each time.
 * On failure *rec keeps its memory (still to be freed) but no render: wv_record_grad
 * refuses it until a render into it succeeds. */
wv_status wv_render_record_into(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                                const wv_grad_opts *g, wv_image *capture, wv_grad_record **rec, wv_error *err);
wv_status wv_record_grad(const wv_grad_record *rec, const wv_image *dcapture, double grad[WV_P_COUNT],
                         double *dot, wv_error *err);
/* dL/dsigma of the scene's camera blur (scene.psf_sigma, pixels) for the same adjoint
 * (0 when the render had no blur). */
wv_status wv_record_grad_psf(const wv_grad_record *rec, const wv_image *dcapture, double *dsigma, wv_error *err);
void wv_record_free(wv_grad_record *rec);

/* A back-lit scene's radiance is linear in the transmission colours (k_t, k_st and k_f, each
 * channel of each yarn type) while the rest of the parameters stays: radiance = base +
 * sum_j c_j basis_j, with the same samples as wv_render. Made from seven renders (all six
 * colours 0, then each yarn type's k_t, k_st or k_f 1), it gives the capture and the colours'
 * gradient for any colours without rendering: what a fit of the colours alone iterates
 * on (docs/fit.md, "Photo pairs"). */
typedef struct wv_trans_basis wv_trans_basis;
wv_status wv_trans_basis_create(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                                wv_trans_basis **out, wv_error *err);
/* The forward band's two images made again at p's forward_width (two renders; the rest of the
 * parameters the basis's, k_f's width the one thing changed): a search over the width costs
 * two renders a width, not a basis. The images of the last 8 widths made are kept: a width
 * made before is copied back, not rendered (the same images: opt must be the same each call). */
wv_status wv_trans_basis_forward_width(wv_trans_basis *b, const wv_params *p, const wv_render_opts *opt,
                                       wv_error *err);
/* The capture of p's transmission colours (its other parameters: the basis's), allocated
 * here; equal to wv_render's up to float rounding. */
wv_status wv_trans_basis_capture(wv_trans_basis *b, const wv_params *p, wv_image *capture, wv_error *err);
/* dL/d(transmission colours) at the last capture's colours, into grad[WV_P_KT_WARP_R ..
 * WV_P_COUNT - 1] (the others untouched), from dL/dcapture. */
wv_status wv_trans_basis_grad(const wv_trans_basis *b, const wv_image *dcapture, double grad[WV_P_COUNT],
                              wv_error *err);
/* p's transmission colours set to those whose capture comes closest to photo (the basis's
 * size) over cells_w x cells_h cells: least squares on the cells' mean linear radiance (the
 * photo's decoded, its clipped or falloff-dark pixels left out), each channel on its own,
 * pulled weakly toward p's colours, each colour within its range. The cells' means barely
 * tell the yarn types apart, so two ways; k_f stays as p has it in both. A third matches k_f alone: */
typedef enum {
  WV_TRANS_MATCH_FREE,    /* k_t and k_st of a channel free */
  WV_TRANS_MATCH_SPLIT,   /* two factors, one on both yarn types' k_t, one on their k_st: p's split kept */
  WV_TRANS_MATCH_FORWARD  /* the forward band's k_f free (the others' as p has them) */
} wv_trans_match;
/* residual (may be NULL): what the matched colours leave unexplained, the cells' squared
 * differences of mean radiance summed over cells and channels, over the same sum for the
 * photo's means (0: explained exactly, 1: no better than black). */
wv_status wv_trans_basis_match(const wv_trans_basis *b, const wv_image *photo, int cells_w, int cells_h,
                               wv_trans_match mode, wv_params *p, double *residual, wv_error *err);
void wv_trans_basis_free(wv_trans_basis *b);

/* Gradient check: analytic gradient of L = sum(dcapture * capture) against
 * central finite differences, (L(theta + h) - L(theta - h)) / 2h with
 * h = rel_step * (range of the parameter), stepping inward at a range edge
 * (one-sided there). Uses the window and precision of g. */
typedef struct {
  double analytic, numeric;
  double rel_err; /* |analytic - numeric| / max(|analytic|, |numeric|); 0 when both are 0 */
} wv_grad_check_entry;

wv_status wv_grad_check(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_grad_opts *g,
                        const wv_image *dcapture, double rel_step, wv_grad_check_entry out[WV_P_COUNT],
                        wv_error *err);

#endif
