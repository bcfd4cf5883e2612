/* woven fuzz: the image-reading harnesses' shared body (fuzz_png, fuzz_jpeg, fuzz_exr
 * differ only in their seeds). */
#ifndef WOVEN_FUZZ_IMAGE_H
#define WOVEN_FUZZ_IMAGE_H

#include <stddef.h>
#include <stdint.h>

/* Pixel count a PNG, JPEG or EXR header declares; -1 when it cannot tell (a
 * malformed header, which the decoder then refuses). */
double fuzz_image_declared_pixels(const uint8_t *data, size_t size);

/* Reads the input with wv_image_read (from memory) and checks the result. */
int fuzz_image_one(const uint8_t *data, size_t size);

#endif
