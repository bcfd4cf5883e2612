/* Choosing the weave pattern (wv_fabricnet_choose_pattern): synthetic targets drawn from
 * the prior of each pattern, rendered in a small close-up scene, and the choice made from
 * their true continuous parameters. That tests the criterion, not a network's accuracy
 * (bench/pattern measures both on the cylinder scene). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/render.h"

/* Flat sample seen from above, close enough that yarns are 2..11 pixels apart (0.044 mm
 * per pixel): the weave is visible, as in a photo at the rig's full resolution. */
static const char *SCENE =
    "{\"name\":\"close\",\"image\":{\"width\":96,\"height\":64,\"spp\":16},"
    "\"camera\":{\"position_mm\":[0,0,8],\"look_at_mm\":[0,0,0],\"vfov_deg\":20},\"sample\":{\"shape\":\"plane\"},"
    "\"light\":{\"position_mm\":[0,8,8],\"intensity\":300},\"response\":{\"encoding\":\"gamma\",\"gamma\":2.2},"
    "\"falloff\":{\"type\":\"gaussian\",\"sigma_px\":80}}";

typedef struct {
  wv_scene scene;
  wv_descriptor *d;
  wv_fabricnet net; /* untrained: only its output ranges are used */
  float *gram;
} fixture;

static int setup(void **state) {
  fixture *f = calloc(1, sizeof *f);
  wv_error e;
  assert_int_equal(wv_scene_parse(SCENE, "test", &f->scene, &e), WV_OK);
  assert_int_equal(wv_descriptor_create_default(&f->d, &e), WV_OK);
  int n = (int)wv_descriptor_size(f->d);
  assert_int_equal(wv_fabricnet_init(&f->net, "default", n, &f->scene, 1, &e), WV_OK);
  f->gram = malloc(sizeof(float) * (size_t)n);
  *state = f;
  return 0;
}

static int teardown(void **state) {
  fixture *f = *state;
  wv_fabricnet_free(&f->net);
  wv_descriptor_free(f->d);
  free(f->gram);
  free(f);
  return 0;
}

/* The choice for a prior draw of 'pattern', from its true continuous parameters. */
static int choose(fixture *f, const char *pattern, uint64_t seed, wv_pattern_choice *c) {
  wv_error e = {0};
  wv_params truth;
  wv_image photo = {0};
  wv_render_opts ro = {0, 0, NULL, NULL, NULL};
  float y[WV_NET_OUT];
  assert_int_equal(wv_params_sample_prior(pattern, seed, &truth, &e), WV_OK);
  assert_int_equal(wv_render(&f->scene, &truth, &ro, &photo, NULL, &e), WV_OK);
  assert_int_equal(wv_descriptor_forward(f->d, &photo, f->gram, &e), WV_OK);
  wv_fabricnet_targets(&truth, y);
  assert_int_equal(wv_fabricnet_choose_pattern(&f->net, f->d, &f->scene, &photo, f->gram, y, NULL, c, &e), WV_OK);
  wv_image_free(&photo);
  fprintf(stderr, "%s seed %llu -> %s:", pattern, (unsigned long long)seed, wv_net_pattern(c->best));
  for (int i = 0; i < WV_NET_PATTERNS; i++) fprintf(stderr, " %s %.6f", wv_net_pattern(i), c->loss[i]);
  fprintf(stderr, "\n");
  return c->best;
}

static void test_picks_true_pattern(void **state) {
  fixture *f = *state;
  int wrong = 0;
  for (int p = 0; p < WV_NET_PATTERNS; p++)
    for (uint64_t seed = 1; seed <= 3; seed++) {
      wv_pattern_choice c;
      int best = choose(f, wv_net_pattern(p), seed, &c);
      wrong += best != p;
      /* each candidate is the network mapping with its own pattern */
      for (int i = 0; i < WV_NET_PATTERNS; i++) assert_string_equal(c.params[i].pattern, wv_net_pattern(i));
      assert_int_equal(c.spp, WV_PATTERN_SPP);
    }
  assert_int_equal(wrong, 0);
}

/* A photo of another size is an error naming both sizes, not a wrong answer. */
static void test_photo_size(void **state) {
  fixture *f = *state;
  wv_error e = {0};
  wv_image photo;
  float y[WV_NET_OUT] = {0};
  wv_pattern_choice c;
  assert_int_equal(wv_image_alloc(&photo, 64, 64, 3, &e), WV_OK);
  assert_int_equal(wv_fabricnet_choose_pattern(&f->net, f->d, &f->scene, &photo, f->gram, y, NULL, &c, &e),
                   WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "64 x 64"));
  assert_non_null(strstr(e.msg, "96 x 64"));
  wv_image_free(&photo);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_picks_true_pattern, setup, teardown),
      cmocka_unit_test_setup_teardown(test_photo_size, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
