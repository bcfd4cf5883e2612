/* woven: IEEE half floats (binary16), the storage of FabricNet's model weights and of
 * the dataset's features. The way back is wv_nn_f16_to_f32 (woven/nn.h). */
#ifndef WOVEN_UTIL_HALF_H
#define WOVEN_UTIL_HALF_H

#include <stdint.h>

uint16_t wv_f32_to_f16(float f); /* round to nearest even; overflow saturates to +-65504 */

#endif
