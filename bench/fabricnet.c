/* FabricNet on a held-out synthetic set (a dataset made with another seed):
 *   - mean normalised absolute error per output of the network alone;
 *   - SSIM of the network-only render against the target, for every sample;
 *   - for the first F targets (cycling through the patterns): the fit from the network's
 *     start and from the pattern-prior start, each for I iterations; the final loss of
 *     both (wv_fit_loss at the scene's resolution and spp) and SSIM after the fit;
 *   - the time of one prediction (model load + photo load + descriptor + forward).
 * Usage: fabricnet MODEL HELDOUT_DIR [F fit targets, default 5] [I iterations, default 60]
 * Prints progress on stderr and one JSON object on the last line of stdout. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "woven/dataset.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/photo.h"
#include "woven/render.h"

static int die(const wv_error *e) {
  fprintf(stderr, "fabricnet bench: %s\n", e->msg);
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: fabricnet MODEL HELDOUT_DIR [fit targets] [fit iterations]\n");
    return 1;
  }
  const char *mpath = argv[1], *dir = argv[2];
  int nfit = argc > 3 ? atoi(argv[3]) : 5, iters = argc > 4 ? atoi(argv[4]) : 60;
  wv_error e = {0};
  wv_dataset_info info;
  if (wv_dataset_info_read(dir, &info, &e)) return die(&e);
  double t0 = bench_now();
  wv_fabricnet net;
  if (wv_fabricnet_load(mpath, &net, &e)) return die(&e);
  double t_load = bench_now() - t0;
  wv_descriptor *d;
  if (wv_descriptor_create("default", NULL, &d, &e)) return die(&e);
  if (wv_fabricnet_check(&net, mpath, wv_descriptor_name(d), wv_descriptor_size(d), &info.scene, &e)) return die(&e);
  const wv_scene *s = &info.scene;
  int total = wv_dataset_pattern_count(&info) * info.per_pattern;
  float *feat = malloc(sizeof(float) * (size_t)net.n_in);
  double err_sum[WV_NET_OUT] = {0}, ssim_net = 0, t_pred = 1e9;
  double fit_ssim_net = 0, fit_ssim_prior = 0, loss_net = 0, loss_prior = 0, ssim_net_sub = 0;
  int nf = 0, wins = 0;
  wv_fit_opts fo;
  wv_fit_opts_default(&fo);
  fo.iters = iters;
  printf("{\"samples\": [\n");
  for (int k = 0; k < total; k++) {
    char png[4096], pj[4096], name[64];
    wv_dataset_path(dir, &info, k, "png", png, sizeof png);
    wv_dataset_path(dir, &info, k, "json", pj, sizeof pj);
    wv_dataset_sample_name(&info, k, name, sizeof name);
    wv_params truth, pred;
    wv_image photo = {0}, r_net = {0};
    wv_photo_info pinfo;
    wv_crop crop = {0, 0, 0, 0};
    if (wv_params_read(pj, &truth, &e)) return die(&e);
    double tp = bench_now();
    if (wv_photo_load(png, s, &crop, &photo, &pinfo, &e)) return die(&e);
    float y[WV_NET_OUT], yt[WV_NET_OUT];
    if (wv_fabricnet_predict(&net, d, &photo, feat, y, NULL, &e)) return die(&e);
    if (wv_fabricnet_params(&net, y, truth.pattern, &pred, &e)) return die(&e);
    tp = bench_now() - tp + t_load;
    if (tp < t_pred) t_pred = tp;
    /* the error on the mapped parameters (densities rounded), renormalised */
    wv_fabricnet_targets(&truth, WV_NET_OUT, yt);
    wv_fabricnet_targets(&pred, WV_NET_OUT, y);
    for (int i = 0; i < WV_NET_OUT; i++) err_sum[i] += fabs((double)y[i] - yt[i]);
    wv_render_opts ro = {0};
    double sn = 0;
    if (wv_render(s, &pred, &ro, &r_net, NULL, &e) || wv_ssim(&photo, &r_net, WV_SSIM_LUMA, &sn, &e)) return die(&e);
    ssim_net += sn;
    printf("  {\"sample\": \"%s\", \"ssim_network\": %.4f", name, sn);
    fprintf(stderr, "%s: SSIM network %.4f\n", name, sn);
    if (nf < nfit) {
      /* network start against prior start, same photo, same options */
      wv_params prior;
      if (wv_params_default(truth.pattern, &prior, &e)) return die(&e);
      const wv_params *starts[2] = {&pred, &prior};
      double loss[2], ssim[2];
      for (int j = 0; j < 2; j++) {
        wv_fit_state st;
        wv_fit_record rec;
        wv_image r = {0};
        wv_scene fs; /* with the registration's offset */
        if (wv_fit_state_init(&st, starts[j], &fo, &e) || wv_fit_run(&st, s, &photo, d, &fo, NULL, NULL, &e) ||
            (wv_fit_scene(&st, s, &fs), 0) || wv_fit_loss(&fs, &photo, d, &st.params, &fo, &rec, &e) ||
            wv_render(&fs, &st.params, &ro, &r, NULL, &e) ||
            wv_ssim(&photo, &r, WV_SSIM_LUMA, &ssim[j], &e))
          return die(&e);
        loss[j] = rec.loss;
        wv_fit_state_free(&st);
        wv_image_free(&r);
      }
      printf(", \"fit_loss_network_start\": %.6f, \"fit_loss_prior_start\": %.6f, \"ssim_fit_network_start\": %.4f, "
             "\"ssim_fit_prior_start\": %.4f",
             loss[0], loss[1], ssim[0], ssim[1]);
      fprintf(stderr, "  fit %d iterations: loss %.5f (network start) vs %.5f (prior start); SSIM %.4f vs %.4f\n",
              iters, loss[0], loss[1], ssim[0], ssim[1]);
      loss_net += loss[0], loss_prior += loss[1], fit_ssim_net += ssim[0], fit_ssim_prior += ssim[1];
      ssim_net_sub += sn;
      wins += loss[0] < loss[1];
      nf++;
    }
    printf("}%s\n", k + 1 < total ? "," : "");
    wv_image_free(&photo), wv_image_free(&r_net);
  }
  printf("]}\n");
  double mean_err = 0;
  printf("{\"model\": \"%s\", \"heldout\": \"%s\", \"samples\": %d, \"predict_seconds\": %.3f, "
         "\"network_abs_error\": {", mpath, dir, total, t_pred);
  for (int i = 0; i < WV_NET_OUT; i++) {
    printf("%s\"%s\": %.4f", i ? ", " : "", wv_fabricnet_output_name(i), err_sum[i] / total);
    mean_err += err_sum[i] / total / WV_NET_OUT;
  }
  printf("}, \"network_abs_error_mean\": %.4f, \"ssim_network\": %.4f, \"fit_targets\": %d, \"fit_iters\": %d",
         mean_err, ssim_net / total, nf, iters);
  if (nf)
    printf(", \"ssim_network_on_fit_targets\": %.4f, \"ssim_fit_network_start\": %.4f, \"ssim_fit_prior_start\": %.4f, "
           "\"fit_loss_network_start\": %.6f, \"fit_loss_prior_start\": %.6f, \"network_start_wins\": %d",
           ssim_net_sub / nf, fit_ssim_net / nf, fit_ssim_prior / nf, loss_net / nf, loss_prior / nf, wins);
  printf("}\n");
  free(feat);
  wv_descriptor_free(d);
  wv_fabricnet_free(&net);
  return 0;
}
