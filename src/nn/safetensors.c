/* A small safetensors reader and F32 writer. The header is untrusted: every
 * number in it is checked against the file before any data is read. */
#include <errno.h>
#include <inttypes.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <fcntl.h>
#include <unistd.h>

#include "woven/nn.h"

/* The reference implementation's limit; real headers are a few hundred kB at most. */
#define ST_MAX_HEADER (100u << 20)

float wv_nn_f16_to_f32(uint16_t h) {
  uint32_t sign = (uint32_t)(h >> 15) & 1u, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
  float v;
  if (e == 0)
    v = ldexpf((float)m, -24); /* zero and subnormals: m * 2^-24 */
  else if (e == 31)
    v = m ? NAN : INFINITY;
  else
    v = ldexpf((float)(m | 0x400u), (int)e - 25); /* (1 + m/1024) 2^(e-15) */
  return sign ? -v : v;
}

float wv_nn_bf16_to_f32(uint16_t h) {
  /* bfloat16 is the top half of an IEEE single. */
  uint32_t u = (uint32_t)h << 16;
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}

static int dtype_size(const char *d) {
  static const struct {
    const char *name;
    int size;
  } tab[] = {{"BOOL", 1}, {"U8", 1},  {"I8", 1},  {"F8_E5M2", 1}, {"F8_E4M3", 1}, {"I16", 2},
             {"U16", 2},  {"F16", 2}, {"BF16", 2}, {"I32", 4},    {"U32", 4},     {"F32", 4},
             {"I64", 8},  {"U64", 8}, {"F64", 8}};
  for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
    if (!strcmp(d, tab[i].name)) return tab[i].size;
  return 0;
}

void wv_st_close(wv_safetensors *st) {
  if (!st) return;
  if (st->file) fclose((FILE *)st->file);
  for (int i = 0; i < st->n; i++) free(st->t[i].name);
  free(st->t);
  free(st->path);
  memset(st, 0, sizeof *st);
}

static int cmp_begin(const void *a, const void *b) {
  const wv_st_tensor *x = *(const wv_st_tensor *const *)a, *y = *(const wv_st_tensor *const *)b;
  if (x->begin != y->begin) return x->begin < y->begin ? -1 : 1;
  return x->end < y->end ? -1 : (x->end > y->end);
}

static void shape_str(char *buf, size_t cap, int ndim, const int64_t *shape) {
  size_t n = 0;
  n += (size_t)snprintf(buf + n, cap - n, "[");
  for (int i = 0; i < ndim && n < cap; i++)
    n += (size_t)snprintf(buf + n, cap - n, i ? ", %" PRId64 : "%" PRId64, shape[i]);
  if (n < cap) snprintf(buf + n, cap - n, "]");
}

/* Parses one header entry into t; returns a message on failure. */
static wv_status parse_entry(const char *path, const char *key, json_t *v, uint64_t data_size,
                             wv_st_tensor *t, wv_error *err) {
  if (!json_is_object(v))
    return wv_fail(err, WV_ERR_FORMAT, "%s: header entry '%s' is not an object", path, key);
  json_t *jd = json_object_get(v, "dtype"), *js = json_object_get(v, "shape"),
         *jo = json_object_get(v, "data_offsets");
  if (!json_is_string(jd))
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has no dtype string", path, key);
  const char *dt = json_string_value(jd);
  int es = dtype_size(dt);
  if (!es || strlen(dt) >= sizeof t->dtype)
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has unknown dtype '%s'", path, key, dt);
  strcpy(t->dtype, dt);
  if (!json_is_array(js) || json_array_size(js) > WV_ST_MAX_DIMS)
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has no valid shape (an array of at most %d sizes)",
                   path, key, WV_ST_MAX_DIMS);
  t->ndim = (int)json_array_size(js);
  uint64_t numel = 1;
  int overflow = 0;
  for (int i = 0; i < t->ndim; i++) {
    json_t *d = json_array_get(js, (size_t)i);
    if (!json_is_integer(d) || json_integer_value(d) < 0)
      return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has an invalid size in its shape", path,
                     key);
    t->shape[i] = (int64_t)json_integer_value(d);
    if (t->shape[i] && numel > UINT64_MAX / 16 / (uint64_t)t->shape[i]) overflow = 1;
    numel *= (uint64_t)t->shape[i];
  }
  if (!json_is_array(jo) || json_array_size(jo) != 2 ||
      !json_is_integer(json_array_get(jo, 0)) || !json_is_integer(json_array_get(jo, 1)))
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has no valid data_offsets [begin, end]",
                   path, key);
  json_int_t b = json_integer_value(json_array_get(jo, 0)),
             e = json_integer_value(json_array_get(jo, 1));
  if (b < 0 || e < b)
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has invalid data_offsets [%lld, %lld]",
                   path, key, (long long)b, (long long)e);
  t->begin = (uint64_t)b, t->end = (uint64_t)e;
  if (t->end > data_size)
    return wv_fail(err, WV_ERR_FORMAT,
                   "%s: tensor '%s' data_offsets [%" PRIu64 ", %" PRIu64
                   "] lie outside the file (its data section has %" PRIu64 " bytes)",
                   path, key, t->begin, t->end, data_size);
  char sh[160];
  shape_str(sh, sizeof sh, t->ndim, t->shape);
  if (overflow)
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has an absurd shape %s", path, key, sh);
  if (numel * (uint64_t)es != t->end - t->begin)
    return wv_fail(err, WV_ERR_FORMAT,
                   "%s: tensor '%s' data_offsets [%" PRIu64 ", %" PRIu64 "] hold %" PRIu64
                   " bytes but shape %s of %s needs %" PRIu64,
                   path, key, t->begin, t->end, t->end - t->begin, sh, dt, numel * (uint64_t)es);
  return WV_OK;
}

wv_status wv_st_open(wv_safetensors *st, const char *path, wv_error *err) {
  memset(st, 0, sizeof *st);
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC); /* a FIFO must not block the open */
  FILE *f = fd < 0 ? NULL : fdopen(fd, "rb");
  if (!f) {
    wv_status e = wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fd >= 0) close(fd);
    return e;
  }
  struct stat sb; /* a directory opens, then reports a nonsensical size */
  int have = fstat(fileno(f), &sb) == 0;
  if (!have || !S_ISREG(sb.st_mode)) {
    int dir = have && S_ISDIR(sb.st_mode);
    fclose(f);
    return wv_fail(err, WV_ERR_IO, "%s: %s", path, dir ? "is a directory" : "is not a regular file");
  }
  st->file = f;
  st->path = strdup(path);
  wv_status rc = WV_OK;
  char *hdr = NULL;
  json_t *root = NULL;
  if (!st->path) {
    rc = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
    goto done;
  }
  if (fseeko(f, 0, SEEK_END) != 0) {
    rc = wv_fail(err, WV_ERR_IO, "%s: cannot seek: %s", path, strerror(errno));
    goto done;
  }
  off_t fsize = ftello(f);
  rewind(f);
  unsigned char lenb[8];
  if (fsize < 8 || fread(lenb, 1, 8, f) != 8) {
    rc = wv_fail(err, WV_ERR_FORMAT,
                 "%s: file is %lld bytes, too short for a safetensors header length (8 bytes)",
                 path, (long long)fsize);
    goto done;
  }
  uint64_t hlen = 0;
  for (int i = 7; i >= 0; i--) hlen = (hlen << 8) | lenb[i]; /* little-endian */
  if (hlen > (uint64_t)fsize - 8) {
    rc = wv_fail(err, WV_ERR_FORMAT,
                 "%s: header length %" PRIu64 " exceeds the file (%lld bytes): truncated or not a safetensors file",
                 path, hlen, (long long)fsize);
    goto done;
  }
  if (hlen < 2 || hlen > ST_MAX_HEADER) {
    rc = wv_fail(err, WV_ERR_FORMAT, "%s: header length %" PRIu64 " is implausible (2 .. %u bytes)",
                 path, hlen, ST_MAX_HEADER);
    goto done;
  }
  hdr = malloc(hlen);
  if (!hdr) {
    rc = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for a %" PRIu64 "-byte header", path, hlen);
    goto done;
  }
  if (fread(hdr, 1, hlen, f) != hlen) {
    rc = wv_fail(err, WV_ERR_IO, "%s: cannot read the header", path);
    goto done;
  }
  st->data_start = 8 + hlen;
  st->data_size = (uint64_t)fsize - st->data_start;
  json_error_t jerr;
  root = json_loadb(hdr, hlen, JSON_REJECT_DUPLICATES, &jerr);
  if (!root) {
    rc = wv_fail(err, WV_ERR_FORMAT, "%s: header is not valid JSON: %s (line %d, column %d)", path,
                 jerr.text, jerr.line, jerr.column);
    goto done;
  }
  if (!json_is_object(root)) {
    rc = wv_fail(err, WV_ERR_FORMAT, "%s: header is not a JSON object", path);
    goto done;
  }
  st->t = calloc(json_object_size(root) + 1, sizeof *st->t);
  if (!st->t) {
    rc = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
    goto done;
  }
  const char *key;
  json_t *v;
  json_object_foreach(root, key, v) {
    if (!strcmp(key, "__metadata__")) continue;
    wv_st_tensor *t = &st->t[st->n];
    if ((rc = parse_entry(path, key, v, st->data_size, t, err)) != WV_OK) goto done;
    if (!(t->name = strdup(key))) {
      rc = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
      goto done;
    }
    st->n++;
  }
  /* No two tensors may share bytes (a file that aliases data is malformed). */
  if (st->n > 1) {
    wv_st_tensor **ord = malloc(sizeof *ord * st->n);
    if (!ord) {
      rc = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
      goto done;
    }
    for (int i = 0; i < st->n; i++) ord[i] = &st->t[i];
    qsort(ord, st->n, sizeof *ord, cmp_begin);
    const wv_st_tensor *last = ord[0]; /* the tensor reaching furthest so far */
    for (int i = 1; i < st->n && rc == WV_OK; i++) {
      if (ord[i]->begin < last->end && ord[i]->end > ord[i]->begin)
        rc = wv_fail(err, WV_ERR_FORMAT,
                     "%s: tensors '%s' [%" PRIu64 ", %" PRIu64 ") and '%s' [%" PRIu64 ", %" PRIu64
                     ") overlap",
                     path, last->name, last->begin, last->end, ord[i]->name, ord[i]->begin,
                     ord[i]->end);
      if (ord[i]->end > last->end) last = ord[i];
    }
    free(ord);
  }
done:
  json_decref(root);
  free(hdr);
  if (rc != WV_OK) wv_st_close(st);
  return rc;
}

const wv_st_tensor *wv_st_find(const wv_safetensors *st, const char *name) {
  for (int i = 0; i < st->n; i++)
    if (!strcmp(st->t[i].name, name)) return &st->t[i];
  return NULL;
}

wv_status wv_st_read_f32(wv_safetensors *st, const char *name, int ndim, const int64_t *shape,
                         float *out, wv_error *err) {
  const wv_st_tensor *t = wv_st_find(st, name);
  if (!t) return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' is missing", st->path, name);
  int es = !strcmp(t->dtype, "F32") ? 4 : (!strcmp(t->dtype, "F16") || !strcmp(t->dtype, "BF16")) ? 2 : 0;
  if (!es)
    return wv_fail(err, WV_ERR_FORMAT,
                   "%s: tensor '%s' has dtype %s; only F32, F16 and BF16 are supported", st->path,
                   name, t->dtype);
  int same = t->ndim == ndim;
  for (int i = 0; same && i < ndim; i++) same = t->shape[i] == shape[i];
  if (!same) {
    char a[160], b[160];
    shape_str(a, sizeof a, t->ndim, t->shape);
    shape_str(b, sizeof b, ndim, shape);
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' has shape %s, expected %s", st->path, name,
                   a, b);
  }
  FILE *f = (FILE *)st->file;
  if (fseeko(f, (off_t)(st->data_start + t->begin), SEEK_SET) != 0)
    return wv_fail(err, WV_ERR_IO, "%s: cannot seek to tensor '%s'", st->path, name);
  uint64_t count = (t->end - t->begin) / (uint64_t)es;
  unsigned char buf[1 << 16];
  uint64_t done = 0;
  int bad = 0;
  while (done < count) {
    size_t chunk = (size_t)((count - done) < sizeof buf / (size_t)es ? count - done : sizeof buf / (size_t)es);
    if (fread(buf, (size_t)es, chunk, f) != chunk)
      return wv_fail(err, WV_ERR_IO, "%s: short read in tensor '%s'", st->path, name);
    for (size_t i = 0; i < chunk; i++) {
      const unsigned char *p = buf + i * es;
      float v;
      if (es == 4) {
        uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        memcpy(&v, &u, sizeof v);
      } else {
        uint16_t u = (uint16_t)(p[0] | p[1] << 8);
        v = t->dtype[0] == 'B' ? wv_nn_bf16_to_f32(u) : wv_nn_f16_to_f32(u);
      }
      bad |= !isfinite(v);
      out[done + i] = v;
    }
    done += chunk;
  }
  if (bad)
    return wv_fail(err, WV_ERR_FORMAT, "%s: tensor '%s' contains NaN or infinite values", st->path,
                   name);
  return WV_OK;
}

wv_status wv_st_write_f32(const char *path, int n, const char *const *names, const int *ndims,
                          const int64_t *const *shapes, const float *const *data, wv_error *err) {
  json_t *root = json_object();
  uint64_t off = 0;
  for (int i = 0; i < n && root; i++) {
    json_t *e = json_object(), *sh = json_array();
    uint64_t numel = 1;
    for (int d = 0; d < ndims[i]; d++) {
      json_array_append_new(sh, json_integer(shapes[i][d]));
      numel *= (uint64_t)shapes[i][d];
    }
    json_object_set_new(e, "dtype", json_string("F32"));
    json_object_set_new(e, "shape", sh);
    json_object_set_new(e, "data_offsets",
                        json_pack("[II]", (json_int_t)off, (json_int_t)(off + 4 * numel)));
    json_object_set_new(root, names[i], e);
    off += 4 * numel;
  }
  char *txt = root ? json_dumps(root, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
  json_decref(root);
  if (!txt) return wv_fail(err, WV_ERR_NOMEM, "%s: cannot build the safetensors header", path);
  size_t hlen = strlen(txt), padded = (hlen + 7) / 8 * 8; /* pad with spaces to 8-byte alignment */
  char tmp[4096];
  if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp) {
    free(txt);
    return wv_fail(err, WV_ERR_INVALID, "%s: path too long", path);
  }
  FILE *f = fopen(tmp, "wb");
  if (!f) {
    free(txt);
    return wv_fail(err, WV_ERR_IO, "%s: cannot create: %s", tmp, strerror(errno));
  }
  unsigned char lenb[8];
  for (int i = 0; i < 8; i++) lenb[i] = (unsigned char)((uint64_t)padded >> (8 * i));
  int ok = fwrite(lenb, 1, 8, f) == 8 && fwrite(txt, 1, hlen, f) == hlen;
  for (size_t i = hlen; ok && i < padded; i++) ok = fputc(' ', f) != EOF;
  free(txt);
  unsigned char buf[1 << 16];
  size_t fill = 0;
  for (int i = 0; ok && i < n; i++) {
    size_t numel = 1;
    for (int d = 0; d < ndims[i]; d++) numel *= (size_t)shapes[i][d];
    for (size_t j = 0; ok && j < numel; j++) {
      uint32_t u;
      memcpy(&u, &data[i][j], 4);
      for (int b = 0; b < 4; b++) buf[fill++] = (unsigned char)(u >> (8 * b)); /* little-endian */
      if (fill == sizeof buf) ok = fwrite(buf, 1, fill, f) == fill, fill = 0;
    }
  }
  if (ok && fill) ok = fwrite(buf, 1, fill, f) == fill;
  if (fclose(f) != 0) ok = 0;
  if (!ok || rename(tmp, path) != 0) {
    remove(tmp);
    return wv_fail(err, WV_ERR_IO, "%s: cannot write: %s", path, strerror(errno));
  }
  return WV_OK;
}
