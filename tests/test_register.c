/* The fit's registration: a weave a couple of yarns/inch off and shifted by an
 * unknown offset is brought back onto the photo (densities to within half a yarn/inch
 * in a 128-pixel window,
 * offset through the pixel -> fabric map), and an exact fit is left alone; the cloth's
 * distortion follows a bent cloth and leaves a straight one; neither moves a two-colour
 * fit in register to please the luminance alone; the first step's coarse grid and climbs
 * give the whole grid's candidates, and none where no coarse score shows a peak; without a
 * peak in the middle window either, the registration stops there. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "fit/fit_internal.h" /* the registration's first step alone */
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"


static void truth(wv_params *p) {
  wv_params_default("twill", p, NULL);
  p->density[WV_WARP] = 140, p->density[WV_WEFT] = 90;
  p->noise_level = 1;
}

static double ssim_in(const wv_scene *s, const wv_params *p, const wv_image *ref, wv_ssim_mode mode) {
  wv_render_opts ro = {0};
  wv_image img;
  assert_int_equal(wv_render(s, p, &ro, &img, NULL, NULL), WV_OK);
  double v;
  assert_int_equal(wv_ssim(ref, &img, mode, &v, NULL), WV_OK);
  wv_image_free(&img);
  return v;
}

static double ssim_of(const wv_scene *s, const wv_params *p, const wv_image *ref) {
  return ssim_in(s, p, ref, WV_SSIM_LUMA);
}

/* Runs the registration from 'from' (offset 0) against a photo of the truth
 * rendered with the fabric shifted by 'shift' mm. */
static void run(const wv_params *from, const double shift[2], wv_fit_state *st, wv_scene *s, wv_image *photo) {
  tu_centre_window(s, "flat45", 128, 128, 16);
  wv_params tp;
  truth(&tp);
  wv_scene shifted = *s;
  shifted.fabric_offset[0] = shift[0], shifted.fabric_offset[1] = shift[1];
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(&shifted, &tp, &ro, photo, NULL, NULL), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.register_radius = 3;
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(st, from, &o, &err), WV_OK);
  if (wv_fit_register(st, s, photo, &o, &err)) fail_msg("%s", err.msg);
  assert_true(st->registered);
}

static void test_register_recovers_density_and_phase(void **state) {
  (void)state;
  wv_params from;
  truth(&from);
  from.density[WV_WARP] = 142, from.density[WV_WEFT] = 88.5;
  const double shift[2] = {0.61, -0.37};
  wv_fit_state st;
  wv_scene s;
  wv_image photo;
  run(&from, shift, &st, &s, &photo);
  wv_scene reg;
  wv_fit_scene(&st, &s, &reg);
  double before = ssim_of(&s, &from, &photo), after = ssim_of(&reg, &st.params, &photo);
  print_message("densities %.2f %.2f, offset %.3f %.3f mm, ncc %.3f -> %.3f, SSIM %.3f -> %.3f\n",
                st.params.density[0], st.params.density[1], st.offset_mm[0], st.offset_mm[1], st.reg_ncc_before,
                st.reg_ncc_after, before, after);
  assert_true(fabs(st.params.density[WV_WARP] - 140) <= 0.5);
  assert_true(fabs(st.params.density[WV_WEFT] - 90) <= 0.5);
  assert_true(st.reg_ncc_after > st.reg_ncc_before + 0.3);
  assert_true(before < 0.6);
  assert_true(after > 0.85);
  assert_true(st.reg_renders[3] > 0); /* a weave in the middle window goes on to the whole image */
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

static void test_register_keeps_an_exact_fit(void **state) {
  (void)state;
  wv_params from;
  truth(&from);
  const double shift[2] = {0, 0};
  wv_fit_state st;
  wv_scene s;
  wv_image photo;
  run(&from, shift, &st, &s, &photo);
  print_message("densities %.2f %.2f, offset %.4f %.4f mm, window SSIM %.3f -> %.3f\n", st.params.density[0],
                st.params.density[1], st.offset_mm[0], st.offset_mm[1], st.reg_ssim_before, st.reg_ssim_after);
  assert_true(fabs(st.params.density[WV_WARP] - 140) <= 0.15);
  assert_true(fabs(st.params.density[WV_WEFT] - 90) <= 0.15);
  assert_true(st.reg_ssim_after >= st.reg_ssim_before);
  wv_scene reg;
  wv_fit_scene(&st, &s, &reg);
  assert_true(ssim_of(&reg, &st.params, &photo) > 0.85);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

/* A satin whose green warp and purple weft differ more in hue than in luminance, and a
 * fit of it in register, but with the heightfields and highlights traded between the
 * yarn types: moving its weave raises the SSIM of luminance and lowers that of the
 * colours (from 0.93 to 0.64 when the luminance decided). Registration and distortion
 * judge by the colours, so they leave it where it is. */
static void test_register_sees_colour(void **state) {
  (void)state;
  wv_error err = {0};
  wv_scene s;
  assert_int_equal(wv_scene_preset("flat45", &s, &err), WV_OK);
  wv_params tp, fit;
  assert_int_equal(wv_params_default("satin5", &tp, &err), WV_OK);
  tp.density[0] = 187, tp.density[1] = 124, tp.noise_level = 3, tp.seed = 758618803;
  tp.heightfield[0] = 0.832, tp.heightfield[1] = 0.212, tp.roughness[0] = 0.978, tp.roughness[1] = 0.461;
  const double kd[2][3] = {{0.231, 0.976, 0.304}, {0.729, 0.502, 0.992}};
  const double ks[2][3] = {{0.521, 0.989, 0.589}, {0.801, 0.616, 0.994}};
  tp.twist_deg = 0, tp.inclination_deg = 32.5, tp.diffuse_blend = 0.437;
  fit = tp;
  fit.density[0] = 187.1, fit.noise_level = 0, fit.seed = 1;
  fit.heightfield[0] = 0, fit.heightfield[1] = 0.337, fit.roughness[0] = 1, fit.roughness[1] = 0.421;
  const double fkd[2][3] = {{0.271, 0.950, 0.291}, {0.904, 0.550, 1.000}};
  const double fks[2][3] = {{0.059, 0.230, 0.463}, {0.182, 0.471, 1.000}};
  fit.twist_deg = -40.8, fit.inclination_deg = 40.9, fit.diffuse_blend = 0.568;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) {
      tp.diffuse[y][c] = kd[y][c], tp.specular[y][c] = ks[y][c];
      fit.diffuse[y][c] = fkd[y][c], fit.specular[y][c] = fks[y][c];
    }
  wv_image photo;
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(&s, &tp, &ro, &photo, NULL, &err), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, &fit, &o, &err), WV_OK);
  st.psf_done = 1, st.psf_sigma = 0.35; /* the blur the fit found */
  wv_scene before_s, after_s;
  wv_fit_scene(&st, &s, &before_s);
  double before = ssim_in(&before_s, &fit, &photo, WV_SSIM_RGB);
  if (wv_fit_register(&st, &s, &photo, &o, &err) || wv_fit_distort(&st, &s, &photo, &o, &err)) fail_msg("%s", err.msg);
  wv_fit_scene(&st, &s, &after_s);
  double after = ssim_in(&after_s, &st.params, &photo, WV_SSIM_RGB);
  print_message("two-colour satin: offset %.4f %.4f mm, SSIM of the colours %.3f -> %.3f\n", st.offset_mm[0],
                st.offset_mm[1], before, after);
  assert_true(before > 0.9);
  assert_true(after > before - 0.01);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

/* The cloth's distortion: a photo of the truth on a bent cloth (a displacement of up to
 * about two yarns toward the window's edges) is brought back into register by the fit's
 * distortion, which then follows the true displacement up to a constant (a whole weave
 * repeat is invisible); an undistorted photo gets no displacement to speak of. */
static void distorted_photo(double amount, wv_scene *s, wv_scene *bent, wv_image *photo) {
  tu_centre_window(s, "flat45", 256, 256, 16);
  *bent = *s;
  if (amount != 0) {
    bent->distort_extent_mm = 16;
    bent->distort[0][2] = 0.25 * amount, bent->distort[0][4] = -0.15 * amount, bent->distort[0][6] = 0.1 * amount;
    bent->distort[1][3] = 0.2 * amount, bent->distort[1][8] = -0.15 * amount, bent->distort[1][1] = 0.05 * amount;
  }
  wv_params tp;
  truth(&tp);
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(bent, &tp, &ro, photo, NULL, NULL), WV_OK);
}

/* The spread over the window of the fitted displacement minus the true one, per axis (mm). */
static void displacement_spread(const wv_scene *fit, const wv_scene *bent, double spread[2]) {
  double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
  for (int j = 0; j <= 8; j++)
    for (int i = 0; i <= 8; i++) {
      double px = 8 + i * 30, py = 8 + j * 30, f[2], g[2];
      assert_true(wv_render_fabric_at(fit, px, py, f) && wv_render_fabric_at(bent, px, py, g));
      for (int k = 0; k < 2; k++) {
        double d = f[k] - g[k];
        lo[k] = d < lo[k] ? d : lo[k], hi[k] = d > hi[k] ? d : hi[k];
      }
    }
  spread[0] = hi[0] - lo[0], spread[1] = hi[1] - lo[1];
}

/* The distortion from the truth against a photo of the truth bent by `amount` (0:
 * straight): the window's scene s, the bent one, the photo, the fit's state and scene. */
static void run_distort(double amount, wv_scene *s, wv_scene *bent, wv_image *photo, wv_fit_state *st,
                        wv_scene *fit) {
  distorted_photo(amount, s, bent, photo);
  wv_params p;
  truth(&p);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(st, &p, &o, &err), WV_OK);
  if (wv_fit_distort(st, s, photo, &o, &err)) fail_msg("%s", err.msg);
  assert_true(st->distorted);
  wv_fit_scene(st, s, fit);
}

static void test_distortion_follows_a_bent_cloth(void **state) {
  (void)state;
  wv_scene s, bent, fit;
  wv_image photo;
  wv_fit_state st;
  run_distort(1, &s, &bent, &photo, &st, &fit);
  wv_params p;
  truth(&p);
  double spread0[2];
  displacement_spread(&s, &bent, spread0);
  double spread[2], before = ssim_of(&s, &p, &photo), after = ssim_of(&fit, &p, &photo);
  displacement_spread(&fit, &bent, spread);
  print_message("bent cloth: displacement spread %.3f / %.3f mm -> %.3f / %.3f mm, SSIM %.3f -> %.3f\n", spread0[0],
                spread0[1], spread[0], spread[1], before, after);
  assert_true(spread0[0] > 0.2 && spread0[1] > 0.2); /* the bend moves yarns by more than a yarn */
  assert_true(spread[0] < 0.03 && spread[1] < 0.03);
  assert_true(before < 0.6 && after > 0.9);
  assert_true(st.dist_ssim_after > st.dist_ssim_before);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

static void test_distortion_leaves_a_straight_cloth(void **state) {
  (void)state;
  wv_scene s, bent, fit;
  wv_image photo;
  wv_fit_state st;
  run_distort(0, &s, &bent, &photo, &st, &fit);
  wv_params p;
  truth(&p);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_error err = {0};
  double spread[2];
  displacement_spread(&fit, &s, spread);
  print_message("straight cloth: displacement spread %.4f / %.4f mm, offset %.4f %.4f mm, SSIM %.3f -> %.3f\n",
                spread[0], spread[1], st.offset_mm[0], st.offset_mm[1], st.dist_ssim_before, st.dist_ssim_after);
  assert_true(spread[0] < 0.01 && spread[1] < 0.01);
  assert_true(fabs(st.offset_mm[0]) < 0.01 && fabs(st.offset_mm[1]) < 0.01);
  assert_true(st.dist_ssim_after >= st.dist_ssim_before);
  /* a cylinder has no distortion */
  wv_fit_state_free(&st);
  wv_scene cyl;
  tu_centre_window(&cyl, "cylinder", 128, 128, 4);
  wv_image_free(&photo);
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(&cyl, &p, &ro, &photo, NULL, NULL), WV_OK);
  assert_int_equal(wv_fit_state_init(&st, &p, &o, &err), WV_OK);
  assert_int_equal(wv_fit_distort(&st, &cyl, &photo, &o, &err), WV_OK);
  assert_true(st.distorted && st.distort_extent_mm == 0);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

/* The whole-range step: the coarse grid with its climbs picks the candidates the whole
 * ratio grid picks, the same densities in the same order, from well under half its
 * renders; for a twill and a satin, each from a start off in both densities. */
static void test_register_coarse_grid_matches_whole(void **state) {
  (void)state;
  const char *pattern[2] = {"twill", "satin"};
  const double dens[2][2] = {{140, 90}, {120, 160}};
  for (int t = 0; t < 2; t++) {
    wv_scene s;
    tu_centre_window(&s, "flat45", 128, 128, 16);
    wv_params tp, from;
    assert_int_equal(wv_params_default(pattern[t], &tp, NULL), WV_OK);
    tp.density[WV_WARP] = dens[t][0], tp.density[WV_WEFT] = dens[t][1];
    wv_render_opts ro = {0};
    wv_image photo;
    assert_int_equal(wv_render(&s, &tp, &ro, &photo, NULL, NULL), WV_OK);
    from = tp;
    from.density[WV_WARP] *= 1.07, from.density[WV_WEFT] *= 0.94;
    wv_fit_opts o;
    wv_fit_opts_default(&o);
    wv_fit_state st;
    wv_error err = {0};
    assert_int_equal(wv_fit_state_init(&st, &from, &o, &err), WV_OK);
    double cw[4][2], cc[4][2];
    int nw = 0, nc = 0, rw = 0, rcn = 0;
    if (wv_fit_register_candidates(&st, &s, &photo, &o, 1, cw, &nw, &rw, &err)) fail_msg("%s", err.msg);
    if (wv_fit_register_candidates(&st, &s, &photo, &o, 0, cc, &nc, &rcn, &err)) fail_msg("%s", err.msg);
    fprintf(stderr, "%s: whole grid %d renders, coarse %d; candidates", pattern[t], rw, rcn);
    for (int i = 0; i < nw; i++) fprintf(stderr, " (%.2f, %.2f)", cw[i][0], cw[i][1]);
    fprintf(stderr, "\n");
    assert_int_equal(nc, nw);
    assert_true(nw >= 1);
    for (int i = 0; i < nw; i++) assert_true(cc[i][0] == cw[i][0] && cc[i][1] == cw[i][1]);
    assert_true(rcn < rw / 2);
    wv_fit_state_free(&st);
    wv_image_free(&photo);
  }
}

/* A 128 x 128 photo of seeded uniform noise: no weave lines up with it anywhere. */
static void noise_photo(uint64_t seed, wv_image *photo) {
  assert_int_equal(wv_image_alloc(photo, 128, 128, 3, NULL), WV_OK);
  tu_rng r = {seed};
  for (size_t i = 0; i < (size_t)128 * 128 * 3; i++) photo->data[i] = (float)(0.2 + 0.6 * tu_rnd(&r));
}

/* A photo whose weave lines up nowhere in the small window (seeded noise): no coarse score
 * shows a peak, and the whole-range step gives no candidates after the coarse grid alone,
 * where the whole grid would hand on four of its noise maxima. */
static void test_register_no_candidates_without_a_peak(void **state) {
  (void)state;
  wv_scene s;
  tu_centre_window(&s, "flat45", 128, 128, 16);
  wv_image photo;
  noise_photo(12345, &photo);
  wv_params from;
  assert_int_equal(wv_params_default("twill", &from, NULL), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_fit_state st;
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(&st, &from, &o, &err), WV_OK);
  double cw[4][2], cc[4][2];
  int nw = 0, nc = 0, rw = 0, rcn = 0;
  if (wv_fit_register_candidates(&st, &s, &photo, &o, 1, cw, &nw, &rw, &err)) fail_msg("%s", err.msg);
  if (wv_fit_register_candidates(&st, &s, &photo, &o, 0, cc, &nc, &rcn, &err)) fail_msg("%s", err.msg);
  fprintf(stderr, "noise: whole grid %d renders, %d candidates; coarse %d renders, %d candidates\n", rw, nw, rcn, nc);
  assert_true(nw >= 1);
  assert_int_equal(nc, 0);
  assert_true(rcn < rw / 3);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

/* A photo whose weave lines up in neither the small nor the middle window (seeded noise):
 * the registration stops after the middle window, before the larger windows render
 * anything, and leaves the fit where it was. */
static void test_register_stops_without_a_middle_peak(void **state) {
  (void)state;
  wv_scene s;
  tu_centre_window(&s, "flat45", 128, 128, 16);
  wv_image photo;
  noise_photo(777, &photo);
  wv_params from;
  truth(&from);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_fit_state st;
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(&st, &from, &o, &err), WV_OK);
  if (wv_fit_register(&st, &s, &photo, &o, &err)) fail_msg("%s", err.msg);
  print_message("noise: renders per window %d %d %d %d, ncc %.3f\n", st.reg_renders[0], st.reg_renders[1],
                st.reg_renders[2], st.reg_renders[3], st.reg_ncc_before);
  assert_true(st.registered);
  assert_true(st.reg_renders[0] > 0 && st.reg_renders[1] > 0);
  assert_int_equal(st.reg_renders[2], 0);
  assert_int_equal(st.reg_renders[3], 0);
  assert_true(st.params.density[WV_WARP] == from.density[WV_WARP] && st.params.density[WV_WEFT] == from.density[WV_WEFT]);
  assert_true(st.offset_mm[0] == 0 && st.offset_mm[1] == 0);
  wv_fit_state_free(&st);
  wv_image_free(&photo);
}

/* A view of the cloth (a pair's back-lit photo): its registration without the whole image's
 * climb, then the distortion, places a view whose densities are a few tenths of a yarn/inch off
 * (a scale read 0.6% short) as well as the registration with that climb does, from fewer
 * renders of the whole image. */
static void test_register_view(void **state) {
  (void)state;
  wv_scene s;
  tu_centre_window(&s, "flat45", 384, 384, 16);
  wv_params tp, from;
  truth(&tp);
  from = tp;
  tp.density[WV_WARP] *= 1.006, tp.density[WV_WEFT] *= 1.006;
  wv_scene shifted = s;
  shifted.fabric_offset[0] = 0.43, shifted.fabric_offset[1] = -0.29;
  wv_render_opts ro = {0};
  wv_image photo;
  assert_int_equal(wv_render(&shifted, &tp, &ro, &photo, NULL, NULL), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.register_radius = 3;
  double placed[2], whole[2], before = ssim_in(&s, &from, &photo, WV_SSIM_RGB);
  for (int k = 0; k < 2; k++) {
    wv_fit_state st;
    wv_error err = {0};
    assert_int_equal(wv_fit_state_init(&st, &from, &o, &err), WV_OK);
    wv_status rc = k ? wv_fit_register_view(&st, &s, &photo, &o, &err) : wv_fit_register_near(&st, &s, &photo, &o, &err);
    if (!rc) rc = wv_fit_distort(&st, &s, &photo, &o, &err);
    if (rc) fail_msg("%s", err.msg);
    wv_scene fit;
    wv_fit_scene(&st, &s, &fit);
    placed[k] = ssim_in(&fit, &st.params, &photo, WV_SSIM_RGB);
    whole[k] = st.reg_renders[3];
    wv_fit_state_free(&st);
  }
  print_message("view of a cloth 0.6%% denser: SSIM %.3f; registered with the whole image's climb %.3f (%g renders "
                "of it), without %.3f (%g)\n", before, placed[0], whole[0], placed[1], whole[1]);
  assert_true(before < 0.6);
  assert_true(placed[0] > 0.85 && placed[1] > placed[0] - 0.02);
  assert_true(whole[1] < whole[0]);
  wv_image_free(&photo);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_register_coarse_grid_matches_whole),
                                     cmocka_unit_test(test_register_no_candidates_without_a_peak),
                                     cmocka_unit_test(test_register_stops_without_a_middle_peak),
                                     cmocka_unit_test(test_register_recovers_density_and_phase),
                                     cmocka_unit_test(test_register_keeps_an_exact_fit),
      cmocka_unit_test(test_register_view),
                                     cmocka_unit_test(test_distortion_follows_a_bent_cloth),
                                     cmocka_unit_test(test_distortion_leaves_a_straight_cloth),
                                     cmocka_unit_test(test_register_sees_colour)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
