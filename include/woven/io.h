/* woven: image and file I/O. PNG (8/16-bit, libpng), JPEG (libjpeg-turbo), EXR (OpenEXR C API).
 * Readers return the file's values as floats without colour decoding: 8/16-bit
 * integers map to [0,1], EXR keeps its float values. Colour encoding is the caller's
 * business (the scene says whether a photo is sRGB, gamma or linear).
 * Writers never leave a partial file: they write to a temporary file next to the
 * target and rename it into place, so an earlier result survives any failure.
 * Directories of outputs are written the same way (wv_outdir below). */
#ifndef WOVEN_IO_H
#define WOVEN_IO_H

#include <stddef.h>
#include <stdio.h>
#include "woven/error.h"
#include "woven/image.h"

typedef struct {
  int bit_depth;        /* 8 or 16 for PNG/JPEG, 16 (half) or 32 for EXR */
  int is_float;         /* 1 for EXR */
  int channels_in_file; /* 1 (grey), 2 (grey+alpha), 3 or 4 */
} wv_image_info;

/* Largest image read: the size in the file's header is checked before any pixel
 * memory is allocated, so a small file claiming a huge image is refused at once. */
#define WV_IMAGE_READ_MAX_SIDE 16384          /* pixels per side */
#define WV_IMAGE_READ_MAX_PIXELS (64L << 20)  /* 64 Mpixel (768 MB as RGB floats) */

/* Reads any supported image (detected from its magic bytes, not its name) and
 * returns it with 3 channels (grey is replicated, alpha dropped). info may be NULL.
 * Images over WV_IMAGE_READ_MAX_SIDE or WV_IMAGE_READ_MAX_PIXELS are refused
 * (WV_ERR_NOMEM) before decoding.
 * Limits: CMYK JPEGs are refused; for EXR the first part is read, it must be a
 * scanline part (tiled and deep are refused) with half or float R,G,B or Y channels,
 * and its data window becomes the image. On failure *img is left empty. */
wv_status wv_image_read(const char *path, wv_image *img, wv_image_info *info, wv_error *err);

/* Checks that a PNG file is whole without decoding it: signature, IHDR first, every
 * chunk's CRC-32 and an IEND chunk (one pass over the file; catches truncated and
 * damaged files). */
wv_status wv_png_check(const char *path, wv_error *err);

/* Writes by extension: .png (8-bit, values clamped to [0,1], no colour encoding
 * applied: pass already-encoded values), .exr (32-bit float, linear).
 * Files are always RGB: a 1-channel image is replicated, a 4th channel is not stored.
 * wv_image_write_png takes bit_depth 8 or 16; EXR output is ZIP-compressed scanlines. */
wv_status wv_image_write(const char *path, const wv_image *img, wv_error *err);
wv_status wv_image_write_png(const char *path, const wv_image *img, int bit_depth, wv_error *err);
wv_status wv_image_write_exr(const char *path, const wv_image *img, wv_error *err);

/* Compresses an image (values in [0,1], 1 or 3+ channels) to JPEG at quality 1..100 in
 * memory and decodes it again into out (3 channels, allocated here). */
wv_status wv_image_jpeg_roundtrip(const wv_image *in, int quality, wv_image *out, wv_error *err);
/* An 8-bit PNG in memory (RGB, or RGBA for a 4-channel image; values clamped
 * to [0,1], no colour encoding applied). *out is malloc'ed; the caller frees it. */
wv_status wv_image_encode_png(const wv_image *img, unsigned char **out, size_t *len, wv_error *err);

/* Opens a file for reading only when it is a regular file: opened without blocking
 * (a FIFO or device never stalls the open), checked with fstat, then switched back to
 * blocking reads. Directories are refused as "is a directory", anything else that
 * is not a regular file as "not a regular file" (WV_ERR_IO, naming path). *fd is
 * close-on-exec; st, when not NULL, receives the file's status. Every reader of a
 * user's file opens it through these. */
struct stat;
wv_status wv_open_regular(const char *path, int *fd, struct stat *st, wv_error *err);
/* wv_open_regular as a stdio stream ("rb"). */
wv_status wv_fopen_regular(const char *path, FILE **fp, wv_error *err);

/* Messages never show more of a file than a short printable excerpt. Copies s into
 * out (len bytes with the NUL): bytes outside printable ASCII become '?', and a
 * longer text is cut with "...". */
void wv_printable_excerpt(const char *s, char *out, size_t len);
/* The JSON readers' messages end in "near '<text of the file>'": keeps at most keep
 * printable characters of that text (WV_EXCERPT_CHARS for a file the user named as
 * that kind of file), or with keep 0 drops it (a file another file refers to). */
#define WV_EXCERPT_CHARS 24
void wv_error_excerpt(wv_error *err, size_t keep);

/* Atomically replaces path with len bytes of data. */
wv_status wv_write_file_atomic(const char *path, const void *data, size_t len, wv_error *err);

/* Limits on whole-file reads: a file (or a device such as /dev/zero) longer than
 * the limit is refused with WV_ERR_NOMEM after reading at most limit + 1 bytes. */
#define WV_READ_MAX_BYTES ((size_t)1 << 30)  /* any file read whole: 1 GiB */
#define WV_JSON_MAX_BYTES ((size_t)64 << 20) /* JSON files (parameters, scenes, checkpoints): 64 MiB */
/* Reads a whole file of at most max bytes (NUL-terminated for convenience); caller
 * frees *data. len may be NULL. A directory is refused ("is a directory"). */
wv_status wv_read_file_max(const char *path, size_t max, char **data, size_t *len, wv_error *err);
/* wv_read_file_max with WV_READ_MAX_BYTES. */
wv_status wv_read_file(const char *path, char **data, size_t *len, wv_error *err);

/* ---- never write over an input ---- */

/* 1 when a and b name the same existing file (same device and inode, links
 * followed), 0 otherwise (also when either does not exist). */
int wv_same_file(const char *a, const char *b);
/* 1 when path is dir itself or lies anywhere below it (symbolic links and ".."
 * resolved; a path that does not exist yet counts where its nearest existing
 * ancestor is); 0 otherwise, also when dir does not exist. */
int wv_path_within(const char *path, const char *dir);
/* Refuses (WV_ERR_INVALID, naming both) an output that would replace one of the
 * inputs: output_is_dir 0: output is a file and must not be any input;
 * output_is_dir 1: output is a directory replaced as a whole and no input may lie
 * inside it. NULL entries in inputs are skipped. */
wv_status wv_check_not_input(const char *output, int output_is_dir, const char *const *inputs, int n_inputs,
                             wv_error *err);

/* ---- temporary files of interrupted runs ---- */

/* Temporary names are "<target>.tmp.XXXXXX" (six letters or digits). Removes, in
 * dir, those whose target is named prefix (any target when prefix is NULL) and
 * that are stale: owned by this user, not locked by a live writer (writers hold
 * a lock on them) and unchanged for WV_TMP_STALE_SECONDS. Files and whole
 * directories are removed; nothing else is touched. Returns how many. */
#define WV_TMP_STALE_SECONDS 10
int wv_remove_stale_temps(const char *dir, const char *prefix);
/* The same for the temporary files of one output file path, in its directory. */
int wv_remove_stale_temps_beside(const char *path);
/* 1 when name has the form of a temporary name. */
int wv_is_temp_name(const char *name);

/* ---- directories of outputs, written whole ---- */

/* A directory of outputs appears whole or not at all: the caller writes every file
 * into od->tmp, a new directory beside the target ("<path>.tmp.XXXXXX", same file
 * system), and commit renames it into place. An existing target is exchanged with
 * it atomically (renameat2 RENAME_EXCHANGE; where the file system cannot, the old
 * directory is renamed aside first and put back if the new one cannot take its
 * place) and then deleted, so on any failure or kill the old directory is intact.
 * While it is being written the temporary directory is locked, so a concurrent
 * wv_remove_stale_temps leaves it alone; after a kill it is stale and removed by
 * the next wv_outdir_begin of the same target. */
typedef struct {
  char *path; /* the target (owned copy; a symbolic link to a directory is resolved) */
  char *tmp;  /* the directory to write into (owned) */
  int fd;     /* open on tmp, holding its lock; -1 when closed */
} wv_outdir;

/* Checks that path can be replaced: absent, or a directory whose entries are all
 * named in own (a NULL-terminated list of the names the output consists of;
 * temporary names are ignored). Anything else (a file, or a directory holding
 * other files, which the replacement would delete) is refused with a message
 * naming it. Call it before long work; wv_outdir_begin checks again. */
wv_status wv_outdir_check(const char *path, const char *const *own, wv_error *err);
/* wv_outdir_check, removes stale temporary directories of this target, then
 * creates od->tmp. On failure od holds nothing to release. */
wv_status wv_outdir_begin(wv_outdir *od, const char *path, const char *const *own, wv_error *err);
/* Puts od->tmp in place of the target. On success or failure od is released and
 * no temporary directory is left; on failure the target is as it was. */
wv_status wv_outdir_commit(wv_outdir *od, wv_error *err);
/* Deletes od->tmp and releases od; the target is untouched. Safe on a released od.
 * err, when not NULL, is the failure's message: the temporary directory's name in
 * it is replaced by the target's, so it names the file the user asked for. */
void wv_outdir_abort(wv_outdir *od, wv_error *err);

#endif
