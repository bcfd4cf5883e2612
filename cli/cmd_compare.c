/* woven compare: SSIM, weave-spectrum correlation and mean absolute difference of two images. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/io.h"
#include "woven/metrics.h"

typedef struct {
  const char *files[2];
  int channels;
  double blur;
} compare_args;

static const cli_opt OPTS[] = {
    CLI_O_ENUM("--channels", compare_args, channels, "luma|rgb", "SSIM on luminance (default) or per channel"),
    CLI_O_REAL("--blur", compare_args, blur, 0, 100, 0, "SIGMA",
               "compare Gaussian blurs of both (sigma in pixels): the shading\nwithout the pixel-scale weave and its noise"),
    CLI_O_END};

static const cli_cmd CMD = {
    "compare",
    "usage: woven compare A B [--channels luma|rgb] [--blur SIGMA] [--json]\n"
    "\n"
    "Compares two images of the same size: SSIM (Wang et al. 2004, 11x11 Gaussian window,\n"
    "sigma 1.5, data range 1, mean over the valid region) on luminance (default) or per\n"
    "channel (mean of R, G, B), the weave-spectrum correlation WSC (Pearson correlation of\n"
    "the log power spectra of the luminance detail of the centre 256 x 256 pixels, DC left\n"
    "out: 1 for the same periodic structure wherever its yarns lie, about 0 against noise;\n"
    "docs/fit.md; omitted below 32 x 32 pixels), and the mean absolute difference. Values\n"
    "are compared as stored (8/16-bit scaled to [0,1], EXR as is).\n",
    NULL, {{OPTS, 0}}, 2, {offsetof(compare_args, files[0]), offsetof(compare_args, files[1])}};

int cmd_compare(int argc, char **argv) {
  cli_ctx c = {0, 0, "compare"};
  compare_args ca = {{NULL, NULL}, 0, 0};
  CLI_PARSE(&CMD, argc, argv, &ca, &c);
  const char **files = ca.files;
  int nfiles = !!files[0] + !!files[1];
  wv_ssim_mode mode = ca.channels ? WV_SSIM_RGB : WV_SSIM_LUMA;
  double blur = ca.blur;
  if (nfiles != 2) return cli_usage_error(c.cmd, "expected two images");
  wv_error err = {0};
  wv_image im[2] = {{0}, {0}};
  for (int i = 0; i < 2; i++)
    if (wv_image_read(files[i], &im[i], NULL, &err)) {
      wv_image_free(&im[0]);
      return cli_fail(&c, &err);
    }
  double ssim = 0, mae = 0, wsc = 0, wscw = 0;
  wv_status st = WV_OK;
  for (int i = 0; i < 2 && blur > 0 && !st; i++) {
    wv_image b;
    if (!(st = wv_image_blur(&im[i], blur, &b, &err))) {
      wv_image_free(&im[i]);
      im[i] = b;
    }
  }
  if (!st) st = wv_ssim(&im[0], &im[1], mode, &ssim, &err);
  if (!st) st = wv_mae(&im[0], &im[1], &mae, &err);
  int has_wsc = im[0].w >= 32 && im[0].h >= 32;
  if (!st && has_wsc) st = wv_wsc(&im[0], &im[1], &wsc, &err);
  if (!st && has_wsc) st = wv_wsc_whitened(&im[0], &im[1], &wscw, &err);
  wv_image_free(&im[0]);
  wv_image_free(&im[1]);
  if (st) {
    wv_error_prefix(&err, "%s vs %s", files[0], files[1]);
    return cli_fail(&c, &err);
  }
  if (c.json)
    cli_print_json(json_pack("{s:o,s:o,s:o,s:s,s:o,s:o,s:o,s:o}", "a", cli_str(files[0]), "b", cli_str(files[1]), "ssim", cli_real(ssim, 6),
                             "ssim_channels", mode == WV_SSIM_LUMA ? "luma" : "rgb", "wsc",
                             has_wsc ? cli_real(wsc, 6) : json_null(), "wsc_whitened",
                             has_wsc ? cli_real(wscw, 6) : json_null(), "mae", cli_real(mae, 6), "blur", cli_real(blur, 6)));
  else if (!c.quiet && has_wsc)
    printf("SSIM (%s) %.4f  WSC %.4f  whitened WSC %.4f  MAE %.5f\n", mode == WV_SSIM_LUMA ? "luma" : "rgb", ssim, wsc,
           wscw, mae);
  else if (!c.quiet)
    printf("SSIM (%s) %.4f  MAE %.5f\n", mode == WV_SSIM_LUMA ? "luma" : "rgb", ssim, mae);
  return 0;
}
