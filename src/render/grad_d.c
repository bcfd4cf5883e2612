/* The gradient kernel in double, for gradient checks: float rounding (~1e-7 of
 * a pixel) divided by a finite-difference step swamps a 1e-3 comparison. */
#include <math.h>
#include <string.h>

#include "render/grad_internal.h"
#include "yarn/yarn_eval.h"

#define REAL double
#define K_PI 3.14159265358979323846
#define K_TENTH 0.1
#define K_SIN sin
#define K_COS cos
#define K_SQRT sqrt
#define K_EXP exp
#define K_DIRS kdirs_d
#define K_PARAMS kparams_d
#define K_LOAD_DIRS load_dirs_d
#define K_DOT dot_d
#define K_SAMPLE sample_d
#define K_PIXEL wv_grad_pixel_d
#include "render/grad_kernel.inc"
