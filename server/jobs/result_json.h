/* result_json.h -- what the kinds' result writers share: a finished specimen becomes the JSON of
 * GET /v1/jobs/{id}/result (api.md "Result"), written by its kind (kind.h: gpd_kind.result;
 * each kind file documents its own format), with these pieces and in these conventions:
 *   - every result begins with {"kind", "seed", "outputs" (the spec's, echoed)};
 *   - non-finite numbers are written as null; reals are printed with 17 significant digits
 *     (they read back bit for bit, as in the exports);
 *   - the text is written as it is produced (gpd_jw below): a worker holds the specimen and
 *     the text, never a tree of the specimen; the small parts (stats, timings) may be built as
 *     jansson trees and written through gpd_jw_json, byte for byte as json_dumps would;
 *   - the per-item arrays of a large specimen take seconds to write: the writer stops early
 *     when the worker's cancel flag comes up.
 * The field names follow server/svg/svg.h.
 *
 * The streaming writer, gpd_jw: JSON text appended to a growable buffer, in the exact bytes of
 * jansson's json_dumps(v, JSON_COMPACT | JSON_REAL_PRECISION(17)) for the same values (no
 * spaces; reals "%.17g" with ".0" added to an integral value and the exponent without "+" or
 * leading zeros; strings escaped as jansson does: \" \\ \b \f \n \r \t, other bytes below 0x20
 * as \u00XX, everything else, UTF-8 included, as is). Invariant: the text is always a prefix of
 * valid JSON; the caller pairs begin/end and puts a key before each value inside an object
 * (a mismatch is a programming error: gpd_jw_take refuses a text whose nesting is open).
 * Every value counts one piece; every GPD_JW_CANCEL_EVERY pieces the writer reads the cancel
 * flag, and once it is up (or memory ran out) every later call does nothing: the writers need
 * no checks of their own. One writer belongs to one thread; the flag may be raised by any.
 * The writer owns its text until gpd_jw_take or gpd_jw_finish hands it over; the buffer
 * doubles as it grows (glibc moves a large block by remapping it, without a copy).
 * Spilling (gpd_jw_spill, the workers'): once the text passes a threshold (a few MB) the writer
 * moves it into an unlinked temporary file (O_TMPFILE, else mkstemp + unlink, in the directory
 * it was given: the database's, so on its disk rather than a RAM /tmp) and from then on appends
 * every GPD_JW_CHUNK bytes to it, so that a worker's memory is the specimen plus a few MB
 * however long the text; the store then copies the file into the database in pieces
 * (store.h, store_text). A file that cannot be made leaves the text in memory (logged); a
 * write that fails (disk full) stops the writer with GPD_JW_IO (errno in w->err). The file
 * goes with its descriptor: a crash leaves nothing behind.
 * Reals of 1e-6 <= |x| < 1e38 are formatted from their exact 17-digit rounding in 128-bit
 * integers (~5x faster than printf, the same bytes), the others by printf. */
#ifndef GPD_RESULT_JSON_H
#define GPD_RESULT_JSON_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "util/util.h"

/* A double as JSON: a real, or null when not finite. */
json_t *gpd_jreal(double x);
/* n doubles as an array of gpd_jreal, or null when v is NULL. */
json_t *gpd_jreals(const double *v, size_t n);

/* stats.fit's members that every specimen kind writes alike (api.md): the fit of a size law
 * (areas in 2D, volumes in 3D: {"law", "target", "achieved", "ks", "ks_critical", "w1", "n",
 * "range"} and, with_curves, "cdf") and a sieve's passing by mass. */
struct gp_fit_area;
struct gp_fit_passing;
json_t *gpd_fit_size(const struct gp_fit_area *a, int with_curves);
json_t *gpd_fit_passing(const struct gp_fit_passing *p);

/* 1 when the worker's cancel flag (raised by another thread with an atomic store; may be
 * NULL) is up. */
int gpd_cancel_raised(const volatile int *cancel);

/* ---- the streaming writer ---- */

#define GPD_JW_CANCEL_EVERY 4096 /* pieces between two looks at the cancel flag (~1 ms) */
#define GPD_JW_MAX_DEPTH 64

#define GPD_JW_SPILL_AT ((size_t)4 << 20) /* the workers' spill threshold: 4 MB */
#define GPD_JW_CHUNK ((size_t)1 << 20)    /* bytes appended to the file at a time, once spilled */

/* the writer's state: anything but OK stops it (INVALID: nested deeper than GPD_JW_MAX_DEPTH;
 * IO: its temporary file could not be written) */
enum { GPD_JW_OK = 0, GPD_JW_CANCELLED, GPD_JW_OOM, GPD_JW_INVALID, GPD_JW_IO };

typedef struct gpd_jw {
    gpd_buf b;                    /* the text so far, or past `spilled` once in the file (owned) */
    int fd;                       /* the temporary file (owned), -1 while the text is in memory */
    uint64_t spilled;             /* bytes of the text already in the file */
    size_t flush_at;              /* b.len that sends b to the file (SIZE_MAX: never) */
    char *spill_dir;              /* where the file is made (owned; NULL: no spilling) */
    int err;                      /* errno of a failed file write (state GPD_JW_IO) */
    const volatile int *cancel;   /* may be NULL */
    unsigned long pieces;         /* values written, for the cancel checks */
    int state;                    /* GPD_JW_*: anything but OK stops the writing */
    int depth;                    /* open objects and arrays */
    int after_key;                /* a key was written: its value comes next, no comma */
    uint64_t nonempty;            /* bit d: the container at depth d has a member already */
    double pause_s;               /* a testing hook: slept at each look at the flag (0: none) */
} gpd_jw;

/* An empty writer that reads *cancel (may be NULL); it keeps its text in memory. */
void gpd_jw_init(gpd_jw *w, const volatile int *cancel);
/* From now on the text spills into a temporary file made in dir once it passes `at` bytes
 * (before anything is written; `at` 0: GPD_JW_SPILL_AT). 0, or -1 (out of memory: the text
 * stays in memory). */
int gpd_jw_spill(gpd_jw *w, const char *dir, size_t at);
/* Drops the text and its file (the writer may be initialised again). */
void gpd_jw_free(gpd_jw *w);
/* The finished text (malloc'ed, NUL-terminated; its length in *len, may be NULL), the writer
 * left empty; NULL (text dropped) when it was cancelled, ran out of memory, could not write its
 * file or has a container still open. A spilled text is read back into memory. */
char *gpd_jw_take(gpd_jw *w, size_t *len);
/* The finished text where it is: in memory (*mem malloc'ed, NUL-terminated, *fd -1) or, once
 * spilled, in the temporary file (*fd, the caller's to close, to be read with pread from
 * offset 0; *mem NULL), *len bytes either way; the writer left empty. 0, or (nothing handed
 * over, text dropped) where gpd_jw_take gives NULL: the errno of a failed write of the file
 * (> 0), else -1 (cancelled, out of memory, nesting open). */
int gpd_jw_finish(gpd_jw *w, char **mem, int *fd, uint64_t *len);

void gpd_jw_begin_object(gpd_jw *w);
void gpd_jw_end_object(gpd_jw *w);
void gpd_jw_begin_array(gpd_jw *w);
void gpd_jw_end_array(gpd_jw *w);
/* A member's name, inside an object; its value follows. */
void gpd_jw_key(gpd_jw *w, const char *key);
/* A string (NUL-terminated, UTF-8), escaped. */
void gpd_jw_string(gpd_jw *w, const char *s);
/* A real: 17 significant digits, null when not finite. */
void gpd_jw_real(gpd_jw *w, double x);
void gpd_jw_integer(gpd_jw *w, long long v);
void gpd_jw_null(gpd_jw *w);
/* [v[0], ...] as reals, or null when v is NULL (as gpd_jreals). */
void gpd_jw_reals(gpd_jw *w, const double *v, size_t n);
/* A jansson value as json_dumps(v, JSON_COMPACT | JSON_REAL_PRECISION(17)) writes it (an
 * object's members in their order); null for NULL. */
void gpd_jw_json(gpd_jw *w, const json_t *v);
/* Each member of object o (in its order) as key and value of the object being written. */
void gpd_jw_members(gpd_jw *w, const json_t *o);

/* The elements i = 0 .. n - 1 of the array being written, element i written by
 * item(w, i, user) (one value each), formatted by up to `threads` threads in blocks of `block`
 * items, each into a writer of its own, and appended in order: the same bytes as the loop
 * over item on w alone, whatever `threads` and `block`. Each thread's writer reads the cancel
 * flag at each block and every GPD_JW_CANCEL_EVERY of its own pieces. The items must only
 * read what they are given (they run at once). Memory: 2 x threads blocks of text besides
 * w's; a round of blocks costs a barrier (a few us), so a block should be some 100 KB of
 * text (a 2D grain is ~7 KB, a sphere ~100 B). */
typedef void (*gpd_jw_item_fn)(gpd_jw *w, size_t i, const void *user);
void gpd_jw_items(gpd_jw *w, size_t n, gpd_jw_item_fn item, const void *user, int threads,
                  size_t block);

/* The head of a result: {"kind": kind, "seed": seed, "outputs": the spec's outputs (when it
 * has them)}, a new object to which a kind adds its other small members (stats, timings) before
 * writing its members (gpd_jw_members) and then its per-item arrays; NULL on out of memory. */
json_t *gpd_result_new(const char *kind, uint64_t seed, const json_t *spec_json);

#endif /* GPD_RESULT_JSON_H */
