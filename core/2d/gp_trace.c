/* gp_trace.c -- see gp_trace.h. */
#include "gp_trace.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void gp_trace_params_defaults(gp_trace_params *p)
{
    if (!p)
        return;
    p->min_pixels = GP_TRACE_MIN_PIXELS_DEFAULT;
    p->keep_border = 0;
}

/* ------------------------------------------------------------------------------------------ */
/* labelling                                                                                   */

typedef struct comp {
    size_t pixels, first; /* first: raster index of its first pixel (the flood's seed) */
    size_t holes, hole_pixels;
    int border;
} comp;

typedef struct labeller {
    const unsigned char *img;
    size_t w, h;
    uint32_t *label; /* w h: 0 unlabelled, 1 .. nfg grains, then background regions */
    uint32_t *queue; /* w h */
} labeller;

/* Floods the region of seed (same class as the seed: grain or background, unlabelled) with
 * lab; 4-neighbours, plus the diagonals when conn8. Returns its size; *border if it reaches
 * the image's edge. */
static size_t flood(const labeller *L, size_t seed, uint32_t lab, int conn8, int *border)
{
    const int fg = L->img[seed] != 0;
    size_t head = 0, tail = 0, w = L->w, h = L->h;
    L->label[seed] = lab;
    L->queue[tail++] = (uint32_t)seed;
    *border = 0;
    while (head < tail) {
        size_t q = L->queue[head++], r = q / w, c = q % w;
        if (r == 0 || c == 0 || r + 1 == h || c + 1 == w)
            *border = 1;
        for (int dr = -1; dr <= 1; dr++) {
            for (int dc = -1; dc <= 1; dc++) {
                if ((dr == 0 && dc == 0) || (!conn8 && dr != 0 && dc != 0))
                    continue;
                if ((dr < 0 && r == 0) || (dc < 0 && c == 0) || (dr > 0 && r + 1 == h) ||
                    (dc > 0 && c + 1 == w))
                    continue;
                size_t nb = (size_t)((long)q + dr * (long)w + dc);
                if (L->label[nb] == 0 && (L->img[nb] != 0) == fg) {
                    L->label[nb] = lab;
                    L->queue[tail++] = (uint32_t)nb;
                }
            }
        }
    }
    return tail;
}

/* Labels the grains (4-connected) into *comps (count *nc), then the background (8-connected),
 * crediting each enclosed background region to the grain above its first pixel: a hole's top
 * row lies strictly below its encloser's top, and a grain inside the hole lies strictly below
 * the hole's top, so that pixel belongs to the encloser. */
static gp_status label_all(const labeller *L, comp **comps, size_t *nc, gp_error *err)
{
    size_t n = L->w * L->h, cap = 0;
    *comps = NULL;
    *nc = 0;
    for (size_t i = 0; i < n; i++) {
        if (!L->img[i] || L->label[i])
            continue;
        if (*nc == cap) {
            cap = cap ? 2 * cap : 64;
            comp *c = realloc(*comps, cap * sizeof *c);
            if (!c)
                return gp_error_set(err, GP_ERR_NOMEM, "trace: out of memory");
            *comps = c;
        }
        comp *c = &(*comps)[*nc];
        memset(c, 0, sizeof *c);
        c->first = i;
        c->pixels = flood(L, i, (uint32_t)(++*nc), 0, &c->border);
    }
    uint32_t next = (uint32_t)*nc + 1;
    for (size_t i = 0; i < n; i++) {
        if (L->img[i] || L->label[i])
            continue;
        int border;
        size_t size = flood(L, i, next++, 1, &border);
        if (border)
            continue;
        uint32_t k = L->label[i - L->w]; /* i is not in row 0: the region would touch it */
        if (k >= 1 && k <= *nc) {
            (*comps)[k - 1].holes++;
            (*comps)[k - 1].hole_pixels += size;
        }
    }
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* crack following                                                                             */

/* E, N, W, S in y-up lattice coordinates; +1 turns left */
static const int DX[4] = {1, 0, -1, 0}, DY[4] = {0, 1, 0, -1};

typedef struct tracer {
    const labeller *L;
    uint32_t k;     /* the grain traced */
    gp_vec2 *buf;   /* crack midpoints */
    size_t cap, n;
} tracer;

/* Is lattice cell (i, j) (y up: image row h-1-j) a pixel of grain k? */
static int inside(const tracer *t, long i, long j)
{
    if (i < 0 || j < 0 || i >= (long)t->L->w || j >= (long)t->L->h)
        return 0;
    return t->L->label[(t->L->h - 1 - (size_t)j) * t->L->w + (size_t)i] == t->k;
}

/* The direction to leave lattice point (x, y) by, having arrived along d with the grain on the
 * left: straight if the pixel ahead-left is grain and ahead-right is not; right if both are;
 * left otherwise -- including the saddle (ahead-right grain, ahead-left not), which keeps the
 * two diagonal pixels apart (4-connectivity). */
static int turn(const tracer *t, long x, long y, int d)
{
    long nx = -DY[d], ny = DX[d]; /* left normal */
    long lx = x + DX[d] + nx, ly = y + DY[d] + ny, rx = x + DX[d] - nx, ry = y + DY[d] - ny;
    int left = inside(t, lx < x ? lx : x, ly < y ? ly : y);
    int right = inside(t, rx < x ? rx : x, ry < y ? ry : y);
    if (left && !right)
        return d;
    if (left && right)
        return (d + 3) % 4;
    return (d + 1) % 4;
}

static gp_status emit(tracer *t, double x, double y, gp_error *err)
{
    if (t->n == t->cap) {
        size_t cap = t->cap ? 2 * t->cap : 256;
        gp_vec2 *b = realloc(t->buf, cap * sizeof *b);
        if (!b)
            return gp_error_set(err, GP_ERR_NOMEM, "trace: out of memory");
        t->buf = b;
        t->cap = cap;
    }
    t->buf[t->n++] = (gp_vec2){x, y};
    return GP_OK;
}

/* Follows grain c's outer boundary from the top edge of its first pixel (westwards: the grain
 * below, on the left), emitting each crack's midpoint, until that crack comes round again. */
static gp_status follow(tracer *t, const comp *c, gp_error *err)
{
    long i0 = (long)(c->first % t->L->w), j0 = (long)(t->L->h - 1 - c->first / t->L->w);
    long x0 = i0 + 1, y0 = j0 + 1, x = i0, y = y0;
    int d = 2;
    size_t limit = 4 * c->pixels + 4;
    t->n = 0;
    gp_status st = emit(t, (double)x0 - 0.5, (double)y0, err);
    for (;;) {
        int nd = turn(t, x, y, d);
        if (x == x0 && y == y0 && nd == 2)
            return st;
        if (st != GP_OK)
            return st;
        if (t->n > limit)
            return gp_error_set(err, GP_ERR_INTERNAL, "trace: boundary of %zu pixels not closed",
                                c->pixels);
        st = emit(t, (double)x + 0.5 * DX[nd], (double)y + 0.5 * DY[nd], err);
        x += DX[nd];
        y += DY[nd];
        d = nd;
    }
}

/* The outline: the midpoints where the boundary changes direction (exact comparisons: the
 * midpoints are on a half-integer grid). */
static gp_status compress(const tracer *t, gp_trace_outline *o, gp_error *err)
{
    size_t n = t->n, m = 0;
    o->pts = malloc(n * sizeof *o->pts);
    if (!o->pts)
        return gp_error_set(err, GP_ERR_NOMEM, "trace: out of memory");
    for (size_t k = 0; k < n; k++) {
        gp_vec2 a = t->buf[(k + n - 1) % n], b = t->buf[k], c = t->buf[(k + 1) % n];
        if (b.x - a.x != c.x - b.x || b.y - a.y != c.y - b.y)
            o->pts[m++] = b;
    }
    o->n = m;
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the image                                                                                   */

void gp_trace_result_free(gp_trace_result *r)
{
    if (!r)
        return;
    for (size_t i = 0; i < r->n; i++)
        free(r->outlines[i].pts);
    free(r->outlines);
    memset(r, 0, sizeof *r);
}

static int keep(const comp *c, const gp_trace_params *p, gp_trace_result *out)
{
    if (c->border && !p->keep_border) {
        out->nborder++;
        return 0;
    }
    if (c->pixels < p->min_pixels) {
        out->nsmall++;
        return 0;
    }
    return 1;
}

/* Traces the kept components into out->outlines (capacity nc). */
static gp_status trace_all(const labeller *L, const comp *comps, size_t nc,
                           const gp_trace_params *p, gp_trace_result *out, gp_error *err)
{
    tracer t = {L, 0, NULL, 0, 0};
    gp_status st = GP_OK;
    for (size_t k = 0; k < nc && st == GP_OK; k++) {
        const comp *c = &comps[k];
        if (!keep(c, p, out))
            continue;
        t.k = (uint32_t)(k + 1);
        st = follow(&t, c, err);
        gp_trace_outline *o = &out->outlines[out->n];
        if (st == GP_OK)
            st = compress(&t, o, err);
        if (st != GP_OK)
            break;
        o->pixels = c->pixels;
        o->holes = c->holes;
        o->hole_pixels = c->hole_pixels;
        o->col = c->first % L->w;
        o->row = c->first / L->w;
        o->touches_border = c->border;
        out->n++;
    }
    free(t.buf);
    return st;
}

gp_status gp_trace_image(const unsigned char *img, size_t w, size_t h, const gp_trace_params *p,
                         gp_trace_result *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "trace: NULL result");
    memset(out, 0, sizeof *out);
    if (!img || w == 0 || h == 0)
        return gp_error_set(err, GP_ERR_INVALID, "trace: need an image of at least 1 x 1");
    if (w > GP_TRACE_MAX_PIXELS / h)
        return gp_error_set(err, GP_ERR_INVALID, "trace: %zu x %zu pixels is too many", w, h);
    gp_trace_params d;
    gp_trace_params_defaults(&d);
    if (!p)
        p = &d;
    labeller L = {img, w, h, calloc(w * h, sizeof(uint32_t)), malloc(w * h * sizeof(uint32_t))};
    comp *comps = NULL;
    size_t nc = 0;
    gp_status st = (L.label && L.queue) ? label_all(&L, &comps, &nc, err)
                                        : gp_error_set(err, GP_ERR_NOMEM, "trace: out of memory");
    free(L.queue);
    out->ncomponents = nc;
    if (st == GP_OK && nc > 0) {
        out->outlines = calloc(nc, sizeof *out->outlines);
        st = out->outlines ? trace_all(&L, comps, nc, p, out, err)
                           : gp_error_set(err, GP_ERR_NOMEM, "trace: out of memory");
    }
    free(L.label);
    free(comps);
    if (st != GP_OK)
        gp_trace_result_free(out);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* PGM                                                                                         */

typedef struct scan {
    const unsigned char *b;
    size_t len, pos;
} scan;

static int is_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/* Skips whitespace and '#' comments (to the end of their line). */
static void skip_blank(scan *s)
{
    while (s->pos < s->len) {
        if (s->b[s->pos] == '#') {
            while (s->pos < s->len && s->b[s->pos] != '\n' && s->b[s->pos] != '\r')
                s->pos++;
        } else if (is_space(s->b[s->pos])) {
            s->pos++;
        } else {
            return;
        }
    }
}

/* A P2 value: a decimal number up to max (leading zeros allowed: some writers pad values into
 * columns); 0 with *ok = 0 if there is none or it is larger. */
static size_t read_uint(scan *s, size_t max, int *ok)
{
    skip_blank(s);
    size_t v = 0, digits = 0;
    *ok = 0;
    while (s->pos < s->len && s->b[s->pos] >= '0' && s->b[s->pos] <= '9') {
        v = 10 * v + (size_t)(s->b[s->pos++] - '0');
        if (v > max)
            return 0;
        digits++;
    }
    if (digits == 0 || (s->pos < s->len && !is_space(s->b[s->pos]) && s->b[s->pos] != '#'))
        return 0;
    *ok = 1;
    return v;
}

/* One number of the header into *v: decimal digits, at most max, ended by whitespace or a
 * comment. A zero-padded number is refused: a reader that counts digits would see another
 * number than one that does not, and a header must mean one size to every check. Digits are
 * read only while the value stays within max, so no number is too long to overflow. */
static gp_status header_uint(scan *s, const char *what, size_t max, size_t *v, gp_error *err)
{
    skip_blank(s);
    size_t start = s->pos;
    *v = 0;
    while (s->pos < s->len && s->b[s->pos] >= '0' && s->b[s->pos] <= '9') {
        size_t d = (size_t)(s->b[s->pos] - '0');
        if (*v > (max - d) / 10)
            return gp_error_set(err, GP_ERR_INVALID, "pgm: the %s is over %zu", what, max);
        *v = 10 * *v + d;
        s->pos++;
    }
    if (s->pos == start)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: the %s is missing or not a number", what);
    if (s->b[start] == '0' && s->pos - start > 1)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: the %s is zero-padded (a leading 0)",
                            what);
    if (s->pos < s->len && !is_space(s->b[s->pos]) && s->b[s->pos] != '#')
        return gp_error_set(err, GP_ERR_INVALID, "pgm: the %s is not followed by whitespace",
                            what);
    return GP_OK;
}

gp_status gp_trace_pgm_header(const void *buf, size_t len, gp_trace_pgm_info *out,
                              gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: NULL output");
    memset(out, 0, sizeof *out);
    scan s = {buf, buf ? len : 0, 2};
    if (s.len < 2 || s.b[0] != 'P' || (s.b[1] != '5' && s.b[1] != '2'))
        return gp_error_set(err, GP_ERR_INVALID, "pgm: not a PGM file (magic P5 or P2)");
    if (s.pos >= s.len || (!is_space(s.b[s.pos]) && s.b[s.pos] != '#'))
        return gp_error_set(err, GP_ERR_INVALID, "pgm: no whitespace after the magic number");
    int binary = s.b[1] == '5';
    size_t w, h, maxval;
    gp_status st = header_uint(&s, "width", GP_TRACE_MAX_PIXELS, &w, err);
    if (st == GP_OK)
        st = header_uint(&s, "height", GP_TRACE_MAX_PIXELS, &h, err);
    if (st == GP_OK)
        st = header_uint(&s, "maxval", 65535, &maxval, err);
    if (st != GP_OK)
        return st;
    if (w == 0 || h == 0)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: %zu x %zu pixels: a side is 0", w, h);
    if (w > GP_TRACE_MAX_PIXELS / h)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: %zu x %zu pixels is over %zu", w, h,
                            GP_TRACE_MAX_PIXELS);
    if (maxval == 0)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: maxval 0 (1 .. 65535 expected)");
    /* P5: exactly one whitespace byte ends the header, the next one is a value (so a "\r\n"
     * leaves the '\n' as the first value); a comment may come before it, as netpbm reads it.
     * P2: the values are read past blanks and comments. */
    if (binary && s.pos < s.len && s.b[s.pos] == '#')
        while (s.pos < s.len && s.b[s.pos] != '\n' && s.b[s.pos] != '\r')
            s.pos++;
    if (binary && (s.pos >= s.len || !is_space(s.b[s.pos])))
        return gp_error_set(err, GP_ERR_INVALID, "pgm: no whitespace after maxval");
    out->w = w;
    out->h = h;
    out->maxval = (unsigned)maxval;
    out->binary = binary;
    out->data = binary ? s.pos + 1 : s.pos;
    out->data_min = binary ? w * h * (maxval > 255 ? 2 : 1) : 2 * w * h - 1;
    return GP_OK;
}

/* The values of g (allocated: w h of them) from s, at the header's data offset; for P5 the
 * caller has checked that the bytes are there. */
static gp_status read_values(scan *s, int binary, gp_trace_gray *g, gp_error *err)
{
    size_t n = g->w * g->h;
    for (size_t i = 0; i < n; i++) {
        size_t v;
        int ok = 1;
        if (!binary) {
            v = read_uint(s, 65535, &ok);
        } else if (g->maxval < 256) {
            v = s->b[s->pos++];
        } else {
            v = ((size_t)s->b[s->pos] << 8) | s->b[s->pos + 1];
            s->pos += 2;
        }
        if (!ok)
            return gp_error_set(err, GP_ERR_INVALID, "pgm: value %zu of %zu is missing or bad", i,
                                n);
        if (v > g->maxval)
            return gp_error_set(err, GP_ERR_INVALID, "pgm: value %zu = %zu exceeds maxval %u", i,
                                v, g->maxval);
        g->v[i] = (unsigned short)v;
    }
    return GP_OK;
}

gp_status gp_trace_pgm_parse(const void *buf, size_t len, gp_trace_gray *out, gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: NULL output");
    memset(out, 0, sizeof *out);
    gp_trace_pgm_info hdr;
    gp_status st = gp_trace_pgm_header(buf, len, &hdr, err);
    if (st != GP_OK)
        return st;
    /* the data must be there before anything is allocated: a header alone must not cost
     * memory in proportion to the size it claims */
    if (len - hdr.data < hdr.data_min)
        return gp_error_set(err, GP_ERR_INVALID, "pgm: truncated: %zu x %zu values %s %zu bytes,"
                            " %zu given", hdr.w, hdr.h, hdr.binary ? "take" : "take at least",
                            hdr.data_min, len - hdr.data);
    out->v = malloc(hdr.w * hdr.h * sizeof *out->v);
    if (!out->v)
        return gp_error_set(err, GP_ERR_NOMEM, "pgm: out of memory for %zu x %zu", hdr.w, hdr.h);
    out->w = hdr.w;
    out->h = hdr.h;
    out->maxval = hdr.maxval;
    scan s = {buf, len, hdr.data};
    st = read_values(&s, hdr.binary, out, err);
    if (st != GP_OK)
        gp_trace_gray_free(out);
    return st;
}

void gp_trace_gray_free(gp_trace_gray *g)
{
    if (!g)
        return;
    free(g->v);
    memset(g, 0, sizeof *g);
}

gp_status gp_trace_threshold(const gp_trace_gray *g, unsigned level, int dark_grains,
                             unsigned char *mask, gp_error *err)
{
    if (!g || !g->v || !mask || g->w == 0 || g->h == 0)
        return gp_error_set(err, GP_ERR_INVALID, "threshold: NULL or empty image");
    size_t n = g->w * g->h;
    for (size_t i = 0; i < n; i++)
        mask[i] = dark_grains ? g->v[i] < level : g->v[i] > level;
    return GP_OK;
}
