/* woven: the image losses that compare a render with a photo, each with its adjoint
 * (the gradient with respect to the render's capture image). The fit minimises their
 * weighted sum; the automatic pattern choice ranks candidates by it.
 *
 *   L_g  texture: mean |Gram(photo) - Gram(render)| over the descriptor's features
 *   L_c  pixel:   mean |down(photo) - down(render)|, down = area average to a small grid
 *   L_s  structure (phase-invariant): mean over the yarn band of
 *        (log(eps + P_render / E_render) - log(eps + P_photo / E_photo))^2, where P is the
 *        power spectrum of the Hann-windowed luminance of the centre crop, smoothed over
 *        3 x 3 frequency bins, and E its mean over the band. Erasing the weave flattens
 *        P's peaks and costs L_s; a shift of the weave does not (the spectrum has no phase);
 *        neither does a change of contrast (P / E).
 *   L_k  detail colour: sum over the 3 x 3 entries of (A_render / tr A_render - A_photo / tr A_photo)^2,
 *        A the covariance of the R, G, B detail (each channel minus its Gaussian blur) over
 *        the centre crop: which way the colour moves between yarns (along the light for a
 *        one-colour cloth, between its two colours for a two-colour one), not how far.
 * docs/fit.md gives the weights and what each term is for. */
#ifndef WOVEN_LOSS_H
#define WOVEN_LOSS_H

#include <stddef.h>

#include "woven/error.h"
#include "woven/image.h"

struct wv_descriptor;

/* ---- The combined image loss L = L_g + w_pixel L_c + w_struct L_s + w_colour L_k of one photo ---- */
#define WV_LOSS_DOWN_W 16 /* the pixel loss's grid */
#define WV_LOSS_DOWN_H 8
typedef struct {
  double w_pixel;     /* weight of L_c */
  double w_struct;    /* weight of L_s (0: not computed) */
  int down_w, down_h; /* the pixel loss's grid (WV_LOSS_DOWN_W x WV_LOSS_DOWN_H) */
  double w_colour;    /* weight of L_k (0: not computed) */
} wv_loss_weights;
typedef struct {
  double total;                          /* gram + w_pixel pixel + w_struct structure + w_colour colour */
  double gram, pixel, structure, colour; /* L_g, L_c, L_s, L_k */
} wv_loss_terms;
typedef struct wv_image_loss wv_image_loss;
/* Precomputes what the photo contributes (its Gram vector, its downsampled image, its
 * spectrum). gram_photo (optional): the photo's raw descriptor features when the caller
 * has them already, saving one descriptor pass. The descriptor d is borrowed and must
 * outlive the object. */
wv_status wv_image_loss_create(const wv_image *photo, struct wv_descriptor *d, const float *gram_photo,
                               const wv_loss_weights *w, wv_image_loss **out, wv_error *err);
void wv_image_loss_free(wv_image_loss *l);
/* The terms for render (the photo's size). With dcap != NULL (an image of render's shape,
 * allocated by the caller) it receives dL/drender, overwritten. Not thread-safe. */
wv_status wv_image_loss_eval(wv_image_loss *l, const wv_image *render, wv_loss_terms *t, wv_image *dcap,
                             wv_error *err);
/* dL/drender into dcap, as wv_image_loss_eval gives it, for the render that call last
 * evaluated (the same image, unchanged) without its descriptor's forward pass again: a trial
 * evaluated without the gradient and then kept costs one pass more, not two. A render other
 * than the last evaluated: WV_ERR_INVALID. */
wv_status wv_image_loss_grad(wv_image_loss *l, const wv_image *render, wv_image *dcap, wv_error *err);

/* ---- L_g and L_c on precomputed pieces ---- */
/* mean |a - b| over n Gram entries; d (may be NULL) receives dL/da = sign(a - b) / n. */
double wv_loss_gram(const float *a, const float *b, size_t n, float *d);

/* ---- L_s: the weave's spectrum ---- */
#define WV_SPECTRUM_SIDE 256   /* the centre crop (smaller images: their largest even square) */
#define WV_SPECTRUM_RMIN 8     /* band: frequencies above 8 bins of 256 (periods under 32 px) */
#define WV_SPECTRUM_EPS 1e-3   /* floor of the normalised power inside the log */
typedef struct wv_spectrum_loss wv_spectrum_loss;
/* Precomputes the photo's log spectrum for images of photo's size. */
wv_status wv_spectrum_loss_create(const wv_image *photo, wv_spectrum_loss **out, wv_error *err);
void wv_spectrum_loss_free(wv_spectrum_loss *s);
/* L_s of render (the photo's size); with d != NULL adds weight * dL_s/drender into d
 * (an image of render's shape). Not thread-safe: one object per thread. */
double wv_spectrum_loss_eval(wv_spectrum_loss *s, const wv_image *render, wv_image *d, float weight);

/* ---- L_k: the colour of the detail ---- */
#define WV_COLOUR_SIDE 256  /* the centre crop (smaller images: their largest square) */
#define WV_COLOUR_SIGMA 2.0 /* the detail: each channel minus its Gaussian blur of this sigma (pixels) */
typedef struct wv_colour_loss wv_colour_loss;
/* Precomputes the photo's normalised detail covariance for images of photo's size (a
 * photo without detail, a flat card, gives L_k = 0 for every render). */
wv_status wv_colour_loss_create(const wv_image *photo, wv_colour_loss **out, wv_error *err);
void wv_colour_loss_free(wv_colour_loss *c);
/* L_k of render (the photo's size) into *value; with d != NULL adds weight * dL_k/drender
 * into d (an image of render's shape). Not thread-safe: one object per thread. */
wv_status wv_colour_loss_eval(wv_colour_loss *c, const wv_image *render, wv_image *d, float weight, double *value,
                              wv_error *err);
#endif
