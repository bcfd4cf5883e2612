/* woven: the image operations the fit's losses use, each with its adjoint
 * (backward) so a loss on processed images can be differentiated back to the
 * render: area downsampling and an L1 difference. (The sensor response and its
 * adjoint are part of the renderers: wv_scene_response, woven/grad.h.)
 * A backward function maps dL/d(output) to dL/d(input); "in place" means out
 * (or din) may be the same image as in (or dout). */
#ifndef WOVEN_IMGOPS_H
#define WOVEN_IMGOPS_H

#include "woven/error.h"
#include "woven/image.h"

/* Area average to w x h (any factor, integer or not, down or up): output pixel
 * (X, Y) is the mean of the input over the rectangle [X fw, (X+1) fw) x
 * [Y fh, (Y+1) fh), fw = in->w / w, fh = in->h / h, partly covered input
 * pixels weighted by the covered area. out is allocated here (in->c channels). */
wv_status wv_image_downsample(const wv_image *in, int w, int h, wv_image *out, wv_error *err);
/* Adjoint: din (allocated here, in_w x in_h, dout->c channels) from dout. */
wv_status wv_image_downsample_backward(int in_w, int in_h, const wv_image *dout, wv_image *din, wv_error *err);

/* Clamp to [0, 1] and round to 8 bits (what a PNG stores and a photo arrives as); in place. */
void wv_image_quantise8(wv_image *img);

/* mean |a - b| over all samples; da (optional, allocated by the caller, a's
 * shape) receives d/da = sign(a - b) / count (0 where a = b). -1 if shapes differ. */
double wv_image_l1(const wv_image *a, const wv_image *b, wv_image *da);

#endif
