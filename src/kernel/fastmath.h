/* Fast math for the renderer's inner loops: polynomial sin/cos, exp and atan2
 * (kernel/fastmath_impl.h, one body) in scalar float (name_f) and 8-wide
 * (name_8), and front ends that pick by type: wv_sin, wv_cos and wv_exp take
 * float, 8-wide or double lanes (double: libm, for gradient checks). */
#ifndef WOVEN_FASTMATH_H
#define WOVEN_FASTMATH_H

#include "kernel/lanes.h"

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "kernel/fastmath_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_8
#include "kernel/lane_begin.h"
#include "kernel/fastmath_impl.h"
#include "kernel/lane_end.h"

#define wv_sin(x) _Generic((x), float: wv_sin_hp_f, wv_f8: wv_sin_hp_8, double: sin)(x)
#define wv_cos(x) _Generic((x), float: wv_cos_hp_f, wv_f8: wv_cos_hp_8, double: cos)(x)
#define wv_exp(x) _Generic((x), float: wv_expf_f, wv_f8: wv_expf_8, double: exp)(x)
#define wv_atan2g(y, x) _Generic((y), float: wv_atan2_f, wv_f8: wv_atan2_8)(y, x)

#endif
