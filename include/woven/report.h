/* woven: what a capture hands back to a person: side-by-side images, the loss
 * plot, and a self-contained HTML report. */
#ifndef WOVEN_REPORT_H
#define WOVEN_REPORT_H

#include "woven/error.h"
#include "woven/fit.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/pattern.h"

/* n images of equal height side by side with gap white pixels between them. */
wv_status wv_image_hconcat(const wv_image *const *imgs, int n, int gap, wv_image *out, wv_error *err);

/* An SVG line plot of the loss terms (total, Gram, w2*pixel, w1*prior), log scale. */
char *wv_loss_svg(const wv_fit_record *log, int n, const wv_fit_opts *o);

/* The centre side x side pixels of img enlarged factor times (nearest neighbour: the
 * pixels stay visible); side is reduced to fit the image. */
wv_status wv_image_centre_zoom(const wv_image *img, int side, int factor, wv_image *out, wv_error *err);

/* The parameters of p that lie on a bound of their range (the fit keeps every parameter
 * inside its range, so these are the ones it wanted to push further): up to cap entries
 * of text such as "inclination_deg = 70 (upper bound)" into lines (each 96 chars). k_f of a
 * cloth without a forward band (all 0, by the fit's choice) is left out. */
int wv_params_at_bounds(const wv_params *p, char (*lines)[96], int cap);

/* The baseline a render must beat: SSIM per RGB channel of the photo against its own copy
 * blurred by a Gaussian of sigma pixels (WV_BLURRED_COPY_SIGMA). Such a copy keeps the
 * photo's colours and shading and none of its weave; a re-render scoring lower reproduces
 * the photo less well than a blur does. */
#define WV_BLURRED_COPY_SIGMA 4.0
wv_status wv_blurred_copy_ssim(const wv_image *photo, double sigma, double *ssim, wv_error *err);

/* What shows the weave to a person, next to SSIM: SSIM per RGB channel and WSC of start
 * and fit against the photo, the photo's blurred-copy SSIM (wv_blurred_copy_ssim) and
 * whether the fit scores below it, how much of the photo's detail is periodic, the weave
 * spectra of photo, start and fit (spectra.png) and the same centre crop of the three,
 * enlarged (zoom.png). Empty paths: not made (the
 * image is too small); wsc and ssim_rgb_blurred -2: not measured. */
#define WV_WEAVE_ZOOM 4
typedef struct {
  double ssim_rgb[2], wsc[2], wsc_whitened[2]; /* [0] start, [1] fit */
  double ssim_rgb_blurred;                     /* the photo's copy blurred by WV_BLURRED_COPY_SIGMA px */
  int below_blurred_copy;                      /* ssim_rgb[1] < ssim_rgb_blurred: the fit is unsure */
  double periodic_share; /* the share of the photo's detail that is periodic (wv_detail_periodic, at
                          * WV_BLURRED_COPY_SIGMA: the detail the blurred copy lacks); -2: not measured */
  char zoom_png[4096], spectra_png[4096];
  int zoom_side, zoom_factor;
} wv_weave_views;

/* Measures v and writes dir/zoom.png and dir/spectra.png. */
wv_status wv_weave_views_write(const char *dir, const wv_image *photo, const wv_image *start, const wv_image *fit,
                               wv_weave_views *v, wv_error *err);

typedef struct {
  const char *title;
  const char *photo_png, *start_png, *fit_png; /* files embedded as data URIs */
  const char *start_label;                     /* "start (prior)" or "network" */
  double ssim_start, ssim_fit;                 /* against the photo */
  const wv_params *start, *fit;
  const char *loss_svg;                        /* inline SVG text */
  const wv_fit_timing *timing;
  int iters;
  const char *descriptor;
  const wv_pattern_choice *pattern_choice;     /* the pattern was chosen automatically (NULL: given) */
  const wv_weave_views *weave;                 /* zoom, spectra, SSIM per channel, WSC (NULL: none) */
  double camera_blur;                          /* the camera blur's sigma in pixels the renders used */
  double camera_blur_measured;                 /* as measured before the fit when it was then fitted (< 0: not) */
  const char *viewer_html;                     /* the interactive viewer beside the report (NULL: none) */
  const char *drape_png;                       /* the fit on the draped cloth under new light (NULL: none) */
  const char *drape_note;                      /* what the drape shows, or why it is missing */
  /* A photo pair: the transmission photo and the fit's re-render in the back-lit scene, SSIM per
   * RGB channel and WSC between them (-2: not measured), the photo's blurred-copy SSIM, whether
   * the re-render scores below it (a warning) and the share of the photo's detail in its
   * spectral peaks (-2: not measured) (NULL photo_t_png: one photo; the report says the
   * transmission parameters were not fitted). */
  const char *photo_t_png, *fit_t_png;
  double ssim_rgb_t, wsc_t, ssim_rgb_blurred_t, periodic_share_t;
  int below_blurred_copy_t;
  int kt_fitted; /* the one photo is back-lit: the fit moved k_t */
  const char *kt_start; /* a pair's transmission colours started from this pair model (NULL: the prior) */
  int kt_tried;         /* ... the prior after the pair model's start scored worse */
  int open_measured;    /* a pair's open area was measured on the back-lit photo's gap glow ... */
  double open_area;     /* ... as this (the yarn width set to match it) */
  int view_t;           /* a pair's back-lit photo has its own view (wv_fit_state.t_related): ... */
  int view_t_related;   /* ... its weave relates to the reflection photo's, by */
  double view_t_scale, view_t_rotation_deg; /* ... this scale and rotation */
} wv_report;

wv_status wv_report_write_html(const char *path, const wv_report *r, wv_error *err);

#endif
