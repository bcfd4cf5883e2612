/* woven: texture descriptors (Gram matrices of CNN features, SPEC section 7).
 * Input images are the capture image as the scene encodes it (RGB floats, about [0,1]). */
#ifndef WOVEN_DESCRIPTOR_H
#define WOVEN_DESCRIPTOR_H

#include <stddef.h>
#include "woven/error.h"
#include "woven/image.h"

typedef struct wv_descriptor wv_descriptor;

/* The embedded default descriptor: no weights file needed. */
wv_status wv_descriptor_create_default(wv_descriptor **out, wv_error *err);
/* VGG-19 features from a safetensors file with torchvision tensor names. */
wv_status wv_descriptor_create_vgg19(const char *weights_path, wv_descriptor **out, wv_error *err);
/* "default" or "vgg19". */
wv_status wv_descriptor_create(const char *name, const char *weights_path, wv_descriptor **out,
                               wv_error *err);
void wv_descriptor_free(wv_descriptor *d);

const char *wv_descriptor_name(const wv_descriptor *d);
/* Number of floats in the flattened Gram vector. */
size_t wv_descriptor_size(const wv_descriptor *d);

/* gram_out: wv_descriptor_size() floats. */
wv_status wv_descriptor_forward(wv_descriptor *d, const wv_image *img, float *gram_out, wv_error *err);
/* Forward and backward in one call: fills gram_out (may be NULL) and dimg (same
 * shape as img, allocated by the caller) with d(sum dgram*gram)/d img. */
wv_status wv_descriptor_backward(wv_descriptor *d, const wv_image *img, const float *dgram,
                                 float *gram_out, wv_image *dimg, wv_error *err);

#endif
