/* result_json.c -- the pieces every result writer uses, and the streaming writer (see
 * result_json.h). */
#define _GNU_SOURCE /* O_TMPFILE, mkostemp */
#include "jobs/result_json.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gp_fit.h"
#include "gp_law.h"
#include "jobs/file_errors.h"

json_t *gpd_jreal(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

json_t *gpd_jreals(const double *v, size_t n)
{
    if (!v) return json_null();
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++) json_array_append_new(a, gpd_jreal(v[i]));
    return a;
}

static json_t *mean_cov(double mean, double cov)
{
    return json_pack("{s:o, s:o}", "mean", gpd_jreal(mean), "cov", gpd_jreal(cov));
}

static json_t *pair(double a, double b)
{
    return json_pack("[o, o]", gpd_jreal(a), gpd_jreal(b));
}

json_t *gpd_fit_size(const gp_fit_area *a, int with_curves)
{
    const char *law = gp_law_name(a->law);
    json_t *o = json_pack("{s:s, s:o, s:o, s:o, s:o, s:o, s:I}", "law", law ? law : "",
                          "target", mean_cov(a->target_mean, a->target_cov), "achieved",
                          mean_cov(a->mean, a->cov), "ks", gpd_jreal(a->ks), "ks_critical",
                          gpd_jreal(a->ks_critical), "w1", gpd_jreal(a->w1), "n",
                          (json_int_t)a->n);
    if (!o) return NULL;
    json_object_set_new(o, "range", json_pack("{s:o, s:o}", "achieved", pair(a->min, a->max),
                                              "target_p001_p999", pair(a->q001, a->q999)));
    if (with_curves && a->ncurve > 0 && a->curve_x && a->curve_target && a->curve_achieved)
        json_object_set_new(o, "cdf",
                            json_pack("{s:o, s:o, s:o}", "x", gpd_jreals(a->curve_x, a->ncurve),
                                      "target", gpd_jreals(a->curve_target, a->ncurve), "achieved",
                                      gpd_jreals(a->curve_achieved, a->ncurve)));
    return o;
}

json_t *gpd_fit_passing(const gp_fit_passing *p)
{
    return json_pack("{s:o, s:o, s:o, s:o}", "diameters", gpd_jreals(p->diameters, p->n), "target",
                     gpd_jreals(p->target, p->n), "achieved", gpd_jreals(p->achieved, p->n),
                     "max_error_pp", gpd_jreal(p->max_error_pp));
}

json_t *gpd_result_new(const char *kind, uint64_t seed, const json_t *spec_json)
{
    json_t *r = json_object();
    if (!r) return NULL;
    json_object_set_new(r, "kind", json_string(kind));
    json_object_set_new(r, "seed", json_integer((json_int_t)seed));
    json_t *o = json_object_get(spec_json, "outputs");
    if (o) json_object_set(r, "outputs", o);
    return r;
}

int gpd_cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

/* ------------------------------------------------------------------ the streaming writer */

void gpd_jw_init(gpd_jw *w, const volatile int *cancel)
{
    memset(w, 0, sizeof *w);
    w->cancel = cancel;
    w->fd = -1;
    w->flush_at = SIZE_MAX;
}

int gpd_jw_spill(gpd_jw *w, const char *dir, size_t at)
{
    free(w->spill_dir);
    w->spill_dir = dir ? strdup(dir) : NULL;
    if (w->fd < 0) w->flush_at = w->spill_dir ? (at ? at : GPD_JW_SPILL_AT) : SIZE_MAX;
    return dir && !w->spill_dir ? -1 : 0;
}

void gpd_jw_free(gpd_jw *w)
{
    free(w->b.buf);
    if (w->fd >= 0) close(w->fd);
    free(w->spill_dir);
    gpd_jw_init(w, w->cancel);
}

/* ---- spilling into a temporary file ---- */

/* An unlinked temporary file in dir: O_TMPFILE where the file system has it, else a named one
 * unlinked at once; -1 (errno set) when neither can be made. */
static int temp_file(const char *dir)
{
#ifdef O_TMPFILE
    int fd = open(dir, O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd >= 0) return fd;
#endif
    size_t n = strlen(dir) + 32;
    char *path = malloc(n);
    if (!path) return -1;
    snprintf(path, n, "%s/.grainpack-result-XXXXXX", dir);
    int tfd = mkostemp(path, O_CLOEXEC);
    if (tfd >= 0) unlink(path);
    free(path);
    return tfd;
}

static int write_all(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t k = write(fd, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) {
            if (k == 0) errno = EIO;
            return -1;
        }
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

/* Moves the buffered text to the file, made when the text first passes the threshold; a file
 * that cannot be made leaves the text in memory, a write that fails stops the writer. */
static void spill(gpd_jw *w)
{
    int first = w->fd < 0;
    if (first) {
        w->fd = temp_file(w->spill_dir);
        if (w->fd < 0) {
            int err = errno;
            gpd_file_error_note("a result's temporary file could not be made", err);
            gpd_log(GPD_LOG_WARN, "cannot make a temporary file for a result in %s (%s); it "
                                  "stays in memory", w->spill_dir, strerror(err));
            w->flush_at = SIZE_MAX;
            return;
        }
        w->flush_at = GPD_JW_CHUNK;
    }
    if (write_all(w->fd, w->b.buf, w->b.len)) {
        w->err = errno;
        w->state = GPD_JW_IO;
        gpd_file_error_note("a result's temporary file could not be written", w->err);
        return;
    }
    w->spilled += w->b.len;
    w->b.len = 0;
    if (first) { /* the buffer grew to the threshold; a chunk's worth is all it needs now */
        free(w->b.buf);
        w->b.buf = NULL;
        w->b.cap = 0;
    }
}

/* n bytes of fd from offset 0, in memory (NUL-terminated); NULL on a failed read or out of
 * memory */
static char *read_back(int fd, uint64_t n)
{
    char *t = n < SIZE_MAX ? malloc((size_t)n + 1) : NULL;
    for (uint64_t off = 0; t && off < n;) {
        ssize_t k = pread(fd, t + off, (size_t)(n - off), (off_t)off);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) {
            free(t);
            return NULL;
        }
        off += (uint64_t)k;
    }
    if (t) t[n] = 0;
    return t;
}

int gpd_jw_finish(gpd_jw *w, char **mem, int *fd, uint64_t *len)
{
    *mem = NULL;
    *fd = -1;
    *len = 0;
    if (w->fd >= 0 && w->state == GPD_JW_OK && w->b.len) spill(w); /* the last piece */
    if (w->state != GPD_JW_OK || w->depth != 0 || w->after_key || (!w->b.buf && w->fd < 0)) {
        int rc = w->state == GPD_JW_IO && w->err > 0 ? w->err : -1;
        gpd_jw_free(w);
        return rc;
    }
    if (w->fd >= 0) {
        *fd = w->fd;
        *len = w->spilled;
        w->fd = -1;
        gpd_jw_free(w);
        return 0;
    }
    char *text = w->b.buf;
    size_t n = w->b.len;
    char *fit = realloc(text, n + 1); /* the doubling's slack back (up to half of it) */
    w->b.buf = NULL;
    gpd_jw_free(w);
    *mem = fit ? fit : text;
    *len = n;
    return 0;
}

char *gpd_jw_take(gpd_jw *w, size_t *len)
{
    char *mem;
    int fd;
    uint64_t n;
    if (gpd_jw_finish(w, &mem, &fd, &n) != 0) return NULL;
    if (fd >= 0) {
        mem = read_back(fd, n);
        close(fd);
        if (!mem) return NULL;
    }
    if (len) *len = (size_t)n;
    return mem;
}

/* appends n bytes; out of memory stops the writer; past flush_at the text goes to the file */
static void put(gpd_jw *w, const char *s, size_t n)
{
    if (gpd_buf_add(&w->b, s, n))
        w->state = GPD_JW_OOM;
    else if (w->b.len >= w->flush_at)
        spill(w);
}

/* A value counts a piece; every GPD_JW_CANCEL_EVERY pieces the flag is read. 1 when the writer
 * has stopped (now or before). */
static int stopped(gpd_jw *w)
{
    if (w->state != GPD_JW_OK) return 1;
    if (++w->pieces % GPD_JW_CANCEL_EVERY == 0) {
        if (w->pause_s > 0) gpd_sleep_s(w->pause_s);
        if (gpd_cancel_raised(w->cancel)) w->state = GPD_JW_CANCELLED;
    }
    return w->state != GPD_JW_OK;
}

/* Before a member or an element: the comma where one is due; 0 when the writer may go on. */
static int separate(gpd_jw *w)
{
    if (w->after_key) { /* the value of a key, which marked its object non-empty */
        w->after_key = 0;
        return 0;
    }
    uint64_t bit = (uint64_t)1 << w->depth;
    if (w->nonempty & bit) put(w, ",", 1);
    w->nonempty |= bit;
    return w->state != GPD_JW_OK;
}

/* before a value */
static int prefix(gpd_jw *w)
{
    return stopped(w) || separate(w);
}

static void begin(gpd_jw *w, char open)
{
    if (prefix(w)) return;
    if (w->depth + 1 >= GPD_JW_MAX_DEPTH) { /* deeper than any result: a bug; refuse it */
        w->state = GPD_JW_INVALID;
        return;
    }
    put(w, &open, 1);
    w->depth++;
    w->nonempty &= ~((uint64_t)1 << w->depth);
}

static void end(gpd_jw *w, char close)
{
    if (w->state != GPD_JW_OK || w->depth == 0) return;
    put(w, &close, 1);
    w->depth--;
}

void gpd_jw_begin_object(gpd_jw *w) { begin(w, '{'); }
void gpd_jw_end_object(gpd_jw *w) { end(w, '}'); }
void gpd_jw_begin_array(gpd_jw *w) { begin(w, '['); }
void gpd_jw_end_array(gpd_jw *w) { end(w, ']'); }

/* s between quotes, escaped as jansson's dump_string does without JSON_ENSURE_ASCII or
 * JSON_ESCAPE_SLASH: runs of plain bytes are copied whole */
static void quoted(gpd_jw *w, const char *s)
{
    put(w, "\"", 1);
    const char *run = s;
    for (const unsigned char *p = (const unsigned char *)s;; p++) {
        unsigned char c = *p;
        if (c >= 0x20 && c != '"' && c != '\\') continue;
        put(w, run, (size_t)((const char *)p - run));
        if (!c) break;
        char esc[8];
        switch (c) {
        case '"': memcpy(esc, "\\\"", 3); break;
        case '\\': memcpy(esc, "\\\\", 3); break;
        case '\b': memcpy(esc, "\\b", 3); break;
        case '\f': memcpy(esc, "\\f", 3); break;
        case '\n': memcpy(esc, "\\n", 3); break;
        case '\r': memcpy(esc, "\\r", 3); break;
        case '\t': memcpy(esc, "\\t", 3); break;
        default: snprintf(esc, sizeof esc, "\\u%04X", (unsigned)c); break;
        }
        put(w, esc, strlen(esc));
        run = (const char *)p + 1;
    }
    put(w, "\"", 1);
}

void gpd_jw_key(gpd_jw *w, const char *key)
{
    /* a key is no piece: only values count for the cancel checks */
    if (w->state != GPD_JW_OK || separate(w)) return;
    quoted(w, key);
    put(w, ":", 1);
    w->after_key = 1;
}

void gpd_jw_string(gpd_jw *w, const char *s)
{
    if (prefix(w)) return;
    quoted(w, s ? s : "");
}

/* x (finite) as jansson's jsonp_dtostr writes it at precision 17: "%.17g", ".0" appended when
 * there is neither a '.' nor an 'e', the exponent without '+' and leading zeros (the C locale:
 * the daemon never sets another) */
static size_t format_real_printf(char *buf, size_t size, double x)
{
    int n = snprintf(buf, size, "%.17g", x);
    if (n < 0 || (size_t)n >= size - 3) return 0;
    size_t len = (size_t)n;
    char *e = strchr(buf, 'e');
    if (!e) {
        if (!strchr(buf, '.')) {
            memcpy(buf + len, ".0", 3);
            len += 2;
        }
        return len;
    }
    char *start = e + 1, *digits = start + 1;
    if (*start == '-') start++;
    while (*digits == '0') digits++;
    if (digits != start) {
        memmove(start, digits, len - (size_t)(digits - buf) + 1);
        len -= (size_t)(digits - start);
    }
    return len;
}

/* ---- the same text without printf, for the reals of a result (~5x faster): the 17
 * significant digits of |x| = m 2^e are the integer m 10^q 2^e (q = 16 - its decimal exponent)
 * rounded half to even, as glibc's printf rounds; exact in 128-bit integers while m 10^q fits,
 * that is for 1e-6 <= |x| < 1e38 (every coordinate, area and angle of a specimen); other
 * values take printf. The unit test holds it to printf byte for byte. */

typedef unsigned __int128 u128;

#define E16 10000000000000000ull /* 10^16: the least 17-digit number */

static u128 pow10_u128(int q) /* 0 <= q <= 38 */
{
    u128 p = 1;
    for (; q >= 19; q -= 19) p *= 10000000000000000000ull;
    static const uint64_t small[19] = {1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull,
                                       1000000ull, 10000000ull, 100000000ull, 1000000000ull,
                                       10000000000ull, 100000000000ull, 1000000000000ull,
                                       10000000000000ull, 100000000000000ull,
                                       1000000000000000ull, 10000000000000000ull,
                                       100000000000000000ull, 1000000000000000000ull};
    return p * small[q];
}

/* floor(m 2^e 10^q) and whether the rest is below, at or above one half (-1, 0, 1): 0 when
 * exact in 128 bits, -1 when it is not (the caller takes printf) */
static int scaled(uint64_t m, int e, int q, uint64_t *n, int *half)
{
    u128 num, den = 1;
    if (q >= 0) {
        if (q > 22) return -1; /* m 10^q < 2^53 2^74 */
        num = (u128)m * pow10_u128(q);
    } else {
        if (q < -38) return -1;
        num = m;
        den = pow10_u128(-q);
    }
    if (e >= 0) {
        if (e > 127 || (num >> (127 - e)) != 0) return -1;
        num <<= e;
    } else {
        if (-e > 126 || den != 1) return -1;
        den = (u128)1 << -e;
    }
    u128 quot = den == 1 ? num : (q >= 0 ? num >> -e : num / den);
    u128 rem = num - quot * den;
    if (quot >> 64) return -1;
    *n = (uint64_t)quot;
    u128 twice = rem << 1; /* rem < den <= 2^126: no overflow */
    *half = twice < den ? -1 : twice == den ? 0 : 1;
    return 0;
}

/* the 17 digits n (10^16 <= n < 10^17) and the decimal exponent of |x|; 0 or -1 (printf) */
static int digits17(double ax, uint64_t *n, int *x10)
{
    uint64_t bits;
    memcpy(&bits, &ax, sizeof bits);
    int be = (int)(bits >> 52);
    if (be == 0 || be == 0x7ff) return -1; /* subnormal, inf, nan */
    uint64_t m = (bits & ((1ull << 52) - 1)) | (1ull << 52);
    int e = be - 1075;
    /* floor(log10(2^(be - 1023))) (78913 / 2^18 ~ log10 2): |x|'s decimal exponent or one
     * less, put right below by the range of n */
    int k = ((be - 1023) * 78913) >> 18;
    for (int tries = 0; tries < 3; tries++) {
        int half;
        if (scaled(m, e, 16 - k, n, &half)) return -1;
        if (*n >= 10 * E16) {
            k++;
            continue;
        }
        if (*n < E16) {
            k--;
            continue;
        }
        if (half > 0 || (half == 0 && (*n & 1))) ++*n;
        if (*n == 10 * E16) { /* 99999999999999999.5 rounded up */
            *n = E16;
            k++;
        }
        *x10 = k;
        return 0;
    }
    return -1;
}

/* %.17g of the digits (without trailing zeros in the fraction), then jansson's touches */
static size_t format_digits(char *buf, int neg, uint64_t n, int k)
{
    static const char pairs[] = "00010203040506070809101112131415161718192021222324252627282930"
                                "31323334353637383940414243444546474849505152535455565758596061"
                                "62636465666768697071727374757677787980818283848586878889909192"
                                "939495969798990";
    char d[18];
    uint32_t lo = (uint32_t)(n % 100000000u), hi = (uint32_t)(n / 100000000u); /* 8 + 9 */
    for (int i = 16; i > 8; i -= 2, lo /= 100) memcpy(d + i - 1, pairs + 2 * (lo % 100), 2);
    for (int i = 8; i > 0; i -= 2, hi /= 100) memcpy(d + i - 1, pairs + 2 * (hi % 100), 2);
    d[0] = (char)('0' + hi);
    int nd = 17;
    while (nd > 1 && d[nd - 1] == '0') nd--;
    char *p = buf;
    if (neg) *p++ = '-';
    if (k < -4 || k >= 17) { /* d.ddde-X: the exponent as jansson leaves it, "e-5", "e17" */
        *p++ = d[0];
        if (nd > 1) {
            *p++ = '.';
            memcpy(p, d + 1, (size_t)nd - 1);
            p += nd - 1;
        }
        p += sprintf(p, "e%d", k);
    } else if (k < 0) { /* 0.000ddd */
        memcpy(p, "0.", 2);
        p += 2;
        memset(p, '0', (size_t)(-k - 1));
        p += -k - 1;
        memcpy(p, d, (size_t)nd);
        p += nd;
    } else { /* ddd.ddd, or ddd.0 (jansson's ".0") */
        int whole = k + 1;
        for (int i = 0; i < whole; i++) *p++ = i < nd ? d[i] : '0';
        *p++ = '.';
        if (nd > whole) {
            memcpy(p, d + whole, (size_t)(nd - whole));
            p += nd - whole;
        } else {
            *p++ = '0';
        }
    }
    *p = 0;
    return (size_t)(p - buf);
}

static size_t format_real(char *buf, size_t size, double x)
{
    uint64_t n;
    int k;
    if (x == 0) return format_real_printf(buf, size, x); /* "0.0", "-0.0" */
    if (digits17(fabs(x), &n, &k) == 0) return format_digits(buf, signbit(x) != 0, n, k);
    return format_real_printf(buf, size, x);
}

void gpd_jw_real(gpd_jw *w, double x)
{
    if (prefix(w)) return;
    char buf[40];
    size_t n = isfinite(x) ? format_real(buf, sizeof buf, x) : 0;
    if (n)
        put(w, buf, n);
    else
        put(w, "null", 4);
}

void gpd_jw_integer(gpd_jw *w, long long v)
{
    if (prefix(w)) return;
    char buf[32];
    int n = snprintf(buf, sizeof buf, "%lld", v);
    put(w, buf, (size_t)n);
}

void gpd_jw_null(gpd_jw *w)
{
    if (prefix(w)) return;
    put(w, "null", 4);
}

void gpd_jw_reals(gpd_jw *w, const double *v, size_t n)
{
    if (!v) {
        gpd_jw_null(w);
        return;
    }
    gpd_jw_begin_array(w);
    for (size_t i = 0; i < n; i++) gpd_jw_real(w, v[i]);
    gpd_jw_end_array(w);
}

/* json_dump_callback's sink */
static int dump_piece(const char *buffer, size_t size, void *data)
{
    gpd_jw *w = data;
    put(w, buffer, size);
    return w->state == GPD_JW_OK ? 0 : -1;
}

void gpd_jw_json(gpd_jw *w, const json_t *v)
{
    if (!v) {
        gpd_jw_null(w);
        return;
    }
    if (prefix(w)) return;
    if (json_dump_callback(v, dump_piece, w,
                           JSON_COMPACT | JSON_REAL_PRECISION(17) | JSON_ENCODE_ANY) &&
        w->state == GPD_JW_OK)
        w->state = GPD_JW_OOM; /* jansson's own failure: memory (or a bad string) */
}

void gpd_jw_members(gpd_jw *w, const json_t *o)
{
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)o, key, v)
    {
        gpd_jw_key(w, key);
        gpd_jw_json(w, v);
    }
}

/* ---- the elements of an array, formatted on several threads ----
 * Rounds of `nt` blocks: in round r, thread t writes block r nt + t into its own writer (an
 * array's elements: "[" then the items, the "[" dropped when appended); at the round's barrier
 * the caller's thread appends the round's blocks in order, while the others already write the
 * next round into the other half of the writers (two sets, by the round's parity, so a set is
 * never written while it is appended). Every thread waits at every round's barrier, so a stop
 * (cancel, out of memory, a failed file write) only skips the work that is left. */
typedef struct items_run {
    gpd_jw *w;
    size_t n, block, nblocks, rounds;
    int nt;
    gpd_jw_item_fn item;
    const void *user;
    gpd_jw *sub; /* 2 nt writers */
    pthread_barrier_t bar;
    pthread_mutex_t mu; /* the start: the threads wait for go, then read nt and rounds */
    pthread_cond_t cv;
    int go;
    int stop;    /* atomic: the caller's writer stopped */
} items_run;

typedef struct items_arg {
    items_run *run;
    int t;
} items_arg;

static void items_block(items_run *R, size_t r, int t)
{
    size_t b = r * (size_t)R->nt + (size_t)t;
    gpd_jw *s = &R->sub[(r & 1) * (size_t)R->nt + (size_t)t];
    s->b.len = 0;
    s->depth = 0;
    s->nonempty = 0;
    s->after_key = 0;
    if (b >= R->nblocks || __atomic_load_n(&R->stop, __ATOMIC_RELAXED)) return;
    if (gpd_cancel_raised(s->cancel)) { /* at each block too: a block may be fewer pieces */
        s->state = GPD_JW_CANCELLED;
        return;
    }
    gpd_jw_begin_array(s);
    size_t i1 = (b + 1) * R->block < R->n ? (b + 1) * R->block : R->n;
    for (size_t i = b * R->block; i < i1 && s->state == GPD_JW_OK; i++)
        R->item(s, i, R->user);
}

/* the caller's thread: round r's blocks after the "[" of each, each a run of elements */
static void items_append(items_run *R, size_t r)
{
    gpd_jw *w = R->w;
    for (int t = 0; t < R->nt && w->state == GPD_JW_OK; t++) {
        gpd_jw *s = &R->sub[(r & 1) * (size_t)R->nt + (size_t)t];
        if (s->state != GPD_JW_OK) {
            w->state = s->state;
            break;
        }
        if (s->b.len <= 1) continue; /* past the last block */
        if (separate(w)) break;
        put(w, s->b.buf + 1, s->b.len - 1);
    }
    if (w->state != GPD_JW_OK) __atomic_store_n(&R->stop, 1, __ATOMIC_RELAXED);
}

static void items_loop(items_run *R, int t)
{
    for (size_t r = 0; r < R->rounds; r++) {
        items_block(R, r, t);
        pthread_barrier_wait(&R->bar);
        if (t == 0) items_append(R, r);
    }
}

static void *items_thread(void *p)
{
    items_arg *a = p;
    items_run *R = a->run;
    pthread_mutex_lock(&R->mu);
    while (!R->go) pthread_cond_wait(&R->cv, &R->mu);
    pthread_mutex_unlock(&R->mu);
    items_loop(R, a->t);
    return NULL;
}

/* The threads that could be started (R->nt at most) run with the caller's; 0, or -1 when
 * the run could not be set up (nothing written: the caller writes alone). */
static int items_threaded(items_run *R)
{
    int nt = R->nt, rc = -1, started = 1;
    R->sub = calloc(2 * (size_t)nt, sizeof *R->sub);
    pthread_t *th = calloc((size_t)nt, sizeof *th);
    items_arg *args = calloc((size_t)nt, sizeof *args);
    if (R->sub && th && args) {
        pthread_mutex_init(&R->mu, NULL);
        pthread_cond_init(&R->cv, NULL);
        for (; started < nt; started++) {
            args[started] = (items_arg){R, started};
            if (pthread_create(&th[started], NULL, items_thread, &args[started]) != 0) break;
        }
        /* as many as started: the blocks are dealt to them */
        R->nt = started;
        R->rounds = (R->nblocks + (size_t)started - 1) / (size_t)started;
        for (int k = 0; k < 2 * started; k++) {
            gpd_jw_init(&R->sub[k], R->w->cancel);
            R->sub[k].pause_s = R->w->pause_s;
        }
        rc = pthread_barrier_init(&R->bar, NULL, (unsigned)started) == 0 ? 0 : -1;
        if (rc) R->rounds = 0; /* the threads then end at once */
        pthread_mutex_lock(&R->mu);
        R->go = 1;
        pthread_cond_broadcast(&R->cv);
        pthread_mutex_unlock(&R->mu);
        if (rc == 0) items_loop(R, 0);
        for (int k = 1; k < started; k++) pthread_join(th[k], NULL);
        if (rc == 0) pthread_barrier_destroy(&R->bar);
        for (int k = 0; k < 2 * started; k++) gpd_jw_free(&R->sub[k]);
        pthread_cond_destroy(&R->cv);
        pthread_mutex_destroy(&R->mu);
    }
    free(R->sub);
    free(th);
    free(args);
    return rc;
}

void gpd_jw_items(gpd_jw *w, size_t n, gpd_jw_item_fn item, const void *user, int threads,
                  size_t block)
{
    if (block < 1) block = 1;
    size_t nblocks = (n + block - 1) / block;
    int nt = threads < 1 ? 1 : threads;
    if ((size_t)nt > nblocks) nt = (int)nblocks;
    if (nt > 1 && w->state == GPD_JW_OK) {
        items_run R = {.w = w, .n = n, .block = block, .nblocks = nblocks, .nt = nt,
                       .item = item, .user = user};
        if (items_threaded(&R) == 0) return;
    }
    for (size_t i = 0; i < n && w->state == GPD_JW_OK; i++) item(w, i, user);
}
