/* Image and file I/O: round trips, foreign files written with the codec
 * libraries directly, corrupt input, and atomic replacement. */
#define _DEFAULT_SOURCE /* flock */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jpeglib.h>
/* The OpenEXR include dir is private to the library target; the headers include
 * each other with quotes, so the prefixed path works here. */
#include <OpenEXR/openexr.h>
#include <png.h>

#include "woven/io.h"

static char dir[512];

static const char *in_dir(char *buf, size_t len, const char *name) {
  snprintf(buf, len, "%s/%s", dir, name);
  return buf;
}

static int setup_dir(void **state) {
  (void)state;
  const char *d = tu_tmpdir("io");
  if (!d) return -1;
  snprintf(dir, sizeof dir, "%s", d);
  return 0;
}

/* ---- helpers ---- */

static wv_image make_image(int w, int h, int c) {
  wv_image img;
  wv_error err = {0};
  assert_int_equal(wv_image_alloc(&img, w, h, c, &err), WV_OK);
  return img;
}

static void write_bytes(const char *path, const void *data, size_t len) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  if (len) assert_int_equal(fwrite(data, 1, len, f), len);
  assert_int_equal(fclose(f), 0);
}

/* Copies the first `keep` bytes of src into dst. */
static void truncate_copy(const char *src, const char *dst, size_t keep) {
  char *data;
  size_t len;
  wv_error err = {0};
  assert_int_equal(wv_read_file(src, &data, &len, &err), WV_OK);
  assert_true(keep < len);
  write_bytes(dst, data, keep);
  free(data);
}

static size_t file_size(const char *path) {
  struct stat st;
  assert_int_equal(stat(path, &st), 0);
  return (size_t)st.st_size;
}

/* Number of leftover temporary files ("*.tmp.*") in d. */
static int count_tmp_files(const char *d) {
  DIR *dp = opendir(d);
  assert_non_null(dp);
  int n = 0;
  for (struct dirent *e; (e = readdir(dp));)
    if (strstr(e->d_name, ".tmp.")) n++;
  closedir(dp);
  return n;
}

/* Reading path must fail with a message naming it; returns the status. */
static wv_status expect_read_failure(const char *path) {
  wv_image img = {.w = 99, .data = (float *)&img};
  wv_error err = {0};
  wv_status s = wv_image_read(path, &img, NULL, &err);
  assert_int_not_equal(s, WV_OK);
  assert_int_equal(err.code, s);
  assert_non_null(strstr(err.msg, path));
  assert_null(img.data);
  return s;
}

/* Writes a PNG of any colour type with libpng; rows are raw samples. */
static void write_raw_png(const char *path, int w, int h, int color, int depth, int interlace,
                          const unsigned char *pixels, size_t rowbytes, const png_color *palette,
                          int npalette, const png_byte *trns, int ntrns) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  assert_non_null(info);
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, depth, color, interlace, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (palette) png_set_PLTE(png, info, palette, npalette);
  if (trns) png_set_tRNS(png, info, trns, ntrns, NULL);
  png_write_info(png, info);
  int passes = png_set_interlace_handling(png);
  for (int p = 0; p < passes; p++)
    for (int y = 0; y < h; y++) png_write_row(png, pixels + rowbytes * y);
  png_write_end(png, NULL);
  png_destroy_write_struct(&png, &info);
  assert_int_equal(fclose(f), 0);
}

/* Writes an 8-bit JPEG (grey, RGB or CMYK by component count) with libjpeg. */
static void write_jpeg(const char *path, int w, int h, int comps, const unsigned char *pixels) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  struct jpeg_compress_struct ci;
  struct jpeg_error_mgr jerr;
  ci.err = jpeg_std_error(&jerr);
  jpeg_create_compress(&ci);
  jpeg_stdio_dest(&ci, f);
  ci.image_width = w;
  ci.image_height = h;
  ci.input_components = comps;
  ci.in_color_space = comps == 1 ? JCS_GRAYSCALE : comps == 3 ? JCS_RGB : JCS_CMYK;
  jpeg_set_defaults(&ci);
  jpeg_set_quality(&ci, 95, TRUE);
  jpeg_start_compress(&ci, TRUE);
  while (ci.next_scanline < ci.image_height) {
    JSAMPROW row = (JSAMPROW)(pixels + (size_t)ci.next_scanline * w * comps);
    jpeg_write_scanlines(&ci, &row, 1);
  }
  jpeg_finish_compress(&ci);
  jpeg_destroy_compress(&ci);
  assert_int_equal(fclose(f), 0);
}

/* A deterministic pattern covering [0,1] plus values that must be clamped. */
static void fill_pattern(wv_image *img, unsigned seed) {
  size_t n = (size_t)img->w * img->h * img->c;
  for (size_t i = 0; i < n; i++) {
    seed = seed * 1664525u + 1013904223u;
    img->data[i] = (float)(seed >> 8) / (float)(1u << 24);
  }
  img->data[0] = -0.25f;
  img->data[1] = 1.75f;
  img->data[2] = NAN;
}

static float expected_quantised(float v, unsigned maxval) {
  if (!(v > 0.0f)) return 0.0f;
  if (v >= 1.0f) return 1.0f;
  return (float)(unsigned)(v * (float)maxval + 0.5f) / (float)maxval;
}

/* ---- PNG ---- */

static void png_round_trip(int depth) {
  char path[600];
  in_dir(path, sizeof path, depth == 8 ? "rt8.png" : "rt16.png");
  wv_image src = make_image(13, 7, 3), back;
  fill_pattern(&src, (unsigned)depth);
  wv_error err = {0};
  assert_int_equal(wv_image_write_png(path, &src, depth, &err), WV_OK);
  wv_image_info info;
  assert_int_equal(wv_image_read(path, &back, &info, &err), WV_OK);
  assert_int_equal(back.w, 13);
  assert_int_equal(back.h, 7);
  assert_int_equal(back.c, 3);
  assert_int_equal(info.bit_depth, depth);
  assert_int_equal(info.is_float, 0);
  assert_int_equal(info.channels_in_file, 3);
  unsigned maxval = depth == 16 ? 65535u : 255u;
  for (size_t i = 0; i < (size_t)13 * 7 * 3; i++)
    assert_true(back.data[i] == expected_quantised(src.data[i], maxval));
  wv_image_free(&src);
  wv_image_free(&back);
}

static void test_png8_round_trip(void **state) {
  (void)state;
  png_round_trip(8);
}

static void test_png16_round_trip(void **state) {
  (void)state;
  png_round_trip(16);
}

/* Neighbouring 16-bit codes survive: they are 1/65535 apart, far below 8-bit steps. */
static void test_png16_precision(void **state) {
  (void)state;
  char path[600];
  in_dir(path, sizeof path, "precise.png");
  wv_image src = make_image(4, 1, 3), back;
  for (int i = 0; i < 12; i++) src.data[i] = (float)(30000 + i) / 65535.0f;
  wv_error err = {0};
  assert_int_equal(wv_image_write_png(path, &src, 16, &err), WV_OK);
  assert_int_equal(wv_image_read(path, &back, NULL, &err), WV_OK);
  for (int i = 0; i < 12; i++) assert_true(back.data[i] == src.data[i]);
  for (int i = 1; i < 12; i++) assert_true(back.data[i] > back.data[i - 1]);
  wv_image_free(&src);
  wv_image_free(&back);
}

static void test_png_grey_replicated(void **state) {
  (void)state;
  char path[600];
  in_dir(path, sizeof path, "grey.png");
  unsigned char px[3 * 2] = {0, 51, 255, 128, 1, 254};
  write_raw_png(path, 3, 2, PNG_COLOR_TYPE_GRAY, 8, PNG_INTERLACE_NONE, px, 3, NULL, 0, NULL, 0);
  wv_image img;
  wv_image_info info;
  wv_error err = {0};
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(img.c, 3);
  assert_int_equal(info.channels_in_file, 1);
  assert_int_equal(info.bit_depth, 8);
  for (int i = 0; i < 6; i++)
    for (int c = 0; c < 3; c++) assert_true(img.data[3 * i + c] == (float)px[i] / 255.0f);
  wv_image_free(&img);
}

static void test_png_other_layouts(void **state) {
  (void)state;
  char path[600];
  wv_image img;
  wv_image_info info;
  wv_error err = {0};

  /* 16-bit grey + alpha: grey replicated, alpha dropped. */
  unsigned char ga[2 * 4] = {0x12, 0x34, 0x00, 0x00, 0xff, 0xff, 0x80, 0x00};
  in_dir(path, sizeof path, "ga16.png");
  write_raw_png(path, 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 16, PNG_INTERLACE_NONE, ga, 8, NULL, 0, NULL,
                0);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(info.channels_in_file, 2);
  assert_int_equal(info.bit_depth, 16);
  for (int c = 0; c < 3; c++) {
    assert_true(img.data[c] == (float)0x1234 / 65535.0f);
    assert_true(img.data[3 + c] == 1.0f);
  }
  wv_image_free(&img);

  /* RGBA, Adam7 interlaced: alpha dropped, all pixels in place. */
  enum { W = 9, H = 9 };
  unsigned char rgba[W * H * 4];
  for (int i = 0; i < W * H * 4; i++) rgba[i] = (unsigned char)(i * 7);
  in_dir(path, sizeof path, "rgba_interlaced.png");
  write_raw_png(path, W, H, PNG_COLOR_TYPE_RGBA, 8, PNG_INTERLACE_ADAM7, rgba, W * 4, NULL, 0, NULL,
                0);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(info.channels_in_file, 4);
  for (int i = 0; i < W * H; i++)
    for (int c = 0; c < 3; c++) assert_true(img.data[3 * i + c] == (float)rgba[4 * i + c] / 255.0f);
  wv_image_free(&img);

  /* Palette with transparency: expanded to RGB, transparency ignored. */
  png_color pal[2] = {{10, 20, 30}, {200, 100, 50}};
  png_byte trns[2] = {0, 255};
  unsigned char idx[4] = {0, 1, 1, 0};
  in_dir(path, sizeof path, "palette.png");
  write_raw_png(path, 4, 1, PNG_COLOR_TYPE_PALETTE, 8, PNG_INTERLACE_NONE, idx, 4, pal, 2, trns, 2);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(img.c, 3);
  assert_int_equal(info.channels_in_file, 4);
  for (int i = 0; i < 4; i++) {
    const png_color *p = &pal[idx[i]];
    assert_true(img.data[3 * i + 0] == p->red / 255.0f);
    assert_true(img.data[3 * i + 1] == p->green / 255.0f);
    assert_true(img.data[3 * i + 2] == p->blue / 255.0f);
  }
  wv_image_free(&img);

  /* 1-bit grey scales to the full range. */
  unsigned char bits[1] = {0xa0}; /* 1 0 1 0 */
  in_dir(path, sizeof path, "grey1.png");
  write_raw_png(path, 4, 1, PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE, bits, 1, NULL, 0, NULL, 0);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_true(img.data[0] == 1.0f && img.data[3] == 0.0f && img.data[6] == 1.0f &&
              img.data[11] == 0.0f);
  wv_image_free(&img);
}

/* Format comes from the content, not the name; grey and RGBA inputs are written as RGB. */
static void test_detect_by_magic(void **state) {
  (void)state;
  char path[600];
  in_dir(path, sizeof path, "really_a_png.jpg");
  wv_image src = make_image(3, 2, 1), back;
  for (int i = 0; i < 6; i++) src.data[i] = (float)i / 5.0f;
  wv_error err = {0};
  assert_int_equal(wv_image_write_png(path, &src, 8, &err), WV_OK);
  assert_int_equal(wv_image_read(path, &back, NULL, &err), WV_OK);
  for (int i = 0; i < 6; i++)
    for (int c = 0; c < 3; c++)
      assert_true(back.data[3 * i + c] == expected_quantised(src.data[i], 255));
  wv_image_free(&back);
  assert_int_equal(wv_image_write(in_dir(path, sizeof path, "x.tiff"), &src, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, path));
  wv_image_free(&src);
}

/* A PNG header announcing more pixels than allowed is refused before decoding. */
static uint32_t crc32_of(const unsigned char *p, size_t n) {
  uint32_t c = 0xffffffffu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

static void put32(unsigned char *p, uint32_t v) {
  p[0] = (unsigned char)(v >> 24);
  p[1] = (unsigned char)(v >> 16);
  p[2] = (unsigned char)(v >> 8);
  p[3] = (unsigned char)v;
}

static void test_too_large_rejected(void **state) {
  (void)state;
  /* Signature, IHDR, then an empty IDAT so that the header reads completely. */
  unsigned char f[8 + 25 + 12] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  unsigned char *ihdr = f + 8;
  put32(ihdr, 13);
  memcpy(ihdr + 4, "IHDR", 4);
  put32(ihdr + 8, 30000); /* 30000 x 30000 = 9e8 pixels > 2^28 */
  put32(ihdr + 12, 30000);
  ihdr[16] = 8; /* depth */
  ihdr[17] = 2; /* RGB */
  put32(ihdr + 21, crc32_of(ihdr + 4, 17));
  unsigned char *idat = ihdr + 25;
  put32(idat, 0);
  memcpy(idat + 4, "IDAT", 4);
  put32(idat + 8, crc32_of(idat + 4, 4));
  char path[600];
  in_dir(path, sizeof path, "huge.png");
  write_bytes(path, f, sizeof f);
  assert_int_equal(expect_read_failure(path), WV_ERR_NOMEM);
  wv_image img;
  wv_error err = {0};
  wv_image_read(path, &img, NULL, &err);
  assert_non_null(strstr(err.msg, "too large"));
}

/* A PNG IHDR of w x h pixels (8-bit RGB) and an empty IDAT: the header reads completely. */
static void write_png_header(const char *path, uint32_t w, uint32_t h) {
  unsigned char f[8 + 25 + 12] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  unsigned char *ihdr = f + 8;
  put32(ihdr, 13);
  memcpy(ihdr + 4, "IHDR", 4);
  put32(ihdr + 8, w);
  put32(ihdr + 12, h);
  ihdr[16] = 8;
  ihdr[17] = 2;
  put32(ihdr + 21, crc32_of(ihdr + 4, 17));
  unsigned char *idat = ihdr + 25;
  put32(idat, 0);
  memcpy(idat + 4, "IDAT", 4);
  put32(idat + 8, crc32_of(idat + 4, 4));
  write_bytes(path, f, sizeof f);
}

/* The read limits (16384 per side, 64 Mpixel) hold in every format, checked from the
 * header alone: tiny files that claim huge images are refused before allocating. */
static void test_read_size_limits(void **state) {
  (void)state;
  char path[600];
  wv_image img;
  wv_error err = {0};
  write_png_header(in_dir(path, sizeof path, "wide.png"), 20000, 1); /* one side over */
  assert_int_equal(expect_read_failure(path), WV_ERR_NOMEM);
  write_png_header(path, 9000, 9000); /* 81 Mpixel: each side fine, the total not */
  assert_int_equal(expect_read_failure(path), WV_ERR_NOMEM);
  wv_image_read(path, &img, NULL, &err);
  assert_non_null(strstr(err.msg, "too large"));

  /* A JPEG whose frame header claims 65470 x 1530. */
  unsigned char px[16 * 8 * 3];
  memset(px, 90, sizeof px);
  write_jpeg(in_dir(path, sizeof path, "claims.jpg"), 16, 8, 3, px);
  char *data;
  size_t len;
  assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
  size_t sof = 0;
  for (size_t i = 2; i + 9 < len && !sof; i++)
    if ((unsigned char)data[i] == 0xff && (unsigned char)data[i + 1] == 0xc0) sof = i;
  assert_true(sof > 0);
  data[sof + 5] = (char)(1530 >> 8), data[sof + 6] = (char)(1530 & 0xff);
  data[sof + 7] = (char)(65470 >> 8), data[sof + 8] = (char)(65470 & 0xff);
  write_bytes(path, data, len);
  free(data);
  assert_int_equal(expect_read_failure(path), WV_ERR_NOMEM);

  /* An EXR whose data window claims 4063296 x 32. */
  wv_image small = make_image(4, 32, 3);
  fill_pattern(&small, 5);
  assert_int_equal(wv_image_write_exr(in_dir(path, sizeof path, "claims.exr"), &small, &err), WV_OK);
  wv_image_free(&small);
  assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
  static const char key[] = "dataWindow\0box2i";
  char *at = NULL;
  for (size_t i = 0; i + sizeof key + 20 < len && !at; i++)
    if (!memcmp(data + i, key, sizeof key)) at = data + i + sizeof key + 4; /* after the size field */
  assert_non_null(at);
  int32_t xmax = 4063295;
  memcpy(at + 8, &xmax, 4); /* box2i: xmin, ymin, xmax, ymax (little-endian) */
  write_bytes(path, data, len);
  free(data);
  assert_int_equal(expect_read_failure(path), WV_ERR_NOMEM);
}

/* Whole-file reads stop at their limit, also on endless devices; directories are named. */
static void test_read_limits(void **state) {
  (void)state;
  char *data = NULL;
  size_t len;
  wv_error err = {0};
  /* devices and FIFOs are refused before the first read: they could be endless or block */
  assert_int_equal(wv_read_file_max("/dev/zero", 1 << 20, &data, &len, &err), WV_ERR_IO);
  assert_null(data);
  assert_non_null(strstr(err.msg, "/dev/zero: not a regular file"));
  char fifo[600];
  assert_int_equal(mkfifo(in_dir(fifo, sizeof fifo, "fifo"), 0600), 0);
  assert_int_equal(wv_read_file(fifo, &data, &len, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "not a regular file"));
  wv_image img;
  assert_int_equal(wv_image_read(fifo, &img, NULL, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "not a regular file"));
  assert_int_equal(wv_png_check(fifo, &err), WV_ERR_IO);
  FILE *fp = NULL;
  assert_int_equal(wv_fopen_regular(fifo, &fp, &err), WV_ERR_IO);
  assert_null(fp);
  unlink(fifo);
  char path[600];
  char big[3000];
  memset(big, 'x', sizeof big);
  write_bytes(in_dir(path, sizeof path, "big.txt"), big, sizeof big);
  assert_int_equal(wv_read_file_max(path, 2999, &data, &len, &err), WV_ERR_NOMEM);
  assert_non_null(strstr(err.msg, "over the limit"));
  assert_int_equal(wv_read_file_max(path, 3000, &data, &len, &err), WV_OK);
  assert_int_equal(len, 3000);
  free(data);
  assert_int_equal(wv_read_file(dir, &data, &len, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "is a directory"));
}

/* Messages show at most a short printable excerpt of a file, or none of it. */
static void test_error_excerpt(void **state) {
  (void)state;
  wv_error err = {0};
  wv_fail(&err, WV_ERR_FORMAT, "p.json:1:4: malformed JSON: '[' or '{' expected near 'root:x:0:0:root:/root:/bin/bash\x01'");
  wv_error kept = err;
  wv_error_excerpt(&kept, WV_EXCERPT_CHARS);
  assert_string_equal(kept.msg, "p.json:1:4: malformed JSON: '[' or '{' expected near 'root:x:0:0:root:/root...'");
  wv_error_excerpt(&err, 0);
  assert_string_equal(err.msg, "p.json:1:4: malformed JSON: '[' or '{' expected");
  char out[8];
  wv_printable_excerpt("ab\tc\x7f", out, sizeof out);
  assert_string_equal(out, "ab?c?");
  wv_printable_excerpt("abcdefghij", out, sizeof out);
  assert_string_equal(out, "abcd...");
}

/* wv_png_check finds truncated and damaged files without decoding. */
static void test_png_check(void **state) {
  (void)state;
  char path[600], bad[600];
  wv_image img = make_image(40, 30, 3);
  fill_pattern(&img, 9);
  wv_error err = {0};
  assert_int_equal(wv_image_write_png(in_dir(path, sizeof path, "whole.png"), &img, 8, &err), WV_OK);
  wv_image_free(&img);
  assert_int_equal(wv_png_check(path, &err), WV_OK);
  size_t n = file_size(path);
  truncate_copy(path, in_dir(bad, sizeof bad, "cut.png"), n - 13);
  assert_int_equal(wv_png_check(bad, &err), WV_ERR_FORMAT);
  char *data;
  size_t len;
  assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
  data[len / 2] ^= 0x20; /* inside IDAT */
  write_bytes(bad, data, len);
  free(data);
  assert_int_equal(wv_png_check(bad, &err), WV_ERR_FORMAT);
  assert_non_null(strstr(err.msg, "checksum"));
}

/* Outputs never land on inputs: the same file under another name, or inside a
 * directory that is replaced whole. */
static void test_same_file(void **state) {
  (void)state;
  char a[600], link[600], sub[600], inner[600], ghost[600], other[600];
  in_dir(a, sizeof a, "same_a.txt");
  write_bytes(a, "a", 1);
  in_dir(link, sizeof link, "same_link.txt");
  unlink(link);
  assert_int_equal(symlink("same_a.txt", link), 0); /* relative to the link's directory */
  assert_true(wv_same_file(a, link));
  assert_false(wv_same_file(a, in_dir(ghost, sizeof ghost, "same_none.txt")));
  in_dir(sub, sizeof sub, "outdir");
  mkdir(sub, 0777);
  snprintf(inner, sizeof inner, "%s/../outdir/photo.png", sub);
  write_bytes(inner, "p", 1);
  assert_true(wv_path_within(inner, sub));
  assert_true(wv_path_within(sub, sub));
  assert_false(wv_path_within(a, sub));
  snprintf(ghost, sizeof ghost, "%s/not/yet/there", sub); /* counted where it would be */
  assert_true(wv_path_within(ghost, sub));
  wv_error err = {0};
  const char *in[3] = {NULL, link, inner};
  assert_int_equal(wv_check_not_input(a, 0, in, 2, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "refusing to write over an input"));
  assert_int_equal(wv_check_not_input(sub, 1, in + 2, 1, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "inside this output directory"));
  assert_int_equal(wv_check_not_input(in_dir(other, sizeof other, "elsewhere"), 1, in, 3, &err), WV_OK);
}

static void make_old(const char *path) {
  struct timespec t[2] = {{1000000000, 0}, {1000000000, 0}}; /* 2001 */
  assert_int_equal(utimensat(AT_FDCWD, path, t, 0), 0);
}

/* Only stale temporary names are removed: old, unlocked, of the named target. */
static void test_stale_temps(void **state) {
  (void)state;
  const char *d = tu_tmpdir("stale");
  char p[8][600];
  const char *names[8] = {"x.png.tmp.AAAAAA", "x.png.tmp.BBBBBB", "x.png.tmp.CCCCCC", "other.tmp.DDDDDD",
                          "x.png.tmp.toolong", "x.png.tmp.EEEEEE", "x.png", "x.png.tmp.FF-FFF"};
  for (int i = 0; i < 8; i++) snprintf(p[i], sizeof p[i], "%s/%s", d, names[i]);
  for (int i = 0; i < 8; i++)
    if (i != 5) write_bytes(p[i], "t", 1);
  assert_int_equal(mkdir(p[5], 0777), 0); /* a temporary directory with content */
  char inner[700];
  snprintf(inner, sizeof inner, "%s/file", p[5]);
  write_bytes(inner, "f", 1);
  make_old(inner);
  for (int i = 0; i < 8; i++)
    if (i != 1) make_old(p[i]); /* BBBBBB stays fresh */
  int fd = open(p[2], O_RDONLY); /* CCCCCC is held by a live writer */
  assert_true(fd >= 0);
  assert_int_equal(flock(fd, LOCK_EX), 0);
  assert_int_equal(wv_remove_stale_temps(d, "x.png"), 2); /* AAAAAA and the directory */
  struct stat st;
  assert_int_not_equal(stat(p[0], &st), 0);
  assert_int_not_equal(stat(p[5], &st), 0);
  for (int i = 1; i < 8; i++)
    if (i != 5) assert_int_equal(stat(p[i], &st), 0);
  assert_int_equal(wv_remove_stale_temps(d, NULL), 1); /* other.tmp.DDDDDD */
  close(fd);
  assert_int_equal(wv_remove_stale_temps(d, NULL), 1); /* CCCCCC, now unlocked */
  assert_true(wv_is_temp_name("a.tmp.Zz09aB"));
  assert_false(wv_is_temp_name(".tmp.Zz09aB"));
  assert_false(wv_is_temp_name("a.tmp.Zz09a"));
}

/* Writes text into dir/name. */
static void put_text(const char *dir, const char *name, const char *text) {
  char p[700];
  wv_error err = {0};
  snprintf(p, sizeof p, "%s/%s", dir, name);
  assert_int_equal(wv_write_file_atomic(p, text, strlen(text), &err), WV_OK);
}

/* dir/name holds text. */
static void expect_text(const char *dir, const char *name, const char *text) {
  char p[700], *data;
  size_t len;
  wv_error err = {0};
  snprintf(p, sizeof p, "%s/%s", dir, name);
  assert_int_equal(wv_read_file(p, &data, &len, &err), WV_OK);
  assert_string_equal(data, text);
  free(data);
}

/* A directory of outputs appears whole or not at all and replaces an earlier one whole. */
static void test_outdir(void **state) {
  (void)state;
  const char *d = tu_tmpdir("outdir");
  static const char *const own[] = {"a.txt", "b.txt", NULL};
  char target[600], p[700];
  snprintf(target, sizeof target, "%s/out", d);
  wv_outdir od;
  wv_error err = {0};
  struct stat st;
  /* new: nothing visible before the commit */
  assert_int_equal(wv_outdir_begin(&od, target, own, &err), WV_OK);
  put_text(od.tmp, "a.txt", "old a");
  put_text(od.tmp, "b.txt", "old b");
  assert_int_not_equal(stat(target, &st), 0);
  assert_int_equal(wv_outdir_commit(&od, &err), WV_OK);
  assert_null(od.tmp);
  assert_int_equal(count_tmp_files(d), 0);
  expect_text(target, "a.txt", "old a");
  /* a run that fails half way: the old directory is untouched, nothing left */
  assert_int_equal(wv_outdir_begin(&od, target, own, &err), WV_OK);
  put_text(od.tmp, "a.txt", "new a");
  wv_outdir_abort(&od, NULL);
  assert_int_equal(count_tmp_files(d), 0);
  expect_text(target, "a.txt", "old a");
  /* replaced whole: b.txt of the old run does not survive */
  assert_int_equal(wv_outdir_begin(&od, target, own, &err), WV_OK);
  put_text(od.tmp, "a.txt", "new a");
  assert_int_equal(wv_outdir_commit(&od, &err), WV_OK);
  expect_text(target, "a.txt", "new a");
  snprintf(p, sizeof p, "%s/b.txt", target);
  assert_int_not_equal(stat(p, &st), 0);
  assert_int_equal(count_tmp_files(d), 0);
  /* a stale temporary directory of the target is removed by the next begin */
  snprintf(p, sizeof p, "%s.tmp.Zz0000", target);
  assert_int_equal(mkdir(p, 0777), 0);
  make_old(p);
  assert_int_equal(wv_outdir_begin(&od, target, own, &err), WV_OK);
  assert_int_not_equal(stat(p, &st), 0);
  wv_outdir_abort(&od, NULL);
  /* refused: a file the output does not consist of, a file as target, "." */
  snprintf(p, sizeof p, "%s/notes.txt", target);
  write_bytes(p, "mine", 4);
  assert_int_equal(wv_outdir_begin(&od, target, own, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "notes.txt"));
  assert_int_equal(wv_outdir_begin(&od, p, own, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "not a directory"));
  assert_int_equal(wv_outdir_check(".", own, &err), WV_ERR_INVALID);
  snprintf(p, sizeof p, "%s/no/such/parent", d);
  assert_int_equal(wv_outdir_check(p, own, &err), WV_ERR_IO);
  assert_int_equal(count_tmp_files(d), 0);
}

/* ---- EXR ---- */

static void test_exr_round_trip(void **state) {
  (void)state;
  char path[600];
  in_dir(path, sizeof path, "rt.exr");
  /* 37 rows: not a multiple of the 16-line ZIP chunk. */
  wv_image src = make_image(11, 37, 3), back;
  fill_pattern(&src, 7);
  float specials[] = {-3.5f, 1e-40f, 65504.0f, 1e30f, -0.0f, 0.1f};
  memcpy(src.data + 3, specials, sizeof specials);
  wv_error err = {0};
  assert_int_equal(wv_image_write(path, &src, &err), WV_OK);
  wv_image_info info;
  assert_int_equal(wv_image_read(path, &back, &info, &err), WV_OK);
  assert_int_equal(info.is_float, 1);
  assert_int_equal(info.bit_depth, 32);
  assert_int_equal(info.channels_in_file, 3);
  assert_int_equal(back.w, 11);
  assert_int_equal(back.h, 37);
  /* NaN included: bit-exact comparison. */
  assert_memory_equal(back.data, src.data, sizeof(float) * 11 * 37 * 3);
  wv_image_free(&back);

  /* One channel is written to R, G and B; a fourth channel is not stored. */
  wv_image grey = make_image(5, 3, 1), rgba = make_image(5, 3, 4);
  fill_pattern(&grey, 3);
  fill_pattern(&rgba, 4);
  assert_int_equal(wv_image_write_exr(path, &grey, &err), WV_OK);
  assert_int_equal(wv_image_read(path, &back, NULL, &err), WV_OK);
  for (int i = 0; i < 15; i++)
    for (int c = 0; c < 3; c++)
      assert_memory_equal(&back.data[3 * i + c], &grey.data[i], sizeof(float));
  wv_image_free(&back);
  assert_int_equal(wv_image_write_exr(path, &rgba, &err), WV_OK);
  assert_int_equal(wv_image_read(path, &back, NULL, &err), WV_OK);
  for (int i = 0; i < 15; i++)
    assert_memory_equal(&back.data[3 * i], &rgba.data[4 * i], 3 * sizeof(float));
  wv_image_free(&back);
  wv_image_free(&grey);
  wv_image_free(&rgba);
  wv_image_free(&src);
}

/* Writes a half-float, luminance-only EXR with the core API: uncompressed scanlines
 * (one line per chunk) or a single tile covering the image. */
static void write_half_y_exr(const char *path, int w, int h, int tiled, const uint16_t *px) {
  exr_context_t ctx;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  int part;
  assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
  assert_int_equal(exr_add_part(ctx, NULL, tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, &part),
                   EXR_ERR_SUCCESS);
  assert_int_equal(exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_NONE),
                   EXR_ERR_SUCCESS);
  if (tiled)
    assert_int_equal(
        exr_set_tile_descriptor(ctx, part, w, h, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN),
        EXR_ERR_SUCCESS);
  assert_int_equal(
      exr_add_channel(ctx, part, "Y", EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
      EXR_ERR_SUCCESS);
  assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
  exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
  for (int y = 0; y < (tiled ? 1 : h); y++) {
    exr_chunk_info_t ci;
    exr_result_t rv = tiled ? exr_write_tile_chunk_info(ctx, part, 0, 0, 0, 0, &ci)
                            : exr_write_scanline_chunk_info(ctx, part, y, &ci);
    assert_int_equal(rv, EXR_ERR_SUCCESS);
    rv = y == 0 ? exr_encoding_initialize(ctx, part, &ci, &enc)
                : exr_encoding_update(ctx, part, &ci, &enc);
    assert_int_equal(rv, EXR_ERR_SUCCESS);
    enc.channels[0].encode_from_ptr = (const uint8_t *)(px + y * w);
    enc.channels[0].user_pixel_stride = 2;
    enc.channels[0].user_line_stride = 2 * w;
    enc.channels[0].user_bytes_per_element = 2;
    enc.channels[0].user_data_type = EXR_PIXEL_HALF;
    if (y == 0)
      assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), EXR_ERR_SUCCESS);
    assert_int_equal(exr_encoding_run(ctx, part, &enc), EXR_ERR_SUCCESS);
  }
  exr_encoding_destroy(ctx, &enc);
  assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
}

static void test_exr_half_grey(void **state) {
  (void)state;
  enum { W = 6, H = 3 };
  /* half bit patterns of 0, 0.5, 1, 2, -1, 0.25 */
  const uint16_t halves[6] = {0x0000, 0x3800, 0x3c00, 0x4000, 0xbc00, 0x3400};
  const float values[6] = {0.0f, 0.5f, 1.0f, 2.0f, -1.0f, 0.25f};
  uint16_t px[W * H];
  for (int i = 0; i < W * H; i++) px[i] = halves[i % 6];
  char path[600];
  wv_image img;
  wv_image_info info;
  wv_error err = {0};
  write_half_y_exr(in_dir(path, sizeof path, "half_y.exr"), W, H, 0, px);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(info.bit_depth, 16);
  assert_int_equal(info.is_float, 1);
  assert_int_equal(info.channels_in_file, 1);
  for (int i = 0; i < W * H; i++)
    for (int c = 0; c < 3; c++) assert_true(img.data[3 * i + c] == values[i % 6]);
  wv_image_free(&img);

  /* Tiled files are refused with a clear message. */
  write_half_y_exr(in_dir(path, sizeof path, "tiled.exr"), W, H, 1, px);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  wv_image_read(path, &img, NULL, &err);
  assert_non_null(strstr(err.msg, "tiled"));
}

/* ---- JPEG ---- */

static void test_jpeg_read(void **state) {
  (void)state;
  enum { W = 32, H = 24 };
  unsigned char rgb[W * H * 3], grey[W * H];
  for (int y = 0; y < H; y++)
    for (int x = 0; x < W; x++) {
      unsigned char *p = rgb + 3 * (y * W + x);
      p[0] = (unsigned char)(x * 255 / (W - 1));
      p[1] = (unsigned char)(y * 255 / (H - 1));
      p[2] = 128;
      grey[y * W + x] = (unsigned char)((x + y) * 255 / (W + H - 2));
    }
  char path[600];
  wv_image img;
  wv_image_info info;
  wv_error err = {0};

  write_jpeg(in_dir(path, sizeof path, "rgb.jpg"), W, H, 3, rgb);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(img.w, W);
  assert_int_equal(img.h, H);
  assert_int_equal(info.bit_depth, 8);
  assert_int_equal(info.channels_in_file, 3);
  double sum = 0, worst = 0;
  for (int i = 0; i < W * H * 3; i++) {
    double d = fabs(img.data[i] - rgb[i] / 255.0);
    sum += d;
    worst = d > worst ? d : worst;
  }
  assert_true(sum / (W * H * 3) < 0.01); /* quality 95, smooth content */
  assert_true(worst < 0.08);
  wv_image_free(&img);

  /* CMYK is refused clearly. */
  unsigned char cmyk[W * H * 4];
  memset(cmyk, 60, sizeof cmyk);
  write_jpeg(in_dir(path, sizeof path, "cmyk.jpg"), W, H, 4, cmyk);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  wv_image_read(path, &img, NULL, &err);
  assert_non_null(strstr(err.msg, "CMYK"));

  write_jpeg(in_dir(path, sizeof path, "grey.jpg"), W, H, 1, grey);
  assert_int_equal(wv_image_read(path, &img, &info, &err), WV_OK);
  assert_int_equal(info.channels_in_file, 1);
  for (int i = 0; i < W * H; i++) {
    assert_true(img.data[3 * i] == img.data[3 * i + 1] && img.data[3 * i] == img.data[3 * i + 2]);
    assert_true(fabs(img.data[3 * i] - grey[i] / 255.0) < 0.03);
  }
  wv_image_free(&img);
}

/* ---- corrupt input ---- */

static void test_corrupt_files(void **state) {
  (void)state;
  char good[600], path[600];
  wv_image img = make_image(40, 30, 3);
  fill_pattern(&img, 11);
  wv_error err = {0};

  /* Random bytes (first byte chosen to match no magic). */
  unsigned char noise[1000];
  unsigned seed = 5;
  for (size_t i = 0; i < sizeof noise; i++)
    noise[i] = (unsigned char)((seed = seed * 1103515245u + 12345u) >> 16);
  noise[0] = 0x42;
  write_bytes(in_dir(path, sizeof path, "noise.png"), noise, sizeof noise);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);

  /* Right magic, garbage after it. */
  static const unsigned char magics[3][8] = {{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'},
                                             {0xff, 0xd8, 0xff, 0xe0},
                                             {0x76, 0x2f, 0x31, 0x01}};
  for (int m = 0; m < 3; m++) {
    memcpy(noise, magics[m], 8);
    write_bytes(in_dir(path, sizeof path, "garbage.img"), noise, sizeof noise);
    assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  }

  /* Truncated PNG, both in the pixel data and in the header. */
  assert_int_equal(wv_image_write_png(in_dir(good, sizeof good, "good.png"), &img, 8, &err), WV_OK);
  truncate_copy(good, in_dir(path, sizeof path, "trunc.png"), file_size(good) / 2);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  wv_image tmp;
  wv_image_read(path, &tmp, NULL, &err);
  assert_non_null(strstr(err.msg, "truncated"));
  truncate_copy(good, path, 20);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);

  /* Truncated JPEG. */
  unsigned char rgb[40 * 30 * 3];
  for (size_t i = 0; i < sizeof rgb; i++) rgb[i] = (unsigned char)(i * 13);
  write_jpeg(in_dir(good, sizeof good, "good.jpg"), 40, 30, 3, rgb);
  truncate_copy(good, in_dir(path, sizeof path, "trunc.jpg"), file_size(good) / 2);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  truncate_copy(good, path, 10);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);

  /* Truncated EXR: in the pixel data, and inside the header. */
  assert_int_equal(wv_image_write_exr(in_dir(good, sizeof good, "good.exr"), &img, &err), WV_OK);
  truncate_copy(good, in_dir(path, sizeof path, "trunc.exr"), file_size(good) * 2 / 3);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  truncate_copy(good, path, 40);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);

  /* Empty, missing, directory. */
  write_bytes(in_dir(path, sizeof path, "empty.png"), "", 0);
  assert_int_equal(expect_read_failure(path), WV_ERR_FORMAT);
  assert_int_equal(expect_read_failure(in_dir(path, sizeof path, "missing.png")), WV_ERR_IO);
  assert_int_equal(expect_read_failure(dir), WV_ERR_IO);
  wv_image_free(&img);
}

/* ---- atomic writes ---- */

static void assert_file_equals(const char *path, const char *data, size_t len) {
  char *got;
  size_t n;
  wv_error err = {0};
  assert_int_equal(wv_read_file(path, &got, &n, &err), WV_OK);
  assert_int_equal(n, len);
  assert_memory_equal(got, data, len);
  free(got);
}

static void test_atomic_failures_keep_old_file(void **state) {
  (void)state;
  char path[600], bad[700], *before;
  size_t before_len;
  wv_error err = {0};
  wv_image img = make_image(8, 8, 3);
  fill_pattern(&img, 9);

  const char *exts[2] = {"keep.png", "keep.exr"};
  for (int e = 0; e < 2; e++) {
    in_dir(path, sizeof path, exts[e]);
    assert_int_equal(wv_image_write(path, &img, &err), WV_OK);
    assert_int_equal(wv_read_file(path, &before, &before_len, &err), WV_OK);

    /* Invalid image: rejected, old file untouched. */
    wv_image broken = {.w = 0, .h = 8, .c = 3, .data = img.data};
    assert_int_equal(wv_image_write(path, &broken, &err), WV_ERR_INVALID);
    assert_non_null(strstr(err.msg, path));
    assert_file_equals(path, before, before_len);

    /* Target directory missing. */
    snprintf(bad, sizeof bad, "%s/no_such_dir/%s", dir, exts[e]);
    assert_int_equal(wv_image_write(bad, &img, &err), WV_ERR_IO);
    assert_non_null(strstr(err.msg, bad));
    assert_non_null(strstr(err.msg, "temporary"));
    free(before);
  }

  /* Failure after the temporary file exists: the target is a directory, so the
   * final rename fails; the temporary file must be gone. */
  in_dir(path, sizeof path, "occupied.png");
  assert_int_equal(mkdir(path, 0755), 0);
  assert_int_equal(wv_image_write(path, &img, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, path));
  assert_int_equal(wv_write_file_atomic(path, "x", 1, &err), WV_ERR_IO);
  struct stat st;
  assert_int_equal(stat(path, &st), 0);
  assert_true(S_ISDIR(st.st_mode));

  assert_int_equal(count_tmp_files(dir), 0);
  wv_image_free(&img);
}

static void test_unwritable_path(void **state) {
  (void)state;
  char file[600], path[700];
  wv_error err = {0};
  wv_image img = make_image(2, 2, 3);
  /* A regular file used as a directory: fails even for root. */
  write_bytes(in_dir(file, sizeof file, "plain.txt"), "x", 1);
  snprintf(path, sizeof path, "%s/out.png", file);
  assert_int_equal(wv_image_write(path, &img, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, path));
  assert_non_null(strstr(err.msg, "Not a directory"));
  snprintf(path, sizeof path, "%s/out.bin", file);
  assert_int_equal(wv_write_file_atomic(path, "abc", 3, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, path));

  /* A read-only directory (permissions do not bind root, so only check otherwise). */
  if (geteuid() != 0) {
    char ro[600];
    in_dir(ro, sizeof ro, "readonly");
    assert_int_equal(mkdir(ro, 0555), 0);
    snprintf(path, sizeof path, "%s/out.exr", ro);
    assert_int_equal(wv_image_write(path, &img, &err), WV_ERR_IO);
    assert_non_null(strstr(err.msg, "Permission denied"));
    assert_int_equal(count_tmp_files(ro), 0);
    chmod(ro, 0755);
  }
  wv_image_free(&img);
}

/* ---- whole files ---- */

static void test_file_round_trip(void **state) {
  (void)state;
  char path[600];
  in_dir(path, sizeof path, "data.bin");
  wv_error err = {0};
  const char first[] = "first version, longer than the second";
  const char second[] = {'a', '\0', 'b'};
  assert_int_equal(wv_write_file_atomic(path, first, sizeof first - 1, &err), WV_OK);
  assert_file_equals(path, first, sizeof first - 1);
  assert_int_equal(wv_write_file_atomic(path, second, sizeof second, &err), WV_OK);
  assert_file_equals(path, second, sizeof second);

  /* New files get the usual mode (not mkstemp's 0600). */
  mode_t mask = umask(022);
  umask(mask);
  struct stat st;
  assert_int_equal(stat(path, &st), 0);
  assert_int_equal(st.st_mode & 0777, 0666 & ~mask);

  /* Replacing a file keeps its mode. */
  assert_int_equal(chmod(path, 0640), 0);
  assert_int_equal(wv_write_file_atomic(path, first, 5, &err), WV_OK);
  assert_int_equal(stat(path, &st), 0);
  assert_int_equal(st.st_mode & 0777, 0640);

  char *data;
  size_t len = 1;
  assert_int_equal(wv_write_file_atomic(path, NULL, 0, &err), WV_OK);
  assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
  assert_int_equal(len, 0);
  assert_int_equal(data[0], '\0');
  free(data);

  assert_int_equal(wv_read_file(in_dir(path, sizeof path, "nope"), &data, &len, &err), WV_ERR_IO);
  assert_null(data);
  assert_non_null(strstr(err.msg, path));
  assert_int_equal(wv_read_file(dir, &data, &len, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, dir));
  assert_int_equal(count_tmp_files(dir), 0);
}

/* ---- threads ---- */

static void *worker(void *arg) {
  int id = (int)(intptr_t)arg;
  char path[600];
  wv_image img = make_image(16, 16, 3), back;
  fill_pattern(&img, (unsigned)id);
  wv_error err = {0};
  intptr_t ok = 1;
  const char *exts[3] = {"png", "exr", "png"};
  for (int round = 0; round < 3; round++) {
    snprintf(path, sizeof path, "%s/thread%d.%s", dir, id, exts[round]);
    ok &= wv_image_write(path, &img, &err) == WV_OK;
    ok &= wv_image_read(path, &back, NULL, &err) == WV_OK;
    wv_image_free(&back);
    snprintf(path, sizeof path, "%s/thread%d_missing.exr", dir, id);
    ok &= wv_image_read(path, &back, NULL, &err) == WV_ERR_IO && strstr(err.msg, path) != NULL;
  }
  wv_image_free(&img);
  return (void *)ok;
}

static void test_threads(void **state) {
  (void)state;
  pthread_t t[4];
  for (int i = 0; i < 4; i++)
    assert_int_equal(pthread_create(&t[i], NULL, worker, (void *)(intptr_t)i), 0);
  for (int i = 0; i < 4; i++) {
    void *ok;
    assert_int_equal(pthread_join(t[i], &ok), 0);
    assert_true(ok == (void *)1);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_png8_round_trip),
      cmocka_unit_test(test_png16_round_trip),
      cmocka_unit_test(test_png16_precision),
      cmocka_unit_test(test_png_grey_replicated),
      cmocka_unit_test(test_png_other_layouts),
      cmocka_unit_test(test_detect_by_magic),
      cmocka_unit_test(test_too_large_rejected),
      cmocka_unit_test(test_exr_round_trip),
      cmocka_unit_test(test_exr_half_grey),
      cmocka_unit_test(test_jpeg_read),
      cmocka_unit_test(test_corrupt_files),
      cmocka_unit_test(test_atomic_failures_keep_old_file),
      cmocka_unit_test(test_unwritable_path),
      cmocka_unit_test(test_file_round_trip),
      cmocka_unit_test(test_threads),
      cmocka_unit_test(test_read_size_limits),
      cmocka_unit_test(test_read_limits),
    cmocka_unit_test(test_error_excerpt),
      cmocka_unit_test(test_png_check),
      cmocka_unit_test(test_same_file),
      cmocka_unit_test(test_stale_temps),
      cmocka_unit_test(test_outdir),
  };
  return cmocka_run_group_tests(tests, setup_dir, NULL);
}
