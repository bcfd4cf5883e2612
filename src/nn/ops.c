/* Element-wise, pooling, Gram, fully connected and loss ops (nn.h). */
#include <math.h>
#include <string.h>

#include "woven/nn.h"

/* Element-wise loops fork only when the work pays for it. */
#define PAR_MIN 32768

void wv_nn_bias_forward(float *y, const float *x, const float *b, int n, int c, int hw) {
#pragma omp parallel for schedule(static) if ((size_t)n * c * hw > PAR_MIN)
  for (int p = 0; p < n * c; p++) {
    const float *xs = x + (size_t)p * hw;
    float *ys = y + (size_t)p * hw, bb = b[p % c];
    for (int i = 0; i < hw; i++) ys[i] = xs[i] + bb;
  }
}

void wv_nn_bias_backward(float *dx, float *db, const float *dy, int n, int c, int hw) {
  if (db) {
#pragma omp parallel for schedule(static) if ((size_t)n * c * hw > PAR_MIN)
    for (int ch = 0; ch < c; ch++) {
      double s = 0.0;
      for (int img = 0; img < n; img++) {
        const float *d = dy + ((size_t)img * c + ch) * hw;
        for (int i = 0; i < hw; i++) s += d[i];
      }
      db[ch] += (float)s;
    }
  }
  if (dx) {
    size_t total = (size_t)n * c * hw;
#pragma omp parallel for simd schedule(static) if (total > PAR_MIN)
    for (size_t i = 0; i < total; i++) dx[i] += dy[i];
  }
}

void wv_nn_relu_forward(float *y, const float *x, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) y[i] = x[i] > 0.0f ? x[i] : 0.0f;
}

void wv_nn_relu_backward(float *dx, const float *x, const float *dy, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) dx[i] += x[i] > 0.0f ? dy[i] : 0.0f;
}

void wv_nn_relu_mask(float *d, const float *y, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) d[i] = y[i] > 0.0f ? d[i] : 0.0f; /* a select, not a branch */
}

void wv_nn_leaky_relu_forward(float *y, const float *x, float slope, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) y[i] = x[i] > 0.0f ? x[i] : slope * x[i];
}

void wv_nn_leaky_relu_backward(float *dx, const float *x, const float *dy, float slope, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) dx[i] += x[i] > 0.0f ? dy[i] : slope * dy[i];
}

void wv_nn_avgpool2_forward(float *y, const float *x, int nc, int h, int w) {
  int oh = h / 2, ow = w / 2;
#pragma omp parallel for schedule(static) if ((size_t)nc * h * w > PAR_MIN)
  for (int r = 0; r < nc * oh; r++) {
    int p = r / oh, oy = r % oh;
    const float *a = x + ((size_t)p * h + 2 * oy) * w, *b = a + w;
    float *d = y + ((size_t)p * oh + oy) * ow;
    for (int ox = 0; ox < ow; ox++)
      d[ox] = 0.25f * (a[2 * ox] + a[2 * ox + 1] + b[2 * ox] + b[2 * ox + 1]);
  }
}

void wv_nn_avgpool2_backward(float *dx, const float *dy, int nc, int h, int w) {
  int oh = h / 2, ow = w / 2;
#pragma omp parallel for schedule(static) if ((size_t)nc * h * w > PAR_MIN)
  for (int r = 0; r < nc * oh; r++) {
    int p = r / oh, oy = r % oh;
    float *a = dx + ((size_t)p * h + 2 * oy) * w, *b = a + w;
    const float *s = dy + ((size_t)p * oh + oy) * ow;
    for (int ox = 0; ox < ow; ox++) {
      float g = 0.25f * s[ox];
      a[2 * ox] += g, a[2 * ox + 1] += g, b[2 * ox] += g, b[2 * ox + 1] += g;
    }
  }
}

void wv_nn_gram_forward(float *g, const float *f, int n, int c, int hw) {
  for (int i = 0; i < n; i++) {
    float *gi = g + (size_t)i * c * c;
    wv_nn_sgemm(0, 1, c, c, hw, 1.0f / hw, f + (size_t)i * c * hw, hw, f + (size_t)i * c * hw, hw,
                0.0f, gi, c);
    /* sgemm's blocked kernels may round the two triangles differently; a Gram matrix is
       symmetric, so mirror the upper one. */
    for (int r = 1; r < c; r++)
      for (int q = 0; q < r; q++) gi[(size_t)r * c + q] = gi[(size_t)q * c + r];
  }
}

void wv_nn_gram_backward(float *df, const float *f, const float *dg, int n, int c, int hw) {
  /* d/dF sum(dG .* F F^T / hw) = (dG + dG^T) F / hw */
  for (int i = 0; i < n; i++) {
    const float *fi = f + (size_t)i * c * hw, *dgi = dg + (size_t)i * c * c;
    float *dfi = df + (size_t)i * c * hw;
    wv_nn_sgemm(0, 0, c, hw, c, 1.0f / hw, dgi, c, fi, hw, 1.0f, dfi, hw);
    wv_nn_sgemm(1, 0, c, hw, c, 1.0f / hw, dgi, c, fi, hw, 1.0f, dfi, hw);
  }
}

void wv_nn_fc_forward(float *y, const float *x, const float *w, const float *b, int batch, int in,
                      int out) {
  wv_nn_sgemm(0, 1, batch, out, in, 1.0f, x, in, w, in, 0.0f, y, out);
  if (b)
    for (int i = 0; i < batch; i++)
      for (int o = 0; o < out; o++) y[(size_t)i * out + o] += b[o];
}

void wv_nn_fc_backward(float *dx, float *dw, float *db, const float *dy, const float *x,
                       const float *w, int batch, int in, int out) {
  if (dx) wv_nn_sgemm(0, 0, batch, in, out, 1.0f, dy, out, w, in, 1.0f, dx, in);
  if (dw) wv_nn_sgemm(1, 0, out, in, batch, 1.0f, dy, out, x, in, 1.0f, dw, in);
  if (db)
    for (int o = 0; o < out; o++) {
      double s = 0.0;
      for (int i = 0; i < batch; i++) s += dy[(size_t)i * out + o];
      db[o] += (float)s;
    }
}

void wv_nn_sigmoid_forward(float *y, const float *x, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) {
    /* Both branches stay finite for any x. */
    if (x[i] >= 0.0f) {
      y[i] = 1.0f / (1.0f + expf(-x[i]));
    } else {
      float e = expf(x[i]);
      y[i] = e / (1.0f + e);
    }
  }
}

void wv_nn_sigmoid_backward(float *dx, const float *y, const float *dy, size_t n) {
#pragma omp parallel for simd schedule(static) if (n > PAR_MIN)
  for (size_t i = 0; i < n; i++) dx[i] += dy[i] * y[i] * (1.0f - y[i]);
}

double wv_nn_l1(const float *a, const float *b, size_t n, int float_diff, float *grad, float g) {
  double s = 0.0;
  for (size_t i = 0; i < n; i++) {
    double d = float_diff ? (double)(a[i] - b[i]) : (double)a[i] - b[i];
    s += fabs(d);
    if (grad) grad[i] += d > 0 ? g : (d < 0 ? -g : 0.0f);
  }
  return s;
}

float wv_nn_l1_forward(const float *pred, const float *target, size_t n) {
  return n ? (float)(wv_nn_l1(pred, target, n, 0, NULL, 0.0f) / n) : 0.0f;
}

void wv_nn_l1_backward(float *dpred, const float *pred, const float *target, float dloss,
                       size_t n) {
  if (!n) return;
  wv_nn_l1(pred, target, n, 0, dpred, dloss / (float)n);
}

float wv_nn_softmax_xent_forward(float *prob, const float *logits, const int *labels, int batch, int k) {
  double loss = 0;
  for (int b = 0; b < batch; b++) {
    const float *z = logits + (size_t)b * k;
    float mx = z[0];
    for (int i = 1; i < k; i++) mx = z[i] > mx ? z[i] : mx;
    double s = 0; /* shifted by the maximum: exp never overflows */
    for (int i = 0; i < k; i++) s += exp((double)z[i] - mx);
    if (labels) loss += log(s) - ((double)z[labels[b]] - mx);
    if (prob)
      for (int i = 0; i < k; i++) prob[(size_t)b * k + i] = (float)(exp((double)z[i] - mx) / s);
  }
  return batch ? (float)(loss / batch) : 0.0f;
}

void wv_nn_softmax_xent_backward(float *dlogits, const float *prob, const int *labels, float dloss, int batch, int k) {
  if (!batch) return;
  float g = dloss / (float)batch;
  for (int b = 0; b < batch; b++)
    for (int i = 0; i < k; i++)
      dlogits[(size_t)b * k + i] += g * (prob[(size_t)b * k + i] - (i == labels[b] ? 1.0f : 0.0f));
}
