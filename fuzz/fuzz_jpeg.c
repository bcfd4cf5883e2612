/* woven fuzz: JPEG reading through wv_image_read, from memory (body in fuzz_image.c;
 * seeds: JPEG files woven writes or ships). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return fuzz_image_one(data, size); }
