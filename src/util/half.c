/* woven: float to IEEE half float conversion (util/half.h). */
#include "util/half.h"

#include <string.h>

uint16_t wv_f32_to_f16(float f) {
  uint32_t x;
  memcpy(&x, &f, 4);
  uint16_t sign = (uint16_t)((x >> 16) & 0x8000);
  uint32_t ax = x & 0x7fffffff;
  if (ax >= 0x7f800000) return sign | (ax > 0x7f800000 ? 0x7e00 : 0x7bff); /* NaN stays NaN; inf saturates */
  if (ax >= 0x477ff000) return sign | 0x7bff;                               /* rounds past 65504: saturate */
  if (ax < 0x33000001) return sign;                                         /* below half the smallest subnormal */
  int e = (int)(ax >> 23) - 127;
  uint32_t m = (ax & 0x7fffff) | 0x800000;
  int shift = e < -14 ? 13 + (-14 - e) : 13; /* subnormals keep fewer bits */
  uint32_t r = m >> shift, rem = m & ((1u << shift) - 1), half = 1u << (shift - 1);
  if (rem > half || (rem == half && (r & 1))) r++; /* round to nearest even */
  if (e < -14) return sign | (uint16_t)r;           /* may carry into the smallest normal: still right */
  return sign | (uint16_t)((((uint32_t)(e + 15)) << 10) + (r - 0x400)); /* a mantissa carry bumps the exponent */
}
