/* woven: FabricNet's synthetic dataset on disk (format in docs/fabricnet.md): which pattern
 * and prior draw each sample is, and making one sample (render, camera augmentation,
 * files). */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

#include "util/half.h"
#include "util/hash.h"
#include "io/json_file.h"
#include "util/json.h"
#include "woven/dataset.h"
#include "woven/descriptor.h"
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/render.h"
#include "woven/weave.h"

static const char *PATTERNS[WV_NET_PATTERNS] = {"plain", "twill", "satin", "twill90", "satin90"};

const char *wv_net_pattern(int i) { return i >= 0 && i < WV_NET_PATTERNS ? PATTERNS[i] : NULL; }

/* Version 1 sets hold the five earlier patterns; version 2 every built-in of the library. */
int wv_dataset_pattern_count(const wv_dataset_info *info) {
  return info->version >= 2 ? wv_weave_builtin_count() : WV_NET_PATTERNS;
}

const char *wv_dataset_pattern(const wv_dataset_info *info, int i) {
  return info->version >= 2 ? wv_weave_builtin_name(i) : wv_net_pattern(i);
}

wv_status wv_dataset_info_write(const char *dir, const wv_dataset_info *info, wv_error *err) {
  json_error_t je;
  json_t *scene = json_loads(info->scene_json, 0, &je);
  if (!scene) return wv_fail(err, WV_ERR_INTERNAL, "scene JSON does not parse: %s", je.text);
  json_t *pats = json_array();
  int np = wv_dataset_pattern_count(info);
  for (int i = 0; i < np; i++) json_array_append_new(pats, json_string(wv_dataset_pattern(info, i)));
  /* the seed is written as a string: JSON integers are signed 64-bit in jansson */
  char seed[32];
  snprintf(seed, sizeof seed, "%llu", (unsigned long long)info->seed);
  char names[128];
  snprintf(names, sizeof names, "samples/<pattern>_<i>.{json,png,%sfeat}, sample k = pattern k%%%d, i = k/%d",
           info->pair ? "t.png," : "", np, np);
  json_t *o = json_pack("{s:s,s:i,s:i,s:s,s:i,s:o,s:i,s:i,s:{s:s,s:i,s:s},s:{s:i,s:i,s:s},s:o,s:s}", "kind",
                        "woven-dataset", "version", info->version, "renderer", info->renderer, "seed", seed,
                        "per_pattern",
                        info->per_pattern, "patterns", pats, "spp", info->spp, "augment", info->augment,
                        "features", "descriptor",
                        info->descriptor, "count", info->n_feat, "format", "f16le", "image", "width",
                        info->scene.width, "height", info->scene.height, "format", "png8", "scene", scene,
                        "sample_names", names);
  if (!o) return wv_fail(err, WV_ERR_INTERNAL, "cannot build dataset.json");
  if (info->draws == WV_DRAWS_PHOTO) json_object_set_new(o, "draws", json_string("photo"));
  if (info->pair) {
    json_t *ts = json_loads(info->tscene_json, 0, &je);
    if (!ts) {
      json_decref(o);
      return wv_fail(err, WV_ERR_INTERNAL, "back-lit scene JSON does not parse: %s", je.text);
    }
    json_object_set_new(o, "transmission_scene", ts);
  }
  char *text = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
  json_decref(o);
  char path[4096];
  snprintf(path, sizeof path, "%s/dataset.json", dir);
  wv_status st = text ? wv_write_file_atomic(path, text, strlen(text), err)
                      : wv_fail(err, WV_ERR_NOMEM, "out of memory for dataset.json");
  free(text);
  return st;
}

wv_status wv_dataset_info_read(const char *dir, wv_dataset_info *info, wv_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/dataset.json", dir);
  struct stat sb;
  if (stat(path, &sb) != 0)
    return wv_fail(err, WV_ERR_IO, "%s is not a woven dataset (no %s); make one with 'woven dataset'", dir, path);
  json_t *o;
  wv_status st = wv_json_load_file(path, &o, err);
  if (st) return st;
  memset(info, 0, sizeof *info);
  const char *kind = NULL, *seed = NULL, *desc = NULL, *fmt = NULL;
  json_t *scene = NULL, *feats = json_object_get(o, "features");
  json_t *jv = json_object_get(o, "version");
  long long version = json_is_integer(jv) ? json_integer_value(jv) : -1;
  if (json_unpack(o, "{s:s}", "kind", &kind) || strcmp(kind, "woven-dataset") || version < 0) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: not a woven dataset description", path);
  } else if (version < 1 || version > WV_DATASET_VERSION) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: dataset format version %lld; this program reads versions 1 to %d (make the dataset again)",
                 path, version, WV_DATASET_VERSION);
  } else if (json_unpack(o, "{s:s,s:{s:s,s:s},s:o}", "seed", &seed, "features", "descriptor", &desc, "format", &fmt,
                         "scene", &scene) ||
             strcmp(fmt, "f16le")) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: missing or invalid fields (seed, features, scene)", path);
  } else if ((st = wv_json_int(o, NULL, "per_pattern", 1, WV_DATASET_MAX_PER_PATTERN, 1, &info->per_pattern, err)) ||
             (st = wv_json_int(o, NULL, "spp", 1, WV_SCENE_MAX_SPP, 1, &info->spp, err)) ||
             (st = wv_json_int(feats, "features", "count", 1, 1 << 24, 1, &info->n_feat, err))) {
    wv_error_prefix(err, "%s", path);
  } else {
    char *end;
    errno = 0;
    info->seed = strtoull(seed, &end, 10);
    if (!*seed || *end || seed[0] == '-' || errno == ERANGE)
      st = wv_fail(err, WV_ERR_FORMAT, "%s: 'seed' is not an unsigned 64-bit integer", path);
    info->version = (int)version;
    info->renderer = 1; /* datasets of the first renderer lack the key */
    if (!st && (st = wv_json_int(o, NULL, "renderer", 1, 1000000, 0, &info->renderer, err)))
      wv_error_prefix(err, "%s", path);
    info->augment = 0; /* version 1 sets have none */
    if (!st && (st = wv_json_int(o, NULL, "augment", 0, 1, 0, &info->augment, err)))
      wv_error_prefix(err, "%s", path);
    json_t *dj = json_object_get(o, "draws"); /* absent: the priors */
    const char *dn = dj ? json_string_value(dj) : "prior";
    if (!st && (!dn || (strcmp(dn, "prior") && strcmp(dn, "photo")) || (dj && version < 2)))
      st = wv_fail(err, WV_ERR_FORMAT, "%s: 'draws' must be \"prior\" or \"photo\" (version 2 and 3 sets)", path);
    info->draws = dn && !strcmp(dn, "photo") ? WV_DRAWS_PHOTO : WV_DRAWS_PRIOR;
    snprintf(info->descriptor, sizeof info->descriptor, "%s", desc);
    char *sj = json_dumps(scene, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
    if (!st && (!sj || strlen(sj) >= sizeof info->scene_json))
      st = wv_fail(err, WV_ERR_FORMAT, "%s: scene description too long", path);
    if (!st) snprintf(info->scene_json, sizeof info->scene_json, "%s", sj);
    if (!st) st = wv_scene_parse(sj, path, &info->scene, err);
    free(sj);
    json_t *ts = json_object_get(o, "transmission_scene");
    if (!st && (ts != NULL) != (version == 3))
      st = wv_fail(err, WV_ERR_FORMAT, "%s: a version 3 dataset (a photo pair set) and only it has a transmission_scene", path);
    if (!st && ts) {
      info->pair = 1;
      char *tj = json_dumps(ts, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
      if (!tj || strlen(tj) >= sizeof info->tscene_json)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: transmission_scene description too long", path);
      if (!st) snprintf(info->tscene_json, sizeof info->tscene_json, "%s", tj);
      if (!st) st = wv_scene_parse(tj, path, &info->tscene, err);
      if (!st && !wv_scene_transmits(&info->tscene))
        st = wv_fail(err, WV_ERR_FORMAT, "%s: transmission_scene is not a back-lit scene", path);
      if (!st && info->n_feat % 2)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: a pair set holds two images' features: an even count", path);
      free(tj);
    }
  }
  json_decref(o);
  return st;
}

void wv_dataset_sample_name(const wv_dataset_info *info, int k, char *buf, size_t cap) {
  int np = wv_dataset_pattern_count(info);
  snprintf(buf, cap, "%s_%d", wv_dataset_pattern(info, k % np), k / np);
}

void wv_dataset_path(const char *dir, const wv_dataset_info *info, int k, const char *ext, char *buf, size_t cap) {
  char name[64];
  wv_dataset_sample_name(info, k, name, sizeof name);
  snprintf(buf, cap, "%s/samples/%s.%s", dir, name, ext);
}

wv_status wv_dataset_sample_params(const wv_dataset_info *info, int k, wv_params *p, wv_error *err) {
  /* one independent stream per sample: resuming or reordering reproduces every draw */
  int np = wv_dataset_pattern_count(info);
  uint64_t s = wv_hash4(info->seed, (uint64_t)(k % np), (uint64_t)(k / np), 0x64617461ULL);
  wv_status st = wv_params_sample_prior(wv_dataset_pattern(info, k % np), s, p, err);
  if (!st && info->draws == WV_DRAWS_PHOTO) {
    /* as the photos show cloths: yarns WV_DATASET_PHOTO_SPACING_LO .. _HI pixels apart at the
     * image centre, each type its own draw, and any noise level; streams of their own */
    double jt[2][2], mm_per_px;
    if (!wv_render_centre_scale(&info->scene, jt, &mm_per_px))
      return wv_fail(err, WV_ERR_INVALID, "the dataset's scene does not see the sample at the image centre");
    for (int y = 0; y < 2; y++) {
      double u = wv_u01d(wv_hash4(info->seed, (uint64_t)(k % np), (uint64_t)(k / np), 0x73706163ULL + (uint64_t)y));
      double px = WV_DATASET_PHOTO_SPACING_LO + (WV_DATASET_PHOTO_SPACING_HI - WV_DATASET_PHOTO_SPACING_LO) * u;
      double d = 25.4 / (px * mm_per_px);
      p->density[y] = d < WV_DENSITY_MIN ? WV_DENSITY_MIN : d > WV_DENSITY_MAX ? WV_DENSITY_MAX : d;
    }
    double u = wv_u01d(wv_hash4(info->seed, (uint64_t)(k % np), (uint64_t)(k / np), 0x6e6f6973ULL));
    int q = (int)(u * 11);
    p->noise_level = q > 10 ? 10 : q;
    st = wv_params_validate(p, err);
  }
  /* A pair set's cloths have open gaps, which the back-lit image shows: the prior has
   * none (yarn width 1), so a width of its own stream, uniform in WV_DATASET_PAIR_WIDTH_LO .. 1. */
  if (!st && info->pair)
    p->yarn_width = WV_DATASET_PAIR_WIDTH_LO + (1 - WV_DATASET_PAIR_WIDTH_LO) *
                                                  wv_u01d(wv_hash4(info->seed, (uint64_t)(k % np), (uint64_t)(k / np), 0x77696474ULL));
  return st;
}

/* Sample k's image in scene s: rendered, then through the camera (stream tag) or quantised. */
static wv_status sample_image(const wv_dataset_info *info, const wv_scene *s, const wv_params *p, int k,
                              int render_threads, const wv_footprints *fp, uint64_t tag, wv_image *img, wv_error *err) {
  wv_render_opts ro = {.spp = info->spp, .threads = render_threads, .footprints = fp};
  wv_image rad = {0};
  wv_status st = wv_render(s, p, &ro, img, info->augment ? &rad : NULL, err);
  if (st) return st;
  if (!info->augment) {
    wv_image_quantise8(img);
    return WV_OK;
  }
  /* the camera's own stream, apart from the prior draw's */
  int np = wv_dataset_pattern_count(info);
  uint64_t seed = wv_hash4(info->seed, (uint64_t)(k % np), (uint64_t)(k / np), tag);
  wv_image_free(img);
  st = wv_camera_augment_blur(s, &rad, seed, info->draws == WV_DRAWS_PHOTO ? WV_AUGMENT_PHOTO_BLUR : WV_AUGMENT_BLUR, img, err);
  wv_image_free(&rad);
  return st;
}

wv_status wv_dataset_make_sample(const char *dir, const wv_dataset_info *info, int k, int render_threads,
                                 const wv_footprints *fp, const wv_footprints *fp_t, wv_descriptor *d, float *feat,
                                 wv_error *err) {
  wv_params p;
  wv_status st = wv_dataset_sample_params(info, k, &p, err);
  if (st) return st;
  wv_image img = {0}, img_t = {0};
  if ((st = sample_image(info, &info->scene, &p, k, render_threads, fp, 0x63616d65ULL, &img, err))) return st;
  if (info->pair && (st = sample_image(info, &info->tscene, &p, k, render_threads, fp_t, 0x7472616eULL, &img_t, err))) {
    wv_image_free(&img);
    return st;
  }
  char path[4096];
  wv_dataset_path(dir, info, k, "json", path, sizeof path);
  st = wv_params_write(path, &p, err);
  wv_dataset_path(dir, info, k, "png", path, sizeof path);
  if (!st) st = wv_image_write_png(path, &img, 8, err);
  wv_dataset_path(dir, info, k, "t.png", path, sizeof path);
  if (!st && info->pair) st = wv_image_write_png(path, &img_t, 8, err);
  if (!st) st = wv_descriptor_forward(d, &img, feat, err);
  if (!st && info->pair) st = wv_descriptor_forward(d, &img_t, feat + info->n_feat / 2, err);
  /* features last: their presence marks a finished sample */
  wv_dataset_path(dir, info, k, "feat", path, sizeof path);
  if (!st) st = wv_dataset_write_features(path, feat, info->n_feat, err);
  wv_image_free(&img), wv_image_free(&img_t);
  return st;
}

/* ---- feature files: "WVFT", u32 version 1, u32 count, u32 CRC-32 of the data, f16 data ---- */
static void put_u32(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get_u32(const unsigned char *b) {
  return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

wv_status wv_dataset_write_features(const char *path, const float *x, int n, wv_error *err) {
  size_t len = 16 + 2 * (size_t)n;
  unsigned char *b = malloc(len);
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %s", path);
  for (int i = 0; i < n; i++) {
    uint16_t h = wv_f32_to_f16(x[i]);
    b[16 + 2 * i] = (unsigned char)h, b[17 + 2 * i] = (unsigned char)(h >> 8);
  }
  memcpy(b, "WVFT", 4);
  put_u32(b + 4, 1);
  put_u32(b + 8, (uint32_t)n);
  put_u32(b + 12, crc32_z(0, b + 16, 2 * (size_t)n));
  wv_status st = wv_write_file_atomic(path, b, len, err);
  free(b);
  return st;
}

wv_status wv_dataset_read_features(const char *path, int n, uint16_t *out, wv_error *err) {
  FILE *f;
  wv_status ost = wv_fopen_regular(path, &f, err);
  if (ost) return ost;
  unsigned char h[16];
  wv_status st = WV_OK;
  if (fread(h, 1, 16, f) != 16 || memcmp(h, "WVFT", 4) || get_u32(h + 4) != 1) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: not a woven feature file (bad header)", path);
  } else if (get_u32(h + 8) != (uint32_t)n) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: holds %u features, the dataset says %d", path, get_u32(h + 8), n);
  } else {
    unsigned char *b = malloc(2 * (size_t)n);
    if (!b) {
      st = wv_fail(err, WV_ERR_NOMEM, "out of memory reading %s", path);
    } else {
      size_t got = fread(b, 1, 2 * (size_t)n, f);
      if (got != 2 * (size_t)n || fgetc(f) != EOF)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: truncated or oversized feature file", path);
      else if (crc32_z(0, b, 2 * (size_t)n) != get_u32(h + 12))
        st = wv_fail(err, WV_ERR_FORMAT, "%s: checksum mismatch (corrupt feature file)", path);
      else
        for (int i = 0; i < n; i++) out[i] = (uint16_t)(b[2 * i] | b[2 * i + 1] << 8);
      free(b);
    }
  }
  fclose(f);
  return st;
}

int wv_dataset_sample_done(const char *dir, const wv_dataset_info *info, int k) {
  char p[4096];
  struct stat sb;
  wv_error e;
  wv_params prm;
  /* The parameters must read back as this sample's pattern, and the PNG must be whole
   * (its chunk checksums: cheap, no decoding). */
  wv_dataset_path(dir, info, k, "json", p, sizeof p);
  if (wv_params_read(p, &prm, &e) || strcmp(prm.pattern, wv_dataset_pattern(info, k % wv_dataset_pattern_count(info)))) return 0;
  wv_dataset_path(dir, info, k, "png", p, sizeof p);
  if (wv_png_check(p, &e)) return 0;
  wv_dataset_path(dir, info, k, "t.png", p, sizeof p);
  if (info->pair && wv_png_check(p, &e)) return 0;
  wv_dataset_path(dir, info, k, "feat", p, sizeof p);
  if (stat(p, &sb) != 0 || sb.st_size != 16 + 2 * (off_t)info->n_feat) return 0;
  uint16_t *tmp = malloc(2 * (size_t)info->n_feat);
  if (!tmp) return 0;
  int ok = wv_dataset_read_features(p, info->n_feat, tmp, &e) == WV_OK;
  free(tmp);
  return ok;
}
