/* json_scan.c -- reading parts of a large JSON text (see json_scan.h). */
#include "util/json_scan.h"

#include <stdlib.h>
#include <string.h>

#include "util/util.h"

#define JS_CACHE (64u * 1024u)
#define JS_KEEP (1u << 20) /* json_scan_load keeps its buffer up to this size between calls */
#define JS_ERR UINT64_MAX

struct js_scan {
    js_source src;
    uint64_t coff; /* the cache holds [coff, coff + clen) of the text */
    size_t clen;
    /* array walk */
    uint64_t apos;
    int afirst, aactive;
    /* json_scan_load */
    char *buf;
    size_t cap;
    unsigned char cache[]; /* JS_CACHE bytes, allocated with the scanner */
};

static int mem_read(void *user, uint64_t off, void *dst, size_t n)
{
    memcpy(dst, (const char *)user + off, n);
    return 0;
}

js_source json_scan_memory_source(const char *text, size_t len)
{
    js_source s = {mem_read, (void *)text, len};
    return s;
}

js_scan *json_scan_open(const js_source *src)
{
    js_scan *s = malloc(sizeof *s + JS_CACHE);
    if (!s) return NULL;
    memset(s, 0, sizeof *s);
    s->src = *src;
    return s;
}

void json_scan_close(js_scan *s)
{
    if (s) free(s->buf);
    free(s);
}

/* Loads the cache at pos (< size); 0 on success. */
static int fill(js_scan *s, uint64_t pos)
{
    uint64_t left = s->src.size - pos;
    size_t n = left < JS_CACHE ? (size_t)left : JS_CACHE;
    if (s->src.read(s->src.user, pos, s->cache, n)) {
        s->clen = 0;
        return -1;
    }
    s->coff = pos;
    s->clen = n;
    return 0;
}

/* the byte at pos, or -1 past the end or when the source fails */
static inline int byte_at(js_scan *s, uint64_t pos)
{
    if (pos >= s->coff && pos - s->coff < s->clen) return s->cache[pos - s->coff];
    if (pos >= s->src.size || fill(s, pos)) return -1;
    return s->cache[0];
}

static inline int is_ws(int c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

static uint64_t skip_ws(js_scan *s, uint64_t pos)
{
    while (is_ws(byte_at(s, pos))) pos++;
    return pos;
}

/* bytes that matter outside strings: 1 quote, 2 opening, 3 closing bracket */
static const unsigned char SPECIAL[256] = {['"'] = 1, ['['] = 2, ['{'] = 2, [']'] = 3, ['}'] = 3};

/* Runs the string/bracket state machine from pos over the cache windows; returns the offset
 * just past the byte that ends the value (the closing quote of a string when in_str, the
 * bracket that closes depth 1 otherwise), JS_ERR at the end of the text or on a failed read.
 * Table-driven: the bulk of a result (digits, commas, points) is passed over a byte per
 * iteration without branching on each kind of byte. */
static uint64_t scan(js_scan *s, uint64_t pos, int in_str, int depth)
{
    int esc = 0;
    const int str_only = in_str;
    for (;;) {
        if (!(pos >= s->coff && pos - s->coff < s->clen)) {
            if (pos >= s->src.size || fill(s, pos)) return JS_ERR;
        }
        const unsigned char *p = s->cache + (pos - s->coff), *e = s->cache + s->clen;
        if (esc && p < e) { /* an escape cut by the window's end */
            p++;
            esc = 0;
        }
        while (p < e) {
            if (in_str) {
                while (p < e && *p != '"' && *p != '\\') p++;
                if (p == e) break;
                if (*p == '\\') {
                    if (++p == e) {
                        esc = 1;
                        break;
                    }
                    p++;
                    continue;
                }
                in_str = 0;
                p++;
                if (str_only) return s->coff + (uint64_t)(p - s->cache);
                continue;
            }
            while (p < e && !SPECIAL[*p]) p++;
            if (p == e) break;
            unsigned char k = SPECIAL[*p++];
            if (k == 1) in_str = 1;
            else if (k == 2) depth++;
            else if (--depth <= 0) return s->coff + (uint64_t)(p - s->cache);
        }
        pos = s->coff + s->clen;
    }
}

/* the end of the value starting at pos, JS_ERR when there is none */
static uint64_t skip_value(js_scan *s, uint64_t pos)
{
    int c = byte_at(s, pos);
    if (c < 0) return JS_ERR;
    if (c == '"') return scan(s, pos + 1, 1, 0);
    if (c == '[' || c == '{') return scan(s, pos + 1, 0, 1);
    /* a number, true, false or null */
    if (!(c == '-' || (c >= '0' && c <= '9') || c == 't' || c == 'f' || c == 'n')) return JS_ERR;
    uint64_t p = pos;
    while ((c = byte_at(s, p)) >= 0 && !is_ws(c) && c != ',' && c != ']' && c != '}' &&
           c != ':' && c != '"' && c != '[' && c != '{')
        p++;
    return p;
}

int json_scan_copy(js_scan *s, uint64_t off, uint64_t end, char *dst)
{
    if (end < off || end > s->src.size) return -1;
    size_t n = (size_t)(end - off);
    if (off >= s->coff && end <= s->coff + s->clen) {
        memcpy(dst, s->cache + (off - s->coff), n);
        return 0;
    }
    return n ? s->src.read(s->src.user, off, dst, n) : 0;
}

int json_scan_members(js_scan *s, js_member_fn fn, void *user)
{
    uint64_t pos = skip_ws(s, 0);
    if (byte_at(s, pos) != '{') return -1;
    pos = skip_ws(s, pos + 1);
    if (byte_at(s, pos) == '}') return 0;
    for (;;) {
        if (byte_at(s, pos) != '"') return -1;
        uint64_t moff = pos, kend = scan(s, pos + 1, 1, 0);
        if (kend == JS_ERR) return -1;
        char key[256];
        uint64_t kl = kend - moff - 2;
        if (kl > sizeof key - 1) kl = sizeof key - 1;
        if (json_scan_copy(s, moff + 1, moff + 1 + kl, key)) return -1;
        key[kl] = 0;
        pos = skip_ws(s, kend);
        if (byte_at(s, pos) != ':') return -1;
        uint64_t voff = skip_ws(s, pos + 1), vend = skip_value(s, voff);
        if (vend == JS_ERR || vend == voff) return -1;
        int r = fn(user, key, moff, voff, vend);
        if (r) return r;
        pos = skip_ws(s, vend);
        int c = byte_at(s, pos);
        if (c == '}') return 0;
        if (c != ',') return -1;
        pos = skip_ws(s, pos + 1);
    }
}

int json_scan_array_begin(js_scan *s, uint64_t off)
{
    s->aactive = 0;
    uint64_t pos = skip_ws(s, off);
    if (byte_at(s, pos) != '[') return -1;
    s->apos = pos + 1;
    s->afirst = 1;
    s->aactive = 1;
    return 0;
}

int json_scan_array_next(js_scan *s, uint64_t *eoff, uint64_t *eend)
{
    if (!s->aactive) return 0;
    uint64_t pos = skip_ws(s, s->apos);
    int c = byte_at(s, pos);
    if (c == ']') {
        s->aactive = 0;
        return 0;
    }
    if (!s->afirst) {
        if (c != ',') goto bad;
        pos = skip_ws(s, pos + 1);
    }
    uint64_t end = skip_value(s, pos);
    if (end == JS_ERR || end == pos) goto bad;
    *eoff = pos;
    *eend = end;
    s->apos = end;
    s->afirst = 0;
    return 1;
bad:
    s->aactive = 0;
    return -1;
}

const char *json_scan_span(js_scan *s, uint64_t off, uint64_t end)
{
    if (end < off || end > s->src.size) return NULL;
    size_t n = (size_t)(end - off);
    /* grow to the span; a buffer grown past JS_KEEP by a rare large span is not kept */
    if (n + 1 > s->cap || (s->cap > JS_KEEP && n + 1 <= JS_KEEP)) {
        size_t cap = n + 1 > 4096 ? n + 1 : 4096;
        free(s->buf);
        s->buf = malloc(cap);
        s->cap = s->buf ? cap : 0;
        if (!s->buf) return NULL;
    }
    if (json_scan_copy(s, off, end, s->buf)) return NULL;
    s->buf[n] = 0;
    return s->buf;
}

json_t *json_scan_load(js_scan *s, uint64_t off, uint64_t end)
{
    if (end <= off) return NULL;
    const char *t = json_scan_span(s, off, end);
    if (!t) return NULL;
    json_error_t e;
    return json_loadb(t, (size_t)(end - off), JSON_DECODE_ANY, &e);
}

/* ------------------------------------------------------------------ object without */

typedef struct without_ctx {
    js_scan *s;
    const char *const *skip;
    uint64_t (*spans)[2];
    gpd_buf out;
    int fail;
} without_ctx;

/* appends [off, end) of the text */
static int append_span(without_ctx *w, uint64_t off, uint64_t end)
{
    size_t n = (size_t)(end - off);
    if (gpd_buf_reserve(&w->out, n) || json_scan_copy(w->s, off, end, w->out.buf + w->out.len)) return -1;
    w->out.len += n;
    w->out.buf[w->out.len] = '\0';
    return 0;
}

static int without_member(void *user, const char *key, uint64_t moff, uint64_t voff,
                          uint64_t vend)
{
    without_ctx *w = user;
    for (const char *const *k = w->skip; k && *k; k++)
        if (!strcmp(key, *k)) {
            if (w->spans) {
                w->spans[k - w->skip][0] = voff;
                w->spans[k - w->skip][1] = vend;
            }
            return 0;
        }
    if ((w->out.len > 1 && gpd_buf_add(&w->out, ",", 1)) || append_span(w, moff, vend)) {
        w->fail = 1;
        return 1;
    }
    return 0;
}

char *json_scan_object_without(const js_source *src, const char *const *skip, size_t *len,
                        uint64_t (*spans)[2])
{
    if (len) *len = 0;
    if (spans)
        for (const char *const *k = skip; k && *k; k++) spans[k - skip][0] = spans[k - skip][1] = 0;
    js_scan *s = json_scan_open(src);
    if (!s) return NULL;
    without_ctx w = {s, skip, spans, {NULL, 0, 0, 0}, 0};
    int ok = gpd_buf_add(&w.out, "{", 1) == 0 && json_scan_members(s, without_member, &w) == 0 &&
             !w.fail && gpd_buf_add(&w.out, "}", 1) == 0;
    json_scan_close(s);
    if (!ok) {
        free(w.out.buf);
        return NULL;
    }
    if (len) *len = w.out.len;
    return w.out.buf;
}
