/* The glTF 2.0 binary (.glb) writer: the JSON chunk is built with jansson, the
 * binary chunk holds the mesh's vertex data and the baked textures as PNG. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/buf.h"
#include "woven/export.h"
#include "woven/io.h"

/* glTF constants (the specification's enum values). */
#define GL_FLOAT 5126
#define GL_UNSIGNED_INT 5125
#define GL_ARRAY_BUFFER 34962
#define GL_ELEMENT_ARRAY_BUFFER 34963
#define GL_LINEAR 9729
#define GL_LINEAR_MIPMAP_LINEAR 9987
#define GL_REPEAT 10497

/* Appends n bytes, then zeros up to a multiple of 4: every view starts aligned. */
static void put(wv_buf *b, const void *src, size_t n) {
  static const unsigned char zeros[4] = {0};
  wv_buf_put(b, src, n);
  wv_buf_put(b, zeros, (4 - b->len % 4) % 4);
}

/* glTF is little-endian; the vertex arrays are copied as the (x86, ARM) host stores them. */
static void put_le32(unsigned char *d, uint32_t v) {
  d[0] = (unsigned char)v, d[1] = (unsigned char)(v >> 8), d[2] = (unsigned char)(v >> 16), d[3] = (unsigned char)(v >> 24);
}

/* Appends data as a new bufferView; returns its index. */
static int add_view(json_t *views, wv_buf *bin, const void *data, size_t n, int target) {
  size_t off = bin->len;
  put(bin, data, n);
  json_t *v = json_pack("{s:i,s:I,s:I}", "buffer", 0, "byteOffset", (json_int_t)off, "byteLength", (json_int_t)n);
  if (target) json_object_set_new(v, "target", json_integer(target));
  json_array_append_new(views, v);
  return (int)json_array_size(views) - 1;
}

static int add_accessor(json_t *accessors, int view, int ctype, int count, const char *type) {
  json_array_append_new(accessors, json_pack("{s:i,s:i,s:i,s:s}", "bufferView", view, "componentType", ctype, "count",
                                             count, "type", type));
  return (int)json_array_size(accessors) - 1;
}

/* A textureInfo tiled by KHR_texture_transform. */
static json_t *tex_info(int index, double sx, double sy) {
  return json_pack("{s:i,s:{s:{s:[f,f]}}}", "index", index, "extensions", "KHR_texture_transform", "scale", sx, sy);
}

wv_status wv_gltf_write(const char *path, const wv_tri_mesh *mesh, const wv_bake *b, const wv_params *p,
                        wv_error *err) {
  wv_status st = wv_tri_mesh_validate(mesh, err);
  if (st) return st;
  wv_tri_mesh m = *mesh;
  float *own_tangents = NULL;
  if (!m.tangents) { /* derived here; the caller's mesh is left as it was */
    if ((st = wv_tri_mesh_tangents(&m, err))) return st;
    own_tangents = m.tangents;
  }
  json_t *root = json_object(), *views = json_array(), *accessors = json_array();
  wv_buf bin = {0};
  int nv = m.vertex_count;
  /* Vertex data. */
  int a_pos = add_accessor(accessors, add_view(views, &bin, m.positions, sizeof(float) * 3 * nv, GL_ARRAY_BUFFER),
                           GL_FLOAT, nv, "VEC3");
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int v = 0; v < nv; v++)
    for (int c = 0; c < 3; c++) lo[c] = fmin(lo[c], m.positions[3 * v + c]), hi[c] = fmax(hi[c], m.positions[3 * v + c]);
  json_t *pa = json_array_get(accessors, a_pos); /* POSITION needs its bounds */
  json_object_set_new(pa, "min", json_pack("[f,f,f]", lo[0], lo[1], lo[2]));
  json_object_set_new(pa, "max", json_pack("[f,f,f]", hi[0], hi[1], hi[2]));
  int a_nrm = add_accessor(accessors, add_view(views, &bin, m.normals, sizeof(float) * 3 * nv, GL_ARRAY_BUFFER),
                           GL_FLOAT, nv, "VEC3");
  int a_tan = add_accessor(accessors, add_view(views, &bin, m.tangents, sizeof(float) * 4 * nv, GL_ARRAY_BUFFER),
                           GL_FLOAT, nv, "VEC4");
  int a_uv = add_accessor(accessors, add_view(views, &bin, m.uvs, sizeof(float) * 2 * nv, GL_ARRAY_BUFFER), GL_FLOAT,
                          nv, "VEC2");
  int a_idx = add_accessor(accessors,
                           add_view(views, &bin, m.indices, sizeof(uint32_t) * m.index_count, GL_ELEMENT_ARRAY_BUFFER),
                           GL_UNSIGNED_INT, m.index_count, "SCALAR");
  /* Textures: one PNG each, in the order the material refers to them. */
  const wv_image *imgs[7] = {&b->base_color, &b->normal,  &b->metal_rough, &b->anisotropy,
                             &b->sheen,      &b->diffuse_transmission, &b->open};
  static const char *names[7] = {"base colour", "normal", "metallic-roughness", "anisotropy", "sheen",
                                 "diffuse transmission", "open area"};
  json_t *images = json_array(), *textures = json_array();
  for (int i = 0; i < (b->has_open ? 7 : 6) && !st; i++) {
    unsigned char *png;
    size_t len;
    if ((st = wv_image_encode_png(imgs[i], &png, &len, err))) break;
    int view = add_view(views, &bin, png, len, 0);
    free(png);
    json_array_append_new(images, json_pack("{s:s,s:i,s:s}", "name", names[i], "bufferView", view, "mimeType",
                                            "image/png"));
    json_array_append_new(textures, json_pack("{s:i,s:i}", "sampler", 0, "source", i));
  }
  /* One tile spans tile_mm; a UV unit spans uv_mm: the transform's scale. */
  double sx = m.uv_mm / b->tile_mm[0], sy = m.uv_mm / b->tile_mm[1];
  json_t *material = json_pack(
      "{s:s,s:{s:o,s:o,s:f,s:f},s:o,s:{s:{s:f,s:f,s:o},s:{s:[f,f,f],s:o,s:f,s:o}}}", "name", p->pattern,
      "pbrMetallicRoughness", "baseColorTexture", tex_info(0, sx, sy), "metallicRoughnessTexture", tex_info(2, sx, sy),
      "metallicFactor", 1.0, "roughnessFactor", 1.0, "normalTexture", tex_info(1, sx, sy), "extensions",
      "KHR_materials_anisotropy", "anisotropyStrength", 1.0, "anisotropyRotation", 0.0, "anisotropyTexture",
      tex_info(3, sx, sy), "KHR_materials_sheen", "sheenColorFactor", 1.0, 1.0, 1.0, "sheenColorTexture",
      tex_info(4, sx, sy), "sheenRoughnessFactor", 1.0, "sheenRoughnessTexture", tex_info(4, sx, sy));
  /* The light through the cloth: diffuse transmission (factor in A, colour in RGB of one
   * texture) and, where the cloth has open gaps, their area as transmission (thin-walled:
   * no KHR_materials_volume). */
  json_t *mext = json_object_get(material, "extensions");
  json_object_set_new(mext, "KHR_materials_diffuse_transmission",
                      json_pack("{s:f,s:o,s:[f,f,f],s:o}", "diffuseTransmissionFactor", 1.0,
                                "diffuseTransmissionTexture", tex_info(5, sx, sy), "diffuseTransmissionColorFactor",
                                1.0, 1.0, 1.0, "diffuseTransmissionColorTexture", tex_info(5, sx, sy)));
  if (b->has_open)
    json_object_set_new(mext, "KHR_materials_transmission",
                        json_pack("{s:f,s:o}", "transmissionFactor", 1.0, "transmissionTexture", tex_info(6, sx, sy)));
  json_object_set_new(material, "doubleSided", json_true()); /* cloth is seen from both sides */
  char *pj = wv_params_to_json(p);
  json_t *params = pj ? json_loads(pj, 0, NULL) : NULL;
  free(pj);
  json_object_set_new(
      material, "extras",
      json_pack("{s:{s:[f,f],s:f,s:i,s:{s:f,s:f,s:f,s:i},s:o*}}", "woven", "tile_mm", b->tile_mm[0], b->tile_mm[1],
                "uv_mm", m.uv_mm, "texture_size", b->base_color.w, "fit", "rms", b->rms, "target_rms", b->target_rms,
                "relative", b->relative, "direction_pairs", b->directions, "params", params));
  json_object_set_new(root, "asset", json_pack("{s:s,s:s}", "version", "2.0", "generator", "woven export"));
  json_t *used = json_pack("[s,s,s,s]", "KHR_materials_anisotropy", "KHR_materials_sheen", "KHR_texture_transform",
                           "KHR_materials_diffuse_transmission");
  if (b->has_open) json_array_append_new(used, json_string("KHR_materials_transmission"));
  json_object_set_new(root, "extensionsUsed", used);
  json_object_set_new(root, "scene", json_integer(0));
  json_object_set_new(root, "scenes", json_pack("[{s:[i]}]", "nodes", 0));
  json_object_set_new(root, "nodes", json_pack("[{s:s,s:i}]", "name", "woven fabric", "mesh", 0));
  json_object_set_new(root, "meshes",
                      json_pack("[{s:s,s:[{s:{s:i,s:i,s:i,s:i},s:i,s:i}]}]", "name", "fabric", "primitives",
                                "attributes", "POSITION", a_pos, "NORMAL", a_nrm, "TANGENT", a_tan, "TEXCOORD_0", a_uv,
                                "indices", a_idx, "material", 0));
  json_object_set_new(root, "materials", json_pack("[o]", material));
  json_object_set_new(root, "samplers", json_pack("[{s:i,s:i,s:i,s:i}]", "magFilter", GL_LINEAR, "minFilter",
                                                  GL_LINEAR_MIPMAP_LINEAR, "wrapS", GL_REPEAT, "wrapT", GL_REPEAT));
  json_object_set_new(root, "images", images);
  json_object_set_new(root, "textures", textures);
  json_object_set_new(root, "bufferViews", views);
  json_object_set_new(root, "accessors", accessors);
  json_object_set_new(root, "buffers", json_pack("[{s:I}]", "byteLength", (json_int_t)bin.len));
  char *text = st ? NULL : json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(9));
  json_decref(root);
  free(own_tangents);
  if (!st && (!text || bin.failed)) st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory building the glTF", path);
  if (st) {
    free(text), free(bin.data);
    return st;
  }
  /* GLB: 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros. */
  size_t jlen = strlen(text), jpad = (4 - jlen % 4) % 4, total = 12 + 8 + jlen + jpad + 8 + bin.len;
  unsigned char *glb = total <= 0xffffffffu ? malloc(total) : NULL;
  if (!glb) {
    free(text), free(bin.data);
    return wv_fail(err, WV_ERR_NOMEM, "%s: the glTF binary (%zu bytes) is too large", path, total);
  }
  put_le32(glb, 0x46546C67u); /* "glTF" */
  put_le32(glb + 4, 2);
  put_le32(glb + 8, (uint32_t)total);
  put_le32(glb + 12, (uint32_t)(jlen + jpad));
  put_le32(glb + 16, 0x4E4F534Au); /* "JSON" */
  memcpy(glb + 20, text, jlen);
  memset(glb + 20 + jlen, ' ', jpad);
  put_le32(glb + 20 + jlen + jpad, (uint32_t)bin.len);
  put_le32(glb + 24 + jlen + jpad, 0x004E4942u); /* "BIN" */
  memcpy(glb + 28 + jlen + jpad, bin.data, bin.len);
  free(text), free(bin.data);
  st = wv_write_file_atomic(path, glb, total, err);
  free(glb);
  return st;
}
