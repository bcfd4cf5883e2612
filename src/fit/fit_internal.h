/* Shared between the fit's source files; not public. */
#ifndef WOVEN_FIT_INTERNAL_H
#define WOVEN_FIT_INTERNAL_H

#include <jansson.h>

#include "woven/fit.h"

/* The options a checkpoint stores ("opts"), as JSON (a new object) ... */
json_t *wv_fit_opts_json(const wv_fit_opts *o);
/* ... and read back, each range-checked as wv_fit_opts_validate checks it; options a
 * checkpoint may lack keep the value o holds. */
wv_status wv_fit_opts_read_json(json_t *opts, wv_fit_opts *o, wv_error *err);

#endif
