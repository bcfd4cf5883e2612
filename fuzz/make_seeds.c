/* woven fuzz: writes the seeds that are not files of the repository into OUT/<harness>/:
 * a FabricNet model and training checkpoint with 4 input features (a few hundred kB
 * instead of the shipped models' 10 MB), small PNGs (woven's own 8- and 16-bit RGB,
 * and grey, grey+alpha, palette and interlaced layouts written with libpng), small
 * JPEGs (baseline colour, grey, progressive with restarts, written with libjpeg), a
 * small EXR, a safetensors file, a dataset description and a fit checkpoint.
 * Usage: fuzz_make_seeds OUT (created if missing). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <jpeglib.h> /* after stdio.h: it uses FILE and size_t */
#include <png.h>

#include "woven/dataset.h"
#include "woven/fabricnet.h"
#include "woven/fit.h"
#include "woven/io.h"
#include "woven/nn.h"
#include "woven/render.h"

static const char *out_dir;

static void check(wv_status s, const wv_error *err) {
  if (s == WV_OK) return;
  fprintf(stderr, "fuzz_make_seeds: %s\n", err->msg);
  exit(1);
}

/* OUT/sub/name, with OUT/sub created. */
static const char *seed_path(const char *sub, const char *name) {
  static char path[4096];
  snprintf(path, sizeof path, "%s/%s", out_dir, sub);
  if (mkdir(path, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "fuzz_make_seeds: cannot create %s\n", path);
    exit(1);
  }
  snprintf(path, sizeof path, "%s/%s/%s", out_dir, sub, name);
  return path;
}

/* A w x h gradient with a little structure, values in [0, 1]. */
static void test_image(wv_image *img, int w, int h) {
  wv_error err;
  check(wv_image_alloc(img, w, h, 3, &err), &err);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++)
      for (int c = 0; c < 3; c++) wv_image_px(img, x, y)[c] = (float)((x * (c + 1) + 3 * y) % 17) / 16.0f;
}

static void write_png_layout(const char *name, int color, int depth, int interlace) {
  const char *path = seed_path("png", name);
  FILE *fp = fopen(path, "wb");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  if (!fp || !png || !info || setjmp(png_jmpbuf(png))) {
    fprintf(stderr, "fuzz_make_seeds: cannot write %s\n", path);
    exit(1);
  }
  png_init_io(png, fp);
  const int w = 5, h = 4;
  png_set_IHDR(png, info, w, h, depth, color, interlace, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (color == PNG_COLOR_TYPE_PALETTE) {
    png_color pal[4] = {{0, 0, 0}, {255, 0, 0}, {0, 255, 0}, {40, 60, 255}};
    png_byte trans[2] = {0, 128};
    png_set_PLTE(png, info, pal, 4);
    png_set_tRNS(png, info, trans, 2, NULL);
  }
  png_write_info(png, info);
  unsigned char row[5 * 8];
  int passes = png_set_interlace_handling(png);
  for (int p = 0; p < passes; p++)
    for (int y = 0; y < h; y++) {
      for (size_t i = 0; i < sizeof row; i++) row[i] = (unsigned char)((i * 37 + (size_t)y * 11) & (depth < 8 ? 0x55 : 0xff));
      png_write_row(png, row);
    }
  png_write_end(png, NULL);
  png_destroy_write_struct(&png, &info);
  fclose(fp);
}

static void write_jpeg(const char *name, int grey, int progressive) {
  const char *path = seed_path("jpeg", name);
  FILE *fp = fopen(path, "wb");
  if (!fp) {
    fprintf(stderr, "fuzz_make_seeds: cannot write %s\n", path);
    exit(1);
  }
  struct jpeg_compress_struct ci;
  struct jpeg_error_mgr jerr;
  ci.err = jpeg_std_error(&jerr);
  jpeg_create_compress(&ci);
  jpeg_stdio_dest(&ci, fp);
  ci.image_width = 16;
  ci.image_height = 12;
  ci.input_components = grey ? 1 : 3;
  ci.in_color_space = grey ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&ci);
  jpeg_set_quality(&ci, 80, TRUE);
  if (progressive) {
    jpeg_simple_progression(&ci);
    ci.restart_interval = 1;
  }
  jpeg_start_compress(&ci, TRUE);
  unsigned char row[16 * 3];
  while (ci.next_scanline < ci.image_height) {
    for (size_t i = 0; i < sizeof row; i++) row[i] = (unsigned char)(i * 13 + ci.next_scanline * 21);
    JSAMPROW rows[1] = {row};
    jpeg_write_scanlines(&ci, rows, 1);
  }
  jpeg_finish_compress(&ci);
  jpeg_destroy_compress(&ci);
  fclose(fp);
}

static void images(void) {
  wv_error err;
  wv_image img;
  test_image(&img, 7, 5);
  check(wv_image_write_png(seed_path("png", "woven8.png"), &img, 8, &err), &err);
  check(wv_image_write_png(seed_path("png", "woven16.png"), &img, 16, &err), &err);
  check(wv_image_write_exr(seed_path("exr", "woven.exr"), &img, &err), &err);
  wv_image_free(&img);
  write_png_layout("grey1.png", PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE);
  write_png_layout("grey_alpha8.png", PNG_COLOR_TYPE_GRAY_ALPHA, 8, PNG_INTERLACE_NONE);
  write_png_layout("palette4.png", PNG_COLOR_TYPE_PALETTE, 4, PNG_INTERLACE_NONE);
  write_png_layout("rgba16_interlaced.png", PNG_COLOR_TYPE_RGB_ALPHA, 16, PNG_INTERLACE_ADAM7);
  write_jpeg("colour.jpg", 0, 0);
  write_jpeg("grey.jpg", 1, 0);
  write_jpeg("progressive.jpg", 0, 1);
}

static void fabricnet(const wv_scene *s) {
  wv_error err;
  wv_fabricnet n;
  check(wv_fabricnet_init(&n, "default", 4, s, NULL, 7, &err), &err);
  check(wv_fabricnet_save(seed_path("fabricnet", "model.bin"), &n, &err), &err);
  size_t np = wv_fabricnet_param_count(&n);
  float *m = calloc(np, sizeof(float)), *v = calloc(np, sizeof(float));
  if (!m || !v) exit(1);
  wv_fabricnet_trainstate ts = {3, 60, 12345, 0.25f, 2};
  check(wv_fabricnet_checkpoint_save(seed_path("fabricnet", "train.ckpt"), &n, m, v, &ts, &err), &err);
  free(m), free(v);
  wv_fabricnet_free(&n);
}

static void safetensors(void) {
  wv_error err;
  const float a[6] = {1, -2, 3.5f, 0, 1e-3f, 7}, b[2] = {0.5f, -0.25f};
  const int64_t sa[2] = {2, 3}, sb[1] = {2};
  const char *names[2] = {"conv.weight", "conv.bias"};
  const int nd[2] = {2, 1};
  const int64_t *shapes[2] = {sa, sb};
  const float *data[2] = {a, b};
  check(wv_st_write_f32(seed_path("safetensors", "two.safetensors"), 2, names, nd, shapes, data, &err), &err);
}

static void dataset(const wv_scene *s) {
  wv_error err;
  wv_dataset_info info = {.version = WV_DATASET_VERSION, .renderer = WV_RENDER_VERSION, .seed = 99,
                          .per_pattern = 3, .spp = 16, .scene = *s, .n_feat = 4};
  char *sj = wv_scene_to_json(s);
  snprintf(info.scene_json, sizeof info.scene_json, "%s", sj);
  free(sj);
  snprintf(info.descriptor, sizeof info.descriptor, "default");
  seed_path("dataset", "");
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/dataset", out_dir);
  check(wv_dataset_info_write(dir, &info, &err), &err);
}

static void fit_checkpoint(void) {
  wv_error err;
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.iters = 4;
  wv_params p;
  check(wv_params_default("satin", &p, &err), &err);
  wv_fit_state st;
  check(wv_fit_state_init(&st, &p, &o, &err), &err);
  st.iter = 2;
  st.params.density[0] += 3;
  for (int i = 0; i < WV_P_COUNT; i++) st.adam_m[i] = 0.01 * i, st.adam_v[i] = 1e-4 * i;
  for (int i = 0; i < st.iter; i++)
    st.log[i] = (wv_fit_record){.iter = i, .loss = 0.5 - 0.1 * i, .gram = 0.4, .prior = 0.01, .pixel = 0.09,
                                .discrete_tried = i, .discrete_kept = i / 2};
  st.registered = 1;
  st.offset_mm[0] = 0.125;
  check(wv_fit_checkpoint_write(seed_path("fit_checkpoint", "checkpoint.json"), &st, &o, "default", &err), &err);
  wv_fit_state_free(&st);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: fuzz_make_seeds OUT\n");
    return 1;
  }
  out_dir = argv[1];
  if (mkdir(out_dir, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "fuzz_make_seeds: cannot create %s\n", out_dir);
    return 1;
  }
  wv_error err;
  wv_scene s;
  check(wv_scene_preset("flat45", &s, &err), &err);
  images();
  fabricnet(&s);
  safetensors();
  dataset(&s);
  fit_checkpoint();
  return 0;
}
