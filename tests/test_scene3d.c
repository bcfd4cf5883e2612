/* The mesh renderer: mesh loading (OBJ, PLY, glTF) and its errors, tangent
 * frames, environment sampling (single and batched), the white furnace, the flat quad against the
 * capture renderer (lit from the front and from behind), light through the cloth (open gaps,
 * the sheet in a white environment, transmission off), edits, the cloth simulation, scene parsing errors,
 * determinism across thread counts, and the ray tracer's streams against its
 * single rays. Small images and few samples. */
#include <math.h>

#define M_PI 3.14159265358979323846
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scene3d/world_internal.h"
#include "testutil.h"
#include "tracer/tracer.h"
#include "util/hash.h"
#include "woven/cloth.h"
#include "woven/emitters.h"
#include "woven/io.h"
#include "woven/mesh.h"
#include "woven/metrics.h"
#include "woven/render.h"
#include "woven/scene3d.h"

static char dir[512];

static const char *file(const char *name, const char *text) {
  static char path[4][1024];
  static int k;
  char *p = path[k++ % 4];
  snprintf(p, 1024, "%s/%s", dir, name);
  if (text) {
    wv_error err = {0};
    if (wv_write_file_atomic(p, text, strlen(text), &err)) fail_msg("%s", err.msg);
  }
  return p;
}

/* A 2 x 1 quad in the xy plane, u along x, v along y, as text in each format. */
static const char *QUAD_OBJ = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                              "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
static const char *QUAD_PLY = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                              "property float z\nproperty float s\nproperty float t\nelement face 2\n"
                              "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n2 0 0 1 0\n"
                              "2 1 0 1 1\n0 1 0 0 1\n3 0 1 2\n3 0 2 3\n";

static void base64(const unsigned char *in, size_t n, char *out) {
  static const char *A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t o = 0;
  for (size_t i = 0; i < n; i += 3) {
    unsigned v = (unsigned)in[i] << 16 | (i + 1 < n ? (unsigned)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
    out[o++] = A[v >> 18 & 63], out[o++] = A[v >> 12 & 63];
    out[o++] = i + 1 < n ? A[v >> 6 & 63] : '=', out[o++] = i + 2 < n ? A[v & 63] : '=';
  }
  out[o] = 0;
}

/* The same quad as glTF 2.0 with an embedded buffer (positions, UVs, indices). */
static const char *quad_gltf(void) {
  static char text[4096];
  unsigned char buf[4 * 12 + 4 * 8 + 6 * 2];
  float pos[12] = {0, 0, 0, 2, 0, 0, 2, 1, 0, 0, 1, 0}, uv[8] = {0, 1, 1, 1, 1, 0, 0, 0}; /* glTF: v down */
  unsigned short ix[6] = {0, 1, 2, 0, 2, 3};
  memcpy(buf, pos, 48), memcpy(buf + 48, uv, 32), memcpy(buf + 80, ix, 12);
  char b64[200];
  base64(buf, sizeof buf, b64);
  snprintf(text, sizeof text,
           "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
           "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2}]}],"
           "\"buffers\":[{\"byteLength\":92,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
           "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,"
           "\"byteLength\":32},{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
           "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\",\"min\":[0,0,0],"
           "\"max\":[2,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
           "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}]}",
           b64);
  return text;
}

static void check_quad(const char *path) {
  wv_mesh m;
  wv_error err = {0};
  if (wv_mesh_load(path, 0, 1, &m, &err)) fail_msg("%s: %s", path, err.msg);
  assert_int_equal(m.nt, 2);
  assert_int_equal(m.nv, 4);
  assert_non_null(m.uv);
  assert_int_equal(wv_mesh_tangents(&m, path, &err), WV_OK);
  for (int v = 0; v < m.nv; v++) {
    /* warp follows v: the tangent (weft, u) is +x, normal x tangent (warp) +y, normal +z */
    assert_true(fabsf(m.tan[4 * v] - 1) < 1e-5f && fabsf(m.tan[4 * v + 1]) < 1e-5f);
    assert_true(fabsf(fabsf(m.nrm[3 * v + 2]) - 1) < 1e-5f);
    assert_true(m.tan[4 * v + 3] * m.nrm[3 * v + 2] > 0); /* +y = (n x t) * w */
    /* u runs with x: the UV at x = 2 is 1 */
    if (m.pos[3 * v] > 1) assert_true(fabsf(m.uv[2 * v] - 1) < 1e-6f);
    if (m.pos[3 * v + 1] > 0.5f) assert_true(fabsf(m.uv[2 * v + 1] - 1) < 1e-6f);
  }
  wv_mesh_free(&m);
}

static void test_mesh_formats(void **state) {
  (void)state;
  check_quad(file("quad.obj", QUAD_OBJ));
  check_quad(file("quad.ply", QUAD_PLY));
  check_quad(file("quad.gltf", quad_gltf()));
}

static void expect_mesh_error(const char *name, const char *text, size_t limit, wv_status code, const char *needle) {
  wv_mesh m;
  wv_error err = {0};
  const char *p = file(name, text);
  wv_status st = wv_mesh_load(p, limit, 1, &m, &err);
  if (st != code || !strstr(err.msg, needle) || !strstr(err.msg, name))
    fail_msg("%s: status %d, message '%s' (wanted %d and '%s')", name, st, err.msg, code, needle);
}

static void test_mesh_errors(void **state) {
  (void)state;
  expect_mesh_error("nouv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 0, WV_ERR_FORMAT, "no UV");
  expect_mesh_error("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                    "f 1/1 2/2 3/3\nf 1/1 2/2 4/4\n", 0, WV_ERR_FORMAT, "degenerate");
  expect_mesh_error("flatuv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 2 0\nf 1/1 2/2 3/3\n", 0,
                    WV_ERR_FORMAT, "degenerate UVs");
  expect_mesh_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n", 0,
                    WV_ERR_FORMAT, "");
  expect_mesh_error("notamesh.obj", "this is not a mesh at all\n", 0, WV_ERR_FORMAT, "");
  expect_mesh_error("truncated.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 50\nproperty list uchar int vertex_indices\n"
                    "end_header\nabc", 0, WV_ERR_FORMAT, "");
  expect_mesh_error("empty.obj", "", 0, WV_ERR_FORMAT, "empty");
  /* a face index beyond the vertices: refused before assimp's post-processing (which aborted) */
  expect_mesh_error("badindex.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float s\nproperty float t\nelement face 1\n"
                    "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n/2 41 2\n",
                    0, WV_ERR_FORMAT, "");
  expect_mesh_error("big.obj", QUAD_OBJ, 64, WV_ERR_NOMEM, "memory limit");
  wv_mesh m;
  wv_error err = {0};
  assert_int_equal(wv_mesh_load(file("missing.obj", NULL), 0, 1, &m, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "missing.obj"));
  /* numbers a mesh brings: coordinates and UVs within range */
  expect_mesh_error("far.obj", "v 0 0 0\nv 2e8 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n", 0, WV_ERR_FORMAT,
                    "vertex 1 has a coordinate of 2e+08 mm");
  expect_mesh_error("biguv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1e20 0\nvt 0 1\nf 1/1 2/2 3/3\n", 0,
                    WV_ERR_FORMAT, "vertex 1 has a UV of (1e+20, 0)");
  expect_mesh_error("quad.fbx", QUAD_OBJ, 0, WV_ERR_FORMAT, "not a mesh file woven reads");
}

/* What a mesh file declares is checked before assimp allocates or recurses for it. */
static void expect_declared(const char *name, const char *text, size_t len, wv_status code, const char *needle) {
  char path[4200];
  snprintf(path, sizeof path, "%s/%s", tu_tmpdir("scene3d"), name);
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(text, 1, len, f), len);
  fclose(f);
  wv_error err = {0};
  wv_status st = wv_mesh_check_file(path, 0, &err);
  if (st != code || (code && (!strstr(err.msg, needle) || !strstr(err.msg, name))))
    fail_msg("%s: status %d, message '%s' (wanted %d and '%s')", name, st, err.msg, code, needle);
}

static char *deep_gltf(int depth) {
  size_t cap = (size_t)depth * 24 + 1024, n = 0;
  char *t = malloc(cap);
  assert_non_null(t);
  n += (size_t)snprintf(t + n, cap - n, "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[");
  for (int i = 0; i + 1 < depth; i++) n += (size_t)snprintf(t + n, cap - n, "{\"children\":[%d]},", i + 1);
  snprintf(t + n, cap - n, "{}]}");
  return t;
}

static void test_mesh_check(void **state) {
  (void)state;
  char *g = deep_gltf(20000);
  expect_declared("deep.gltf", g, strlen(g), WV_ERR_FORMAT, "more than 256 levels deep");
  free(g);
  g = deep_gltf(WV_MESH_MAX_NODE_DEPTH);
  expect_declared("deep256.gltf", g, strlen(g), WV_OK, "");
  free(g);
  static const char cyc[] = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"children\":[1]},{\"children\":[0]}]}";
  expect_declared("cycle.gltf", cyc, sizeof cyc - 1, WV_ERR_FORMAT, "levels deep (or has a cycle)");
  static const char two[] = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"children\":[2]},{\"children\":[2]},{}]}";
  expect_declared("twoparents.gltf", two, sizeof two - 1, WV_ERR_FORMAT, "more than one parent");
  static const char acc[] = "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":8,\"uri\":\"data:,AAAAAAAAAAA=\"}],"
                            "\"bufferViews\":[{\"buffer\":0,\"byteLength\":8}],\"accessors\":[{\"bufferView\":0,"
                            "\"componentType\":5126,\"count\":1000,\"type\":\"VEC3\"}]}";
  expect_declared("acc.gltf", acc, sizeof acc - 1, WV_ERR_FORMAT, "accessor 0 reads past its buffer view");
  static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n";
  expect_declared("bomb.ply", ply, sizeof ply - 1, WV_ERR_NOMEM, "declares 2000000000 vertices");
  static const char ply2[] = "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n0123456789";
  expect_declared("short.ply", ply2, sizeof ply2 - 1, WV_ERR_FORMAT, "more than its 10 bytes of data can hold");
  /* a GLB whose binary chunk claims 2 GB */
  static const char js[] = "{\"asset\":{\"version\":\"2.0\"}} "; /* 28 bytes: chunks are 4-aligned */
  unsigned char glb[12 + 8 + sizeof js - 1 + 8 + 16];
  uint32_t total = sizeof glb, jl = sizeof js - 1, bl = 0x7ffffff0;
  memcpy(glb, "glTF\2\0\0\0", 8), memcpy(glb + 8, &total, 4), memcpy(glb + 12, &jl, 4), memcpy(glb + 16, "JSON", 4);
  memcpy(glb + 20, js, jl), memcpy(glb + 20 + jl, &bl, 4), memcpy(glb + 24 + jl, "BIN", 4);
  memset(glb + 28 + jl, 0, 16);
  expect_declared("chunk.glb", (const char *)glb, sizeof glb, WV_ERR_FORMAT, "a GLB chunk declares 2147483632 bytes");
  static const char stl[84] = {0};
  char stl2[84];
  memcpy(stl2, stl, 84);
  stl2[83] = 0x10; /* 268 million triangles in 84 bytes */
  expect_declared("bomb.stl", stl2, 84, WV_ERR_FORMAT, "declares 268435456 triangles");
  /* a FIFO as a mesh: refused at once, never opened for blocking reads */
  char fifo[4200];
  snprintf(fifo, sizeof fifo, "%s/fifo.obj", tu_tmpdir("scene3d"));
  unlink(fifo);
  assert_int_equal(mkfifo(fifo, 0600), 0);
  wv_error err = {0};
  assert_int_equal(wv_mesh_check_file(fifo, 0, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "not a regular file"));
  unlink(fifo);
}

/* A material refused after its parameter file's path was read frees that path (the
 * sanitizer build's leak check fails otherwise). */
static void test_material_refused(void **state) {
  (void)state;
  const char *json = "{\"image\": {\"width\": 8, \"height\": 6}, \"camera\": {\"position_mm\": [0, 0, 100], "
                     "\"look_at_mm\": [0, 0, 0], \"vfov_deg\": 30}, \"materials\": {\"m\": {\"fabric\": \"x.json\", \"uv_mm\": [0, 0]}}, "
                     "\"objects\": [{\"sphere\": {\"radius_mm\": 10}, \"material\": \"m\"}]}";
  wv_scene3d s;
  wv_error err = {0};
  assert_int_equal(wv_scene3d_parse(json, "refused.json", NULL, &s, &err), WV_ERR_INVALID);
  if (!strstr(err.msg, "uv_mm")) fail_msg("%s", err.msg);
}

/* Importance sampling of an environment: the returned pdf is the pdf's value
 * there, the pdf integrates to 1, and E[L / pdf] is the integral of L. */
static void test_env_sampling(void **state) {
  (void)state;
  wv_image img;
  wv_error err = {0};
  assert_int_equal(wv_env_builtin("sky", 64, &img, &err), WV_OK);
  for (size_t i = 0; i < (size_t)img.w * img.h * 3; i++) img.data[i] *= 0.5f + wv_u01(wv_mix64(i)); /* texture */
  wv_envmap e;
  assert_int_equal(wv_envmap_init(&e, &img, 1.0, 30.0, "test", &err), WV_OK);
  /* quadrature over the sphere: the pdf's integral and the radiance's */
  double pdf_int = 0, l_int = 0;
  int N = 1024;
  for (int i = 0; i < N; i++)
    for (int j = 0; j < 2 * N; j++) {
      double th = M_PI * (i + 0.5) / N, ph = 2 * M_PI * (j + 0.5) / (2 * N);
      float d[3] = {(float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph))}, c[3];
      double dw = sin(th) * (M_PI / N) * (M_PI / N);
      pdf_int += wv_envmap_pdf(&e, d) * dw;
      wv_envmap_eval(&e, d, c);
      l_int += c[1] * dw;
    }
  print_message("pdf integral %.5f, radiance integral %.5f\n", pdf_int, l_int);
  assert_true(fabs(pdf_int - 1) < 2e-3);
  double est = 0;
  int M = 200000;
  for (int k = 0; k < M; k++) {
    float d[3], c[3];
    uint64_t h = wv_hash2((uint64_t)k, 1, 2);
    float pdf = wv_envmap_sample(&e, wv_u01(h), (float)((h >> 16) & 0xffffff) / 16777216.0f, d, c);
    assert_true(pdf > 0);
    assert_true(fabsf(pdf - wv_envmap_pdf(&e, d)) <= 1e-3f * pdf);
    assert_true(fabsf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1) < 1e-4f);
    est += c[1] / pdf;
  }
  est /= M;
  print_message("importance-sampled estimate %.5f\n", est);
  assert_true(fabs(est - l_int) < 0.01 * l_int);
  wv_envmap_free(&e);
  wv_image_free(&img);
}

/* The batched sampler (it reads the tables in stages) gives the single sampler's
 * directions, radiance and pdf bit for bit: maps from 16 to 2048 wide, smooth,
 * textured and with a sharp sun, turned or not, numbers at the ends of [0, 1)
 * included. */
static void test_env_sample_batch(void **state) {
  (void)state;
  const struct {
    const char *name;
    int width;
    double rot;
    int texture;
  } maps[] = {{"sky", 64, 30, 1}, {"studio", 1024, 0, 0}, {"white", 16, 0, 0}, {"sky", 2048, 77, 0}};
  enum { N = 20000 };
  static float u[N][2];
  static wv_env_sample out[N];
  for (int k = 0; k < N; k++) {
    uint64_t h = wv_hash2((uint64_t)k, 3, 4);
    u[k][0] = wv_u01(h), u[k][1] = (float)((h >> 16) & 0xffffff) / 16777216.0f;
  }
  u[0][0] = u[0][1] = 0.0f, u[1][0] = u[1][1] = 0.99999994f, u[2][0] = 0.5f, u[2][1] = 0.25f;
  for (size_t m = 0; m < sizeof maps / sizeof *maps; m++) {
    wv_image img;
    wv_error err = {0};
    wv_envmap e;
    assert_int_equal(wv_env_builtin(maps[m].name, maps[m].width, &img, &err), WV_OK);
    if (maps[m].texture)
      for (size_t i = 0; i < (size_t)img.w * img.h * 3; i++) img.data[i] *= 0.5f + wv_u01(wv_mix64(i));
    assert_int_equal(wv_envmap_init(&e, &img, 1.0, maps[m].rot, "test", &err), WV_OK);
    wv_envmap_sample_n(&e, N - 3, (const float(*)[2])u, out); /* not a multiple of the block */
    int same = 1;
    for (int k = 0; k < N - 3; k++) {
      float d[3], c[3], pdf = wv_envmap_sample(&e, u[k][0], u[k][1], d, c);
      same &= !memcmp(d, out[k].d, sizeof d) && !memcmp(c, out[k].rgb, sizeof c) && !memcmp(&pdf, &out[k].pdf, sizeof pdf);
    }
    if (!same) fail_msg("%s %d: the batched environment samples differ", maps[m].name, maps[m].width);
    wv_envmap_free(&e);
    wv_image_free(&img);
  }
}

/* Pixel (x, y) of a w x h map turned by rot (radians) that the direction d lies in,
 * from its angles in double; 0 when d is within 1e-4 of a pixel of an edge. */
static int ref_pixel(const float d[3], int w, int h, double rot, int *x, int *y) {
  double mx = cos(rot) * d[0] - sin(rot) * d[2], mz = sin(rot) * d[0] + cos(rot) * d[2];
  double cy = d[1] < -1 ? -1 : d[1] > 1 ? 1 : d[1];
  double fx = (atan2(mx, -mz) + M_PI) / (2 * M_PI) * w, fy = acos(cy) / M_PI * h;
  *x = (int)floor(fx), *y = (int)floor(fy);
  *x = *x < 0 ? 0 : *x >= w ? w - 1 : *x, *y = *y < 0 ? 0 : *y >= h ? h - 1 : *y;
  return fabs(fx - floor(fx + 0.5)) > 1e-4 && fabs(fy - floor(fy + 0.5)) > 1e-4;
}

/* Interval i of a CDF of n intervals with cdf[i] <= u < cdf[i + 1]. */
static int ref_find(const float *cdf, int n, float u) {
  int lo = 0, hi = n;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (cdf[mid] <= u) lo = mid;
    else hi = mid;
  }
  return lo;
}

/* A direction's pixel (found by comparisons with tables of the pixels' edges, no
 * acos or atan2) is the one of its angles in double, away from the edges; a drawn
 * direction is the point of its pixel that the numbers ask for (cos theta and the
 * longitude at the numbers' fractions across the pixel, within 1e-6 and 2e-6 rad:
 * the longitude is turned from the column's centre by Taylor series), of unit
 * length, with the density and radiance its direction looks up, those of the pixel
 * it lies in: maps from 2 x 1 to 1025 x 512,
 * turned or not, some pixels black. */
static void test_env_pixels(void **state) {
  (void)state;
  const struct {
    int w, h;
    double rot;
  } maps[] = {{2, 1, 0}, {3, 2, 10}, {7, 3, 0}, {8, 4, 200}, {64, 32, 30}, {1025, 512, -77}};
  for (size_t m = 0; m < sizeof maps / sizeof *maps; m++) {
    int w = maps[m].w, h = maps[m].h;
    double rot = maps[m].rot * M_PI / 180;
    wv_image img;
    wv_error err = {0};
    assert_int_equal(wv_image_alloc(&img, w, h, 3, &err), WV_OK);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) img.data[i] = (i / 3) % 7 == 3 ? 0.0f : 0.1f + wv_u01(wv_mix64(i));
    wv_envmap e;
    assert_int_equal(wv_envmap_init(&e, &img, 1.0, maps[m].rot, "test", &err), WV_OK);
    int wrong = 0, far = 0, checked = 0, same = 1;
    double worst[3] = {0, 0, 0}; /* a drawn direction's cos theta, longitude (away from the poles) and length */
    for (int k = 0; k < 100000; k++) { /* lookups of directions uniform on the sphere */
      uint64_t hs = wv_hash2((uint64_t)k, 5, 6);
      double z = 2 * wv_u01(hs) - 1, ph = 2 * M_PI * wv_u01(hs >> 20), r = sqrt(1 - z * z);
      float d[3] = {(float)(r * cos(ph)), (float)z, (float)(r * sin(ph))};
      int x, y;
      if (!ref_pixel(d, w, h, rot, &x, &y)) continue;
      checked++;
      wrong += wv_envmap_at(&e, d).texel != (size_t)y * w + x;
    }
    for (int k = 0; k < 100000; k++) { /* draws */
      uint64_t hs = wv_hash2((uint64_t)k, 7, 8);
      float u1 = wv_u01(hs), u2 = (float)((hs >> 16) & 0xffffff) / 16777216.0f, d[3], c[3];
      float pdf = wv_envmap_sample(&e, u1, u2, d, c), c2[3], pdf2 = wv_envmap_lookup(&e, d, c2);
      same &= pdf == pdf2 && !memcmp(c, c2, sizeof c);
      int y = ref_find(e.cdf_row, h, u1);
      const float *row = e.cdf_col + (size_t)y * (w + 1);
      int x = ref_find(row, w, u2);
      double fy = ((double)u1 - e.cdf_row[y]) / ((double)e.cdf_row[y + 1] - e.cdf_row[y]);
      double fx = ((double)u2 - row[x]) / ((double)row[x + 1] - row[x]);
      double cy = cos(M_PI * y / h) + fy * (cos(M_PI * (y + 1) / h) - cos(M_PI * y / h));
      double ph = 2 * M_PI * (x + fx) / w - M_PI; /* turned back: the angle of (mx, -mz) */
      double got = atan2(cos(rot) * d[0] - sin(rot) * d[2], -(sin(rot) * d[0] + cos(rot) * d[2]));
      double dph = fabs(remainder(got - ph, 2 * M_PI));
      worst[0] = fmax(worst[0], fabs(d[1] - cy));
      if (1 - cy * cy > 1e-4) worst[1] = fmax(worst[1], dph);
      worst[2] = fmax(worst[2], fabs(sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]) - 1));
      int px, py;
      if (!ref_pixel(d, w, h, rot, &px, &py)) continue;
      const float *rp = e.cdf_col + (size_t)py * (w + 1);
      double omega = (cos(M_PI * py / h) - cos(M_PI * (py + 1) / h)) * 2 * M_PI / w;
      double want_pdf = ((double)e.cdf_row[py + 1] - e.cdf_row[py]) * ((double)rp[px + 1] - rp[px]) / omega;
      far += !(fabs(pdf - want_pdf) <= 1e-5 * want_pdf) || c[0] != img.data[((size_t)py * w + px) * 3];
    }
    print_message("%d x %d: %d of %d lookups in another pixel, %d draws off their pixel's density or radiance; "
                  "drawn directions' largest errors: cos theta %.2g, longitude %.2g rad, length %.2g\n",
                  w, h, wrong, checked, far, worst[0], worst[1], worst[2]);
    assert_true(checked > 90000);
    assert_int_equal(wrong, 0);
    assert_int_equal(far, 0);
    if (!same) fail_msg("%d x %d: a draw's pdf or radiance is not its direction's", w, h);
    assert_true(worst[0] < 1e-6 && worst[1] < 2e-6 && worst[2] < 1e-6);
    wv_envmap_free(&e);
    wv_image_free(&img);
  }
}

/* The bounce's turn (a table and short Taylor series instead of libm) gives cos and
 * sin of 2 pi u within 2e-7, on a million numbers and at the ends of [0, 1) and of
 * the table's steps. */
static void test_turn(void **state) {
  (void)state;
  wv_turn_table t;
  wv_turn_table_make(&t);
  double worst = 0;
  for (int k = 0; k < 1000000 + 4 * WV_TURN_STEPS; k++) {
    float u = k < 1000000 ? wv_u01(wv_mix64((uint64_t)k)) : (float)((k - 1000000) / 4) / WV_TURN_STEPS;
    if (k >= 1000000 && k % 4 == 1) u = nextafterf(u, 0.0f); /* just below a step */
    if (k >= 1000000 && k % 4 == 2) u = nextafterf(u, 1.0f);
    if (k >= 1000000 && k % 4 == 3) u = 0x1.fffffep-1f;
    if (u < 0) continue;
    float c, s;
    wv_turn(&t, u, &c, &s);
    worst = fmax(worst, fmax(fabs(c - cos(2 * M_PI * u)), fabs(s - sin(2 * M_PI * u))));
  }
  print_message("turn: largest error %.3g\n", worst);
  assert_true(worst < 2e-7);
}

static void render_text(const char *json, int threads, wv_image *cap, wv_image *rad) {
  wv_scene3d s;
  wv_world *w;
  wv_error err = {0};
  if (wv_scene3d_parse(json, "test scene", WOVEN_SOURCE_DIR "/scenes", &s, &err)) fail_msg("%s", err.msg);
  if (wv_world_load(&s, NULL, threads, &w, &err)) fail_msg("%s", err.msg);
  wv_scene3d_opts o = {.threads = threads};
  if (wv_scene3d_render(&s, w, &o, cap, rad, NULL, &err)) fail_msg("%s", err.msg);
  wv_world_free(w);
  wv_scene3d_free(&s);
}

/* A Lambertian sphere in a uniform white environment reflects its albedo (one
 * bounce of a convex object; the light comes only from the environment), with
 * bounces (environment samples and bounce rays weighted by MIS) and without
 * (direct light only: the environment samples alone). */
static void test_white_furnace(void **state) {
  (void)state;
  const char *fmt =
      "{\"image\": {\"width\": 24, \"height\": 24, \"spp\": 64},"
      "\"camera\": {\"position_mm\": [0, 0, 10], \"look_at_mm\": [0, 0, 0], \"vfov_deg\": 20},"
      "\"environment\": {\"uniform\": 1},"
      "\"materials\": {\"m\": {\"lambert\": [0.5, 0.25, 0.8]}},"
      "\"objects\": [{\"sphere\": {\"centre_mm\": [0, 0, 0], \"radius_mm\": 1.2}, \"material\": \"m\"}],"
      "\"render\": {\"max_bounces\": %d}, \"response\": {\"encoding\": \"linear\", \"clip\": 0}}";
  for (int bounces = 0; bounces <= 3; bounces += 3) {
    char json[1024];
    snprintf(json, sizeof json, fmt, bounces);
    wv_image cap, rad;
    render_text(json, 2, &cap, &rad);
    double sum[3] = {0}, n = 0;
    for (int y = 8; y < 16; y++) /* the sphere's inner pixels */
      for (int x = 8; x < 16; x++, n++)
        for (int c = 0; c < 3; c++) sum[c] += wv_image_px(&rad, x, y)[c];
    const double albedo[3] = {0.5, 0.25, 0.8};
    for (int c = 0; c < 3; c++) {
      print_message("%d bounces, channel %d: %.5f (albedo %.2f)\n", bounces, c, sum[c] / n, albedo[c]);
      assert_true(fabs(sum[c] / n - albedo[c]) < 0.01 * albedo[c]);
    }
    assert_true(fabsf(wv_image_px(&rad, 0, 0)[0] - 1.0f) < 1e-6f); /* background: the environment */
    wv_image_free(&cap), wv_image_free(&rad);
  }
}

/* The flat quad of scenes/quad-flat45.json (back: quad-flat45-back.json, the light
 * behind the cloth as in the flat45-back preset) through the mesh path against the
 * capture renderer's preset (a 96 x 96 centre window, the capture renderer at 256
 * spp): SSIM and mean absolute difference of the captures; opaque: the mesh
 * renderer's transmission off; keep (may be NULL): its capture. */
static void quad_against_rig(int back, int opaque, double *ssim, double *mae, wv_image *keep) {
  char *text;
  wv_error err = {0};
  assert_int_equal(wv_read_file(back ? WOVEN_SOURCE_DIR "/scenes/quad-flat45-back.json"
                                     : WOVEN_SOURCE_DIR "/scenes/quad-flat45.json",
                                &text, NULL, &err),
                   WV_OK);
  wv_scene3d s;
  assert_int_equal(wv_scene3d_parse(text, "quad-flat45.json", WOVEN_SOURCE_DIR "/scenes", &s, &err), WV_OK);
  free(text);
  wv_scene ref;
  tu_centre_window(&ref, back ? "flat45-back" : "flat45", 96, 96, 64);
  s.width = s.height = 96, s.vfov_deg = ref.vfov_deg, s.opaque = opaque;
  s.response.width = s.response.height = 96, s.response.falloff = 0, ref.falloff = 0;
  wv_world *w;
  assert_int_equal(wv_world_load(&s, NULL, 2, &w, &err), WV_OK);
  wv_scene3d_opts o = {.threads = 2};
  wv_image a, b;
  assert_int_equal(wv_scene3d_render(&s, w, &o, &a, NULL, NULL, &err), WV_OK);
  wv_params p;
  assert_int_equal(wv_params_read(WOVEN_SOURCE_DIR "/examples/twill.json", &p, &err), WV_OK);
  wv_render_opts ro = {.spp = 256, .threads = 2};
  assert_int_equal(wv_render(&ref, &p, &ro, &b, NULL, &err), WV_OK);
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_LUMA, ssim, &err), WV_OK);
  assert_int_equal(wv_mae(&a, &b, mae, &err), WV_OK);
  if (keep) *keep = a;
  else wv_image_free(&a);
  wv_image_free(&b);
  wv_world_free(w);
  wv_scene3d_free(&s);
}

/* The flat quad through the mesh path matches the capture renderer's flat45 scene
 * (a 96 x 96 centre window) within sampling noise. */
static void test_quad_matches_flat45(void **state) {
  (void)state;
  double ssim, mae;
  quad_against_rig(0, 0, &ssim, &mae, NULL);
  print_message("quad vs flat45: SSIM %.4f, MAE %.4f\n", ssim, mae);
  assert_true(ssim > 0.98);
  assert_true(mae < 0.01);
}

/* Light through the cloth: the quad lit from behind renders what the capture
 * renderer's flat45-back preset renders (the kernel's specular and diffuse
 * transmission, the shadow ray leaving the far side); with transmission off the
 * cloth is opaque and the image black. */
static void test_quad_matches_flat45_back(void **state) {
  (void)state;
  double ssim, mae;
  wv_image a;
  quad_against_rig(1, 0, &ssim, &mae, &a);
  double mean = wv_image_mean(&a);
  print_message("quad vs flat45-back: SSIM %.4f, MAE %.4f, mean %.4f\n", ssim, mae, mean);
  assert_true(ssim > 0.98);
  assert_true(mae < 0.01);
  assert_true(mean > 0.1);
  wv_image_free(&a);
  quad_against_rig(1, 1, &ssim, &mae, &a);
  assert_true(wv_image_mean(&a) == 0.0);
  wv_image_free(&a);
}

/* Straight through the open gaps: a sheet of black yarns (nothing scattered or
 * reflected) of yarn width 0.5 in front of a uniform white environment shows the
 * environment on the open area (1 - 0.5)^2 = 0.25 of it; opaque, nothing. */
static void test_gap_fraction(void **state) {
  (void)state;
  const char *params = file("black_gaps.json",
      "{\"version\": 2, \"pattern\": \"plain\", \"density\": {\"warp\": 60, \"weft\": 60},"
      " \"heightfield\": {\"warp\": 1, \"weft\": 1}, \"diffuse\": {\"warp\": [0, 0, 0], \"weft\": [0, 0, 0]},"
      " \"specular\": {\"warp\": [0, 0, 0], \"weft\": [0, 0, 0]}, \"transmission\": {\"warp\": [0, 0, 0], \"weft\": [0, 0, 0]},"
      " \"roughness\": {\"warp\": 0.3, \"weft\": 0.3}, \"twist_deg\": 0, \"inclination_deg\": 20,"
      " \"diffuse_blend\": 0.4, \"noise_level\": 0, \"thickness\": 2, \"yarn_width\": 0.5, \"seed\": 1}");
  char params_abs[2048], cwd[1024];
  assert_non_null(getcwd(cwd, sizeof cwd));
  snprintf(params_abs, sizeof params_abs, "%s%s%s", params[0] == '/' ? "" : cwd, params[0] == '/' ? "" : "/", params);
  for (int opaque = 0; opaque < 2; opaque++) {
    char json[4096];
    snprintf(json, sizeof json,
             "{\"image\": {\"width\": 48, \"height\": 48, \"spp\": 4},"
             "\"camera\": {\"position_mm\": [0, 0, 30], \"look_at_mm\": [0, 0, 0], \"vfov_deg\": 20},"
             "\"environment\": {\"uniform\": 1},"
             "\"materials\": {\"f\": {\"fabric\": \"%s\", \"uv_mm\": [1, 1]}},"
             "\"objects\": [{\"quad\": {\"centre_mm\": [0, 0, 0], \"u_axis\": [1, 0, 0], \"v_axis\": [0, 1, 0],"
             " \"size_mm\": [40, 40]}, \"material\": \"f\"}],"
             "\"render\": {\"max_bounces\": 2, \"transmission\": %s},"
             " \"response\": {\"encoding\": \"linear\", \"clip\": 0}}",
             params_abs, opaque ? "false" : "true");
    wv_image cap, rad;
    render_text(json, 2, &cap, &rad);
    double mean = wv_image_mean(&rad);
    print_message("black yarns, width 0.5, %s: mean radiance %.5f\n", opaque ? "opaque" : "transmitting", mean);
    if (opaque) assert_true(mean == 0.0);
    else assert_true(fabs(mean - 0.25) < 0.01);
    wv_image_free(&cap), wv_image_free(&rad);
  }
}

/* The sheet in a uniform white environment: the light through it (the image's
 * mean transmitting minus opaque) is the same estimated by the environment's
 * samples alone (direct light only: the samples behind the sheet shaded by the
 * transmission) and with bounces (those samples weighed by MIS against bounces
 * that may go through the sheet). */
static void test_sheet_furnace(void **state) {
  (void)state;
  double mean[2][2];
  for (int bounces = 0; bounces < 2; bounces++)
    for (int opaque = 0; opaque < 2; opaque++) {
      char json[1024];
      snprintf(json, sizeof json,
               "{\"image\": {\"width\": 32, \"height\": 32, \"spp\": 64},"
               "\"camera\": {\"position_mm\": [0, 0, 30], \"look_at_mm\": [0, 0, 0], \"vfov_deg\": 20},"
               "\"environment\": {\"uniform\": 1},"
               "\"materials\": {\"f\": {\"fabric\": \"../examples/twill.json\", \"uv_mm\": [1, 1]}},"
               "\"objects\": [{\"quad\": {\"centre_mm\": [0, 0, 0], \"u_axis\": [1, 0, 0], \"v_axis\": [0, 1, 0],"
               " \"size_mm\": [40, 40]}, \"material\": \"f\"}],"
               "\"render\": {\"max_bounces\": %d, \"transmission\": %s},"
               " \"response\": {\"encoding\": \"linear\", \"clip\": 0}}",
               bounces, opaque ? "false" : "true");
      wv_image cap, rad;
      render_text(json, 2, &cap, &rad);
      mean[bounces][opaque] = wv_image_mean(&rad);
      wv_image_free(&cap), wv_image_free(&rad);
    }
  double t0 = mean[0][0] - mean[0][1], t1 = mean[1][0] - mean[1][1];
  print_message("light through the sheet: %.5f direct only, %.5f with bounces\n", t0, t1);
  assert_true(t0 > 0.05);
  assert_true(fabs(t1 - t0) < 0.02 * t0);
}

/* Transmission off reproduces the reflection-only renderer: the bundled scene
 * (tiny, few samples) renders, with render.transmission false, the capture whose
 * mean the renderer gives without the cloth's transmission (0.456951; 0.456927 before
 * the pixel's sample grid held as many cells as samples, 0.456964 before the
 * environment's draws became uniform in solid angle within a pixel). */
static void test_opaque_is_reflection_only(void **state) {
  (void)state;
  char *text;
  wv_error err = {0};
  assert_int_equal(wv_read_file(WOVEN_SOURCE_DIR "/scenes/drape-studio.json", &text, NULL, &err), WV_OK);
  const char *full = "\"width\": 1024, \"height\": 768, \"spp\": 64";
  char *at = strstr(text, full);
  assert_non_null(at);
  memcpy(at, "\"width\":   48, \"height\":  36, \"spp\":  2", strlen(full));
  at = strstr(text, "\"render\": {");
  assert_non_null(at);
  char *off = malloc(strlen(text) + 32);
  assert_non_null(off);
  at += strlen("\"render\": {");
  sprintf(off, "%.*s\"transmission\": false, %s", (int)(at - text), text, at);
  wv_image a, b, ra, rb;
  render_text(off, 2, &a, &ra);
  render_text(text, 2, &b, &rb);
  double ma = wv_image_mean(&a), mb = wv_image_mean(&b);
  print_message("drape-studio 48 x 36, 2 spp: opaque %.6f, transmitting %.6f\n", ma, mb);
  assert_true(fabs(ma - 0.456951) < 2e-6);
  free(text), free(off);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&ra), wv_image_free(&rb);
}

/* A diffuse edit with a mask: where the mask is 1 the fabric turns darker; edit
 * maps of the wrong type or size are refused with the file's name. */
static void test_edits(void **state) {
  (void)state;
  wv_image map, mask;
  wv_error err = {0};
  assert_int_equal(wv_image_alloc(&map, 4, 4, 3, &err), WV_OK);
  assert_int_equal(wv_image_alloc(&mask, 4, 4, 3, &err), WV_OK);
  for (int y = 0; y < 4; y++)
    for (int x = 0; x < 4; x++)
      for (int c = 0; c < 3; c++) wv_image_px(&map, x, y)[c] = 0.1f, wv_image_px(&mask, x, y)[c] = x < 2;
  assert_int_equal(wv_image_write_exr(file("dark.exr", NULL), &map, &err), WV_OK);
  assert_int_equal(wv_image_write_png(file("left.png", NULL), &mask, 8, &err), WV_OK);
  wv_image_px(&map, 0, 0)[0] = 0.5f; /* not grey */
  assert_int_equal(wv_image_write_exr(file("colour.exr", NULL), &map, &err), WV_OK);
  wv_image_free(&mask);
  assert_int_equal(wv_image_alloc(&mask, 3, 4, 3, &err), WV_OK);
  assert_int_equal(wv_image_write_png(file("small.png", NULL), &mask, 8, &err), WV_OK);
  file("fake.png", "not an image");
  char json[4096];
  const char *fmt =
      "{\"image\": {\"width\": 32, \"height\": 32, \"spp\": 4},"
      "\"camera\": {\"position_mm\": [0, 0, 8], \"look_at_mm\": [0, 0, 0], \"vfov_deg\": 6},"
      "\"lights\": [{\"type\": \"directional\", \"direction\": [0.5, 0.3, 1], \"irradiance\": 3}],"
      "\"materials\": {\"f\": {\"fabric\": \"../examples/twill.json\", \"uv_mm\": [20, 20]}},"
      "\"objects\": [{\"quad\": {\"centre_mm\": [0, 0, 0], \"size_mm\": [1, 1]}, \"material\": \"f\"}],"
      "\"edits\": [{\"material\": \"f\", \"apply\": \"%s\", \"map\": \"%s/%s\", \"mask\": \"%s/%s\"}],"
      "\"render\": {\"max_bounces\": 0}}";
  char cwd[512];
  assert_non_null(getcwd(cwd, sizeof cwd));
  snprintf(json, sizeof json, fmt, "diffuse_replace", cwd, file("dark.exr", NULL), cwd, file("left.png", NULL));
  wv_image cap, rad;
  render_text(json, 2, &cap, &rad);
  double left = 0, right = 0;
  for (int y = 4; y < 28; y++) /* the mask's left half (u < 0.5) is the image's left half */
    for (int x = 2; x < 14; x++) left += wv_image_px(&rad, x, y)[1], right += wv_image_px(&rad, x + 16, y)[1];
  print_message("edited half %.4f, untouched half %.4f\n", left, right);
  assert_true(left < 0.7 * right);
  wv_image_free(&cap), wv_image_free(&rad);
  struct {
    const char *op, *map, *mask, *needle;
  } bad[] = {{"heightfield", "colour.exr", "left.png", "grey"},
             {"diffuse_multiply", "dark.exr", "small.png", "mask is 3 x 4"},
             {"diffuse_multiply", "fake.png", "left.png", "PNG or EXR"},
             {"roughness", "none.png", "left.png", "none.png"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(json, sizeof json, fmt, bad[i].op, cwd, file(bad[i].map, NULL), cwd, file(bad[i].mask, NULL));
    wv_scene3d s;
    wv_world *w = NULL;
    assert_int_equal(wv_scene3d_parse(json, "edit scene", WOVEN_SOURCE_DIR "/scenes", &s, &err), WV_OK);
    wv_status st = wv_world_load(&s, NULL, 1, &w, &err);
    if (!st || !strstr(err.msg, bad[i].needle)) fail_msg("%s: status %d, '%s'", bad[i].map, st, err.msg);
    assert_null(w);
    wv_scene3d_free(&s);
  }
  wv_image_free(&map), wv_image_free(&mask);
}

/* The cloth lands on the sphere and the floor without passing through them, the
 * same way every time. */
static void test_cloth(void **state) {
  (void)state;
  wv_cloth_opts o;
  wv_cloth_defaults(&o);
  o.res = 12, o.seconds = 0.8, o.steps_per_second = 300;
  wv_mesh a, b;
  wv_error err = {0};
  assert_int_equal(wv_cloth_drape(&o, &a, &err), WV_OK);
  assert_int_equal(wv_cloth_drape(&o, &b, &err), WV_OK);
  assert_int_equal(a.nv, 13 * 13);
  assert_int_equal(a.nt, 2 * 12 * 12);
  assert_memory_equal(a.pos, b.pos, sizeof(float) * 3 * (size_t)a.nv);
  float top = -1e9f;
  for (int v = 0; v < a.nv; v++) {
    const float *p = a.pos + 3 * v;
    float d = sqrtf(p[0] * p[0] + (p[1] - 80) * (p[1] - 80) + p[2] * p[2]);
    assert_true(d >= 80.0f - 0.5f); /* outside the sphere */
    assert_true(p[1] >= -1e-3f);    /* above the floor */
    top = p[1] > top ? p[1] : top;
  }
  assert_true(top > 150 && top < 175); /* it rests on the sphere's top (160 mm) */
  assert_int_equal(wv_mesh_validate(&a, "cloth", 1, &err), WV_OK);
  /* the OBJ it writes reads back */
  const char *p = file("cloth.obj", NULL);
  assert_int_equal(wv_mesh_write_obj(p, &a, "test", &err), WV_OK);
  wv_mesh c;
  assert_int_equal(wv_mesh_load(p, 0, 1, &c, &err), WV_OK);
  assert_int_equal(c.nt, a.nt);
  wv_mesh_free(&a), wv_mesh_free(&b), wv_mesh_free(&c);
}

static void expect_parse_error(const char *json, const char *needle) {
  wv_scene3d s;
  wv_error err = {0};
  wv_status st = wv_scene3d_parse(json, "bad.json", NULL, &s, &err);
  if (!st || !strstr(err.msg, needle) || !strstr(err.msg, "bad.json"))
    fail_msg("status %d, '%s' (wanted '%s')", st, err.msg, needle);
}

static void test_parse_errors(void **state) {
  (void)state;
  const char *head = "{\"image\": {\"width\": 8, \"height\": 8}, \"camera\": {\"position_mm\": [0, 0, 8], "
                     "\"look_at_mm\": [0, 0, 0], \"vfov_deg\": 40}, ";
  char buf[2048];
#define BAD(tail, needle) (snprintf(buf, sizeof buf, "%s%s", head, tail), expect_parse_error(buf, needle))
  expect_parse_error("{\"image\": ", "malformed JSON");
  expect_parse_error("[1, 2]", "top level");
  BAD("\"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": []}", "at least one object");
  BAD("\"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": [{\"sphere\": {\"centre_mm\": [0,0,0], "
      "\"radius_mm\": 1}, \"material\": \"x\"}]}", "no material named 'x'");
  BAD("\"materials\": {\"m\": {\"lambert\": 2}}, \"objects\": []}", "materials.m.lambert");
  BAD("\"materials\": {\"m\": {\"lambert\": 0.5, \"shiny\": 1}}, \"objects\": []}", "materials.m.shiny");
  BAD("\"lights\": [{\"type\": \"laser\"}], \"materials\": {}}", "laser");
  BAD("\"environment\": {\"builtin\": \"beach\"}, \"materials\": {}}", "beach");
  BAD("\"environment\": {\"builtin\": \"sky\", \"uniform\": 1}, \"materials\": {}}", "exactly one");
  BAD("\"render\": {\"max_bounces\": -1}, \"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": [{\"mesh\": "
      "\"a.obj\", \"material\": \"m\"}]}", "render.max_bounces");
  BAD("\"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": [{\"mesh\": \"a.obj\", \"quad\": {}, "
      "\"material\": \"m\"}]}", "exactly one");
  /* the capture scenes' response: the same keys (but the camera blur) and ranges */
#define OBJ "\"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": [{\"mesh\": \"a.obj\", \"material\": \"m\"}], "
  BAD(OBJ "\"response\": {\"exposure\": 2e6}}", "'response.exposure' = 2000000 must be in (0, 1000000]");
  BAD(OBJ "\"response\": {\"encoding\": \"gamma\", \"gamma\": 10}}", "'response.gamma' = 10 is outside (0.1, 10)");
  BAD(OBJ "\"response\": {\"encoding\": \"log\"}}", "'response.encoding' = 'log': expected srgb, gamma or linear");
  BAD(OBJ "\"response\": {\"psf_sigma_px\": 1}}", "unknown key 'response.psf_sigma_px'");
  BAD(OBJ "\"falloff\": {\"type\": \"gaussian\", \"sigma_px\": 0}}", "'falloff.sigma_px' = 0 must be in (0, 1e+09]");
#undef OBJ
  /* a scene that names a missing file parses (no file is read), then fails to load naming the file */
  wv_scene3d s;
  wv_world *w = NULL;
  wv_error err = {0};
  snprintf(buf, sizeof buf, "%s%s", head,
           "\"materials\": {\"m\": {\"lambert\": 0.5}}, \"objects\": [{\"mesh\": \"no/such.obj\", \"material\": \"m\"}]}");
  assert_int_equal(wv_scene3d_parse(buf, "ok.json", "/nonexistent", &s, &err), WV_OK);
  assert_int_equal(wv_world_load(&s, NULL, 1, &w, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "/nonexistent/no/such.obj"));
  assert_null(w);
  wv_scene3d_free(&s);
#undef BAD
}

/* The bundled scene (tiny, few samples): the same image on 1 and 2 threads, and
 * all three kinds of light plus an environment together stay finite. */
static void test_deterministic(void **state) {
  (void)state;
  char *text;
  wv_error err = {0};
  assert_int_equal(wv_read_file(WOVEN_SOURCE_DIR "/scenes/drape-studio.json", &text, NULL, &err), WV_OK);
  char *at = strstr(text, "\"width\": 1024, \"height\": 768, \"spp\": 64");
  assert_non_null(at);
  memcpy(at, "\"width\":   48, \"height\":  36, \"spp\":  2", strlen("\"width\": 1024, \"height\": 768, \"spp\": 64"));
  wv_image a, b, ra, rb;
  render_text(text, 1, &a, &ra);
  render_text(text, 2, &b, &rb);
  assert_memory_equal(ra.data, rb.data, sizeof(float) * 3 * 48 * 36);
  double mean = wv_image_mean(&a);
  assert_true(mean > 0.05 && mean < 0.95);
  free(text);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&ra), wv_image_free(&rb);
  const char *lights =
      "{\"image\": {\"width\": 16, \"height\": 16, \"spp\": 4},"
      "\"camera\": {\"position_mm\": [0, 40, 60], \"look_at_mm\": [0, 0, 0], \"vfov_deg\": 60},"
      "\"environment\": {\"builtin\": \"sky\", \"width\": 64},"
      "\"lights\": [{\"type\": \"point\", \"position_mm\": [0, 50, 0], \"intensity\": 2000},"
      " {\"type\": \"spot\", \"position_mm\": [30, 50, 0], \"look_at_mm\": [0, 0, 0], \"intensity\": [3000, 2000, 1000]},"
      " {\"type\": \"directional\", \"direction\": [1, 1, 0], \"irradiance\": 1},"
      " {\"type\": \"area\", \"position_mm\": [0, 30, 30], \"look_at_mm\": [0, 0, 0], \"size_mm\": [10, 10], \"radiance\": 20}],"
      "\"materials\": {\"f\": {\"fabric\": \"../examples/satin.json\", \"uv_mm\": [1, 1]}, \"g\": {\"lambert\": 0.4}},"
      "\"objects\": [{\"sphere\": {\"centre_mm\": [0, 10, 0], \"radius_mm\": 10, \"segments\": 24}, \"material\": \"f\"},"
      " {\"quad\": {\"centre_mm\": [0, 0, 0], \"u_axis\": [1, 0, 0], \"v_axis\": [0, 0, -1], \"size_mm\": [200, 200]},"
      " \"material\": \"g\"}]}";
  render_text(lights, 2, &a, &ra);
  for (size_t i = 0; i < 16 * 16 * 3; i++) assert_true(isfinite(ra.data[i]) && ra.data[i] >= 0);
  assert_true(wv_image_mean(&ra) > 0.01);
  wv_image_free(&a), wv_image_free(&ra);
}

/* Rays leaving the bundled scene's floor (planar; the cloth and the ball are not)
 * that the box test says meet nothing meet nothing in the tracer either: upward
 * rays from points just above the floor, grazing ones included; most are decided by
 * the box, and some of the others do meet the cloth or the ball. */
static void test_leaves_scene(void **state) {
  (void)state;
  wv_scene3d s;
  wv_world *w;
  wv_error err = {0};
  char *text;
  assert_int_equal(wv_read_file(WOVEN_SOURCE_DIR "/scenes/drape-studio.json", &text, NULL, &err), WV_OK);
  if (wv_scene3d_parse(text, "drape-studio", WOVEN_SOURCE_DIR "/scenes", &s, &err)) fail_msg("%s", err.msg);
  free(text);
  if (wv_world_load(&s, NULL, 1, &w, &err)) fail_msg("%s", err.msg);
  assert_int_equal(w->nobjects, 3);
  assert_true(!w->planar[0] && !w->planar[1] && w->planar[2]); /* cloth, ball, floor */
  enum { N = 200000 };
  int culled = 0, hits = 0, wrong = 0;
  for (int j = 0; j < N; j++) {
    float o[3], d[3];
    double u = wv_u01(wv_hash4(9, (uint64_t)j, 0, 1)), v = wv_u01(wv_hash4(9, (uint64_t)j, 1, 1));
    double a = 2 * M_PI * wv_u01(wv_hash4(9, (uint64_t)j, 2, 1)), z = j % 10 ? wv_u01(wv_hash4(9, (uint64_t)j, 3, 1)) : 1e-4 * u;
    o[0] = (float)(500 * (2 * u - 1)), o[1] = 0.05f, o[2] = (float)(500 * (2 * v - 1));
    d[0] = (float)(sqrt(1 - z * z) * cos(a)), d[1] = (float)z, d[2] = (float)(sqrt(1 - z * z) * sin(a));
    wv_trace_hit hit;
    int got;
    wv_tracer_intersect_n(w->tracer, (const float(*)[3])&o, (const float(*)[3])&d, 1, &hit, &got);
    hits += got;
    if (wv_world_leaves_scene(w, 2, o, d)) culled++, wrong += got;
  }
  print_message("%d of %d rays from the floor decided by the box, %d meet something, %d wrongly\n", culled, N, hits, wrong);
  assert_int_equal(wrong, 0);
  assert_true(culled > N / 2 && hits > N / 20);
  wv_world_free(w);
  wv_scene3d_free(&s);
}

/* Rays traced together (streams of any length, over the 64-ray batches and under
 * the length at which a stream is traced ray by ray) find what each ray alone finds. */
static void test_tracer_streams(void **state) {
  (void)state;
  wv_error err = {0};
  wv_mesh mesh[2];
  const double c[3] = {0, 1, 0}, o[3] = {0, 0, 0}, eu[3] = {1, 0, 0}, ev[3] = {0, 0, -1};
  assert_int_equal(wv_mesh_sphere(c, 1.0, 12, 24, &mesh[0], &err), WV_OK);
  assert_int_equal(wv_mesh_quad(o, eu, ev, 8, 8, 1, &mesh[1], &err), WV_OK);
  const wv_mesh *list[2] = {&mesh[0], &mesh[1]};
  wv_tracer *t;
  assert_int_equal(wv_tracer_create(list, 2, 1, 0, &t, &err), WV_OK);
  enum { N = 150 };
  float org[N][3], dir[N][3], tmax[N];
  for (int j = 0; j < N; j++) { /* from around the sphere, most toward it */
    uint64_t h = wv_hash4(7, (uint64_t)j, 0, 1);
    float len = 0;
    for (int i = 0; i < 3; i++) {
      org[j][i] = 3.0f * (wv_u01(wv_hash4(7, (uint64_t)j, 1 + (uint64_t)i, 1)) - 0.5f) + (i == 1 ? 2.0f : 0.0f);
      dir[j][i] = (float)c[i] - org[j][i] + 1.5f * (wv_u01(h >> (8 * i)) - 0.5f);
      len += dir[j][i] * dir[j][i];
    }
    for (int i = 0; i < 3; i++) dir[j][i] /= (j % 4 ? 1.0f : -1.0f) * sqrtf(len); /* a quarter away from it */
    tmax[j] = j % 3 ? INFINITY : 1.5f;
  }
  wv_trace_hit all[N], one;
  int got_all[N], got_one, occ[N], hits = 0, blocked = 0;
  wv_tracer_intersect_n(t, (const float(*)[3])org, (const float(*)[3])dir, N, all, got_all);
  wv_tracer_occluded_n(t, (const float(*)[3])org, (const float(*)[3])dir, tmax, N, occ);
  for (int j = 0; j < N; j++) {
    wv_tracer_intersect_n(t, (const float(*)[3])&org[j], (const float(*)[3])&dir[j], 1, &one, &got_one);
    assert_int_equal(got_all[j], got_one);
    if (got_one) {
      assert_true(all[j].t == one.t && all[j].b1 == one.b1 && all[j].b2 == one.b2);
      assert_int_equal(all[j].geom, one.geom);
      assert_int_equal(all[j].prim, one.prim);
      hits++;
    }
    assert_int_equal(occ[j], wv_tracer_occluded(t, org[j], dir[j], 0.0f, tmax[j]));
    blocked += occ[j];
  }
  fprintf(stderr, "%d of %d rays hit, %d blocked\n", hits, N, blocked);
  assert_true(hits > N / 4 && hits < N); /* both hits and misses */
  assert_true(blocked > 0 && blocked < hits);
  /* rays from one point: the coherent stream agrees */
  wv_trace_hit from[N];
  int got_from[N];
  float same[N][3];
  for (int j = 0; j < N; j++) memcpy(same[j], org[0], sizeof same[j]);
  wv_tracer_intersect_from(t, org[0], (const float(*)[3])dir, N, from, got_from);
  wv_tracer_intersect_n(t, (const float(*)[3])same, (const float(*)[3])dir, N, all, got_all);
  for (int j = 0; j < N; j++) {
    assert_int_equal(got_from[j], got_all[j]);
    if (got_from[j]) assert_true(from[j].t == all[j].t && from[j].prim == all[j].prim && from[j].geom == all[j].geom);
  }
  wv_tracer_free(t);
  wv_mesh_free(&mesh[0]), wv_mesh_free(&mesh[1]);
}

int main(void) {
  const char *d = tu_tmpdir("scene3d");
  if (!d) return 1;
  snprintf(dir, sizeof dir, "%s", d);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mesh_formats),  cmocka_unit_test(test_mesh_errors), cmocka_unit_test(test_mesh_check),
      cmocka_unit_test(test_material_refused),
      cmocka_unit_test(test_env_sampling),  cmocka_unit_test(test_env_sample_batch),
      cmocka_unit_test(test_env_pixels),    cmocka_unit_test(test_turn),
      cmocka_unit_test(test_white_furnace),
      cmocka_unit_test(test_quad_matches_flat45), cmocka_unit_test(test_quad_matches_flat45_back),
      cmocka_unit_test(test_gap_fraction),  cmocka_unit_test(test_sheet_furnace),
      cmocka_unit_test(test_opaque_is_reflection_only),
      cmocka_unit_test(test_edits),
      cmocka_unit_test(test_cloth),         cmocka_unit_test(test_parse_errors),
      cmocka_unit_test(test_deterministic), cmocka_unit_test(test_tracer_streams),
      cmocka_unit_test(test_leaves_scene),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
