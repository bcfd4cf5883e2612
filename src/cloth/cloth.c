/* The cloth simulation (woven/cloth.h): position-based dynamics on a square grid
 * of particles with stretch, shear and bending constraints, obstacle and floor
 * collisions with friction, and self-distance through a spatial hash. */
#include "woven/cloth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/hash.h"

void wv_cloth_defaults(wv_cloth_opts *o) {
  memset(o, 0, sizeof *o);
  o->res = 64;
  o->size_mm = 300;
  o->drop_height_mm = 200;
  o->rotation_deg = 20;
  o->offset_mm[0] = 12, o->offset_mm[1] = -8;
  o->obstacle = WV_OBSTACLE_SPHERE;
  o->centre_mm[1] = 80, o->radius_mm = 80;
  o->box_min_mm[0] = -200, o->box_min_mm[1] = 0, o->box_min_mm[2] = -200;
  o->box_max_mm[0] = 60, o->box_max_mm[1] = 120, o->box_max_mm[2] = 200;
  o->floor_y = 0;
  o->seconds = 3;
  o->steps_per_second = 600;
  o->iterations = 8;
  o->bend_stiffness = 0.05;
  o->friction = 0.5;
  o->seed = 1;
}

typedef struct {
  int i, j;
  float rest, k;
} constraint;

typedef struct {
  int n;            /* particles */
  float *x, *p, *v; /* positions, predictions, velocities: n x 3 */
  unsigned char *contact;
} state;

static void project(state *s, const constraint *c) {
  float *a = s->p + 3 * c->i, *b = s->p + 3 * c->j;
  float d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (l < 1e-9f) return;
  float f = 0.5f * c->k * (l - c->rest) / l;
  for (int k = 0; k < 3; k++) a[k] += f * d[k], b[k] -= f * d[k];
}

/* Pushes particle q out of the obstacles and above the floor (thickness h). */
static int collide(const wv_cloth_opts *o, float *q, float h) {
  int hit = 0;
  if (o->obstacle == WV_OBSTACLE_SPHERE) {
    float d[3], r = (float)o->radius_mm + h;
    for (int k = 0; k < 3; k++) d[k] = q[k] - (float)o->centre_mm[k];
    float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (l < r && l > 1e-9f) {
      for (int k = 0; k < 3; k++) q[k] = (float)o->centre_mm[k] + d[k] * (r / l);
      hit = 1;
    }
  } else if (o->obstacle == WV_OBSTACLE_BOX) {
    float best = INFINITY;
    int axis = -1, up = 0;
    for (int k = 0; k < 3; k++) {
      float lo = (float)o->box_min_mm[k] - h, hi = (float)o->box_max_mm[k] + h;
      if (q[k] <= lo || q[k] >= hi) {
        axis = -2;
        break;
      }
      if (q[k] - lo < best) best = q[k] - lo, axis = k, up = 0;
      if (hi - q[k] < best) best = hi - q[k], axis = k, up = 1;
    }
    if (axis >= 0) {
      q[axis] = up ? (float)o->box_max_mm[axis] + h : (float)o->box_min_mm[axis] - h;
      hit = 1;
    }
  }
  if (q[1] < (float)o->floor_y + h) q[1] = (float)o->floor_y + h, hit = 1;
  return hit;
}

/* Particles closer than dmin that are not grid neighbours (within 2 cells) are
 * pushed apart: a uniform grid of cell dmin, hashed into buckets. */
static void self_distance(state *s, int res, float dmin, int *head, int *next, int nb) {
  int w = res + 1;
  float inv = 1.0f / dmin;
  for (int b = 0; b < nb; b++) head[b] = -1;
  for (int i = s->n - 1; i >= 0; i--) {
    const float *q = s->p + 3 * i;
    uint64_t h = wv_hash4((uint64_t)(int64_t)floorf(q[0] * inv), (uint64_t)(int64_t)floorf(q[1] * inv),
                          (uint64_t)(int64_t)floorf(q[2] * inv), 0);
    int b = (int)(h % (uint64_t)nb);
    next[i] = head[b], head[b] = i;
  }
  for (int i = 0; i < s->n; i++) {
    float *a = s->p + 3 * i;
    int64_t cx = (int64_t)floorf(a[0] * inv), cy = (int64_t)floorf(a[1] * inv), cz = (int64_t)floorf(a[2] * inv);
    for (int dz = -1; dz <= 1; dz++)
      for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
          uint64_t h = wv_hash4((uint64_t)(cx + dx), (uint64_t)(cy + dy), (uint64_t)(cz + dz), 0);
          for (int j = head[h % (uint64_t)nb]; j >= 0; j = next[j]) {
            if (j <= i || (abs(j % w - i % w) <= 2 && abs(j / w - i / w) <= 2)) continue;
            float *b = s->p + 3 * j, d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            float l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            if (l2 >= dmin * dmin || l2 < 1e-18f) continue;
            float l = sqrtf(l2), f = 0.5f * (dmin - l) / l;
            for (int k = 0; k < 3; k++) a[k] -= f * d[k], b[k] += f * d[k];
          }
        }
  }
}

wv_status wv_cloth_drape(const wv_cloth_opts *o, wv_mesh *out, wv_error *err) {
  memset(out, 0, sizeof *out);
  if (o->res < 2 || o->res > 512) return wv_fail(err, WV_ERR_INVALID, "cloth resolution %d is outside 2..512", o->res);
  if (!(o->size_mm > 0 && o->size_mm < 1e6)) return wv_fail(err, WV_ERR_INVALID, "cloth size must be positive");
  if (!(o->seconds >= 0 && o->seconds <= 60) || o->steps_per_second < 10 || o->steps_per_second > 100000 ||
      o->iterations < 1 || o->iterations > 100)
    return wv_fail(err, WV_ERR_INVALID, "cloth timing: seconds 0..60, steps per second 10..100000, iterations 1..100");
  if (o->obstacle == WV_OBSTACLE_SPHERE && !(o->radius_mm > 0))
    return wv_fail(err, WV_ERR_INVALID, "the sphere's radius must be positive");
  int w = o->res + 1, n = w * w, nt = 2 * o->res * o->res;
  wv_status st = wv_mesh_alloc(out, n, nt, 1, 0, err);
  if (st) return st;
  state s = {n, malloc(sizeof(float) * 3 * (size_t)n), malloc(sizeof(float) * 3 * (size_t)n),
             calloc((size_t)n * 3, sizeof(float)), calloc((size_t)n, 1)};
  int ncons = 0, cap = 6 * n, nb = 2 * n;
  constraint *cons = malloc(sizeof *cons * (size_t)cap);
  int *head = malloc(sizeof(int) * (size_t)nb), *next = malloc(sizeof(int) * (size_t)n);
  if (!s.x || !s.p || !s.v || !s.contact || !cons || !head || !next) {
    st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the cloth");
    goto done;
  }
  float spacing = (float)(o->size_mm / o->res);
  double a = o->rotation_deg * 3.14159265358979323846 / 180, ca = cos(a), sa = sin(a);
  for (int j = 0; j < w; j++)
    for (int i = 0; i < w; i++) {
      int k = j * w + i;
      double lx = (i / (double)o->res - 0.5) * o->size_mm, lz = (j / (double)o->res - 0.5) * o->size_mm;
      float jitter = 0.02f * (wv_u01(wv_hash2((uint64_t)k, 7, o->seed)) - 0.5f);
      s.x[3 * k] = (float)(ca * lx - sa * lz + o->offset_mm[0]);
      s.x[3 * k + 1] = (float)o->drop_height_mm + jitter;
      s.x[3 * k + 2] = (float)(sa * lx + ca * lz + o->offset_mm[1]);
      /* u along the first side; v against z, so that u x v points up (the top face is the front) */
      out->uv[2 * k] = (float)i / o->res, out->uv[2 * k + 1] = 1.0f - (float)j / o->res;
    }
  /* stretch (1 apart), shear (diagonals), bending (2 apart) */
  static const int off[6][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}, {2, 0}, {0, 2}};
  for (int j = 0; j < w; j++)
    for (int i = 0; i < w; i++)
      for (int c = 0; c < 6; c++) {
        int i2 = i + off[c][0], j2 = j + off[c][1];
        if (i2 < 0 || i2 >= w || j2 < 0 || j2 >= w) continue;
        float rest = spacing * sqrtf((float)(off[c][0] * off[c][0] + off[c][1] * off[c][1]));
        cons[ncons++] = (constraint){j * w + i, j2 * w + i2, rest, c < 2 ? 1.0f : c < 4 ? 0.6f : (float)o->bend_stiffness};
      }
  float dt = 1.0f / (float)o->steps_per_second, h = 0.35f * spacing, dmin = 0.6f * spacing;
  float damp = powf(0.2f, dt); /* velocities lose 80% a second: a calm drape */
  int steps = (int)lround(o->seconds * o->steps_per_second);
  for (int step = 0; step < steps; step++) {
    for (int k = 0; k < n; k++) {
      s.v[3 * k + 1] -= 9810.0f * dt;
      for (int c = 0; c < 3; c++) {
        s.v[3 * k + c] *= damp;
        s.p[3 * k + c] = s.x[3 * k + c] + dt * s.v[3 * k + c];
      }
    }
    for (int it = 0; it < o->iterations; it++) {
      for (int c = 0; c < ncons; c++) project(&s, &cons[c]);
      for (int k = 0; k < n; k++) s.contact[k] = (unsigned char)collide(o, s.p + 3 * k, h);
    }
    self_distance(&s, o->res, dmin, head, next, nb);
    for (int k = 0; k < n; k++) {
      float *q = s.p + 3 * k, *x = s.x + 3 * k;
      if (collide(o, q, h) || s.contact[k]) /* friction: keep only part of the sliding motion */
        for (int c = 0; c < 3; c++) q[c] = x[c] + (1.0f - (float)o->friction) * (q[c] - x[c]);
      for (int c = 0; c < 3; c++) {
        s.v[3 * k + c] = (q[c] - x[c]) / dt;
        x[c] = q[c];
      }
    }
  }
  for (int k = 0; k < n; k++) {
    for (int c = 0; c < 3; c++)
      if (!isfinite(s.x[3 * k + c])) {
        st = wv_fail(err, WV_ERR_INTERNAL, "the cloth simulation diverged (try more steps per second)");
        goto done;
      }
    memcpy(out->pos + 3 * k, s.x + 3 * k, 3 * sizeof(float));
  }
  uint32_t *ix = out->idx;
  for (int j = 0; j < o->res; j++)
    for (int i = 0; i < o->res; i++) {
      uint32_t p00 = (uint32_t)(j * w + i), p10 = p00 + 1, p01 = p00 + (uint32_t)w, p11 = p01 + 1;
      *ix++ = p00, *ix++ = p11, *ix++ = p10; /* wound so that the normal is u x v */
      *ix++ = p00, *ix++ = p01, *ix++ = p11;
    }
  memset(out->nrm, 0, sizeof(float) * 3 * (size_t)n);
  for (int t = 0; t < nt; t++) { /* area-weighted smooth normals */
    const uint32_t *q = out->idx + 3 * t;
    float *p0 = out->pos + 3 * q[0], *p1 = out->pos + 3 * q[1], *p2 = out->pos + 3 * q[2], e1[3], e2[3];
    for (int c = 0; c < 3; c++) e1[c] = p1[c] - p0[c], e2[c] = p2[c] - p0[c];
    float nn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    for (int v = 0; v < 3; v++)
      for (int c = 0; c < 3; c++) out->nrm[3 * q[v] + c] += nn[c];
  }
  for (int k = 0; k < n; k++) {
    float *v = out->nrm + 3 * k, l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
    else v[1] = 1;
  }
done:
  free(s.x), free(s.p), free(s.v), free(s.contact), free(cons), free(head), free(next);
  if (st) wv_mesh_free(out);
  return st;
}
