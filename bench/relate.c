/* How two photos of a weave relate (wv_weave_relate): the scale and rotation that carry the
 * first photo's weave spectrum onto the second's, and whether they relate at all.
 *   relate A B [C D ...]
 * Each pair of images (A with B, C with D, ...) is read whole (as stored, no scene) and
 * compared; prints one line per pair, then one JSON object on the last line. */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>

#include "woven/analysis.h"
#include "woven/io.h"

static void die(const wv_error *e) {
  fprintf(stderr, "relate: %s\n", e->msg);
  exit(1);
}

int main(int argc, char **argv) {
  if (argc < 3 || (argc - 1) % 2) {
    fprintf(stderr, "usage: relate A B [C D ...]  (pairs of images of one weave)\n");
    return 2;
  }
  json_t *pairs = json_array();
  for (int i = 1; i + 1 < argc; i += 2) {
    wv_error e = {0};
    wv_image a = {0}, b = {0};
    wv_weave_relation r;
    if (wv_image_read(argv[i], &a, NULL, &e) || wv_image_read(argv[i + 1], &b, NULL, &e) ||
        wv_weave_relate(&a, &b, &r, &e))
      die(&e);
    printf("%s -> %s: %s, scale %.4f, rotation %+.3f deg, %d of %d peaks, score %.3f (%d px window)\n", argv[i],
           argv[i + 1], r.found ? "related" : "not related", r.scale, r.rotation_deg, r.matched, 2 * WV_RELATE_PEAKS,
           r.score, r.window);
    json_array_append_new(pairs, json_pack("{s:s,s:s,s:b,s:f,s:f,s:i,s:f,s:i}", "a", argv[i], "b", argv[i + 1],
                                           "related", r.found, "scale", r.scale, "rotation_deg", r.rotation_deg,
                                           "matched", r.matched, "score", r.score, "window", r.window));
    wv_image_free(&a), wv_image_free(&b);
  }
  json_t *root = json_pack("{s:o}", "pairs", pairs);
  char *text = json_dumps(root, JSON_COMPACT);
  printf("%s\n", text);
  free(text);
  json_decref(root);
  return 0;
}
