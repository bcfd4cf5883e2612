/* Shared helpers for the cmocka tests. */
#ifndef WOVEN_TESTUTIL_H
#define WOVEN_TESTUTIL_H
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

/* A fresh empty directory under the test's working directory. */
const char *tu_tmpdir(const char *name);
#endif
