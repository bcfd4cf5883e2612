/* glTF export and viewer page: the standard model's closed forms, the bake's
 * least-squares fit (recovering a Lambertian fabric), the .glb's structure read
 * back, the meshes, and bad input (nothing written). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "export/std_model.h"
#include "woven/export.h"
#include "woven/maps.h"
#include "woven/io.h"
#include "woven/view.h"

#define PI_D 3.14159265358979323846

static wv_std_lut *lut(void) {
  static wv_std_lut l;
  static int done;
  if (!done) wv_std_lut_init(&l), done = 1;
  return &l;
}

/* The GGX albedo table: in (0, 1], falling with roughness at normal view. */
static void test_std_lut(void **state) {
  (void)state;
  const wv_std_lut *l = lut();
  for (int i = 0; i < WV_STD_LUT; i++)
    for (int j = 0; j < WV_STD_LUT; j++) assert_true(l->ess[i][j] > 0.2f && l->ess[i][j] <= 1.001f);
  assert_true(wv_std_lut_ess(l, 0.05f, 1.0f) > 0.98f); /* a smooth mirror loses nothing */
  assert_true(wv_std_lut_ess(l, 1.0f, 1.0f) < wv_std_lut_ess(l, 0.5f, 1.0f));
}

/* Closed forms at l = v = n: D V = 1 / (4 pi alpha^2) for the isotropic lobe, and
 * the anisotropic lobe with strength 0 equals it in any direction. */
static void test_std_closed_forms(void **state) {
  (void)state;
  wv_std_material m = {{0.5f, 0.5f, 0.5f}, 0.0f, 0.5f, 0.0f, {1, 0}, {0, 0, 0}, 0.5f, {0, 0, 1}, 0.0f};
  float z[3] = {0, 0, 1};
  wv_std_terms t;
  wv_std_spec_terms(&m, lut(), z, z, &t);
  float alpha = 0.25f;
  assert_float_equal(t.vd, 1.0f / (4.0f * (float)PI_D * alpha * alpha), 1e-3f * t.vd);
  assert_float_equal(t.nl, 1.0f, 1e-6f);
  /* a rotated axis changes nothing while the strength is 0 */
  float l[3] = {0.3f, -0.4f, 0.8660254f}, v[3] = {-0.5f, 0.1f, 0.8602325f};
  wv_std_terms a, b;
  wv_std_spec_terms(&m, lut(), l, v, &a);
  m.aniso_dir[0] = 0.6f, m.aniso_dir[1] = 0.8f;
  wv_std_spec_terms(&m, lut(), l, v, &b);
  assert_float_equal(a.vd, b.vd, 1e-6f * a.vd);
  /* with strength 1 the lobe stretches along the axis: a half vector tilted
   * along it keeps more of the peak than one tilted across it */
  m.aniso = 1.0f, m.aniso_dir[0] = 1, m.aniso_dir[1] = 0;
  float vx[3] = {-0.34202f, 0, 0.93969f};
  float la[3] = {0.5f, 0, 0.8660254f}, ly[3] = {0, 0.5f, 0.8660254f};
  wv_std_terms tx, ty;
  wv_std_spec_terms(&m, lut(), la, z, &tx);
  wv_std_spec_terms(&m, lut(), ly, z, &ty);
  assert_true(tx.vd > 2.0f * ty.vd);
  /* the model is linear in the colours as wv_std_linear says */
  m.sheen[0] = 0.3f, m.sheen_roughness = 0.6f, m.metallic = 0.0f;
  float o1[3], o2[3];
  wv_std_eval(&m, lut(), la, vx, o1);
  m.base[1] = 0.7f;
  wv_std_eval(&m, lut(), la, vx, o2);
  assert_float_equal(o1[0], o2[0], 1e-7f); /* channels do not mix ... */
  assert_true(o2[1] > o1[1]);               /* ... and more base colour reflects more */
  for (int c = 0; c < 3; c++) assert_true(isfinite(o1[c]) && o1[c] >= 0);
}

/* Energy: the model's albedo under a white furnace (integral of out over the
 * hemisphere of light directions) stays below 1 for white colours. */
static void test_std_energy(void **state) {
  (void)state;
  wv_std_material m = {{1, 1, 1}, 0.0f, 0.6f, 0.5f, {1, 0}, {0.5f, 0.5f, 0.5f}, 0.5f, {0, 0, 1}, 0.0f};
  float v[3] = {0.5f, 0.0f, 0.8660254f};
  double sum = 0;
  const int n = 128;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      double mu = (i + 0.5) / n, ph = 2 * PI_D * (j + 0.5) / n, s = sqrt(1 - mu * mu);
      float l[3] = {(float)(s * cos(ph)), (float)(s * sin(ph)), (float)mu}, o[3];
      wv_std_eval(&m, lut(), l, v, o);
      sum += o[1];
    }
  double albedo = sum * 2 * PI_D / ((double)n * n);
  assert_true(albedo > 0.5 && albedo < 1.05);
}

static void params_of(const char *pattern, wv_params *p) {
  wv_error err = {0};
  assert_int_equal(wv_params_default(pattern, p, &err), WV_OK);
}

/* A fabric with no specular lobe and diffuse blend 0 is Lambertian about the
 * macro normal: the fit finds its colour (within the standard model's Fresnel
 * terms) and a small residual. */
static void test_bake_lambertian(void **state) {
  (void)state;
  wv_params p;
  params_of("twill", &p);
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) p.specular[y][c] = 0.0, p.diffuse[y][c] = c == 0 ? 0.6 : 0.2;
  p.diffuse_blend = 0.0;
  wv_bake_opts o;
  wv_bake_opts_default(&o);
  o.texture_size = 8, o.samples = 1, o.directions = 24;
  wv_bake b;
  wv_error err = {0};
  assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_OK);
  assert_true(b.relative < 0.08);
  assert_float_equal(b.relative, b.rms / b.target_rms, 1e-9);
  wv_scene srgb;
  memset(&srgb, 0, sizeof srgb);
  srgb.encoding = WV_ENC_SRGB;
  for (int i = 0; i < 8 * 8; i++) {
    const float *bc = b.base_color.data + 3 * i, *mr = b.metal_rough.data + 3 * i;
    assert_float_equal(wv_decode(&srgb, bc[0]), 0.6f, 0.08f);
    assert_float_equal(wv_decode(&srgb, bc[1]), 0.2f, 0.04f);
    assert_true(mr[2] < 0.2f); /* hardly metallic */
  }
  wv_bake_free(&b);
}

/* Every pattern's prior mean bakes with a residual well under the signal. */
static void test_bake_residual(void **state) {
  (void)state;
  static const char *pats[] = {"plain", "twill", "satin"};
  for (int k = 0; k < 3; k++) {
    wv_params p;
    params_of(pats[k], &p);
    wv_bake_opts o;
    wv_bake_opts_default(&o);
    o.texture_size = 12, o.samples = 2, o.directions = 32;
    wv_bake b;
    wv_error err = {0};
    assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_OK);
    assert_true(b.target_rms > 0.01);
    assert_true(b.relative > 0.0 && b.relative < 0.35);
    /* stored values are on the 8-bit grid, normals unit after decoding */
    for (int i = 0; i < 12 * 12 * 3; i++) {
      float v = b.normal.data[i] * 255.0f;
      assert_float_equal(v, roundf(v), 1e-3f);
    }
    wv_bake_free(&b);
  }
}

static uint32_t le32(const unsigned char *d) { return d[0] | d[1] << 8 | d[2] << 16 | (uint32_t)d[3] << 24; }

/* The .glb read back: header, chunks, the JSON's references inside the binary
 * chunk, the tiling scale, the textures decoding to the bake's values. */
static void test_glb_structure(void **state) {
  (void)state;
  wv_params p;
  params_of("satin", &p);
  wv_bake_opts o;
  wv_bake_opts_default(&o);
  o.texture_size = 16, o.samples = 1, o.directions = 16;
  wv_bake b;
  wv_tri_mesh m;
  wv_error err = {0};
  assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_OK);
  assert_int_equal(wv_tri_mesh_quad(50.0, &m, &err), WV_OK);
  const char *dir = tu_tmpdir("export_glb");
  char path[512];
  snprintf(path, sizeof path, "%s/quad.glb", dir);
  assert_int_equal(wv_gltf_write(path, &m, &b, &p, &err), WV_OK);
  char *data;
  size_t len;
  assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
  const unsigned char *d = (const unsigned char *)data;
  assert_int_equal(le32(d), 0x46546C67u);
  assert_int_equal(le32(d + 4), 2);
  assert_int_equal(le32(d + 8), len);
  uint32_t jlen = le32(d + 12);
  assert_int_equal(le32(d + 16), 0x4E4F534Au);
  assert_int_equal(jlen % 4, 0);
  uint32_t blen = le32(d + 20 + jlen);
  assert_int_equal(le32(d + 24 + jlen), 0x004E4942u);
  assert_int_equal(20 + jlen + 8 + blen, len);
  const unsigned char *bin = d + 28 + jlen;
  json_error_t je;
  json_t *root = json_loadb(data + 20, jlen, 0, &je);
  assert_non_null(root);
  assert_string_equal(json_string_value(json_object_get(json_object_get(root, "asset"), "version")), "2.0");
  json_t *views = json_object_get(root, "bufferViews");
  size_t i;
  json_t *v;
  json_array_foreach(views, i, v) {
    json_int_t off = json_integer_value(json_object_get(v, "byteOffset")), n = json_integer_value(json_object_get(v, "byteLength"));
    assert_true(off % 4 == 0 && off + n <= (json_int_t)blen);
  }
  json_t *mat = json_array_get(json_object_get(root, "materials"), 0);
  json_t *scale = json_object_get(json_object_get(json_object_get(json_object_get(json_object_get(mat, "pbrMetallicRoughness"),
                                  "baseColorTexture"), "extensions"), "KHR_texture_transform"), "scale");
  assert_float_equal(json_real_value(json_array_get(scale, 0)), 50.0 / b.tile_mm[0], 1e-4);
  assert_float_equal(json_real_value(json_array_get(scale, 1)), 50.0 / b.tile_mm[1], 1e-4);
  json_t *fit = json_object_get(json_object_get(json_object_get(mat, "extras"), "woven"), "fit");
  assert_float_equal(json_real_value(json_object_get(fit, "relative")), b.relative, 1e-6);
  assert_non_null(json_object_get(json_object_get(mat, "extensions"), "KHR_materials_anisotropy"));
  assert_non_null(json_object_get(json_object_get(mat, "extensions"), "KHR_materials_sheen"));
  /* the vertex positions are the mesh's; the textures the bake's */
  json_t *acc = json_array_get(json_object_get(root, "accessors"), 0);
  json_t *pv = json_array_get(views, (size_t)json_integer_value(json_object_get(acc, "bufferView")));
  assert_memory_equal(bin + json_integer_value(json_object_get(pv, "byteOffset")), m.positions, sizeof(float) * 12);
  const wv_image *imgs[5] = {&b.base_color, &b.normal, &b.metal_rough, &b.anisotropy, &b.sheen};
  json_t *images = json_object_get(root, "images");
  for (int k = 0; k < 5; k++) {
    json_t *iv = json_array_get(views, (size_t)json_integer_value(json_object_get(json_array_get(images, (size_t)k), "bufferView")));
    char ip[512];
    snprintf(ip, sizeof ip, "%s/tex%d.png", dir, k);
    assert_int_equal(wv_write_file_atomic(ip, bin + json_integer_value(json_object_get(iv, "byteOffset")),
                                          (size_t)json_integer_value(json_object_get(iv, "byteLength")), &err), WV_OK);
    wv_image back;
    wv_image_info info;
    assert_int_equal(wv_image_read(ip, &back, &info, &err), WV_OK);
    assert_int_equal(info.channels_in_file, imgs[k]->c);
    for (int y = 0; y < 16; y++)
      for (int x = 0; x < 16; x++)
        for (int c = 0; c < 3; c++)
          assert_float_equal(wv_image_px(&back, x, y)[c], wv_image_px(imgs[k], x, y)[c], 1e-6f);
    wv_image_free(&back);
  }
  json_decref(root);
  free(data);
  wv_bake_free(&b);
  wv_tri_mesh_free(&m);
}

/* The light through the cloth: the bake's diffuse transmission (factor x colour) has
 * the mean of woven's transmission map, its open-area texture the open area (1 - w)^2;
 * the glTF carries KHR_materials_diffuse_transmission, and KHR_materials_transmission
 * only where the cloth has open gaps. */
static void test_bake_transmission(void **state) {
  (void)state;
  for (int gaps = 0; gaps < 2; gaps++) {
    wv_params p;
    params_of("twill", &p);
    p.yarn_width = gaps ? 0.75 : 1.0;
    for (int y = 0; y < 2; y++) p.transmission[y][0] = 0.4, p.transmission[y][1] = 0.2, p.transmission[y][2] = 0.1;
    wv_bake_opts o;
    wv_bake_opts_default(&o);
    o.texture_size = 16, o.samples = 2, o.directions = 16;
    wv_bake b;
    wv_error err = {0};
    assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_OK);
    assert_int_equal(b.has_open, gaps);
    wv_maps mp;
    assert_int_equal(wv_maps_generate(&p, 64, &mp, &err), WV_OK);
    double want[3] = {0}, got[3] = {0}, open = 0;
    for (int i = 0; i < 64 * 64; i++)
      for (int c = 0; c < 3; c++) want[c] += mp.transmission.data[3 * i + c] / (64.0 * 64.0);
    wv_scene srgb;
    memset(&srgb, 0, sizeof srgb);
    srgb.encoding = WV_ENC_SRGB;
    for (int i = 0; i < 16 * 16; i++) {
      const float *dt = b.diffuse_transmission.data + 4 * i, *op = b.open.data + 3 * i;
      for (int c = 0; c < 3; c++) got[c] += dt[3] * wv_decode(&srgb, dt[c]) / 256.0;
      open += op[0] / 256.0;
      if (op[0] == 1.0f) assert_true(dt[3] == 0.0f); /* nothing diffuse where no yarn is */
    }
    for (int c = 0; c < 3; c++) assert_float_equal(got[c], want[c], 0.04 * want[c] + 2e-3);
    assert_float_equal(open, gaps ? 0.25 * 0.25 : 0.0, 0.01);
    wv_maps_free(&mp);
    wv_tri_mesh m;
    assert_int_equal(wv_tri_mesh_quad(20.0, &m, &err), WV_OK);
    char path[512];
    snprintf(path, sizeof path, "%s/t%d.glb", tu_tmpdir("export_trans"), gaps);
    assert_int_equal(wv_gltf_write(path, &m, &b, &p, &err), WV_OK);
    char *data;
    size_t len;
    assert_int_equal(wv_read_file(path, &data, &len, &err), WV_OK);
    json_error_t je;
    json_t *root = json_loadb(data + 20, le32((const unsigned char *)data + 12), 0, &je);
    assert_non_null(root);
    json_t *ext = json_object_get(json_array_get(json_object_get(root, "materials"), 0), "extensions");
    json_t *dtx = json_object_get(ext, "KHR_materials_diffuse_transmission");
    assert_non_null(dtx);
    assert_int_equal(json_integer_value(json_object_get(json_object_get(dtx, "diffuseTransmissionTexture"), "index")), 5);
    assert_int_equal(json_integer_value(json_object_get(json_object_get(dtx, "diffuseTransmissionColorTexture"), "index")), 5);
    json_t *tx = json_object_get(ext, "KHR_materials_transmission");
    assert_true((tx != NULL) == gaps);
    if (tx) assert_int_equal(json_integer_value(json_object_get(json_object_get(tx, "transmissionTexture"), "index")), 6);
    assert_int_equal(json_array_size(json_object_get(root, "images")), gaps ? 7 : 6);
    assert_int_equal(json_array_size(json_object_get(root, "extensionsUsed")), gaps ? 5 : 4);
    json_decref(root);
    free(data);
    wv_tri_mesh_free(&m);
    wv_bake_free(&b);
  }
}

/* Meshes: unit normals, tangents orthogonal with a sign, and the drape's cap
 * keeps arc length along the radii; tangents from UVs match the quad's. */
static void test_meshes(void **state) {
  (void)state;
  wv_tri_mesh q, dr;
  wv_error err = {0};
  assert_int_equal(wv_tri_mesh_quad(10.0, &q, &err), WV_OK);
  assert_int_equal(wv_tri_mesh_drape(600.0, 150.0, 40, &dr, &err), WV_OK);
  assert_int_equal(wv_tri_mesh_validate(&q, &err), WV_OK);
  assert_int_equal(wv_tri_mesh_validate(&dr, &err), WV_OK);
  for (int v = 0; v < dr.vertex_count; v++) {
    const float *n = dr.normals + 3 * v, *t = dr.tangents + 4 * v;
    assert_float_equal(n[0] * t[0] + n[1] * t[1] + n[2] * t[2], 0.0f, 1e-4f);
  }
  /* vertex (i, 20) on the centre row: distance over the cap from the top = |u - 0.5| 600 mm */
  for (int i = 14; i <= 20; i++) {
    const float *pt = dr.positions + 3 * (20 * 41 + i);
    double ang = atan2(sqrt((double)pt[0] * pt[0] + (double)pt[2] * pt[2]), pt[1]), arc = 150.0 * ang, rho = fabs(i / 40.0 - 0.5) * 600.0;
    if (rho < 150.0 * 50.0 * PI_D / 180.0) assert_float_equal(arc, rho, 0.05);
  }
  float *own = q.tangents;
  q.tangents = NULL;
  assert_int_equal(wv_tri_mesh_tangents(&q, &err), WV_OK);
  for (int v = 0; v < 4; v++) assert_memory_equal(q.tangents + 4 * v, own + 4 * v, sizeof(float) * 4);
  free(own);
  q.indices[0] = 99; /* out of range */
  assert_int_equal(wv_tri_mesh_validate(&q, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "index"));
  wv_tri_mesh_free(&q), wv_tri_mesh_free(&dr);
  assert_int_equal(wv_tri_mesh_drape(600, -1, 10, &dr, &err), WV_ERR_INVALID);
}

static int exists(const char *p) {
  struct stat sb;
  return stat(p, &sb) == 0;
}

/* Bad input: clear errors, nothing written. */
static void test_bad_input(void **state) {
  (void)state;
  wv_error err = {0};
  const char *dir = tu_tmpdir("export_bad");
  wv_source src;
  assert_int_equal(wv_source_load(dir, &src, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "no finished fit"));
  wv_params p;
  params_of("plain", &p);
  wv_bake_opts o;
  wv_bake_opts_default(&o);
  o.texture_size = 4;
  wv_bake b;
  assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_ERR_INVALID);
  o.texture_size = 8, o.samples = 1, o.directions = 8;
  snprintf(p.pattern, sizeof p.pattern, "houndstooth");
  assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "houndstooth"));
  params_of("plain", &p);
  /* a field of 0 takes its default: texture_size 64 */
  wv_bake_opts z = {.samples = 1, .directions = 8};
  assert_int_equal(wv_bake_fabric(&p, &z, &b, &err), WV_OK);
  assert_int_equal(b.base_color.w, 64);
  assert_int_equal(b.directions, 8);
  wv_bake_free(&b);
  assert_int_equal(wv_bake_fabric(&p, &o, &b, &err), WV_OK);
  wv_tri_mesh m;
  assert_int_equal(wv_tri_mesh_quad(10, &m, &err), WV_OK);
  char path[512];
  snprintf(path, sizeof path, "%s/missing/x.glb", dir);
  assert_int_equal(wv_gltf_write(path, &m, &b, &p, &err), WV_ERR_IO);
  assert_false(exists(path));
  m.uv_mm = 0; /* invalid mesh: refused before anything is written */
  snprintf(path, sizeof path, "%s/x.glb", dir);
  assert_int_equal(wv_gltf_write(path, &m, &b, &p, &err), WV_ERR_INVALID);
  assert_false(exists(path));
  /* the viewer refuses parameters out of range, writing nothing */
  wv_scene s;
  assert_int_equal(wv_scene_preset("flat45", &s, &err), WV_OK);
  p.roughness[0] = 3.0;
  wv_view_opts vo = {.params = &p, .scene = &s};
  snprintf(path, sizeof path, "%s/v.html", dir);
  assert_int_equal(wv_view_write(path, &vo, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "roughness"));
  assert_false(exists(path));
  wv_bake_free(&b);
  wv_tri_mesh_free(&m);
}

/* The viewer page: its data block parses, carries the parameters, the exact
 * seed, every built-in weave's segment table and the scene; no script closes early. */
static void test_view_page(void **state) {
  (void)state;
  wv_params p;
  wv_scene s;
  wv_error err = {0};
  params_of("twill90", &p);
  p.seed = 0x7fffffff12345678LL;
  assert_int_equal(wv_scene_preset("cylinder", &s, &err), WV_OK);
  const char *dir = tu_tmpdir("view_page");
  char path[512];
  snprintf(path, sizeof path, "%s/v.html", dir);
  wv_view_opts vo = {.params = &p, .scene = &s, .title = "t"};
  assert_int_equal(wv_view_write(path, &vo, &err), WV_OK);
  char *html;
  assert_int_equal(wv_read_file(path, &html, NULL, &err), WV_OK);
  const char *tag = "<script id=\"woven-data\" type=\"application/json\">";
  char *a = strstr(html, tag);
  assert_non_null(a);
  a += strlen(tag);
  char *e = strstr(a, "</script>");
  assert_non_null(e);
  json_error_t je;
  json_t *d = json_loadb(a, (size_t)(e - a), 0, &je);
  assert_non_null(d);
  assert_string_equal(json_string_value(json_object_get(json_object_get(d, "params"), "pattern")), "twill90");
  json_t *sw = json_object_get(d, "seed_words");
  assert_int_equal(json_integer_value(json_array_get(sw, 0)), 0x7fffffff);
  assert_int_equal(json_integer_value(json_array_get(sw, 1)), 0x12345678);
  assert_string_equal(json_string_value(json_object_get(json_object_get(json_object_get(d, "scene"), "sample"), "shape")),
                      "cylinder");
  static const char *names[] = {"plain", "twill", "satin", "twill90", "satin90"};
  for (int k = 0; k < 5; k++) {
    wv_weave w;
    assert_int_equal(wv_weave_builtin(names[k], &w, &err), WV_OK);
    json_t *jw = json_object_get(json_object_get(d, "weaves"), names[k]);
    assert_int_equal(json_integer_value(json_object_get(jw, "rows")), w.rows);
    json_t *cells = json_object_get(jw, "cells");
    for (int r = 0; r < w.rows; r++)
      for (int c = 0; c < w.cols; c++) {
        json_int_t v = json_integer_value(json_array_get(cells, (size_t)(r * w.cols + c)));
        assert_int_equal(v & 0xff, w.cell[r][c].type);
        assert_int_equal(v >> 8 & 0xff, w.cell[r][c].len);
        assert_int_equal(v >> 16, w.cell[r][c].index);
      }
  }
  assert_int_equal(json_array_size(json_object_get(d, "ranges")), WV_P_COUNT + 3);
  json_decref(d);
  /* nine inlined scripts plus the data, each closed once */
  int n = 0;
  for (char *q = html; (q = strstr(q, "</script>")); q++) n++;
  assert_int_equal(n, 10);
  assert_null(strstr(html, "<!-- woven:inline -->"));
  free(html);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_std_lut),        cmocka_unit_test(test_std_closed_forms),
      cmocka_unit_test(test_std_energy),     cmocka_unit_test(test_bake_lambertian),
      cmocka_unit_test(test_bake_residual),  cmocka_unit_test(test_glb_structure),
      cmocka_unit_test(test_meshes),         cmocka_unit_test(test_bad_input),
      cmocka_unit_test(test_view_page),
      cmocka_unit_test(test_bake_transmission),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
