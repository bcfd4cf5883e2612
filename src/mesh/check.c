/* Checks of a mesh file before assimp reads it: the format (from the name, confirmed
 * by the content), the element counts a PLY header or a binary STL declares, the
 * lines of an OBJ, a GLB's chunk lengths and a glTF's accessors, buffers and node
 * tree. assimp allocates what a header declares and recurses over the node tree
 * before woven sees the result, so both are bounded here (docs/hardening.md). */
#include <ctype.h>
#include <jansson.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "woven/io.h"
#include "woven/mesh.h"

typedef enum { FMT_NONE, FMT_OBJ, FMT_PLY, FMT_STL, FMT_GLTF, FMT_GLB } mesh_format;

static mesh_format format_of(const char *path) {
  static const struct {
    const char *ext;
    mesh_format f;
  } T[] = {{".obj", FMT_OBJ}, {".ply", FMT_PLY}, {".stl", FMT_STL}, {".gltf", FMT_GLTF}, {".glb", FMT_GLB}};
  const char *slash = strrchr(path, '/'), *dot = strrchr(slash ? slash : path, '.');
  for (size_t i = 0; dot && i < sizeof T / sizeof T[0]; i++)
    if (!strcasecmp(dot, T[i].ext)) return T[i].f;
  return FMT_NONE;
}

/* Bytes assimp and woven hold for nv vertices and nt triangles, against the limit. */
static wv_status check_counts(const char *path, unsigned long long nv, unsigned long long nt, size_t limit,
                              const char *what, wv_error *err) {
  if (nv > WV_MESH_MAX_ELEMENTS || nt > WV_MESH_MAX_ELEMENTS)
    return wv_fail(err, WV_ERR_NOMEM, "%s: %s %llu vertices and %llu faces (at most %d of each)", path, what, nv, nt,
                   WV_MESH_MAX_ELEMENTS);
  size_t need = wv_mesh_bytes((long long)nv, (long long)nt);
  if (need > limit)
    return wv_fail(err, WV_ERR_NOMEM, "%s: %s %llu vertices and %llu faces, which need %zu MB, above the memory limit of "
                   "%zu MB", path, what, nv, nt, need >> 20, limit >> 20);
  return WV_OK;
}

/* ---- PLY: the header's elements against the memory limit and the file's size ---- */

static int ply_type_size(const char *t) {
  static const struct {
    const char *n;
    int s;
  } T[] = {{"char", 1},  {"uchar", 1},  {"int8", 1},   {"uint8", 1},   {"short", 2}, {"ushort", 2},
           {"int16", 2}, {"uint16", 2}, {"int", 4},    {"uint", 4},    {"int32", 4}, {"uint32", 4},
           {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  for (size_t i = 0; i < sizeof T / sizeof T[0]; i++)
    if (!strcmp(t, T[i].n)) return T[i].s;
  return 0;
}

static wv_status check_ply(const char *path, FILE *f, unsigned long long size, size_t limit, wv_error *err) {
  char line[256];
  unsigned long long nv = 0, nf = 0, min_bytes = 0, count = 0, elem_min = 0;
  int binary = -1, lines = 0, have_elem = 0;
  unsigned long long header = 0;
  for (;;) {
    if (!fgets(line, sizeof line, f))
      return wv_fail(err, WV_ERR_FORMAT, "%s: the PLY header has no end_header line", path);
    header += strlen(line);
    if (!strchr(line, '\n') && !feof(f))
      return wv_fail(err, WV_ERR_FORMAT, "%s: PLY header line %d is longer than %zu bytes", path, lines + 1,
                     sizeof line - 2);
    if (++lines > 4096) return wv_fail(err, WV_ERR_FORMAT, "%s: the PLY header has more than 4096 lines", path);
    char a[64] = "", b[64] = "", c[64] = "", d[64] = "";
    int k = sscanf(line, "%63s %63s %63s %63s", a, b, c, d);
    if (lines == 1) {
      if (strcmp(a, "ply")) return wv_fail(err, WV_ERR_FORMAT, "%s: not a PLY file (no 'ply' line first)", path);
      continue;
    }
    if (!strcmp(a, "end_header")) break;
    if (!strcmp(a, "format") && k >= 2) {
      binary = strcmp(b, "ascii") != 0;
    } else if (!strcmp(a, "element") && k >= 3) {
      if (have_elem) min_bytes += count * elem_min;
      char *end;
      if (c[0] == '-' || !isdigit((unsigned char)c[0]))
        return wv_fail(err, WV_ERR_FORMAT, "%s: PLY element '%.32s' has no valid count", path, b);
      count = strtoull(c, &end, 10);
      if (*end || count > WV_MESH_MAX_ELEMENTS)
        return wv_fail(err, WV_ERR_NOMEM, "%s: the PLY header declares %.24s %.32s elements (at most %d)", path, c, b,
                       WV_MESH_MAX_ELEMENTS);
      if (!strcmp(b, "vertex")) nv = count;
      if (!strcmp(b, "face")) nf = count;
      have_elem = 1, elem_min = 0;
    } else if (!strcmp(a, "property") && have_elem) {
      /* the least an element's property takes: ascii a digit and a separator; binary
       * its size (a list at least its count) */
      int list = !strcmp(b, "list") && k >= 4;
      int s = ply_type_size(list ? c : b);
      elem_min += binary ? (unsigned long long)(s > 0 ? s : 1) : 2;
    }
  }
  if (have_elem) min_bytes += count * elem_min;
  if (binary < 0) return wv_fail(err, WV_ERR_FORMAT, "%s: the PLY header has no format line", path);
  wv_status st = check_counts(path, nv, nf, limit, "the PLY header declares", err);
  if (st) return st;
  if (min_bytes > size - header)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the PLY header declares %llu vertices and %llu faces, more than its %llu "
                   "bytes of data can hold", path, nv, nf, size - header);
  return WV_OK;
}

/* ---- OBJ: counted line by line; material libraries must be regular files ---- */

static wv_status check_mtllib(const char *path, const char *names, wv_error *err) {
  const char *slash = strrchr(path, '/');
  int dirlen = slash ? (int)(slash - path) : 0;
  char name[1024], full[4096];
  for (const char *p = names;;) {
    while (*p == ' ' || *p == '\t') p++;
    size_t n = strcspn(p, " \t\r\n");
    if (!n) return WV_OK;
    if (n < sizeof name) {
      memcpy(name, p, n);
      name[n] = 0;
      if (name[0] == '/' || !slash) snprintf(full, sizeof full, "%s", name);
      else snprintf(full, sizeof full, "%.*s/%s", dirlen, path, name);
      struct stat sb;
      if (stat(full, &sb) == 0 && !S_ISREG(sb.st_mode))
        return wv_fail(err, WV_ERR_IO, "%s: its material library %s is not a regular file", path, full);
    }
    p += n;
  }
}

static wv_status check_obj(const char *path, FILE *f, size_t limit, wv_error *err) {
  /* assimp makes a vertex per face corner before joining identical ones */
  unsigned long long corners = 0, tris = 0, coords = 0;
  char buf[1 << 16];
  int at_start = 1, kind = 0; /* kind: 0 other line, 'f' face, 'v' vertex data */
  int in_token = 0;
  unsigned long long tokens = 0;
  char head[8];
  int hn = 0;
  char lib[2048];
  size_t libn = 0;
  int in_lib = 0;
  wv_status st = WV_OK;
  for (size_t n; !st && (n = fread(buf, 1, sizeof buf, f)) > 0;) {
    for (size_t i = 0; i < n && !st; i++) {
      char ch = buf[i];
      if (ch == '\n') {
        if (kind == 'f' && tokens > 1) corners += tokens - 1, tris += tokens > 3 ? tokens - 3 : 1;
        if (in_lib) {
          lib[libn] = 0;
          st = check_mtllib(path, lib, err);
        }
        at_start = 1, kind = 0, in_token = 0, tokens = 0, hn = 0, in_lib = 0, libn = 0;
        continue;
      }
      if (at_start) {
        if (ch == ' ' || ch == '\t' || ch == '\r') {
          if (hn == 0) continue;
          head[hn] = 0;
          at_start = 0;
          if (!strcmp(head, "f")) kind = 'f', tokens = 1, in_token = 0;
          else if (!strcmp(head, "v") || !strcmp(head, "vt") || !strcmp(head, "vn")) coords++;
          else if (!strcmp(head, "mtllib")) in_lib = 1;
          continue;
        }
        if (hn < (int)sizeof head - 1) head[hn++] = ch;
        else at_start = 0;
        continue;
      }
      if (in_lib && libn < sizeof lib - 1) lib[libn++] = ch;
      if (kind == 'f') {
        int sp = ch == ' ' || ch == '\t' || ch == '\r';
        if (!sp && !in_token) tokens++;
        in_token = !sp;
      }
    }
  }
  if (!st && kind == 'f' && tokens > 1) corners += tokens - 1, tris += tokens > 3 ? tokens - 3 : 1;
  if (!st && in_lib) {
    lib[libn] = 0;
    st = check_mtllib(path, lib, err);
  }
  if (st) return st;
  if (coords > WV_MESH_MAX_ELEMENTS)
    return wv_fail(err, WV_ERR_NOMEM, "%s: %llu vertex lines (at most %d)", path, coords, WV_MESH_MAX_ELEMENTS);
  return check_counts(path, corners, tris, limit, "the OBJ file's faces have", err);
}

/* ---- STL: a binary file's triangle count against its size ---- */

static wv_status check_stl(const char *path, FILE *f, unsigned long long size, size_t limit, wv_error *err) {
  unsigned char h[84];
  size_t n = fread(h, 1, sizeof h, f);
  if (n >= 5 && !memcmp(h, "solid", 5)) { /* ascii (or a binary whose header starts so): bounded by its size */
    if (n == sizeof h) {
      unsigned long long cnt = h[80] | (unsigned long long)h[81] << 8 | (unsigned long long)h[82] << 16 |
                               (unsigned long long)h[83] << 24;
      if (84 + 50 * cnt == size) return check_counts(path, 3 * cnt, cnt, limit, "the STL file declares", err);
    }
    return check_counts(path, size / 16, size / 48, limit, "the STL file's size allows", err);
  }
  if (n < sizeof h) return wv_fail(err, WV_ERR_FORMAT, "%s: not an STL file (too short)", path);
  unsigned long long cnt = h[80] | (unsigned long long)h[81] << 8 | (unsigned long long)h[82] << 16 |
                           (unsigned long long)h[83] << 24;
  if (84 + 50 * cnt > size)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the STL header declares %llu triangles, more than its %llu bytes hold", path,
                   cnt, size);
  return check_counts(path, 3 * cnt, cnt, limit, "the STL header declares", err);
}

/* ---- glTF 2.0 (and the JSON chunk of a GLB) ---- */

static json_int_t int_of(json_t *o, const char *key, json_int_t dflt) {
  json_t *v = json_object_get(o, key);
  return json_is_integer(v) ? json_integer_value(v) : dflt;
}

static int components(const char *type) {
  static const struct {
    const char *n;
    int c;
  } T[] = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT2", 4}, {"MAT3", 9}, {"MAT4", 16}};
  for (size_t i = 0; type && i < sizeof T / sizeof T[0]; i++)
    if (!strcmp(type, T[i].n)) return T[i].c;
  return 0;
}

static int component_size(json_int_t t) {
  switch (t) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
  }
}

/* The node tree: every node has at most one parent and lies at most
 * WV_MESH_MAX_NODE_DEPTH levels deep (a cycle counts as too deep). */
static wv_status check_nodes(const char *path, json_t *nodes, wv_error *err) {
  size_t n = json_array_size(nodes);
  if (!n) return WV_OK;
  long *parent = malloc(n * sizeof *parent), *depth = malloc(n * sizeof *depth), *chain = NULL;
  wv_status st = parent && depth ? WV_OK : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  for (size_t i = 0; !st && i < n; i++) parent[i] = -1, depth[i] = -1;
  for (size_t i = 0; !st && i < n; i++) {
    json_t *ch = json_object_get(json_array_get(nodes, i), "children");
    for (size_t k = 0; !st && k < json_array_size(ch); k++) {
      json_t *c = json_array_get(ch, k);
      json_int_t j = json_is_integer(c) ? json_integer_value(c) : -1;
      if (j < 0 || (size_t)j >= n)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: node %zu has a child that is not a node", path, i);
      else if (parent[j] >= 0 || (size_t)j == i)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: node %lld has more than one parent (the nodes must form trees)", path,
                     (long long)j);
      else
        parent[j] = (long)i;
    }
  }
  if (!st && !(chain = malloc((WV_MESH_MAX_NODE_DEPTH + 1) * sizeof *chain)))
    st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  /* each node's depth from its parents', remembered, so the whole tree costs O(n) */
  for (size_t i = 0; !st && i < n; i++) {
    int len = 0;
    long j = (long)i;
    while (j >= 0 && depth[j] < 0) {
      if (len > WV_MESH_MAX_NODE_DEPTH) break;
      chain[len++] = j;
      j = parent[j];
    }
    long d = j >= 0 ? depth[j] : 0;
    if (len > WV_MESH_MAX_NODE_DEPTH || d + len > WV_MESH_MAX_NODE_DEPTH) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: its node tree is more than %d levels deep (or has a cycle)", path,
                   WV_MESH_MAX_NODE_DEPTH);
      break;
    }
    for (int k = len - 1; k >= 0; k--) depth[chain[k]] = ++d;
  }
  free(parent), free(depth), free(chain);
  return st;
}

/* A buffer's bytes: a file beside the glTF (regular, large enough), a data: URI
 * (its base64 text long enough) or, without a URI, the GLB's binary chunk. */
static wv_status check_buffer(const char *path, json_t *b, size_t i, unsigned long long bin_len, wv_error *err) {
  json_int_t len = int_of(b, "byteLength", -1);
  if (len < 0) return wv_fail(err, WV_ERR_FORMAT, "%s: buffer %zu has no valid byteLength", path, i);
  json_t *u = json_object_get(b, "uri");
  const char *uri = json_string_value(u);
  unsigned long long have;
  if (!u) {
    have = bin_len;
  } else if (!uri) {
    return wv_fail(err, WV_ERR_FORMAT, "%s: buffer %zu has a uri that is not a string", path, i);
  } else if (!strncmp(uri, "data:", 5)) {
    const char *comma = strchr(uri, ',');
    have = comma ? (unsigned long long)strlen(comma + 1) / 4 * 3 : 0;
  } else {
    if (strchr(uri, '%') || strstr(uri, "://"))
      return wv_fail(err, WV_ERR_FORMAT, "%s: buffer %zu's uri is not a plain file name", path, i);
    const char *slash = strrchr(path, '/');
    char full[4096];
    if (uri[0] == '/' || !slash) snprintf(full, sizeof full, "%s", uri);
    else snprintf(full, sizeof full, "%.*s/%s", (int)(slash - path), path, uri);
    int fd;
    struct stat sb;
    wv_status st = wv_open_regular(full, &fd, &sb, err);
    if (st) return wv_error_prefix(err, "%s: buffer %zu", path, i), st;
    close(fd);
    have = (unsigned long long)sb.st_size;
  }
  if ((unsigned long long)len > have)
    return wv_fail(err, WV_ERR_FORMAT, "%s: buffer %zu declares %lld bytes but holds %llu", path, i, (long long)len,
                   have);
  return WV_OK;
}

/* The JSON text must fit the JSON limit and, parsed (here and again by assimp), the
 * memory limit: embedded data URIs belong in a .bin file or a GLB's binary chunk. */
static wv_status check_json_size(const char *path, unsigned long long len, size_t limit, wv_error *err) {
  if (len > WV_JSON_MAX_BYTES || len > limit / WV_MESH_JSON_COST)
    return wv_fail(err, WV_ERR_NOMEM, "%s: its glTF JSON of %llu bytes is over the limit of %zu bytes (%zu MB, or "
                   "the memory limit / %d); keep large data in a .bin file or a GLB", path, len,
                   (size_t)WV_JSON_MAX_BYTES < limit / WV_MESH_JSON_COST ? (size_t)WV_JSON_MAX_BYTES
                                                                         : limit / WV_MESH_JSON_COST,
                   (size_t)WV_JSON_MAX_BYTES >> 20, WV_MESH_JSON_COST);
  return WV_OK;
}

static wv_status check_gltf_json(const char *path, const char *text, size_t len, unsigned long long bin_len,
                                 size_t limit, wv_error *err) {
  json_error_t je;
  json_t *r = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
  if (!r) return wv_fail(err, WV_ERR_FORMAT, "%s:%d:%d: malformed glTF JSON", path, je.line, je.column);
  wv_status st = WV_OK;
  json_t *asset = json_object_get(r, "asset"), *ver = json_object_get(asset, "version");
  const char *v = json_string_value(ver);
  if (!json_is_object(r) || !v || v[0] != '2')
    st = wv_fail(err, WV_ERR_FORMAT, "%s: not a glTF 2.0 file (asset.version must be \"2.x\")", path);
  json_t *buffers = json_object_get(r, "buffers"), *views = json_object_get(r, "bufferViews");
  json_t *acc = json_object_get(r, "accessors"), *meshes = json_object_get(r, "meshes");
  json_t *nodes = json_object_get(r, "nodes");
  for (size_t i = 0; !st && i < json_array_size(buffers); i++)
    st = check_buffer(path, json_array_get(buffers, i), i, bin_len, err);
  /* accessors: counts, and the bytes they read inside their buffer view */
  size_t na = json_array_size(acc);
  unsigned long long *abytes = na ? calloc(na, sizeof *abytes) : NULL;
  if (na && !abytes && !st) st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  for (size_t i = 0; !st && i < na; i++) {
    json_t *a = json_array_get(acc, i);
    json_int_t count = int_of(a, "count", -1);
    int nc = components(json_string_value(json_object_get(a, "type")));
    int cs = component_size(int_of(a, "componentType", 0));
    if (count < 1 || count > WV_MESH_MAX_ELEMENTS || !nc || !cs) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: accessor %zu has an invalid count, type or componentType (at most %d "
                   "elements)", path, i, WV_MESH_MAX_ELEMENTS);
      break;
    }
    /* assimp converts every element to floats or 32-bit indices */
    abytes[i] = (unsigned long long)count * (unsigned long long)(nc * 4 > 16 ? nc * 4 : 16);
    json_t *bv = json_object_get(a, "bufferView");
    if (bv) {
      json_int_t k = json_is_integer(bv) ? json_integer_value(bv) : -1;
      json_t *view = k >= 0 ? json_array_get(views, (size_t)k) : NULL;
      json_int_t vlen = int_of(view, "byteLength", -1), stride = int_of(view, "byteStride", 0);
      json_int_t off = int_of(a, "byteOffset", 0), buf = int_of(view, "buffer", -1);
      json_int_t blen = int_of(json_array_get(buffers, buf >= 0 ? (size_t)buf : (size_t)-1), "byteLength", -1);
      json_int_t voff = int_of(view, "byteOffset", 0);
      unsigned long long elem = (unsigned long long)nc * (unsigned long long)cs;
      unsigned long long step = stride > 0 ? (unsigned long long)stride : elem;
      if (!view || vlen < 0 || blen < 0 || off < 0 || voff < 0 || stride < 0 ||
          (unsigned long long)voff + (unsigned long long)vlen > (unsigned long long)blen ||
          (unsigned long long)off + step * (unsigned long long)(count - 1) + elem > (unsigned long long)vlen)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: accessor %zu reads past its buffer view", path, i);
    }
  }
  /* what the meshes cost, once per node that instances them (node transforms are
   * applied by copying), against the memory limit */
  size_t nm = json_array_size(meshes), nn = json_array_size(nodes);
  unsigned long long total = 0;
  unsigned long long *uses = nm ? calloc(nm, sizeof *uses) : NULL;
  if (nm && !uses && !st) st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  for (size_t i = 0; !st && i < nn; i++) {
    json_int_t m = int_of(json_array_get(nodes, i), "mesh", -1);
    if (m >= 0 && (size_t)m < nm) uses[m]++;
  }
  for (size_t m = 0; !st && m < nm; m++) {
    json_t *prims = json_object_get(json_array_get(meshes, m), "primitives");
    unsigned long long cost = 0;
    for (size_t p = 0; p < json_array_size(prims); p++) {
      json_t *pr = json_array_get(prims, p), *attrs = json_object_get(pr, "attributes"), *v2;
      const char *k2;
      json_object_foreach(attrs, k2, v2) {
        json_int_t ai = json_is_integer(v2) ? json_integer_value(v2) : -1;
        if (ai >= 0 && (size_t)ai < na) cost += abytes[ai];
      }
      json_int_t ii = int_of(pr, "indices", -1);
      if (ii >= 0 && (size_t)ii < na) cost += abytes[ii];
      if (cost > limit) break;
    }
    unsigned long long k = uses[m] ? uses[m] : 1;
    if (cost > limit || k > limit / (cost ? cost : 1) || (total += cost * k) > limit) {
      st = wv_fail(err, WV_ERR_NOMEM, "%s: its meshes, once per node that places them, need more than the memory "
                   "limit of %zu MB", path, limit >> 20);
    }
  }
  if (!st) st = check_nodes(path, nodes, err);
  free(abytes), free(uses);
  json_decref(r);
  return st;
}

static wv_status read_all(const char *path, FILE *f, size_t len, char **out, wv_error *err) {
  *out = malloc(len + 1);
  if (!*out) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  if (fread(*out, 1, len, f) != len) {
    free(*out), *out = NULL;
    return wv_fail(err, WV_ERR_FORMAT, "%s: truncated file", path);
  }
  (*out)[len] = 0;
  return WV_OK;
}

static uint32_t le32(const unsigned char *b) {
  return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static wv_status check_glb(const char *path, FILE *f, unsigned long long size, size_t limit, wv_error *err) {
  unsigned char h[20];
  if (fread(h, 1, sizeof h, f) != sizeof h || memcmp(h, "glTF", 4))
    return wv_fail(err, WV_ERR_FORMAT, "%s: not a GLB file (no glTF header)", path);
  unsigned long long total = le32(h + 8), jlen = le32(h + 12);
  if (le32(h + 4) != 2) return wv_fail(err, WV_ERR_FORMAT, "%s: not a glTF 2.0 binary (version %u)", path, le32(h + 4));
  if (total > size || total < 20)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the GLB header declares %llu bytes but the file has %llu", path, total, size);
  if (memcmp(h + 16, "JSON", 4) || jlen > total - 20)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the GLB's first chunk is not JSON or is longer than the file", path);
  char *text;
  wv_status st = check_json_size(path, jlen, limit, err);
  if (!st) st = read_all(path, f, (size_t)jlen, &text, err);
  if (st) return st;
  unsigned long long pos = 20 + jlen, bin = 0;
  pos += (4 - pos % 4) % 4;
  if (pos + 8 <= total) {
    unsigned char c[8];
    if (fseek(f, (long)pos, SEEK_SET) != 0 || fread(c, 1, 8, f) != 8)
      st = wv_fail(err, WV_ERR_FORMAT, "%s: truncated GLB chunk", path);
    else if ((bin = le32(c)) > total - pos - 8)
      st = wv_fail(err, WV_ERR_FORMAT, "%s: a GLB chunk declares %llu bytes, more than the file holds", path, bin);
  }
  if (!st) st = check_gltf_json(path, text, (size_t)jlen, bin, limit, err);
  free(text);
  return st;
}

wv_status wv_mesh_check_file(const char *path, size_t limit, wv_error *err) {
  if (!limit) limit = (size_t)WV_MESH_DEFAULT_LIMIT_MB << 20;
  mesh_format fmt = format_of(path);
  if (fmt == FMT_NONE)
    return wv_fail(err, WV_ERR_FORMAT, "%s: not a mesh file woven reads (.obj, .ply, .stl, .gltf or .glb)", path);
  FILE *f;
  struct stat sb;
  int fd;
  wv_status st = wv_open_regular(path, &fd, &sb, err);
  if (st) return st;
  if (!(f = fdopen(fd, "rb"))) {
    close(fd);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  }
  unsigned long long size = (unsigned long long)sb.st_size;
  if (size > limit)
    st = wv_fail(err, WV_ERR_NOMEM, "%s: the mesh file (%llu MB) is larger than the memory limit of %zu MB", path,
                 size >> 20, limit >> 20);
  else if (size == 0)
    st = wv_fail(err, WV_ERR_FORMAT, "%s: empty file, not a mesh", path);
  else if (fmt == FMT_PLY)
    st = check_ply(path, f, size, limit, err);
  else if (fmt == FMT_OBJ)
    st = check_obj(path, f, limit, err);
  else if (fmt == FMT_STL)
    st = check_stl(path, f, size, limit, err);
  else if (fmt == FMT_GLB)
    st = check_glb(path, f, size, limit, err);
  else {
    char *text;
    if (!(st = check_json_size(path, size, limit, err)) && !(st = read_all(path, f, (size_t)size, &text, err))) {
      if (strlen(text) != size) st = wv_fail(err, WV_ERR_FORMAT, "%s: a glTF file holds a NUL byte", path);
      else st = check_gltf_json(path, text, (size_t)size, 0, limit, err);
      free(text);
    }
  }
  fclose(f);
  return st;
}
