/* The gradient renderer's pixel loop in double, for gradient checks: float
 * rounding (~1e-7 of a pixel) divided by a finite-difference step swamps a
 * 1e-3 comparison. */
#include <math.h>
#include <string.h>

#include "render/grad_internal.h"

#define REAL double
#define K_PARAMS wv_shade_params_d
#define K_DIRS wv_dirs_d
#define K_GRAD wv_shade_grad_d
#define K_SHADE wv_shade_d
#define K_PIXEL wv_grad_pixel_d
#include "render/grad_kernel.inc"
