/* woven: what a capture hands back to a person: side-by-side images, the loss
 * plot, and a self-contained HTML report. */
#ifndef WOVEN_REPORT_H
#define WOVEN_REPORT_H

#include "woven/error.h"
#include "woven/fabricnet.h"
#include "woven/fit.h"
#include "woven/image.h"
#include "woven/params.h"

/* n images of equal height side by side with gap white pixels between them. */
wv_status wv_image_hconcat(const wv_image *const *imgs, int n, int gap, wv_image *out, wv_error *err);

/* An SVG line plot of the loss terms (total, Gram, w2*pixel, w1*prior), log scale. */
char *wv_loss_svg(const wv_fit_record *log, int n, const wv_fit_opts *o);

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
  const char *viewer_html;                     /* the interactive viewer beside the report (NULL: none) */
  const char *drape_png;                       /* the fit on the draped cloth under new light (NULL: none) */
  const char *drape_note;                      /* what the drape shows, or why it is missing */
} wv_report;

wv_status wv_report_write_html(const char *path, const wv_report *r, wv_error *err);

#endif
