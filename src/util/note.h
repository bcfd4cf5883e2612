/* woven: a formatted line for a job's optional note callback (progress messages). */
#ifndef WOVEN_UTIL_NOTE_H
#define WOVEN_UTIL_NOTE_H

typedef void (*wv_note_fn)(void *user, const char *text);
/* Formats the line and passes it to fn; nothing when fn is NULL. */
void wv_note(wv_note_fn fn, void *user, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

#endif
