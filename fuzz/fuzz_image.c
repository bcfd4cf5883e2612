/* woven fuzz: image reading (wv_image_read: format sniffing, then libpng, libjpeg-turbo
 * or the OpenEXR core API) on an in-memory file. Decoding time and memory grow with
 * the size a header declares, not with the input, so inputs declaring more than
 * FUZZ_MAX_PIXELS are skipped: the limit on declared sizes is wv_io_check_size's,
 * checked before any allocation and covered by the unit tests, and what the fuzzer
 * is after is the decoding of small images. */
#include "fuzz_image.h"

#include <math.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/io.h"

#define FUZZ_MAX_PIXELS 1048576.0 /* 2^20 */

static uint32_t be16(const uint8_t *p) { return (uint32_t)p[0] << 8 | p[1]; }
static uint32_t be32(const uint8_t *p) { return be16(p) << 16 | be16(p + 2); }
static int32_t le32(const uint8_t *p) {
  return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
}

/* PNG: IHDR is the first chunk, width and height at bytes 16..23. */
static double png_pixels(const uint8_t *d, size_t n) {
  if (n < 24 || memcmp(d + 12, "IHDR", 4)) return -1;
  return (double)be32(d + 16) * be32(d + 20);
}

/* JPEG: walk the markers up to the first start-of-frame (SOF0..SOF15 but DHT, JPG, DAC). */
static double jpeg_pixels(const uint8_t *d, size_t n) {
  size_t i = 2;
  while (i + 4 <= n) {
    if (d[i] != 0xff) return -1;
    uint8_t m = d[i + 1];
    if (m == 0xff) { /* fill byte */
      i++;
      continue;
    }
    if (m == 0x01 || (m >= 0xd0 && m <= 0xd8)) { /* markers without a length */
      i += 2;
      continue;
    }
    if (m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc)
      return i + 9 <= n ? (double)be16(d + i + 5) * be16(d + i + 7) : -1;
    if (m == 0xda || m == 0xd9) return -1; /* scan data or end before any frame */
    i += 2 + be16(d + i + 2);
  }
  return -1;
}

/* EXR: the first header's attributes (name, type, size, value) up to an empty name. */
static double exr_pixels(const uint8_t *d, size_t n) {
  size_t i = 8;
  while (i < n && d[i]) {
    const uint8_t *name = d + i, *z = memchr(name, 0, n - i);
    if (!z) return -1;
    const uint8_t *type = z + 1, *tz = type < d + n ? memchr(type, 0, (size_t)(d + n - type)) : NULL;
    if (!tz || tz + 5 > d + n) return -1;
    int32_t len = le32(tz + 1);
    const uint8_t *val = tz + 5;
    if (len < 0 || (size_t)len > (size_t)(d + n - val)) return -1;
    if (!strcmp((const char *)name, "dataWindow") && len == 16) {
      double w = (double)le32(val + 8) - le32(val) + 1, h = (double)le32(val + 12) - le32(val + 4) + 1;
      return w > 0 && h > 0 ? w * h : -1;
    }
    i = (size_t)(val - d) + (size_t)len;
  }
  return -1;
}

double fuzz_image_declared_pixels(const uint8_t *data, size_t size) {
  static const uint8_t png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static const uint8_t jpeg[3] = {0xff, 0xd8, 0xff};
  static const uint8_t exr[4] = {0x76, 0x2f, 0x31, 0x01};
  if (size >= 8 && !memcmp(data, png, 8)) return png_pixels(data, size);
  if (size >= 3 && !memcmp(data, jpeg, 3)) return jpeg_pixels(data, size);
  if (size >= 4 && !memcmp(data, exr, 4)) return exr_pixels(data, size);
  return -1;
}

int fuzz_image_one(const uint8_t *data, size_t size) {
  if (fuzz_image_declared_pixels(data, size) > FUZZ_MAX_PIXELS) return 0;
  fuzz_file f;
  fuzz_file_open(&f, data, size);
  wv_image img;
  wv_image_info info;
  wv_error err = {0};
  wv_status st = wv_image_read(f.path, &img, &info, &err);
  fuzz_check_refusal(st, &err, f.path);
  fuzz_file_close(&f);
  if (st != WV_OK) {
    if (img.data || img.w || img.h) fuzz_fail("refused image left data behind: %s", err.msg);
    return 0;
  }
  if (img.c != 3 || img.w < 1 || img.h < 1 || !img.data) fuzz_fail("bad image %d x %d x %d", img.w, img.h, img.c);
  if ((info.bit_depth != 8 && info.bit_depth != 16 && info.bit_depth != 32) || info.channels_in_file < 1 ||
      info.channels_in_file > 4)
    fuzz_fail("bad image info: depth %d, %d channels", info.bit_depth, info.channels_in_file);
  /* Every value is read (uninitialised or out-of-bounds memory shows up under the
   * sanitizers); integer formats decode into [0, 1]. */
  size_t n = (size_t)img.w * img.h * 3;
  for (size_t i = 0; i < n; i++)
    if (!info.is_float && !(img.data[i] >= 0.0f && img.data[i] <= 1.0f))
      fuzz_fail("integer image value %g outside [0, 1]", (double)img.data[i]);
  wv_image_free(&img);
  return 0;
}
