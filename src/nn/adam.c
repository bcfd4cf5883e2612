/* Adam (Kingma & Ba, ICLR 2015), bias-corrected; weight decay decoupled as in AdamW;
 * optionally projected onto a box after each step. FabricNet's training and the fit (in
 * normalised parameter coordinates, box [0, 1]); a pair's transmission colours alone, twelve
 * values whose evaluations are exact, step by L-BFGS (lbfgs.c). */
#include <math.h>
#include <stdlib.h>

#include "woven/nn.h"

wv_status wv_nn_adam_init(wv_nn_adam *a, size_t n, float lr, wv_error *err) {
  a->n = n;
  a->lr = lr;
  a->beta1 = 0.9f;
  a->beta2 = 0.999f;
  a->eps = 1e-8f;
  a->weight_decay = 0.0f;
  a->t = 0;
  a->m = calloc(n ? n : 1, sizeof(float));
  a->v = calloc(n ? n : 1, sizeof(float));
  if (!a->m || !a->v) {
    wv_nn_adam_free(a);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for Adam state of %zu parameters", n);
  }
  return WV_OK;
}

static void step(wv_nn_adam *a, float *params, const float *grads, int box, float lo, float hi) {
  a->t++;
  /* Bias corrections in double: beta^t underflows gracefully for long runs. */
  float c1 = (float)(1.0 - pow(a->beta1, (double)a->t));
  float c2 = (float)(1.0 - pow(a->beta2, (double)a->t));
  float b1 = a->beta1, b2 = a->beta2, lr = a->lr, eps = a->eps, wd = a->weight_decay;
  float *m = a->m, *v = a->v;
  size_t n = a->n;
#pragma omp parallel for schedule(static) if (n > 65536)
  for (size_t i = 0; i < n; i++) {
    float g = grads[i];
    m[i] = b1 * m[i] + (1.0f - b1) * g;
    v[i] = b2 * v[i] + (1.0f - b2) * g * g;
    float mh = m[i] / c1, vh = v[i] / c2;
    float p = params[i] - lr * (mh / (sqrtf(vh) + eps) + wd * params[i]);
    params[i] = box ? (p < lo ? lo : p > hi ? hi : p) : p;
  }
}

void wv_nn_adam_step(wv_nn_adam *a, float *params, const float *grads) { step(a, params, grads, 0, 0, 0); }

void wv_nn_adam_step_box(wv_nn_adam *a, float *params, const float *grads, float lo, float hi) {
  step(a, params, grads, 1, lo, hi);
}

void wv_nn_adam_free(wv_nn_adam *a) {
  if (!a) return;
  free(a->m);
  free(a->v);
  a->m = a->v = NULL;
  a->n = 0;
}
