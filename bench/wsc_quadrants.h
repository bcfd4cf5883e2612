/* The WSC the same weave scores against itself: a photo's four quadrants against each other,
 * the reference for a re-render's WSC (docs/fit.md, "WSC"). */
#ifndef WOVEN_BENCH_WSC_QUADRANTS_H
#define WOVEN_BENCH_WSC_QUADRANTS_H
#include <string.h>

#include "woven/image.h"
#include "woven/metrics.h"

/* WSC (whitened: 1) of the four quadrants of img against each other, the mean of the six
 * pairs, in *out. */
static inline wv_status bench_wsc_quadrants(const wv_image *img, int whitened, double *out, wv_error *err) {
  int h = img->w < img->h ? img->w / 2 : img->h / 2;
  wv_image q[4] = {{0}};
  wv_status rc = WV_OK;
  for (int k = 0; k < 4 && !rc; k++)
    if (!(rc = wv_image_alloc(&q[k], h, h, 3, err)))
      for (int y = 0; y < h; y++)
        memcpy(wv_image_px(&q[k], 0, y), wv_image_px(img, (k & 1) * h, (k >> 1) * h + y),
               sizeof(float) * 3 * (size_t)h);
  double sum = 0, v;
  for (int a = 0; a < 4 && !rc; a++)
    for (int b = a + 1; b < 4 && !rc; b++)
      if (!(rc = (whitened ? wv_wsc_whitened : wv_wsc)(&q[a], &q[b], &v, err))) sum += v;
  for (int k = 0; k < 4; k++) wv_image_free(&q[k]);
  *out = sum / 6;
  return rc;
}
#endif
