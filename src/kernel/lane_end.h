/* Closes a lane template instance opened by kernel/lane_begin.h. */
#undef WV_L
#undef WV_P
#undef WV_M
#undef WV_I
#undef WV_U
#undef WV_W
#undef WV_R
#undef WV_B
#undef WV_PB
#undef WV_FN
#undef WV_TRUE
#undef WV_LP
#undef WV_LANE
