/* svg_items.c -- the item sources of the SVG views (svg.h): a result's grains, cells or spheres,
 * one at a time, from a JSON array in memory, from an array of a JSON text walked element by
 * element (json_scan.h), or from a pack (core/export: an export pack, or a 2D view pack). A
 * fv3d pack's grains have no 2D numbers: their views read its records through the items'
 * reader (svg_fv3d.c). */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"

const char *const svg_items_part_name[3] = {"grains", "cells", "spheres"};
const char *const svg_items_desc_name[4] = {"elongation", "roundness", "circularity", "regularity"};

/* p resized for n elements of size bytes, its capacity *cap doubled from first until they fit;
 * NULL (p untouched) on out of memory */
static void *room(void *p, size_t *cap, size_t n, size_t size, size_t first)
{
    size_t c = *cap ? *cap : first;
    while (c < n) c *= 2;
    void *q = realloc(p, c * size);
    if (q) *cap = c;
    return q;
}

/* room for n points in the item; -1 on out of memory */
static int pts_room(svg_item *c, size_t n)
{
    if (n <= c->cap) return 0;
    double *xy = room(c->xy, &c->cap, n, 2 * sizeof *c->xy, 256);
    if (!xy) return -1;
    c->xy = xy;
    return 0;
}

/* room for n rings in the item; -1 on out of memory */
static int rings_room(svg_item *c, size_t n)
{
    if (n <= c->rcap) return 0;
    size_t *r = room(c->rings, &c->rcap, n, sizeof *c->rings, 8);
    if (!r) return -1;
    c->rings = r;
    return 0;
}

/* ------------------------------------------------------------------ items */

static void item_clear(svg_item *c)
{
    c->npts = c->nrings = 0;
    c->area = c->orientation_deg = NAN;
    for (int k = 0; k < 4; k++) c->desc[k] = c->q[k] = NAN;
    c->seed[0] = c->seed[1] = NAN;
}

/* appends the points of a JSON ring; -1 on out of memory */
int svg_items_ring(svg_item *c, const json_t *ring)
{
    size_t n = json_array_size(ring);
    if (pts_room(c, c->npts + n)) return -1;
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(ring, i);
        c->xy[2 * (c->npts + i)] = svg_plot_jnum(json_array_get(p, 0), NAN);
        c->xy[2 * (c->npts + i) + 1] = svg_plot_jnum(json_array_get(p, 1), NAN);
    }
    c->npts += n;
    return 0;
}

int svg_items_from_json(gp_svg_part part, svg_item *c, const json_t *e)
{
    item_clear(c);
    if (part == GP_SVG_SPHERES) {
        for (int a = 0; a < 4; a++) c->q[a] = svg_plot_jnum(json_array_get(e, (size_t)a), NAN);
        return 0;
    }
    c->area = svg_plot_jnum(json_object_get(e, "area"), NAN);
    c->orientation_deg = svg_plot_jnum(json_object_get(e, "orientation_deg"), NAN);
    if (part == GP_SVG_GRAINS) {
        const json_t *d = json_object_get(e, "descriptors");
        for (int k = 0; k < 4; k++) c->desc[k] = svg_plot_jnum(json_object_get(d, svg_items_desc_name[k]), NAN);
        return svg_items_ring(c, json_object_get(e, "contour"));
    }
    const json_t *sd = json_object_get(e, "seed");
    c->seed[0] = svg_plot_jnum(json_array_get(sd, 0), NAN);
    c->seed[1] = svg_plot_jnum(json_array_get(sd, 1), NAN);
    const json_t *polys = json_object_get(e, "polygons");
    size_t np = json_array_size(polys);
    if (rings_room(c, np)) return -1;
    for (size_t j = 0; j < np; j++) {
        size_t before = c->npts;
        if (svg_items_ring(c, json_array_get(polys, j))) return -1;
        c->rings[c->nrings++] = c->npts - before;
    }
    return 0;
}

static gp_svg_items *items_new(gp_svg_part part)
{
    if ((unsigned)part > GP_SVG_SPHERES) return NULL;
    gp_svg_items *it = calloc(1, sizeof *it);
    if (it) it->part = part;
    return it;
}

void svg_items_free(svg_item *c)
{
    free(c->xy);
    free(c->rings);
}

void gp_svg_items_close(gp_svg_items *it)
{
    if (it) {
        json_scan_close(it->js);
        gp_export_reader_destroy(it->e);
        gp_export_reader_destroy(it->ep);
        svg_items_free(&it->cur);
    }
    free(it);
}

/* ------------------------------------------------------------------ in memory */

/* -- in memory */
static int json_rewind(gp_svg_items *it)
{
    it->idx = 0;
    return 0;
}

static int json_next(gp_svg_items *it)
{
    if (it->idx >= json_array_size(it->arr)) return 0;
    if (svg_items_from_json(it->part, &it->cur, json_array_get(it->arr, it->idx++))) return -1;
    if (it->light) it->cur.npts = it->cur.nrings = 0; /* as the other sources give it */
    return 1;
}

gp_svg_items *gp_svg_items_json(const json_t *array, gp_svg_part part)
{
    if (!json_is_array(array)) return NULL;
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    it->arr = array;
    it->rewind = json_rewind;
    it->next = json_next;
    return it;
}

/* ------------------------------------------------------------------ the element parser */

/* An element's text read straight into the item (the scan source): the same values as
 * svg_items_from_json() gives for the parsed element, without building a JSON tree (three times
 * faster on cells, which are read in three passes). A number is read with strtod (the C
 * locale: the daemon never sets another), null and any other value where a number belongs
 * give NaN, unknown members are skipped. -1 on text that is not JSON. */
typedef struct pp {
    const char *p, *e;
} pp;

static void pp_ws(pp *q)
{
    while (q->p < q->e && (*q->p == ' ' || *q->p == '\n' || *q->p == '\r' || *q->p == '\t')) q->p++;
}

/* bytes that matter when passing over a value: 1 quote, 2 opening, 3 closing bracket */
static const unsigned char PP_SPECIAL[256] = {['"'] = 1, ['['] = 2, ['{'] = 2, [']'] = 3, ['}'] = 3};
/* bytes that end a number, true, false or null (NUL too: a span is NUL-terminated) */
static const unsigned char PP_END[256] = {[0] = 1,   [' '] = 1, ['\n'] = 1, ['\r'] = 1, ['\t'] = 1,
                                          [','] = 1, [']'] = 1, ['}'] = 1,  [':'] = 1};

/* passes over the string whose opening quote q is at */
static int pp_skip_string(pp *q)
{
    for (const char *p = q->p + 1; p < q->e; p++) {
        if (*p == '\\') {
            if (++p == q->e) break;
        } else if (*p == '"') {
            q->p = p + 1;
            return 0;
        }
    }
    return -1;
}

/* passes over one value of any type; table-driven, as json_scan.c's scan, since a light pass
 * passes over every contour (a grain's text is 95 % its points) */
static int pp_skip(pp *q)
{
    pp_ws(q);
    if (q->p >= q->e) return -1;
    char c = *q->p;
    if (c == '"') return pp_skip_string(q);
    if (c == '[' || c == '{') {
        int depth = 0;
        const char *p = q->p, *e = q->e;
        for (;;) {
            while (p < e && !PP_SPECIAL[(unsigned char)*p]) p++;
            if (p == e) return -1;
            unsigned char k = PP_SPECIAL[(unsigned char)*p];
            if (k == 1) {
                q->p = p;
                if (pp_skip_string(q)) return -1;
                p = q->p;
                continue;
            }
            p++;
            if (k == 2) depth++;
            else if (--depth == 0) {
                q->p = p;
                return 0;
            }
        }
    }
    const char *s = q->p;
    while (q->p < q->e && !PP_END[(unsigned char)*q->p]) q->p++;
    return q->p > s ? 0 : -1;
}

/* The fast path of a number (pp_num), where x86's long double makes it exact: 1 with *v and
 * past it, 0 to leave it to strtod. Up to 19 significant digits make an integer m exactly;
 * m times or over a power of ten up to 10^27 (exact in the 64-bit mantissa: 5^27 < 2^64) is
 * one rounding there, and rounding that to a double gives strtod's value unless it landed on a
 * midpoint between two doubles (its 11 extra bits 0x400): that, a subnormal or overflowing
 * value, more digits, a larger exponent and anything but a plain JSON number that ends at a
 * delimiter go to strtod. Four times faster than strtod on a result's 17-digit numbers, which
 * the views read by the million (cells, and grains without a pack). */
#if LDBL_MANT_DIG == 64 && (defined(__x86_64__) || defined(__i386__))
static const long double POW10[28] = {
    1e0L,  1e1L,  1e2L,  1e3L,  1e4L,  1e5L,  1e6L,  1e7L,  1e8L,  1e9L,
    1e10L, 1e11L, 1e12L, 1e13L, 1e14L, 1e15L, 1e16L, 1e17L, 1e18L, 1e19L,
    1e20L, 1e21L, 1e22L, 1e23L, 1e24L, 1e25L, 1e26L, 1e27L};

/* digits from *p (before e) into *m, counting them in *nd (leading zeros of an integer still
 * zero are not significant); how many were read */
static int pp_digits(const char **p, const char *e, uint64_t *m, int *nd)
{
    const char *s = *p;
    for (; *p < e && (unsigned)(**p - '0') < 10; (*p)++) {
        if (*m == 0 && **p == '0') continue;
        if (++*nd <= 19) *m = *m * 10 + (uint64_t)(**p - '0');
    }
    return (int)(*p - s);
}

static int pp_num_fast(const char *p, const char *e, const char **end, double *v)
{
    int neg = p < e && *p == '-';
    p += neg;
    uint64_t m = 0;
    int nd = 0, e10 = 0;
    if (!pp_digits(&p, e, &m, &nd)) return 0;
    if (p < e && *p == '.') {
        p++;
        e10 = -pp_digits(&p, e, &m, &nd); /* m counts in units of the last fraction digit */
        if (!e10) return 0;
    }
    if (p < e && (*p == 'e' || *p == 'E')) {
        p++;
        int es = p < e && *p == '-' ? -1 : 1;
        p += p < e && (*p == '-' || *p == '+');
        int x = 0, n = 0;
        for (; p < e && (unsigned)(*p - '0') < 10 && n < 5; p++, n++) x = x * 10 + (*p - '0');
        if (!n || n == 5) return 0;
        e10 += es * x;
    }
    if (p < e && !PP_END[(unsigned char)*p]) return 0;
    if (nd > 19 || e10 < -27 || e10 > 27) return 0;
    long double r = (long double)m;
    r = e10 < 0 ? r / POW10[-e10] : r * POW10[e10];
    uint64_t mant;
    memcpy(&mant, &r, sizeof mant); /* the 64-bit mantissa of x87's extended format */
    if (m && ((mant & 0x7ff) - 0x3ff <= 2 || r < DBL_MIN || r > DBL_MAX)) return 0;
    *v = neg ? -(double)r : (double)r;
    *end = p;
    return 1;
}
#else
static int pp_num_fast(const char *p, const char *e, const char **end, double *v)
{
    (void)p, (void)e, (void)end, (void)v;
    return 0;
}
#endif

/* a number (or NaN for null or any other value) */
static int pp_num(pp *q, double *v)
{
    pp_ws(q);
    *v = NAN;
    if (q->p >= q->e) return -1;
    char c = *q->p;
    if (c == '-' || (c >= '0' && c <= '9')) {
        if (pp_num_fast(q->p, q->e, &q->p, v)) return 0;
        char *end;
        double x = strtod(q->p, &end);
        if (end == q->p || end > q->e) return -1;
        q->p = end;
        *v = x;
        return 0;
    }
    return pp_skip(q);
}

/* the next element of a container whose opening bracket was passed: 1 (q at the element), 0
 * after the closing one (close), -1 */
static int pp_item(pp *q, int *first, char close)
{
    pp_ws(q);
    if (q->p >= q->e) return -1;
    if (*q->p == close) {
        q->p++;
        return 0;
    }
    if (!*first) {
        if (*q->p != ',') return -1;
        q->p++;
        pp_ws(q);
    }
    *first = 0;
    return 1;
}

/* the next element of an array whose '[' was passed: 1 (q at the element), 0 after ']', -1 */
static int pp_next(pp *q, int *first) { return pp_item(q, first, ']'); }

/* 1 and past '[' when an array starts here */
static int pp_open(pp *q, char bracket)
{
    pp_ws(q);
    if (q->p < q->e && *q->p == bracket) {
        q->p++;
        return 1;
    }
    return 0;
}

/* up to n numbers of an array (NaN for the missing ones and for a value that is no array) */
static int pp_nums(pp *q, double *v, int n)
{
    for (int i = 0; i < n; i++) v[i] = NAN;
    if (!pp_open(q, '[')) return pp_skip(q);
    int first = 1, r, i = 0;
    while ((r = pp_next(q, &first)) > 0) {
        double x;
        if (pp_num(q, &x)) return -1;
        if (i < n) v[i] = x;
        i++;
    }
    return r;
}

/* a ring [[x,y],...] appended to the item's points (no points when it is no array) */
static int pp_ring(pp *q, svg_item *c)
{
    if (!pp_open(q, '[')) return pp_skip(q);
    int first = 1, r;
    while ((r = pp_next(q, &first)) > 0) {
        if (pts_room(c, c->npts + 1)) return -1;
        if (pp_nums(q, c->xy + 2 * c->npts, 2)) return -1;
        c->npts++;
    }
    return r;
}

/* the next member of an object whose '{' was passed: 1 with its key (escapes kept) and q at
 * its value, 0 after '}', -1 */
static int pp_member(pp *q, int *first, const char **key, size_t *klen)
{
    int r = pp_item(q, first, '}');
    if (r <= 0) return r;
    if (q->p >= q->e || *q->p != '"') return -1;
    const char *k = ++q->p;
    while (q->p < q->e && *q->p != '"') q->p += *q->p == '\\' ? 2 : 1;
    if (q->p >= q->e) return -1;
    *key = k;
    *klen = (size_t)(q->p - k);
    q->p++;
    pp_ws(q);
    if (q->p >= q->e || *q->p != ':') return -1;
    q->p++;
    return 1;
}

static int key_is(const char *k, size_t n, const char *name)
{
    return strlen(name) == n && !memcmp(k, name, n);
}

/* the descriptors object of a grain into c->desc (NaN for those it lacks) */
static int pp_descriptors(pp *q, svg_item *c)
{
    for (int j = 0; j < 4; j++) c->desc[j] = NAN;
    if (!pp_open(q, '{')) return pp_skip(q);
    int first = 1, r;
    const char *k;
    size_t kl;
    while ((r = pp_member(q, &first, &k, &kl)) > 0) {
        int j = 0;
        while (j < 4 && !key_is(k, kl, svg_items_desc_name[j])) j++;
        if (j < 4 ? pp_num(q, &c->desc[j]) : pp_skip(q)) return -1;
    }
    return r;
}

/* the polygons of a cell: their rings one after the other, and each ring's length */
static int pp_polygons(pp *q, svg_item *c)
{
    c->npts = c->nrings = 0;
    if (!pp_open(q, '[')) return pp_skip(q);
    int first = 1, r;
    while ((r = pp_next(q, &first)) > 0) {
        if (rings_room(c, c->nrings + 1)) return -1;
        size_t before = c->npts;
        if (pp_ring(q, c)) return -1;
        c->rings[c->nrings++] = c->npts - before;
    }
    return r;
}

/* the element's members into c; light: its points skipped */
static int item_parse(gp_svg_part part, svg_item *c, const char *text, size_t len, int light)
{
    item_clear(c);
    pp q = {text, text + len};
    if (part == GP_SVG_SPHERES) return pp_nums(&q, c->q, 4);
    if (!pp_open(&q, '{')) return pp_skip(&q);
    int first = 1, r;
    const char *k;
    size_t kl;
    while ((r = pp_member(&q, &first, &k, &kl)) > 0) {
        int rc;
        if (key_is(k, kl, "area")) rc = pp_num(&q, &c->area);
        else if (key_is(k, kl, "orientation_deg")) rc = pp_num(&q, &c->orientation_deg);
        else if (part == GP_SVG_GRAINS && key_is(k, kl, "contour")) {
            c->npts = 0;
            rc = light ? pp_skip(&q) : pp_ring(&q, c);
        } else if (part == GP_SVG_GRAINS && key_is(k, kl, "descriptors"))
            rc = pp_descriptors(&q, c);
        else if (part == GP_SVG_CELLS && key_is(k, kl, "seed"))
            rc = pp_nums(&q, c->seed, 2);
        else if (part == GP_SVG_CELLS && key_is(k, kl, "polygons"))
            rc = light ? pp_skip(&q) : pp_polygons(&q, c);
        else
            rc = pp_skip(&q);
        if (rc) return -1;
    }
    return r;
}

int svg_items_parse(gp_svg_part part, svg_item *c, const char *text, size_t len)
{
    return item_parse(part, c, text, len, 0);
}

int svg_items_parse_light(gp_svg_part part, svg_item *c, const char *text, size_t len)
{
    return item_parse(part, c, text, len, 1);
}

/* ------------------------------------------------------------------ an array of a JSON text */

/* -- an array of a JSON text, element by element */
static int scan_rewind(gp_svg_items *it)
{
    return json_scan_array_begin(it->js, it->off);
}

static int scan_next(gp_svg_items *it)
{
    uint64_t a, b;
    int r = json_scan_array_next(it->js, &a, &b);
    if (r <= 0) return r;
    const char *t = json_scan_span(it->js, a, b);
    if (!t) return -1;
    return item_parse(it->part, &it->cur, t, (size_t)(b - a), it->light) ? -1 : 1;
}

gp_svg_items *gp_svg_items_scan(const js_source *text, uint64_t off, gp_svg_part part)
{
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    it->js = json_scan_open(text);
    if (!it->js) {
        gp_svg_items_close(it);
        return NULL;
    }
    it->off = off;
    it->rewind = scan_rewind;
    it->next = scan_next;
    return it;
}

/* ------------------------------------------------------------------ an export pack */

/* -- an export pack */
static int pack_rewind(gp_svg_items *it)
{
    it->k = 0;
    return 0;
}

static int pack_next(gp_svg_items *it)
{
    gp_export_reader *e = it->e;
    svg_item *c = &it->cur;
    if (it->k >= gp_export_reader_info(e)->nitems) return 0;
    uint64_t k = it->k++;
    item_clear(c);
    if (it->part == GP_SVG_SPHERES) {
        if (gp_export_reader_sphere(e, k, c->q, NULL)) return -1;
        return 1;
    }
    if (gp_export_reader_info(e)->dim == GP_EXPORT_FV3D) {
        /* a 3D grain has none of the item's 2D numbers (all NaN): its views read the pack's
         * records through it->e themselves (svg_fv3d.c) */
        gp_export_grain3 g3;
        return gp_export_reader_grain3(e, k, &g3, NULL) ? -1 : 1;
    }
    gp_export_grain g;
    if (gp_export_reader_grain(e, k, &g, NULL)) return -1;
    if (!it->light) {
        if (pts_room(c, (size_t)g.point_count)) return -1;
        for (uint64_t i = 0; i < g.point_count; i++)
            if (gp_export_reader_point(it->ep, g.point_first + i, c->xy + 2 * i, NULL)) return -1;
        c->npts = (size_t)g.point_count;
    }
    c->area = g.area;
    c->orientation_deg = g.orientation_deg;
    c->desc[0] = g.elongation;
    c->desc[1] = g.roundness;
    c->desc[2] = g.circularity;
    c->desc[3] = g.regularity;
    /* the pack keeps raw doubles; the JSON result writes a non-finite one as null */
    if (!isfinite(c->area)) c->area = NAN;
    if (!isfinite(c->orientation_deg)) c->orientation_deg = NAN;
    for (int j = 0; j < 4; j++)
        if (!isfinite(c->desc[j])) c->desc[j] = NAN;
    for (size_t i = 0; i < 2 * c->npts; i++)
        if (!isfinite(c->xy[i])) c->xy[i] = NAN;
    return 1;
}

/* whether a pack of dimension dim holds the items of part: spheres a 3D pack's, grains a 2D or
 * a fv3d pack's */
static int pack_has(int dim, gp_svg_part part)
{
    if (part == GP_SVG_SPHERES) return dim == 3;
    return part == GP_SVG_GRAINS && (dim == 2 || dim == GP_EXPORT_FV3D);
}

gp_svg_items *gp_svg_items_pack(const gp_export_source *pack, gp_svg_part part)
{
    if (part == GP_SVG_CELLS) return NULL;
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    gp_error err;
    if (gp_export_reader_open(pack, &it->e, &err) ||
        !pack_has(gp_export_reader_info(it->e)->dim, part) ||
        (gp_export_reader_info(it->e)->dim == 2 && gp_export_reader_open(pack, &it->ep, &err))) {
        gp_svg_items_close(it);
        return NULL;
    }
    it->rewind = pack_rewind;
    it->next = pack_next;
    return it;
}

/* ------------------------------------------------------------------ what the views read */

gp_svg_items *svg_items_open(const gp_svg_input *in, gp_svg_part part, int *failed)
{
    *failed = 0;
    if (in->open) return in->open(in->user, part, failed);
    const json_t *a = json_object_get(in->summary, svg_items_part_name[part]);
    gp_svg_items *it = gp_svg_items_json(a, part);
    if (!it && json_is_array(a)) *failed = 1;
    return it;
}

gp_svg_items *svg_items_open_light(const gp_svg_input *in, gp_svg_part part, int *failed)
{
    gp_svg_items *it = svg_items_open(in, part, failed);
    if (it) it->light = 1;
    return it;
}

int svg_items_fold(gp_svg_items *it, void (*fn)(void *user, const svg_item *c), void *user)
{
    int r = it->rewind(it) ? -1 : 1;
    while (r > 0 && (r = it->next(it)) > 0) fn(user, &it->cur);
    return r < 0 ? -1 : 0;
}

double *svg_items_collect(const gp_svg_input *in, gp_svg_part part, int field, size_t *n,
                          int *failed)
{
    *n = 0;
    gp_svg_items *it = svg_items_open_light(in, part, failed);
    if (!it) return NULL;
    size_t cap = 0;
    double *v = NULL;
    int r = it->rewind(it) ? -1 : 1;
    while (r > 0 && (r = it->next(it)) > 0) {
        const svg_item *c = &it->cur;
        double x = field == 0 ? c->area : field == 1 ? c->orientation_deg : c->desc[field - 2];
        if (isnan(x)) continue;
        double *nv = *n < cap ? v : room(v, &cap, *n + 1, sizeof *v, 1024);
        if (!nv) {
            r = -1;
            break;
        }
        v = nv;
        v[(*n)++] = x;
    }
    gp_svg_items_close(it);
    if (r < 0) *failed = 1;
    if (r < 0 || !*n) {
        free(v);
        *n = 0;
        return NULL;
    }
    return v;
}
