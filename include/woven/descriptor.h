/* woven: texture descriptors (Gram matrices of CNN features, SPEC section 7).
 * Input images are the capture image as the scene encodes it (RGB floats, about [0,1]).
 * docs/descriptor.md describes the networks.
 *
 * The Gram vector is the concatenation of one C x C block per layer (row-major,
 * both triangles), each G = F F^T / (H W) for the layer's feature map F.
 * A descriptor keeps scratch buffers sized on first use (re-allocated when the
 * image size changes), so one descriptor must not be used from two threads at
 * once; create one per thread instead. Calls parallelise internally with OpenMP
 * (and make OpenBLAS single-threaded, see woven/nn.h). */
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
/* A VGG-style stack read from a safetensors file with torchvision indexing: cfg[i] > 0
 * is a 3x3 convolution (padding 1) with that many filters followed by ReLU, tensors
 * features.N.weight (cfg[i], channels in, 3, 3) and features.N.bias; cfg[i] == 0 is a
 * 2x2 average pool followed by a Gram layer. N is torchvision's module index: a
 * convolution and its ReLU take two indices, a pool one. The last entry must be a
 * pool. VGG-19 is
 * {64,64,0, 128,128,0, 256,256,256,256,0, 512,512,512,512,0, 512,512,512,512,0}. */
wv_status wv_descriptor_create_vgg(const char *weights_path, const int *cfg, int ncfg,
                                   wv_descriptor **out, wv_error *err);
/* "default" or "vgg19". */
wv_status wv_descriptor_create(const char *name, const char *weights_path, wv_descriptor **out,
                               wv_error *err);
void wv_descriptor_free(wv_descriptor *d);

const char *wv_descriptor_name(const wv_descriptor *d);
/* Number of floats in the flattened Gram vector. */
size_t wv_descriptor_size(const wv_descriptor *d);

/* Gram layers: their number, and for each its channel count and the offset of its
 * block in the Gram vector. */
int wv_descriptor_layer_count(const wv_descriptor *d);
wv_status wv_descriptor_layer_info(const wv_descriptor *d, int layer, int *channels,
                                   size_t *offset, wv_error *err);
/* Per-layer weights, all 1 at creation: layer l's block of gram_out is multiplied by
 * w[l] (and its gradient accordingly). w holds wv_descriptor_layer_count() values. */
wv_status wv_descriptor_set_layer_weights(wv_descriptor *d, const float *w, wv_error *err);
/* Smallest image side the descriptor accepts (pixels). */
int wv_descriptor_min_side(const wv_descriptor *d);

/* gram_out: wv_descriptor_size() floats. */
wv_status wv_descriptor_forward(wv_descriptor *d, const wv_image *img, float *gram_out, wv_error *err);
/* Forward and backward in one call: fills gram_out and dimg (same shape as img,
 * allocated by the caller) with d(sum dgram*gram)/d img. gram_out may be NULL: the
 * Gram matrices are then not computed, which saves time when the caller has them. */
wv_status wv_descriptor_backward(wv_descriptor *d, const wv_image *img, const float *dgram,
                                 float *gram_out, wv_image *dimg, wv_error *err);

#endif
