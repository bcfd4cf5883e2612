/* The gradient kernel in float: the production path. Its value arithmetic is
 * the forward renderer's, so the capture it returns matches wv_render. */
#include <math.h>
#include <string.h>

#include "render/grad_internal.h"
#include "yarn/yarn_eval.h"

#define REAL float
#define K_PI 3.14159265358979f
#define K_TENTH 0.1f
#define K_SIN wv_sin_hp
#define K_COS wv_cos_hp
#define K_SQRT sqrtf
#define K_EXP wv_expf
#define K_DIRS kdirs_f
#define K_PARAMS kparams_f
#define K_LOAD_DIRS load_dirs_f
#define K_DOT dot_f
#define K_SAMPLE sample_f
#define K_PIXEL wv_grad_pixel_f
#include "render/grad_kernel.inc"
