/* The adapter between the baker and the production shading: the export module
 * evaluates the woven BRDF only through these functions, which call the
 * shading kernel (kernel/kernel.h: wv_fabric_prepare, wv_kernel_shade). */
#include <stdlib.h>

#include "export/export_internal.h"
#include "kernel/kernel.h"

struct wv_export_fabric {
  wv_fabric fab;
};

wv_status wv_export_fabric_create(const wv_params *p, wv_export_fabric **out, wv_error *err) {
  *out = NULL;
  wv_export_fabric *f = malloc(sizeof *f);
  if (!f) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the fabric");
  wv_status st = wv_fabric_prepare(p, &f->fab, err);
  if (st) {
    free(f);
    return st;
  }
  f->fab.ym.period_rows = f->fab.ym.weave.rows;
  f->fab.ym.period_cols = f->fab.ym.weave.cols;
  f->fab.glints = 0;
  *out = f;
  return WV_OK;
}

void wv_export_fabric_free(wv_export_fabric *f) { free(f); }

const wv_yarn_model *wv_export_fabric_yarns(const wv_export_fabric *f) { return &f->fab.ym; }

void wv_export_woven_eval(const wv_export_fabric *f, float fx, float fy, const float wi[3], const float wo[3],
                          float out[3]) {
  wv_kernel_shade(&f->fab, fx, fy, wi, wo, out); /* zero below either horizon */
}
