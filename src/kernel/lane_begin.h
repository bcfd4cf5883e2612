/* Opens one instance of a lane template (see kernel/lanes.h): set WV_LANE to
 * WV_LANE_F, WV_LANE_8 or WV_LANE_D, include this, then the template(s), then
 * kernel/lane_end.h. No include guard: included once per instance. */
#include "kernel/lanes.h"

#define WV_LANE_F 1
#define WV_LANE_8 8
#define WV_LANE_D 2

#if WV_LANE == WV_LANE_F
#define WV_L float
#define WV_P float
#define WV_M int
#define WV_I int64_t
#define WV_U uint64_t
#define WV_W uint32_t
#define WV_R float
#define WV_B(x) ((float)(x))
#define WV_PB(x) ((float)(x))
#define WV_FN(name) name##_f
#define WV_TRUE 1
#elif WV_LANE == WV_LANE_8
#define WV_L wv_f8
#define WV_P wv_f8
#define WV_M wv_i8
#define WV_I wv_i8
#define WV_U wv_q8
#define WV_W wv_w8
#define WV_R float
#define WV_B(x) wv_splat8((float)(x))
#define WV_PB(x) wv_splat8((float)(x))
#define WV_FN(name) name##_8
#define WV_TRUE wv_splati8(-1)
#elif WV_LANE == WV_LANE_D
#define WV_L double
#define WV_P float
#define WV_M int
#define WV_I int64_t
#define WV_U uint64_t
#define WV_W uint32_t
#define WV_R double
#define WV_B(x) ((double)(x))
#define WV_PB(x) ((float)(x))
#define WV_FN(name) name##_d
#define WV_TRUE 1
#else
#error "WV_LANE must be WV_LANE_F, WV_LANE_8 or WV_LANE_D"
#endif
/* Positions widened to the shading type (a no-op except in WV_LANE_D). */
#define WV_LP(x) ((WV_L)(x))
