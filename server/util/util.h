/* util.h -- what every part of grainpackd uses: its error style, the logger, the clock, job
 * ids and a growable byte buffer.
 *
 * The error style of server/ (one for all its files):
 *   - A function that can fail returns an int, 0 on success and non-zero on failure: -1, or a
 *     value of a named enum where callers must tell failures apart (store_rc, svg_job_rc). One
 *     that makes something returns it, or NULL on failure. A predicate returns 1 or 0. (The
 *     HTTP handlers return libmicrohttpd's MHD_YES / MHD_NO, having queued the answer.)
 *   - What went wrong goes where it is used: into a gpd_err the caller passes when a client is
 *     told (an HTTP status and a one-line message, gpd_err_set), else into the log (gpd_log) at
 *     the place it happened, once; at start-up, before the log, on stderr. Functions that only
 *     pass a failure on log nothing.
 *   - Out of memory is a failure like any other (500 "internal" where a client is waiting).
 */
#ifndef GPD_UTIL_H
#define GPD_UTIL_H

#include <stddef.h>

/* ---- errors told to a client ---- */

typedef struct gpd_err {
    int status;    /* the HTTP status of the failure: 400, 409, 500, ... (0 before any) */
    char msg[512]; /* one line, without the status */
} gpd_err;

/* Sets *e (e may be NULL: nothing is kept). */
void gpd_err_set(gpd_err *e, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* ---- logging (stderr) ---- */

typedef enum { GPD_LOG_ERROR = 0, GPD_LOG_WARN, GPD_LOG_INFO, GPD_LOG_DEBUG } gpd_log_level;

/* Parses "error", "warn", "info", "debug"; -1 when unknown. */
int gpd_log_parse_level(const char *s);
/* Messages above level are dropped (default GPD_LOG_INFO). */
void gpd_log_set_level(gpd_log_level level);
/* 1 when a message at level would be written (to skip making one that would not). */
int gpd_log_enabled(gpd_log_level level);
void gpd_log(gpd_log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* ---- time and ids ---- */

/* RFC 3339 UTC with milliseconds, e.g. "2026-11-23T17:25:47.123Z" (buf >= 32). */
void gpd_now_rfc3339(char *buf, size_t len);
/* The same for the time ago_s seconds before now (the cut-off of the retention sweep). */
void gpd_past_rfc3339(double ago_s, char *buf, size_t len);
double gpd_monotonic_s(void);
/* Sleeps s seconds, through signals. */
void gpd_sleep_s(double s);
/* 32 lower-case hex digits from /dev/urandom; 0 on success. */
int gpd_new_id(char out[33]);
/* 1 when s looks like a job id (1..64 chars of [0-9a-zA-Z_-]). */
int gpd_id_is_plausible(const char *s);

/* ---- a growable buffer ---- */

/* Text or bytes appended at the end, always followed by a NUL (once anything is in it). After
 * a failed allocation oom is set, the contents stay as they were and every later append is a
 * no-op, so that a writer checks once, at the end. Zero-initialise; free(buf) when done. */
typedef struct gpd_buf {
    char *buf;
    size_t len, cap;
    int oom;
} gpd_buf;

/* Room for n more bytes and the NUL; 0, or -1 (oom). */
int gpd_buf_reserve(gpd_buf *b, size_t n);
/* Appends n bytes; 0, or -1 (oom). */
int gpd_buf_add(gpd_buf *b, const void *p, size_t n);
/* Appends formatted text; 0, or -1 (oom). */
int gpd_buf_printf(gpd_buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* ---- the heap ---- */

/* Gives the freed heap back to the system (glibc's malloc_trim), so that a daemon that built a
 * big specimen or picture is small again once idle. A no-op where malloc is not glibc's: under
 * ASan glibc's arenas are never initialised, and two threads trimming at once raced in its lazy
 * initialisation (a read of a NULL top chunk in mtrim, seen in CI on a cancel). */
void gpd_heap_trim(void);

#endif /* GPD_UTIL_H */
