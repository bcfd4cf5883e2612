/* woven: image comparison metrics. */
#ifndef WOVEN_METRICS_H
#define WOVEN_METRICS_H

#include "woven/error.h"
#include "woven/image.h"

typedef enum {
  WV_SSIM_LUMA = 0, /* on luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of the given values */
  WV_SSIM_RGB = 1   /* per channel, then the mean of the three */
} wv_ssim_mode;

/* SSIM of Wang, Bovik, Sheikh, Simoncelli (2004): 11 x 11 Gaussian window with
 * sigma 1.5, K1 = 0.01, K2 = 0.03, data range 1 (values in [0,1]), population
 * (not sample) covariances, mean over the windows that lie inside the image
 * (the 'valid' region). Images must have the same size, at least 11 x 11. */
wv_status wv_ssim(const wv_image *a, const wv_image *b, wv_ssim_mode mode, double *out, wv_error *err);

/* Mean absolute difference over all samples. */
wv_status wv_mae(const wv_image *a, const wv_image *b, double *out, wv_error *err);

#endif
