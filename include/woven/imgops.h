/* woven: the image operations the fit's losses use, each with its adjoint
 * (backward) so a loss on processed images can be differentiated back to the
 * render: area downsampling, the pieces of the sensor response (clipping,
 * colour encoding, falloff mask; SPEC section 6) and an L1 difference.
 * A backward function maps dL/d(output) to dL/d(input); "in place" means out
 * (or din) may be the same image as in (or dout). */
#ifndef WOVEN_IMGOPS_H
#define WOVEN_IMGOPS_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/scene.h"

/* Area average to w x h (any factor, integer or not, down or up): output pixel
 * (X, Y) is the mean of the input over the rectangle [X fw, (X+1) fw) x
 * [Y fh, (Y+1) fh), fw = in->w / w, fh = in->h / h, partly covered input
 * pixels weighted by the covered area. out is allocated here (in->c channels). */
wv_status wv_image_downsample(const wv_image *in, int w, int h, wv_image *out, wv_error *err);
/* Adjoint: din (allocated here, in_w x in_h, dout->c channels) from dout. */
wv_status wv_image_downsample_backward(int in_w, int in_h, const wv_image *dout, wv_image *din, wv_error *err);

/* The scene's colour encoding of one linear value in double, and its slope
 * d encode / d linear (0 for linear <= 0, where encode is clamped to 0). */
double wv_encode_d(const wv_scene *s, double linear);
double wv_encode_slope(const wv_scene *s, double linear);
/* The scene's falloff mask at pixel (x, y) of its full image (1 without falloff). */
double wv_falloff_mask(const wv_scene *s, int x, int y);

/* Colour encoding (as wv_encode) per value; in place allowed. */
void wv_image_encode(const wv_scene *s, const wv_image *in, wv_image *out);
void wv_image_encode_backward(const wv_scene *s, const wv_image *in, const wv_image *dout, wv_image *din);
/* min(v, clip); clip <= 0 means no clipping. The derivative is 0 where v > clip
 * (at v = clip the left derivative 1, as wv_scene_response_backward). */
void wv_image_clip(const wv_image *in, float clip, wv_image *out);
void wv_image_clip_backward(const wv_image *in, float clip, const wv_image *dout, wv_image *din);
/* Multiply by the falloff mask of the scene; images are the scene's size. */
void wv_image_mask(const wv_scene *s, const wv_image *in, wv_image *out);
void wv_image_mask_backward(const wv_scene *s, const wv_image *dout, wv_image *din);
/* Multiply by a constant (the response's exposure); linear, so its backward is itself. */
void wv_image_scale(const wv_image *in, float k, wv_image *out);

/* Gaussian blur of standard deviation sigma pixels, separable, per channel, edges
 * clamped, kernel radius ceil(3 sigma); sigma <= 0 copies. out is allocated here. */
wv_status wv_image_blur(const wv_image *in, double sigma, wv_image *out, wv_error *err);
/* Clamp to [0, 1] and round to 8 bits (what a PNG stores and a photo arrives as); in place. */
void wv_image_quantise8(wv_image *img);

/* mean |a - b| over all samples; da (optional, allocated by the caller, a's
 * shape) receives d/da = sign(a - b) / count (0 where a = b). -1 if shapes differ. */
double wv_image_l1(const wv_image *a, const wv_image *b, wv_image *da);

#endif
