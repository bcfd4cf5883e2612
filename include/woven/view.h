/* woven: the interactive viewer, one self-contained HTML page that shades the
 * true woven model in WebGL (web/viewer/: three.js from npm, the fabric shader
 * fabric.frag mirroring src/yarn, src/render and src/scene). It shows the
 * capture rig as the scene's camera sees it, a flat swatch and a draped sheet in
 * a studio, with an orbit camera, a movable light, sliders for the parameters and
 * a before/after toggle against the photo. Nothing is fetched when it is viewed. */
#ifndef WOVEN_VIEW_H
#define WOVEN_VIEW_H

#include "woven/error.h"
#include "woven/params.h"
#include "woven/scene.h"

/* params and scene are required; zero (NULL) in the others: no photo, the default title. */
typedef struct {
  const wv_params *params;
  const wv_scene *scene;  /* the capture rig shown */
  const char *photo;      /* optional photo (any format woven reads), cropped and scaled
                             to the scene's image as a fit does */
  const char *title;      /* optional; NULL: "woven viewer" */
} wv_view_opts;

/* Writes the page atomically (nothing is left on failure). */
wv_status wv_view_write(const char *path, const wv_view_opts *o, wv_error *err);

#endif
