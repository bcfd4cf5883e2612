/* woven: image comparison metrics, and the centre windows they compare. */
#ifndef WOVEN_METRICS_H
#define WOVEN_METRICS_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/scene.h"

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

/* ---- centre windows ----
 * A search that renders many candidates compares the centre of the image only. */
/* The centre w x h window of a scene (same pixels as the full image there). */
void wv_scene_centre_window(const wv_scene *s, int w, int h, wv_scene *out);
/* Copies the matching centre w x h pixels of a full-size image. */
wv_status wv_image_centre_crop(const wv_image *full, int w, int h, wv_image *out, wv_error *err);

/* ---- the weave's spectrum ----
 * A weave is a periodic texture, and at one or two pixels per yarn its structure lives
 * in the detail of the luminance, not in its shading. These functions share one
 * definition of that detail and of its power spectrum: the registration's phase
 * correlation, the weave-spectrum correlation and the weave analysis (analysis.h). */
#define WV_DETAIL_SIGMA 4.0   /* pixels: keeps the yarn and rib frequencies, drops shading and falloff */
#define WV_WSC_SIZE 256       /* WSC compares the centre 256 x 256 pixels */
#define WV_WSC_DC_RADIUS 4.0  /* bins around DC left out of the correlation */
#define WV_WSC_Z_FLOOR 2.0    /* whitened WSC: robust deviations a bin must stand above its ring */
#define WV_WSC_Z_CAP 10.0     /* ... counted up to here */

/* Luminance detail of the w x h window of img at (x0, y0): Y (Rec. 709 weights of the
 * stored values) minus its Gaussian blur of sigma WV_DETAIL_SIGMA, standardised to zero
 * mean and unit variance (a flat window gives zeros), times the 2-D Hann window
 * (0.5 - 0.5 cos(2 pi (x + 0.5) / w)) (the same in y). out: w * h floats. */
wv_status wv_image_detail(const wv_image *img, int x0, int y0, int w, int h, float *out, wv_error *err);
/* The same with the Hann window (hann = 1) or without it (0). */
wv_status wv_image_detail_window(const wv_image *img, int x0, int y0, int w, int h, int hann, float *out,
                                 wv_error *err);

/* The weave spectrum of the n x n window of img at (x0, y0) (n even, inside the image):
 * log(1 + |FFT(detail)|^2), unnormalised FFT, centred (row-major, DC at (n/2, n/2),
 * frequency (u, v) bins at (n/2 + u, n/2 + v), v downward as image rows).
 * out: n * n floats. */
wv_status wv_weave_spectrum(const wv_image *img, int x0, int y0, int n, float *out, wv_error *err);

/* How much of an image's detail is periodic. The detail is the luminance (Rec. 709 weights)
 * minus its Gaussian blur of sigma px; share is the part of its power (over the whole image)
 * in the bins of its spectrum holding at least 8 times the mean of the 9 x 9 bins about them:
 * near 1 for a clean render of a weave, near 0 for noise, in between for a photo whose weave
 * lies under the grain of its cloth and sensor. periodic (may be NULL): each channel's detail
 * kept at those bins only (w x h x 3, allocated here), the periodic texture in register with
 * img. img: RGB, at least 9 x 9. */
wv_status wv_detail_periodic(const wv_image *img, double sigma, double *share, wv_image *periodic, wv_error *err);

/* Weave-spectrum correlation (WSC): the Pearson correlation of the weave spectra of
 * the centre 256 x 256 pixels of a and b over the bins farther than 4 bins from DC.
 * Phase-invariant: it asks whether the two images hold the same periodic structure
 * (the same yarn spacings, ribs and floats), not whether their yarns line up. Two
 * regions of one weave score high, a weave against white noise about 0. Images may
 * differ in size; a side under 256 pixels uses the largest centred even square
 * both images hold (at least 32 pixels). */
wv_status wv_wsc(const wv_image *a, const wv_image *b, double *out, wv_error *err);
/* The same from two spectra of n x n (from wv_weave_spectrum). */
double wv_wsc_spectra(const float *sa, const float *sb, int n);

/* The whitened weave spectrum z of a weave spectrum S (n x n, from wv_weave_spectrum): with
 * L = log P, P = |FFT|^2 = exp(S) - 1, q = (L - median of L over its ring) / (1.4826 MAD
 * over the ring), rings one bin wide around DC, and z = q - floor_z clipped to
 * [0, cap_z - floor_z] (floor 0, cap 10: the weave analysis's peak prominence). It
 * divides out the radial envelope (the camera's and the renderer's blur, the yarns'
 * shading fall-off), which dominates the log spectrum, and keeps what stands out of it:
 * the weave's lattice of peaks. Rings with almost no power (a millionth of the window's
 * median power) and bins within WV_WSC_DC_RADIUS of DC get 0. z: n * n floats; it may
 * be spec itself (whitened in place: spec is read whole before z is written). */
wv_status wv_spectrum_whiten(const float *spec, int n, double floor_z, double cap_z, float *z, wv_error *err);

/* Whitened WSC: the Pearson correlation of the whitened weave spectra (wv_spectrum_whiten,
 * floor WV_WSC_Z_FLOOR, cap WV_WSC_Z_CAP: what stands out of the noise, a strong peak not
 * deciding alone) of the centre windows of a and b, chosen as wv_wsc chooses them. WSC is dominated by the
 * spectra's radial envelope, so any render with the photo's blur scores close to the
 * photo's own WSC whatever its weave; the whitened correlation asks only whether the peaks
 * (yarn spacings, ribs, floats) are where the photo has them. Invariant to a radial blur of
 * either image; white noise scores about 0. */
wv_status wv_wsc_whitened(const wv_image *a, const wv_image *b, double *out, wv_error *err);

#endif
