/* The gradient integrator, the differentiable renderer: capture and dL/dtheta
 * in one pass (woven/grad.h).
 *
 * Per pixel, the 8-wide row loop (render/rows.c; gradient_double.c in
 * double) returns the radiance and, per yarn
 * type, the sums radiance is linear in (specular and diffuse factors) with
 * their derivatives with respect to the non-linear parameters. The sensor
 * response is per pixel, so its adjoint dL/dradiance is known as soon as the
 * pixel's radiance is: one pass, no stored image, no second render. When the
 * adjoint depends on the capture (wv_render_record), those per-pixel sums are
 * kept instead and wv_record_grad does the same accumulation afterwards. A camera blur
 * (the scene's psf_sigma) couples pixels: the response then waits for every pixel's
 * radiance, the records are always kept, and the adjoint passes through the blur's
 * transpose; each blur pass runs a row at a time over the record (wv_psf_run,
 * sensor/sensor.h), the work on each row done as it comes out. */
#include "woven/grad.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_internal.h"

#define DEG (3.14159265358979323846 / 180.0)

/* The albedos the adjoint pass weighs the per-type sums with; with the light behind
 * the cloth (transmit) the sums are the transmission's, weighed by kst and kt. */
typedef struct {
  double kd[2][3], ks[2][3], kt[2][3], kst[2][3];
  int transmit;
} wv_grad_model;

/* In float mode the floats the forward renderer uses, widened exactly. */
static void albedos_from_fabric(const wv_fabric *f, wv_grad_model *g) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      g->kd[y][c] = f->P.kd[y][c], g->ks[y][c] = f->P.ks[y][c], g->kt[y][c] = f->P.kt[y][c],
      g->kst[y][c] = f->P.kst[y][c];
}
static void albedos_from_double(const wv_shade_params_d *P, wv_grad_model *g) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      g->kd[y][c] = P->kd[y][c], g->ks[y][c] = P->ks[y][c], g->kt[y][c] = P->kt[y][c], g->kst[y][c] = P->kst[y][c];
}

/* Gradient slots per type, for the linear parameters. */
static const int KD_ID[2] = {WV_P_KD_WARP_R, WV_P_KD_WEFT_R};
static const int KS_ID[2] = {WV_P_KS_WARP_R, WV_P_KS_WEFT_R};
static const int KT_ID[2] = {WV_P_KT_WARP_R, WV_P_KT_WEFT_R};
static const int KST_ID[2] = {WV_P_KST_WARP_R, WV_P_KST_WEFT_R};
static const int KF_ID[2] = {WV_P_KF_WARP_R, WV_P_KF_WEFT_R};
static const int BETA_ID[2] = {WV_P_BETA_WARP, WV_P_BETA_WEFT};
static const int ALPHA_ID[2] = {WV_P_ALPHA_WARP, WV_P_ALPHA_WEFT};

enum { NG = WV_P_COUNT + 1 }; /* the gradient, then the dot */

/* A row's partial sums of the gradient and the dot, as named locals (they stay in
 * registers over the row); written out into the gradient's slots by sums_out. */
typedef struct {
  double df[2][3], ks[2][3]; /* per type: the diffuse (k_d, or k_t with the light behind) and specular (k_s, or
                              * k_st) albedos */
  double kf[2][3];           /* the forward band's colour (the light behind only) */
  double beta[2], alpha[2], umax, twist, blend, dot;
} row_sums;

static void sums_out(const wv_grad_model *gm, const row_sums *g, double out[NG]) {
  const int *DF_ID = gm->transmit ? KT_ID : KD_ID, *S_ID = gm->transmit ? KST_ID : KS_ID;
  memset(out, 0, NG * sizeof *out);
  for (int y = 0; y < 2; y++) {
    for (int c = 0; c < 3; c++) out[DF_ID[y] + c] = g->df[y][c], out[S_ID[y] + c] = g->ks[y][c];
    if (gm->transmit)
      for (int c = 0; c < 3; c++) out[KF_ID[y] + c] = g->kf[y][c];
    out[BETA_ID[y]] = g->beta[y], out[ALPHA_ID[y]] = g->alpha[y];
  }
  out[WV_P_UMAX_DEG] = g->umax, out[WV_P_TWIST_DEG] = g->twist, out[WV_P_BLEND] = g->blend;
  out[WV_P_COUNT] = g->dot;
}

/* Add a pixel's contribution given gr[c] = dL/dradiance_c; J: its sums / spp, per type. */
WV_INLINE void accumulate(const wv_grad_model *gm, const double *J, const double gr[3], row_sums *g) {
  const double(*kdf)[3] = gm->transmit ? gm->kt : gm->kd;  /* the diffuse sums' albedo */
  const double(*ksf)[3] = gm->transmit ? gm->kst : gm->ks; /* the specular sums' */
  for (int y = 0; y < 2; y++, J += WV_J_COUNT) {
    double ws = 0, wd = 0; /* dL/dS and dL/dDF of this type */
    for (int c = 0; c < 3; c++) {
      g->df[y][c] += gr[c] * J[WV_J_DF];
      g->ks[y][c] += gr[c] * J[WV_J_S];
      g->kf[y][c] += gr[c] * J[WV_J_F];
      ws += gr[c] * ksf[y][c];
      wd += gr[c] * kdf[y][c];
    }
    g->beta[y] += ws * J[WV_J_S_BETA] + wd * J[WV_J_DF_BETA];
    g->alpha[y] += ws * J[WV_J_S_ALPHA];
    g->umax += ws * J[WV_J_S_UMAX] + wd * J[WV_J_DF_UMAX];
    g->twist += ws * J[WV_J_S_PSI];
    g->blend += wd * J[WV_J_DF_BLEND];
  }
}

/* What the adjoint pass needs of a pixel once it is rendered. */
typedef struct {
  double cap[3];   /* the capture (in double mode the unrounded double value) */
  double slope[3]; /* d capture / d radiance reaching the sensor (after the blur), 0 where clipped */
  double rad[3];   /* the radiance, before the camera blur */
  double J[2][WV_J_COUNT]; /* the pixel's sums / spp */
} pixel_rec;

enum { NJ = 2 * WV_J_COUNT };

/* The record: per pixel, row-major, one array per quantity, so that each pass over it
 * reads only what it needs. A float-mode record keeps the capture, the radiance and
 * the sums as floats, as they are made (120 bytes a pixel in all); a double-mode one
 * keeps doubles. The arrays share one block, kept from render to render
 * (wv_render_record_into). */
struct wv_grad_record {
  int w, h, dbl, spp, threads;
  int valid;        /* 0: the last render into it failed */
  double psf_sigma; /* the scene's camera blur (0: none) */
  wv_grad_model gm;
  void *mem;        /* the block */
  size_t bytes;     /* its size */
  double *slope;    /* 3 a pixel */
  float *capf, *radf, *Jf;  /* float mode: 3, 3 and NJ a pixel; the sums before the division by spp */
  double *capd, *radd, *Jd; /* double mode: the same, the sums / spp */
};

/* Room for a W x H render in the record's block, grown when too small. */
static int rec_room(wv_grad_record *rec, int W, int H, int dbl) {
  size_t n = (size_t)W * H, v = dbl ? sizeof(double) : sizeof(float);
  size_t bytes = n * (3 * sizeof(double) + (3 + 3 + NJ) * v);
  if (bytes > rec->bytes) {
    free(rec->mem);
    rec->bytes = 0;
    if (!(rec->mem = malloc(bytes))) return 0;
    rec->bytes = bytes;
  }
  rec->slope = rec->mem;
  char *f = (char *)(rec->slope + 3 * n);
  rec->capf = rec->radf = rec->Jf = NULL, rec->capd = rec->radd = rec->Jd = NULL;
  if (dbl) rec->capd = (double *)f, rec->radd = rec->capd + 3 * n, rec->Jd = rec->radd + 3 * n;
  else rec->capf = (float *)f, rec->radf = rec->capf + 3 * n, rec->Jf = rec->radf + 3 * n;
  return 1;
}

/* Pixel k's rendered values into the record (the response's too unless a blur follows). */
static void rec_put(wv_grad_record *rec, size_t k, const wv_grad_pixel *pix, const pixel_rec *pr, int responded) {
  for (int c = 0; c < 3; c++) {
    if (responded) rec->slope[3 * k + c] = pr->slope[c];
    if (rec->dbl) {
      rec->radd[3 * k + c] = pr->rad[c];
      if (responded) rec->capd[3 * k + c] = pr->cap[c];
    } else {
      rec->radf[3 * k + c] = (float)pix->rad[c];
      if (responded) rec->capf[3 * k + c] = (float)pr->cap[c];
    }
  }
  for (int y = 0; y < 2; y++)
    for (int j = 0; j < WV_J_COUNT; j++) {
      if (rec->dbl) rec->Jd[NJ * k + y * WV_J_COUNT + j] = pr->J[y][j];
      else rec->Jf[NJ * k + y * WV_J_COUNT + j] = (float)pix->J[y][j];
    }
}

/* v / spp; the product by inv = 1 / spp where that is the same number (spp a power of
 * two), as it is made for every sum of every pixel (inv made once, outside the loops). */
static double per_sample(double v, int spp, double inv) { return spp & (spp - 1) ? v / spp : v * inv; }

/* Sensor response of one pixel and its slope in double mode. */
static void respond_d(const wv_scene *s, int px, int py, const double rad[3], float cap[3], pixel_rec *rec) {
  double m = wv_response_mask(s, px, py);
  for (int c = 0; c < 3; c++) {
    rec->cap[c] = wv_respond_d(s, m, rad[c], &rec->slope[c]);
    cap[c] = (float)rec->cap[c];
  }
}

/* Pixels a block of the float response (respond_f). */
#define RESPOND_MAX 64

/* Sensor response of n <= RESPOND_MAX pixels from (px, py), their radiance in float, and
 * their slopes: wv_scene_response's arithmetic, so the capture is wv_render's. */
static void respond_f(const wv_scene *s, int px, int py, int n, const float (*rad)[3], float (*cap)[3],
                      double (*slope)[3]) {
  double mask[RESPOND_MAX];
  wv_response_mask_row(s, px, py, n, mask);
  wv_respond_n(s, mask, n, 3, &rad[0][0], &cap[0][0], &slope[0][0]);
}

/* The pixel's radiance and, with sums, its sums / spp. */
static void keep(int spp, double inv, const wv_grad_pixel *pix, pixel_rec *rec, int sums) {
  for (int c = 0; c < 3; c++) rec->rad[c] = pix->rad[c];
  if (sums)
    for (int y = 0; y < 2; y++)
      for (int j = 0; j < WV_J_COUNT; j++) rec->J[y][j] = per_sample(pix->J[y][j], spp, inv);
}

/* Add a pixel's contribution and its dot term; with gb != NULL (a camera blur) gb holds
 * dL/dradiance already, made by the blur's adjoint. */
WV_INLINE void backward_pixel(const wv_grad_model *gm, const double cap[3], const double slope[3], const double *J,
                              const float dc[3], const double *gb, row_sums *g) {
  double gr[3];
  for (int c = 0; c < 3; c++) {
    g->dot += (double)dc[c] * cap[c];
    gr[c] = gb ? gb[c] : (double)dc[c] * slope[c];
  }
  accumulate(gm, J, gr, g);
}

/* Row y of a record against its adjoint (gb: the row's dL/dradiance with a blur, else
 * NULL): its partials into out[NG]. */
static void backward_row(const wv_grad_record *rec, const wv_image *dcap, int y, const double *gb, double *out) {
  row_sums g;
  memset(&g, 0, sizeof g);
  double inv = 1.0 / rec->spp;
  for (int i = 0; i < rec->w; i++) {
    size_t k = (size_t)y * rec->w + i;
    double cap[3], J[NJ];
    if (rec->dbl) {
      for (int c = 0; c < 3; c++) cap[c] = rec->capd[3 * k + c];
      memcpy(J, rec->Jd + NJ * k, sizeof J);
    } else {
      const float *Jf = rec->Jf + NJ * k;
      for (int c = 0; c < 3; c++) cap[c] = rec->capf[3 * k + c];
      for (int j = 0; j < NJ; j++) J[j] = per_sample(Jf[j], rec->spp, inv);
    }
    backward_pixel(&rec->gm, cap, rec->slope + 3 * k, J, wv_image_px(dcap, i, y), gb ? gb + 3 * i : NULL, &g);
  }
  sums_out(&rec->gm, &g, out);
}

/* The camera blur's passes over a record, row by row (wv_psf_run): the radiance or
 * slope .* dL/dcapture in, and out the response (into the record and the capture), the
 * gradient's per-row partials or dL/dsigma's. */
typedef struct {
  const wv_scene *s;
  const wv_grad_record *rec;
  wv_grad_record *out;   /* the response pass's record */
  int x0, y0;            /* the window's corner in the image */
  wv_image *capture;     /* may be NULL */
  const wv_image *dcap;  /* dL/dcapture */
  double *rows;          /* per-row partials */
} blur_pass;

static void load_radiance(void *ctx, int y, double *row) {
  const wv_grad_record *rec = ((const blur_pass *)ctx)->rec;
  size_t m = (size_t)rec->w * 3, o = (size_t)y * m;
  if (rec->dbl) memcpy(row, rec->radd + o, m * sizeof *row);
  else
    for (size_t e = 0; e < m; e++) row[e] = rec->radf[o + e];
}

/* With a camera blur the response acts on the blurred radiance, which needs every
 * pixel's radiance first: the records' captures and slopes are made after the render,
 * a row at a time (wv_scene_capture's arithmetic). */
static void store_response(void *ctx, int y, const double *row) {
  enum { B = RESPOND_MAX }; /* pixels a block: the response's powers are taken a block at once */
  const blur_pass *bp = ctx;
  wv_grad_record *rec = bp->out;
  for (int i0 = 0; i0 < rec->w; i0 += B) {
    int n = rec->w - i0 < B ? rec->w - i0 : B;
    float b[B][3], cap[B][3];
    double sl[B][3];
    if (rec->dbl) {
      for (int i = 0; i < n; i++) {
        pixel_rec pr;
        respond_d(bp->s, bp->x0 + i0 + i, bp->y0 + y, row + 3 * (i0 + i), cap[i], &pr);
        for (int c = 0; c < 3; c++)
          sl[i][c] = pr.slope[c], rec->capd[3 * ((size_t)y * rec->w + i0 + i) + c] = pr.cap[c];
      }
    } else {
      for (int i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) b[i][c] = (float)row[3 * (i0 + i) + c];
      respond_f(bp->s, bp->x0 + i0, bp->y0 + y, n, (const float(*)[3])b, cap, sl);
    }
    for (int i = 0; i < n; i++) {
      size_t k = (size_t)y * rec->w + i0 + i;
      for (int c = 0; c < 3; c++) {
        rec->slope[3 * k + c] = sl[i][c];
        if (!rec->dbl) rec->capf[3 * k + c] = cap[i][c];
      }
      if (bp->capture) memcpy(wv_image_px(bp->capture, i0 + i, y), cap[i], sizeof cap[i]);
    }
  }
}

/* slope .* dL/dcapture: what the blur's adjoint takes. */
static void load_adjoint(void *ctx, int y, double *row) {
  const blur_pass *bp = ctx;
  size_t m = (size_t)bp->rec->w * 3, o = (size_t)y * m;
  for (size_t e = 0; e < m; e++) row[e] = (double)bp->dcap->data[o + e] * bp->rec->slope[o + e];
}

/* dL/dradiance = K^T (slope .* dL/dcapture) of a row: its pixels' contributions. */
static void store_gradient(void *ctx, int y, const double *gb) {
  const blur_pass *bp = ctx;
  backward_row(bp->rec, bp->dcap, y, gb, bp->rows + (size_t)y * NG);
}

/* dL/dsigma of a row: sum dL/dcapture .* slope .* (dK/dsigma radiance). */
static void store_dsigma(void *ctx, int y, const double *dk) {
  const blur_pass *bp = ctx;
  size_t m = (size_t)bp->rec->w * 3, o = (size_t)y * m;
  double sum = 0;
  for (size_t e = 0; e < m; e++) sum += (double)bp->dcap->data[o + e] * bp->rec->slope[o + e] * dk[e];
  bp->rows[y] = sum;
}

static wv_status blur_run(wv_psf_op op, blur_pass *bp, void (*load)(void *, int, double *),
                          void (*store)(void *, int, const double *), wv_error *err) {
  const wv_grad_record *rec = bp->rec;
  wv_psf_stream ps = {.op = op, .sigma = rec->psf_sigma, .w = rec->w, .h = rec->h, .c = 3,
                      .threads = rec->threads, .load = load, .store = store, .ctx = bp};
  return wv_psf_run(&ps, err);
}

/* The totals out, angles converted from per radian to per degree. */
static void output(const double total[NG], double grad[WV_P_COUNT], double *dot) {
  for (int i = 0; i < WV_P_COUNT; i++) grad[i] = total[i];
  grad[WV_P_UMAX_DEG] *= DEG;
  grad[WV_P_TWIST_DEG] *= DEG;
  if (dot) *dot = total[WV_P_COUNT];
}

/* The render: either with an adjoint (fused: gradient rows out, nothing kept)
 * or without (every pixel kept in rec, a record made here or reused). */
static wv_status run(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_grad_opts *go,
                     const wv_image *dcap, double grad[WV_P_COUNT], double *dot, wv_image *capture_out,
                     wv_grad_record *rec, wv_error *err) {
  if (capture_out) memset(capture_out, 0, sizeof *capture_out);
  if (rec) rec->valid = 0;
  if (!s || !p) return wv_fail(err, WV_ERR_INVALID, "render_grad: a scene and parameters are required");
  if (s->psf_sigma > 0 && !rec) {
    /* the blur couples pixels: record every pixel, then run the adjoint over the records */
    wv_grad_record *r = calloc(1, sizeof *r);
    if (!r) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a gradient record");
    wv_status st = run(s, p, opt, go, NULL, NULL, NULL, capture_out, r, err);
    if (!st) st = wv_record_grad(r, dcap, grad, dot, err);
    wv_record_free(r);
    if (st && capture_out) wv_image_free(capture_out);
    return st;
  }
  int x0 = 0, y0 = 0, W = s->width, H = s->height, dbl = go && go->double_precision;
  if (go && (go->width || go->height)) {
    x0 = go->x0, y0 = go->y0, W = go->width, H = go->height;
    if (W < 1 || H < 1 || x0 < 0 || y0 < 0 || x0 > s->width - W || y0 > s->height - H)
      return wv_fail(err, WV_ERR_INVALID, "window %d x %d at (%d, %d) is not inside the %d x %d image", W, H, x0,
                     y0, s->width, s->height);
  }
  wv_fabric fab;
  int spp;
  wv_status st = wv_render_setup(s, p, opt, W, H, &fab, &spp, err);
  if (st) return st;
  wv_camera_rig rig;
  if ((st = wv_rig_prepare_opts(s, opt, &rig, err))) return st;
  if (!rec && (!dcap || !dcap->data || dcap->w != W || dcap->h != H || dcap->c != 3))
    return wv_fail(err, WV_ERR_INVALID, "dL/dcapture must be a %d x %d RGB image (got %d x %d x %d)", W, H,
                   dcap ? dcap->w : 0, dcap ? dcap->h : 0, dcap ? dcap->c : 0);

  wv_grad_model gm;
  wv_shade_params_d Pd; /* double mode: the parameters in double */
  if (dbl) {
    wv_shade_params_double(p, &Pd);
    albedos_from_double(&Pd, &gm);
  } else {
    albedos_from_fabric(&fab, &gm);
  }
  gm.transmit = rig.transmit;

  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  double *rows = NULL;
  if (rec) {
    if (!rec_room(rec, W, H, dbl))
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for the derivatives of %d x %d pixels", W, H);
    rec->w = W, rec->h = H, rec->dbl = dbl, rec->spp = spp, rec->gm = gm, rec->psf_sigma = s->psf_sigma;
    rec->threads = threads;
  } else if (!(rows = calloc((size_t)H * NG, sizeof *rows))) {
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for %d gradient rows", H);
  }
  if (capture_out && (st = wv_image_alloc(capture_out, W, H, 3, err))) {
    free(rows);
    return st;
  }
  int blur = s->psf_sigma > 0, rows_done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int r = 0; r < H; r++) {
    if (opt && opt->progress && omp_get_thread_num() == 0) {
      int d;
#pragma omp atomic read
      d = rows_done;
      opt->progress(opt->progress_user, (double)d / H);
    }
    wv_grad_pixel pix[8];
    double inv = 1.0 / spp;
    row_sums g;
    memset(&g, 0, sizeof g);
    float crad[8][3], ccap[8][3]; /* float mode without a blur: the chunk's response */
    double cslope[8][3];
    for (int i = 0; i < W; i++) {
      if (i % 8 == 0 && !dbl) {
        int n = W - i < 8 ? W - i : 8;
        wv_render_row(&rig, &fab, y0 + r, x0 + i, n, spp, NULL, pix);
        if (!blur) {
          for (int k = 0; k < n; k++)
            for (int c = 0; c < 3; c++) crad[k][c] = (float)pix[k].rad[c];
          respond_f(s, x0 + i, y0 + r, n, (const float(*)[3])crad, ccap, cslope);
        }
      }
      if (dbl) wv_grad_pixel_d(&rig, &fab, &Pd, x0 + i, y0 + r, spp, &pix[i % 8]);
      pixel_rec pr;
      float cap[3];
      keep(spp, inv, &pix[i % 8], &pr, rows || dbl); /* a float record keeps the sums as made */
      /* with a camera blur the response comes after the loop, on the blurred radiance */
      if (!blur && dbl) respond_d(s, x0 + i, y0 + r, pr.rad, cap, &pr);
      if (!blur && !dbl)
        for (int c = 0; c < 3; c++) cap[c] = ccap[i % 8][c], pr.cap[c] = cap[c], pr.slope[c] = cslope[i % 8][c];
      if (rec) rec_put(rec, (size_t)r * W + i, &pix[i % 8], &pr, !blur);
      if (blur) continue;
      if (capture_out) memcpy(wv_image_px(capture_out, i, r), cap, sizeof cap);
      if (rows) backward_pixel(&gm, pr.cap, pr.slope, &pr.J[0][0], wv_image_px(dcap, i, r), NULL, &g);
    }
    if (rows) sums_out(&gm, &g, rows + (size_t)r * NG);
#pragma omp atomic update
    rows_done++;
  }
  if (opt && opt->progress) opt->progress(opt->progress_user, 1.0);
  if (rec && blur) {
    blur_pass bp = {.s = s, .rec = rec, .out = rec, .x0 = x0, .y0 = y0, .capture = capture_out};
    if ((st = blur_run(WV_PSF_K, &bp, load_radiance, store_response, err))) {
      if (capture_out) wv_image_free(capture_out);
      return st;
    }
  }
  if (rows) { /* reduce in row order: the sum does not depend on the thread schedule */
    double total[NG];
    memset(total, 0, sizeof total);
    for (int r = 0; r < H; r++)
      for (int i = 0; i < NG; i++) total[i] += rows[(size_t)r * NG + i];
    output(total, grad, dot);
    free(rows);
  }
  if (rec) rec->valid = 1;
  return WV_OK;
}

wv_status wv_render_grad_ex(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                            const wv_grad_opts *go, const wv_image *dcap, double grad[WV_P_COUNT], double *dot,
                            wv_image *capture_out, wv_error *err) {
  if (!grad) return wv_fail(err, WV_ERR_INVALID, "render_grad: no gradient array");
  return run(s, p, opt, go, dcap, grad, dot, capture_out, NULL, err);
}

wv_status wv_render_record_into(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                                const wv_grad_opts *g, wv_image *capture, wv_grad_record **rec, wv_error *err) {
  if (!rec) return wv_fail(err, WV_ERR_INVALID, "render_record: no record pointer");
  if (!*rec && !(*rec = calloc(1, sizeof **rec)))
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a gradient record");
  return run(s, p, opt, g, NULL, NULL, NULL, capture, *rec, err);
}

wv_status wv_render_record(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                           const wv_grad_opts *g, wv_image *capture, wv_grad_record **rec, wv_error *err) {
  if (!rec) return wv_fail(err, WV_ERR_INVALID, "render_record: no record pointer");
  *rec = NULL;
  wv_status st = wv_render_record_into(s, p, opt, g, capture, rec, err);
  if (st) {
    wv_record_free(*rec);
    *rec = NULL;
  }
  return st;
}

/* A record and an adjoint that fit it. */
static wv_status record_check(const wv_grad_record *rec, const wv_image *dcap, const char *what, wv_error *err) {
  if (!rec->valid) return wv_fail(err, WV_ERR_INVALID, "%s: the record holds no render (its render failed)", what);
  if (!dcap || !dcap->data || dcap->w != rec->w || dcap->h != rec->h || dcap->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "dL/dcapture must be a %d x %d RGB image (got %d x %d x %d)", rec->w,
                   rec->h, dcap ? dcap->w : 0, dcap ? dcap->h : 0, dcap ? dcap->c : 0);
  return WV_OK;
}

wv_status wv_record_grad(const wv_grad_record *rec, const wv_image *dcap, double grad[WV_P_COUNT], double *dot,
                         wv_error *err) {
  if (!rec || !grad) return wv_fail(err, WV_ERR_INVALID, "record_grad: a record and a gradient array are required");
  wv_status st = record_check(rec, dcap, "record_grad", err);
  if (st) return st;
  /* The same per-row partials as the fused pass, made in parallel and summed in row order:
   * bitwise the same result whatever the threads. */
  double *rows = calloc((size_t)rec->h * NG, sizeof *rows);
  if (!rows) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %d gradient rows", rec->h);
  if (rec->psf_sigma > 0) {
    /* dL/dradiance = K^T (slope .* dL/dcapture), K the camera blur, a row at a time */
    blur_pass bp = {.rec = rec, .dcap = dcap, .rows = rows};
    if ((st = blur_run(WV_PSF_KT, &bp, load_adjoint, store_gradient, err))) {
      free(rows);
      return st;
    }
  } else {
#pragma omp parallel for schedule(static) num_threads(rec->threads)
    for (int r = 0; r < rec->h; r++) backward_row(rec, dcap, r, NULL, rows + (size_t)r * NG);
  }
  double total[NG];
  memset(total, 0, sizeof total);
  for (int r = 0; r < rec->h; r++)
    for (int k = 0; k < NG; k++) total[k] += rows[(size_t)r * NG + k];
  free(rows);
  output(total, grad, dot);
  return WV_OK;
}

wv_status wv_record_grad_psf(const wv_grad_record *rec, const wv_image *dcap, double *dsigma, wv_error *err) {
  if (!rec || !dsigma) return wv_fail(err, WV_ERR_INVALID, "record_grad_psf: a record and an output are required");
  wv_status st = record_check(rec, dcap, "record_grad_psf", err);
  if (st) return st;
  *dsigma = 0;
  if (!(rec->psf_sigma > 0)) return WV_OK;
  /* capture = respond(K radiance): dL/dsigma = sum dL/dcapture .* slope .* (dK/dsigma radiance),
   * dK/dsigma = dKy Kx + Ky dKx made a row at a time, summed per row, then in row order */
  double *rows = calloc((size_t)rec->h, sizeof *rows);
  if (!rows) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %d rows of the camera blur's derivative", rec->h);
  blur_pass bp = {.rec = rec, .dcap = dcap, .rows = rows};
  if (!(st = blur_run(WV_PSF_DK, &bp, load_radiance, store_dsigma, err))) {
    double sum = 0;
    for (int r = 0; r < rec->h; r++) sum += rows[r];
    *dsigma = sum;
  }
  free(rows);
  return st;
}

void wv_record_free(wv_grad_record *rec) {
  if (!rec) return;
  free(rec->mem);
  free(rec);
}

wv_status wv_render_grad(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_image *dcap,
                         double grad[WV_P_COUNT], wv_image *capture_out, wv_error *err) {
  return wv_render_grad_ex(s, p, opt, NULL, dcap, grad, NULL, capture_out, err);
}

wv_status wv_grad_check(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_grad_opts *g,
                        const wv_image *dcap, double rel_step, wv_grad_check_entry out[WV_P_COUNT], wv_error *err) {
  if (!(rel_step > 0 && rel_step < 0.5)) return wv_fail(err, WV_ERR_INVALID, "rel_step %g is outside (0, 0.5)", rel_step);
  double grad[WV_P_COUNT], dummy[WV_P_COUNT];
  wv_status st = wv_render_grad_ex(s, p, opt, g, dcap, grad, NULL, NULL, err);
  if (st) return st;
  for (int i = 0; i < WV_P_COUNT; i++) {
    double lo, hi, x = wv_param_get(p, i);
    wv_param_range(i, &lo, &hi);
    double h = rel_step * (hi - lo), xp = x + h, xm = x - h;
    if (xp > hi) xp = x; /* at a range edge: one-sided, inward */
    if (xm < lo) xm = x;
    wv_params q = *p;
    double Lp, Lm;
    wv_param_set(&q, i, xp);
    if ((st = wv_render_grad_ex(s, &q, opt, g, dcap, dummy, &Lp, NULL, err))) return st;
    wv_param_set(&q, i, xm);
    if ((st = wv_render_grad_ex(s, &q, opt, g, dcap, dummy, &Lm, NULL, err))) return st;
    double num = (Lp - Lm) / (xp - xm), a = grad[i];
    double scale = fabs(a) > fabs(num) ? fabs(a) : fabs(num);
    out[i].analytic = a, out[i].numeric = num;
    out[i].rel_err = scale > 0 ? fabs(a - num) / scale : 0.0;
  }
  return WV_OK;
}
