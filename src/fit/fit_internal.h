/* Shared between the fit's source files; not public. */
#ifndef WOVEN_FIT_INTERNAL_H
#define WOVEN_FIT_INTERNAL_H

#include <jansson.h>

#include "woven/fit.h"

/* The options a checkpoint stores ("opts"), as JSON (a new object) ... */
json_t *wv_fit_opts_json(const wv_fit_opts *o);
/* ... and read back, each range-checked as wv_fit_opts_validate checks it; options a
 * checkpoint may lack keep the value o holds. */
wv_status wv_fit_opts_read_json(json_t *opts, wv_fit_opts *o, wv_error *err);

/* The registration's first step alone (register.c): up to 4 candidate density pairs of the
 * whole range, scored in the centre 64 x 64 window of s (as wv_fit_register, with the
 * fit's camera blur and offset of st) for st's parameters; with whole, from every point of
 * the ratio grid instead of the coarse grid and its climbs. *renders: how many renders
 * that took. */
wv_status wv_fit_register_candidates(const wv_fit_state *st, const wv_scene *s, const wv_image *photo,
                                     const wv_fit_opts *o, int whole, double cand[4][2], int *nc, int *renders,
                                     wv_error *err);

/* The whole image's SSIM per RGB channel of p in register at its own densities: the phase
 * (a fabric offset on st's) by one phase correlation, kept if it raises the SSIM with the
 * weave in step, as wv_fit_register keeps it. */
wv_status wv_fit_register_phase(const wv_fit_state *st, const wv_scene *s, const wv_image *photo,
                                const wv_params *p, const wv_fit_opts *o, double *ssim, wv_error *err);

/* wv_fit_register without its first step: the densities are searched near st's only (the
 * grid of whole yarns/inch +-register_radius, then the climbs), for a photo whose densities are
 * known to be close (a pair's back-lit photo in its own view). */
wv_status wv_fit_register_near(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                               wv_error *err);

/* wv_fit_register_near for a view of the cloth, not its parameters (a pair's back-lit photo):
 * without the last climb on the whole image (to a tenth of a yarn/inch), whose many renders of
 * the whole image the distortion after it replaces: its displacement's linear terms are a
 * density's last tenths, and the view's densities are not the cloth's (docs/fit.md, "Photo
 * pairs"). The shift is still read on the whole image. */
wv_status wv_fit_register_view(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                               wv_error *err);

#endif
