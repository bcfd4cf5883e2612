/* The fit's registration: a weave a couple of yarns/inch off and shifted by an
 * unknown offset is brought back onto the photo (densities to within half a yarn/inch
 * in a 128-pixel window,
 * offset through the pixel -> fabric map), and an exact fit is left alone. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"


static void truth(wv_params *p) {
  wv_params_default("twill", p, NULL);
  p->density[WV_WARP] = 140, p->density[WV_WEFT] = 90;
  p->noise_level = 1;
}

static double ssim_of(const wv_scene *s, const wv_params *p, const wv_image *ref) {
  wv_render_opts ro = {0, 0, NULL, NULL, NULL};
  wv_image img;
  assert_int_equal(wv_render(s, p, &ro, &img, NULL, NULL), WV_OK);
  double v;
  assert_int_equal(wv_ssim(ref, &img, WV_SSIM_LUMA, &v, NULL), WV_OK);
  wv_image_free(&img);
  return v;
}

/* Runs the registration from 'from' (offset 0) against a photo of the truth
 * rendered with the fabric shifted by 'shift' mm. */
static void run(const wv_params *from, const double shift[2], wv_fit_state *st, wv_scene *s, wv_image *photo) {
  tu_centre_window(s, "flat45", 128, 128, 16);
  wv_params tp;
  truth(&tp);
  wv_scene shifted = *s;
  shifted.fabric_offset[0] = shift[0], shifted.fabric_offset[1] = shift[1];
  wv_render_opts ro = {0, 0, NULL, NULL, NULL};
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

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_register_recovers_density_and_phase),
                                     cmocka_unit_test(test_register_keeps_an_exact_fit)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
