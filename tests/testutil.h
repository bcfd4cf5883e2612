/* Shared helpers for the cmocka tests. */
#ifndef WOVEN_TESTUTIL_H
#define WOVEN_TESTUTIL_H
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "woven/scene.h"

/* The centre w x h pixels of a preset scene (the same pixels as the full image
 * there), rendered at spp. */
void tu_centre_window(wv_scene *s, const char *preset, int w, int h, int spp);

/* A fresh empty directory under the test's working directory. */
const char *tu_tmpdir(const char *name);
#endif
