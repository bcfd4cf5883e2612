/* The gradient renderer's pixel loop in float: the production path. Its value
 * arithmetic is the forward renderer's, so the capture it returns matches wv_render. */
#include <math.h>
#include <string.h>

#include "render/grad_internal.h"

#define REAL float
#define K_PARAMS wv_shade_params_f
#define K_DIRS wv_dirs_f
#define K_GRAD wv_shade_grad_f
#define K_SHADE wv_shade_f
#define K_PIXEL wv_grad_pixel_f
#include "render/grad_kernel.inc"
