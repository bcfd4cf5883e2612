/* woven: formatted lines for the note callbacks of library jobs (util/note.h). */
#include "util/note.h"

#include <stdarg.h>
#include <stdio.h>

void wv_note(wv_note_fn fn, void *user, const char *fmt, ...) {
  if (!fn) return;
  char text[8400];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(text, sizeof text, fmt, ap);
  va_end(ap);
  fn(user, text);
}
