/* Forward renderer: the pixel sampler's coverage, determinism, convergence of the default
 * spp, the twill90 symmetry of the maps, light through the cloth (flat45-back) and its maps,
 * golden images. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sampler/sampler.h"
#include "testutil.h"

#define M_PI 3.14159265358979323846
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/grad.h"
#include "woven/render.h"
#include "woven/yarn.h"
#include "woven/dataset.h"

/* A centred w x h window of a scene: same pixels as the full image there. */
static void crop_scene(wv_scene *s, int w, int h) {
  double t = tan(0.5 * s->vfov_deg * M_PI / 180.0) * h / s->height;
  s->vfov_deg = 2.0 * atan(t) * 180.0 / M_PI;
  s->width = w, s->height = h;
}

static void render(const char *scene, const char *pattern, int w, int h, int spp, int threads, int64_t seed,
                   wv_image *out) {
  wv_scene s;
  wv_params p;
  wv_error err = {0};
  assert_int_equal(wv_scene_preset(scene, &s, &err), WV_OK);
  if (w) crop_scene(&s, w, h);
  assert_int_equal(wv_params_default(pattern, &p, &err), WV_OK);
  p.seed = seed;
  wv_render_opts o = {.spp = spp, .threads = threads};
  if (wv_render(&s, &p, &o, out, NULL, &err)) fail_msg("%s", err.msg);
}

static void test_deterministic(void **state) {
  (void)state;
  wv_image a, b, c, d;
  render("cylinder", "twill", 96, 48, 16, 1, 5, &a);
  render("cylinder", "twill", 96, 48, 16, 2, 5, &b);
  render("cylinder", "twill", 96, 48, 16, 2, 5, &c);
  render("cylinder", "twill", 96, 48, 16, 2, 6, &d);
  size_t n = (size_t)a.w * a.h * 3;
  assert_memory_equal(a.data, b.data, n * sizeof(float)); /* thread count does not matter */
  assert_memory_equal(b.data, c.data, n * sizeof(float)); /* same seed: bit-identical */
  assert_true(wv_image_mad(&c, &d) > 1e-4);                /* another seed: other noise */
  for (size_t i = 0; i < n; i++) assert_true(isfinite(a.data[i]) && a.data[i] >= 0.0f && a.data[i] <= 1.0f);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&c), wv_image_free(&d);
}

/* Footprints made once give the same image as the per-render ones (forward and
 * the gradient renderer's capture), and another geometry is refused. */
static void test_footprints_cache(void **state) {
  (void)state;
  wv_scene s;
  wv_params p;
  wv_error err = {0};
  assert_int_equal(wv_scene_preset("cylinder", &s, &err), WV_OK);
  crop_scene(&s, 96, 160); /* taller than the cylinder's silhouette: traced pixels too */
  s.vfov_deg *= 3;
  assert_int_equal(wv_params_default("satin", &p, &err), WV_OK);
  wv_footprints *fp;
  assert_int_equal(wv_footprints_create(&s, 2, &fp, &err), WV_OK);
  wv_render_opts plain = {.spp = 8, .threads = 2}, cached = {.spp = 8, .threads = 2, .footprints = fp};
  wv_image a, b;
  assert_int_equal(wv_render(&s, &p, &plain, &a, NULL, &err), WV_OK);
  assert_int_equal(wv_render(&s, &p, &cached, &b, NULL, &err), WV_OK);
  size_t n = (size_t)a.w * a.h * 3;
  assert_memory_equal(a.data, b.data, n * sizeof(float));
  int dark = 0; /* the window shows background: both paths are exercised */
  for (size_t i = 0; i < n; i += 3) dark += a.data[i] == 0.0f;
  assert_true(dark > 0);
  wv_image_free(&b);
  wv_grad_record *rec = NULL;
  assert_int_equal(wv_render_record(&s, &p, &cached, NULL, &b, &rec, &err), WV_OK);
  assert_memory_equal(a.data, b.data, n * sizeof(float));
  wv_record_free(rec);
  wv_image_free(&b);
  s.fabric_offset[0] += 0.5; /* another geometry */
  assert_int_equal(wv_render(&s, &p, &cached, &b, NULL, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "footprints"));
  wv_footprints_free(fp);
  wv_image_free(&a);
}

/* SPEC 6: doubling the default spp changes the image by < 1% (mean absolute
 * difference on the [0,1] capture image), on a 200 x 100 centre window. */
static void test_default_spp_converged(void **state) {
  (void)state;
  const char *scenes[] = {"cylinder", "flat45"};
  const char *pats[] = {"twill", "satin", "plain"};
  for (int si = 0; si < 2; si++) {
    wv_scene s;
    wv_scene_preset(scenes[si], &s, NULL);
    for (int k = 0; k < 3; k++) {
      wv_image a, b;
      render(scenes[si], pats[k], 200, 100, s.spp, 0, 1, &a);
      render(scenes[si], pats[k], 200, 100, 2 * s.spp, 0, 1, &b);
      double mad = wv_image_mad(&a, &b), mean = wv_image_mean(&b);
      print_message("%s %s spp %d vs %d: MAD %.5f (mean %.3f)\n", scenes[si], pats[k], s.spp, 2 * s.spp, mad, mean);
      assert_true(mad < 0.01);
      wv_image_free(&a), wv_image_free(&b);
    }
    /* and prior draws of every pattern (bench/spp_convergence measures more) */
    for (int k = 0; k < WV_NET_PATTERNS; k++) {
      wv_params p;
      wv_error err = {0};
      assert_int_equal(wv_params_sample_prior(wv_net_pattern(k), (uint64_t)(90 + k), &p, &err), WV_OK);
      wv_scene c = s;
      crop_scene(&c, 200, 100);
      wv_render_opts o1 = {.spp = s.spp}, o2 = {.spp = 2 * s.spp};
      wv_image a, b;
      assert_int_equal(wv_render(&c, &p, &o1, &a, NULL, &err), WV_OK);
      assert_int_equal(wv_render(&c, &p, &o2, &b, NULL, &err), WV_OK);
      double mad = wv_image_mad(&a, &b);
      print_message("%s prior %s spp %d vs %d: MAD %.5f\n", scenes[si], wv_net_pattern(k), s.spp, 2 * s.spp, mad);
      assert_true(mad < 0.01);
      wv_image_free(&a), wv_image_free(&b);
    }
  }
}

/* twill90 = 1 - twill^T is the twill mirrored about the pattern's diagonal (a
 * 90-degree rotation combined with a flip; see docs/model.md). With warp and weft
 * parameters swapped and the twist negated (a mirror flips handedness), its maps
 * must equal the twill maps transposed, vectors mapped (x, y, z) -> (-y, -x, z). */
static void test_twill90_is_mirrored_twill(void **state) {
  (void)state;
  for (int tw = 0; tw < 2; tw++) {
    wv_params a, b;
    wv_params_default("twill", &a, NULL);
    a.density[WV_WARP] = 130, a.density[WV_WEFT] = 90;
    a.heightfield[WV_WARP] = 1.4, a.heightfield[WV_WEFT] = 0.7;
    a.roughness[WV_WARP] = 0.8, a.roughness[WV_WEFT] = 0.55;
    a.diffuse[WV_WARP][0] = 0.9, a.diffuse[WV_WEFT][2] = 0.1;
    a.twist_deg = tw ? -25 : 0;
    a.noise_level = 0; /* segment noise is hashed by segment identity, not symmetric */
    b = a;
    snprintf(b.pattern, sizeof b.pattern, "twill90");
    for (int i = 0; i < 2; i++) {
      b.density[i] = a.density[1 - i], b.heightfield[i] = a.heightfield[1 - i], b.roughness[i] = a.roughness[1 - i];
      for (int c = 0; c < 3; c++) b.diffuse[i][c] = a.diffuse[1 - i][c], b.specular[i][c] = a.specular[1 - i][c];
    }
    b.twist_deg = -a.twist_deg;
    wv_maps ma, mb;
    int N = 128;
    assert_int_equal(wv_maps_generate(&a, N, &ma, NULL), WV_OK);
    assert_int_equal(wv_maps_generate(&b, N, &mb, NULL), WV_OK);
    double worst = 0;
    int compared = 0;
    for (int y = 0; y < N; y++)
      for (int x = 0; x < N; x++) {
        const float *na = wv_image_px(&ma.normal, x, y), *nb = wv_image_px(&mb.normal, y, x);
        const float *ta = wv_image_px(&ma.tangent, x, y), *tb = wv_image_px(&mb.tangent, y, x);
        float ida = wv_image_px(&ma.yarn_id, x, y)[0], idb = wv_image_px(&mb.yarn_id, y, x)[1];
        assert_true(ida == idb); /* warp of twill <-> weft of twill90 */
        double dn = fabs(na[0] + nb[1]) + fabs(na[1] + nb[0]) + fabs(na[2] - nb[2]);
        double s = (ta[0] * -tb[1] + ta[1] * -tb[0] + ta[2] * tb[2]) < 0 ? -1 : 1; /* fibers have no sign */
        double dt = fabs(ta[0] + s * tb[1]) + fabs(ta[1] + s * tb[0]) + fabs(ta[2] - s * tb[2]);
        worst = fmax(worst, fmax(dn, dt));
        for (int c = 0; c < 3; c++) {
          assert_true(wv_image_px(&ma.diffuse, x, y)[c] == wv_image_px(&mb.diffuse, y, x)[c]);
          assert_true(wv_image_px(&ma.roughness, x, y)[c] == wv_image_px(&mb.roughness, y, x)[c]);
        }
        compared++;
      }
    print_message("twill90 vs mirrored twill (twist %g): worst vector difference %.2e\n", a.twist_deg, worst);
    assert_true(worst < 1e-4);
    assert_int_equal(compared, N * N);
    wv_maps_free(&ma), wv_maps_free(&mb);
  }
}

/* Tiles must join seamlessly: the first column continues the last one, and
 * noise repeats with the tile. */
static void test_maps_tile(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("satin", &p, NULL);
  p.noise_level = 5;
  wv_maps a, b;
  assert_int_equal(wv_maps_generate(&p, 64, &a, NULL), WV_OK);
  p.seed = 99;
  assert_int_equal(wv_maps_generate(&p, 64, &b, NULL), WV_OK);
  assert_true(wv_image_mad(&a.normal, &b.normal) > 1e-4); /* the seed changes the noise */
  /* sample just beyond the right edge through the yarn model: equals column 0 */
  wv_yarn_model m;
  wv_params_yarn_model(&p, &m, NULL);
  m.period_rows = m.weave.rows, m.period_cols = m.weave.cols;
  for (int y = 0; y < 64; y++) {
    float fy = (float)(-(y + 0.5) / 64 * b.tile_mm[1]);
    wv_yarn_point p0, p1;
    wv_yarn_eval(&m, (float)(0.5 / 64 * b.tile_mm[0]), fy, &p0);
    wv_yarn_eval(&m, (float)((64.5) / 64 * b.tile_mm[0]), fy, &p1);
    assert_true(p0.type == p1.type && fabsf(p0.beta - p1.beta) < 1e-6f);
    assert_true(fabsf(p0.n[0] - p1.n[0]) < 1e-3f && fabsf(p0.n[2] - p1.n[2]) < 1e-3f);
  }
  wv_maps_free(&a), wv_maps_free(&b);
}

/* Mean of the capture's channel c (c = 3: all three) over the centred square of side n. */
static double centre_mean(const wv_image *im, int n, int c) {
  double sum = 0;
  int x0 = (im->w - n) / 2, y0 = (im->h - n) / 2;
  for (int y = y0; y < y0 + n; y++)
    for (int x = x0; x < x0 + n; x++)
      for (int k = 0; k < 3; k++)
        if (c == 3 || k == c) sum += wv_image_px(im, x, y)[k];
  return sum / ((double)n * n * (c == 3 ? 3 : 1));
}

/* The brightest value of the centred square of side n. */
static double centre_max(const wv_image *im, int n) {
  double m = 0;
  int x0 = (im->w - n) / 2, y0 = (im->h - n) / 2;
  for (int y = y0; y < y0 + n; y++)
    for (int x = x0; x < x0 + n; x++)
      for (int k = 0; k < 3; k++) m = fmax(m, wv_image_px(im, x, y)[k]);
  return m;
}

/* A centred size x size window of a preset; glow > 0 sets the gap glow's radiance. */
static void render_params(const char *scene, const wv_params *p, int size, int spp, double glow, wv_image *out) {
  wv_scene s;
  wv_error err = {0};
  assert_int_equal(wv_scene_preset(scene, &s, &err), WV_OK);
  crop_scene(&s, size, size);
  if (glow > 0) s.glow_radiance = glow;
  wv_render_opts o = {.spp = spp};
  if (wv_render(&s, p, &o, out, NULL, &err)) fail_msg("%s", err.msg);
}

/* The same view on an image twice smaller (wv_scene_downscale, as a fit iterating at
 * --iter-scale 2 sees it): the back-lit rig's gap glow, falloff and blur, all given in
 * pixels, keep their place on the cloth, so the small render matches the large one
 * averaged down. */
static void test_downscale(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("plain", &p, NULL);
  p.yarn_width = 0.7, p.density[0] = p.density[1] = 60;
  wv_scene s, half;
  wv_error err = {0};
  assert_int_equal(wv_scene_preset("flat45-back", &s, &err), WV_OK);
  crop_scene(&s, 128, 128);
  s.glow_radiance = 0.5, s.psf_sigma = 2; /* below the clip; a blur too */
  wv_scene_downscale(&s, 2, &half);
  assert_int_equal(half.width, 64);
  assert_true(half.glow_sigma == s.glow_sigma / 2 && half.psf_sigma == 1);
  wv_render_opts o = {.spp = 16};
  wv_image big, small, down;
  assert_int_equal(wv_render(&s, &p, &o, &big, NULL, &err), WV_OK);
  assert_int_equal(wv_render(&half, &p, &o, &small, NULL, &err), WV_OK);
  assert_int_equal(wv_image_downsample(&big, 64, 64, &down, &err), WV_OK);
  /* the glow's ring between 8 and 24 pixels of the small image's centre, and the whole */
  double ring[2] = {0, 0}, whole[2] = {0, 0};
  int nr = 0;
  for (int y = 0; y < 64; y++)
    for (int x = 0; x < 64; x++) {
      double r = hypot(x + 0.5 - 32, y + 0.5 - 32), a = 0, b = 0;
      for (int c = 0; c < 3; c++) a += wv_image_px(&small, x, y)[c] / 3, b += wv_image_px(&down, x, y)[c] / 3;
      whole[0] += a / 4096, whole[1] += b / 4096;
      if (r >= 8 && r < 24) ring[0] += a, ring[1] += b, nr++;
    }
  ring[0] /= nr, ring[1] /= nr;
  print_message("downscale: ring %.4f against %.4f averaged down, whole %.4f against %.4f\n", ring[0], ring[1],
                whole[0], whole[1]);
  assert_true(fabs(ring[0] - ring[1]) < 0.03 * ring[1]);
  assert_true(fabs(whole[0] - whole[1]) < 0.03 * whole[1]);
  wv_image_free(&big), wv_image_free(&small), wv_image_free(&down);
}

/* The back-lit rig (flat45-back): light passes where the front-lit rig without its
 * light is black; open gaps show the light itself (the gap glow), brighter where
 * the gaps are wider than a pixel (a lower density); the colour is the
 * transmission colours': the diffuse one's, and the specular one's apart from the specular
 * reflection's. */
static void test_back_lit(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("twill", &p, NULL);
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      p.specular[y][c] = p.transmission_specular[y][c] = 0.1, p.diffuse[y][c] = 0.4, p.transmission[y][c] = 0.3;
  wv_image front, back;
  wv_scene s;
  wv_error err = {0};
  assert_int_equal(wv_scene_preset("flat45", &s, &err), WV_OK);
  crop_scene(&s, 96, 96);
  s.light_intensity = 0; /* the front light off */
  wv_render_opts o = {.spp = 8};
  assert_int_equal(wv_render(&s, &p, &o, &front, NULL, &err), WV_OK);
  render_params("flat45-back", &p, 96, 8, 0, &back);
  assert_true(centre_mean(&front, 96, 3) == 0.0);
  assert_true(centre_mean(&back, 96, 3) > 0.1);
  wv_image_free(&front);
  /* no open gap at full yarn width: no glow; gaps (yarn width 0.7, open area 9%) glow */
  wv_image gaps, wide;
  p.yarn_width = 0.7;
  render_params("flat45-back", &p, 96, 8, 0, &gaps);
  double glow8 = centre_mean(&gaps, 8, 3);
  assert_true(glow8 > centre_mean(&back, 8, 3) + 0.05);
  /* at 30 yarns per inch a gap is two pixels wide: some pixels see it whole (a glow of
   * radiance 0.5, below the clip: at 8 the centre clips either way) */
  wv_image_free(&gaps);
  render_params("flat45-back", &p, 96, 8, 0.5, &gaps);
  p.density[0] = p.density[1] = 30;
  render_params("flat45-back", &p, 96, 8, 0.5, &wide);
  print_message("back-lit: no gaps %.3f, gaps %.3f (centre 8 px); brightest of the centre 16 px: 140/85 yarns per "
                "inch %.3f, 30 %.3f\n", centre_mean(&back, 8, 3), glow8, centre_max(&gaps, 16), centre_max(&wide, 16));
  assert_true(centre_max(&wide, 16) > centre_max(&gaps, 16) + 0.05);
  assert_true(fabs(centre_mean(&wide, 32, 3) - centre_mean(&gaps, 32, 3)) < 0.1); /* the same open area */
  wv_image_free(&back), wv_image_free(&gaps), wv_image_free(&wide);
  /* the colour follows the transmission colour (red through the yarns, then blue) */
  wv_image red, blue;
  p.yarn_width = 1;
  for (int y = 0; y < 2; y++) {
    p.transmission[y][0] = 0.6, p.transmission[y][1] = p.transmission[y][2] = 0.05;
  }
  render_params("flat45-back", &p, 64, 8, 0, &red);
  for (int y = 0; y < 2; y++) {
    p.transmission[y][2] = 0.6, p.transmission[y][0] = p.transmission[y][1] = 0.05;
  }
  render_params("flat45-back", &p, 64, 8, 0, &blue);
  assert_true(centre_mean(&red, 64, 0) > 2 * centre_mean(&red, 64, 2));
  assert_true(centre_mean(&blue, 64, 2) > 2 * centre_mean(&blue, 64, 0));
  /* no diffuse transmission: a green specular transmission colour makes the light through the
   * cloth green, whatever the specular reflection's colour (red); black without it */
  wv_image green, none;
  wv_params q = p;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      q.transmission[y][c] = 0, q.transmission_specular[y][c] = c == 1 ? 0.8 : 0.05, q.specular[y][c] = c == 0;
  render_params("flat45-back", &q, 64, 8, 0, &green);
  assert_true(centre_mean(&green, 64, 1) > 0.02 && centre_mean(&green, 64, 1) > 3 * centre_mean(&green, 64, 0));
  memset(q.transmission_specular, 0, sizeof q.transmission_specular);
  render_params("flat45-back", &q, 64, 8, 0, &none);
  assert_true(centre_mean(&none, 64, 0) == 0.0 && centre_mean(&none, 64, 1) == 0.0);
  wv_image_free(&green), wv_image_free(&none);
  /* the forward renderer and the gradient renderer's capture agree, glow included */
  wv_image dc, cap;
  double g[WV_P_COUNT];
  p.yarn_width = 0.7;
  wv_image_free(&red);
  render_params("flat45-back", &p, 64, 8, 0, &red);
  assert_int_equal(wv_scene_preset("flat45-back", &s, &err), WV_OK);
  crop_scene(&s, 64, 64);
  assert_int_equal(wv_image_alloc(&dc, 64, 64, 3, &err), WV_OK);
  memset(dc.data, 0, sizeof(float) * 64 * 64 * 3);
  assert_int_equal(wv_render_grad(&s, &p, &o, &dc, g, &cap, &err), WV_OK);
  assert_memory_equal(cap.data, red.data, sizeof(float) * 64 * 64 * 3);
  wv_image_free(&red), wv_image_free(&blue), wv_image_free(&dc), wv_image_free(&cap);
}

/* The transmission and open-area maps: the open area is (1 - w)^2 of the tile (no yarn
 * of either kind), dark in the transmission map; elsewhere the transmission map is the
 * yarn's k_t + k_f (the light the forward band carries at normal incidence), dimmed by the
 * cloth's thickness. */
static void test_maps_transmission(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("twill", &p, NULL);
  p.yarn_width = 0.8;
  for (int c = 0; c < 3; c++) p.transmission[WV_WARP][c] = 0.2 + 0.1 * c, p.transmission[WV_WEFT][c] = 0.6;
  p.transmission_forward[WV_WARP][0] = 0.3, p.transmission_forward[WV_WARP][1] = 0.1; /* warp: 0.5, 0.4, 0.4 */
  for (int c = 0; c < 3; c++) p.transmission_forward[WV_WEFT][c] = 0.2;             /* weft: 0.8 */
  wv_maps m;
  assert_int_equal(wv_maps_generate(&p, 256, &m, NULL), WV_OK);
  double open = 0, t = 0;
  int n = 256 * 256, warp = 0;
  for (int i = 0; i < n; i++) {
    const float *o = m.open.data + 3 * i, *kt = m.transmission.data + 3 * i, *id = m.yarn_id.data + 3 * i;
    open += o[0];
    assert_true(o[0] == 0.0f || o[0] == 1.0f);
    if (o[0] == 1.0f) {
      assert_true(kt[0] == 0.0f && kt[1] == 0.0f && kt[2] == 0.0f && id[0] == 0.0f && id[1] == 0.0f);
      continue;
    }
    for (int c = 0; c < 3; c++) assert_true(kt[c] > 0.0f && kt[c] <= 0.8f + 1e-6f);
    if (id[0] == 1.0f) { /* on a warp yarn: its colour, dimmed alike in every channel */
      assert_true(kt[0] <= 0.5f + 1e-6f && kt[0] >= 0.5f / 3);
      assert_true(fabsf(kt[2] / kt[0] - 0.8f) < 1e-4f);
      warp++;
    }
    t += kt[1];
  }
  assert_true(fabs(open / n - 0.04) < 0.005);
  assert_true(warp > n / 4 && t > 0);
  wv_maps_free(&m);
}

/* Golden images guard against unintended changes of the forward model. The
 * cases reach every shading path: whole vectors of one pixel's samples (16 spp),
 * vectors packed with several pixels' samples (3 spp, and 12 = one vector and
 * 4 packed), silhouette pixels traced sample by sample (a field of view three
 * times the preset's), segment noise, gaps and glints, and points past the
 * 8-wide integer range, which fall back to the scalar kernel (a fabric offset
 * of 10 km).
 * To update after an intended change: WOVEN_UPDATE_GOLDEN=1 ./test_render
 * (from the build's tests/ directory), then review and commit tests/golden/. */
static void test_golden(void **state) {
  (void)state;
  static const struct {
    const char *scene, *pattern, *file;
    int spp, variant; /* 0: the preset's centre; 1: wide view, noise, gaps; 2: far offset (the fabric coordinates at the limit) */
  } cases[] = {{"cylinder", "twill", "cylinder_twill", 16, 0},
               {"cylinder", "satin", "cylinder_satin", 16, 0},
               {"flat45", "plain", "flat45_plain", 16, 0},
               {"flat45", "twill90", "flat45_twill90", 16, 0},
               {"flat45", "satin90", "flat45_satin90", 16, 0},
               {"cylinder", "twill", "cylinder_twill_wide_spp12", 12, 1},
               {"flat45", "satin", "flat45_satin_spp3", 3, 1},
               {"flat45", "plain", "flat45_plain_far", 8, 2},
               {"flat45-back", "satin", "flat45-back_satin", 16, 0},
               {"flat45-back", "twill", "flat45-back_twill_gaps", 12, 1}};
  int update = getenv("WOVEN_UPDATE_GOLDEN") != NULL;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    wv_scene s;
    wv_params p;
    wv_error err = {0};
    assert_int_equal(wv_scene_preset(cases[i].scene, &s, &err), WV_OK);
    crop_scene(&s, 64, 48);
    assert_int_equal(wv_params_default(cases[i].pattern, &p, &err), WV_OK);
    p.seed = 3;
    if (cases[i].variant == 1) {
      s.vfov_deg *= 3;
      p.noise_level = 4, p.yarn_width = 0.85, p.specular_noise = 1;
    } else if (cases[i].variant == 2) {
      s.fabric_offset[0] = 1e4, s.fabric_offset[1] = -1e4; /* the scenes' limit, WV_SCENE_MAX_OFFSET_MM */
    }
    wv_render_opts o = {.spp = cases[i].spp};
    wv_image img, ref;
    if (wv_render(&s, &p, &o, &img, NULL, &err)) fail_msg("%s", err.msg);
    char path[512];
    snprintf(path, sizeof path, "%s/tests/golden/%s.exr", WOVEN_SOURCE_DIR, cases[i].file);
    if (update) {
      assert_int_equal(wv_image_write_exr(path, &img, &err), WV_OK);
      print_message("updated %s\n", path);
    } else {
      if (wv_image_read(path, &ref, NULL, &err)) fail_msg("%s", err.msg);
      double mad = wv_image_mad(&img, &ref), worst = 0;
      for (size_t k = 0; k < (size_t)img.w * img.h * 3; k++) worst = fmax(worst, fabs(img.data[k] - ref.data[k]));
      /* loose enough for other compilers' float rounding, tight enough for any model change */
      if (!(mad < 2e-4 && worst < 0.05)) fail_msg("%s: MAD %g, max %g", path, mad, worst);
      wv_image_free(&ref);
    }
    wv_image_free(&img);
  }
}

/* At every spp the pixel's samples fill its whole grid, one a cell, and their x values lie
 * in distinct 1/spp strata, as do their y values: no part of the pixel goes unsampled (a
 * grid with more cells than samples left its last cells empty at 8 or 32 spp). */
static void test_sampler_covers_pixel(void **state) {
  (void)state;
  for (int spp = 1; spp <= 300; spp++) {
    int nx, ny;
    wv_pixel_grid(spp, &nx, &ny);
    assert_int_equal(nx * ny, spp);
    assert_true(ny <= nx);
    unsigned char *used = calloc((size_t)3 * spp, 1);
    assert_non_null(used);
    for (int px = 0; px < 3; px++) {
      memset(used, 0, (size_t)3 * spp);
      wv_pixel_sampler_f ps = wv_pixel_sampler_make(px, 7, 64, 11);
      for (int s = 0; s < spp; s++) {
        float sx, sy;
        wv_sample_at_f(&ps, nx, ny, s, &sx, &sy);
        assert_true(sx >= 0 && sx < 1 && sy >= 0 && sy < 1);
        int cx = (int)(sx * nx), cy = (int)(sy * ny), stx = (int)(sx * spp), sty = (int)(sy * spp);
        assert_false(used[cy * nx + cx]++);           /* one sample a cell */
        assert_false(used[spp + stx]++);              /* distinct x strata */
        assert_false(used[2 * spp + sty]++);          /* distinct y strata */
      }
    }
    free(used);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_sampler_covers_pixel), cmocka_unit_test(test_deterministic), cmocka_unit_test(test_footprints_cache),
                                     cmocka_unit_test(test_default_spp_converged),
                                     cmocka_unit_test(test_twill90_is_mirrored_twill), cmocka_unit_test(test_maps_tile),
                                     cmocka_unit_test(test_back_lit), cmocka_unit_test(test_downscale),
                                     cmocka_unit_test(test_maps_transmission),
                                     cmocka_unit_test(test_golden)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
