/* gp_outline.c -- see gp_outline.h. */
#include "gp_outline.h"

#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_fourier.h"
#include "gp_shape.h"

#define GP_PI 3.14159265358979323846

struct gp_outline {
    gp_outline_params p;
    gp_fourier *f;
    gp_vec2 *poly;   /* the cleaned outline in local coordinates, capacity cap */
    gp_vec2 *kernel; /* cap + 4 */
    size_t cap;
    double *r;       /* np radii */
    double *delta;   /* nmodes phases, when the caller passes none */
};

void gp_outline_params_defaults(gp_outline_params *p)
{
    if (!p)
        return;
    *p = (gp_outline_params){0};
    p->np = GP_FOURIER_NP_DEFAULT;
    p->nmodes = GP_FOURIER_NP_DEFAULT / 2;
    p->descriptors = 1;
    p->min_outlines = 10;
}

static gp_status check_params(const gp_outline_params *p, gp_error *err)
{
    if (p->np < GP_FOURIER_NP_MIN)
        return gp_error_set(err, GP_ERR_INVALID, "outline: np = %zu rays, must be >= %d", p->np,
                            GP_FOURIER_NP_MIN);
    if (p->nmodes < 2 || p->nmodes > gp_fourier_max_modes(p->np))
        return gp_error_set(err, GP_ERR_INVALID,
                            "outline: nmodes = %zu must be in [2, %zu] for np = %zu rays",
                            p->nmodes, gp_fourier_max_modes(p->np), p->np);
    if (p->min_outlines < 1)
        return gp_error_set(err, GP_ERR_INVALID, "outline: min_outlines must be >= 1");
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* step 1: cleaning                                                                            */

static int same(gp_vec2 a, gp_vec2 b)
{
    return a.x == b.x && a.y == b.y;
}

/* Drops consecutive repeats and the closing duplicates into out (may alias pts): returns the
 * count kept. Exact equality: a repeat is a digitiser's or a JSON writer's artefact, while two
 * distinct points however close are the outline's own. */
static size_t drop_repeats(const gp_vec2 *pts, size_t n, gp_vec2 *out)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (m > 0 && same(out[m - 1], pts[i]))
            continue;
        out[m++] = pts[i];
    }
    while (m > 1 && same(out[m - 1], out[0]))
        m--;
    return m;
}

static void reverse(gp_vec2 *p, size_t n)
{
    for (size_t i = 0, j = n - 1; i < j; i++, j--) {
        gp_vec2 t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
}

/* Step 1 with the centroid and area it finds on the way. */
static gp_status clean_impl(const gp_vec2 *pts, size_t n, gp_vec2 *out, size_t *nout,
                            unsigned *flags, gp_vec2 *centroid, double *area, gp_error *err)
{
    *nout = 0;
    if (!pts || !out)
        return gp_error_set(err, GP_ERR_INVALID, "outline: NULL points");
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(pts[i].x) || !isfinite(pts[i].y))
            return gp_error_set(err, GP_ERR_INVALID, "outline: point %zu is not finite", i);
    }
    size_t m = drop_repeats(pts, n, out);
    if (m < n && flags)
        *flags |= GP_OUTLINE_DEDUPED;
    if (m < 3)
        return gp_error_set(err, GP_ERR_INVALID,
                            "outline: %zu distinct points (of %zu given), need >= 3", m, n);
    /* gp_poly_centroid's zero-area test (relative to the sum of |cross| terms) */
    if (gp_poly_centroid(out, m, centroid, NULL) != GP_OK)
        return gp_error_set(err, GP_ERR_DEGENERATE,
                            "outline: the %zu points enclose no area (collinear or retraced)", m);
    double a = gp_poly_signed_area(out, m);
    if (a < 0) {
        reverse(out, m);
        if (flags)
            *flags |= GP_OUTLINE_REVERSED;
    }
    *area = fabs(a);
    *nout = m;
    return GP_OK;
}

gp_status gp_outline_clean(const gp_vec2 *pts, size_t n, gp_vec2 *out, size_t *nout,
                           unsigned *flags, gp_error *err)
{
    size_t m = 0;
    gp_vec2 c;
    double a;
    if (flags)
        *flags = 0;
    gp_status st = clean_impl(pts, n, out, &m, flags, &c, &a, err);
    if (nout)
        *nout = m;
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* step 2: star shape, winding and the kernel                                                  */

/* 1 if p is strictly left of every edge of the counter-clockwise polygon (exact); else 0 and
 * *bad the first edge that fails. */
static int sees_all_edges(const gp_vec2 *poly, size_t n, gp_vec2 p, size_t *bad)
{
    for (size_t k = 0; k < n; k++) {
        if (gp_orient2d(poly[k], poly[(k + 1) % n], p) <= 0) {
            *bad = k;
            return 0;
        }
    }
    return 1;
}

/* The angle edge k subtends at p, in (0, pi) when p is strictly left of it. */
static double edge_angle(gp_vec2 a, gp_vec2 b, gp_vec2 p)
{
    double ax = a.x - p.x, ay = a.y - p.y, bx = b.x - p.x, by = b.y - p.y;
    return atan2(ax * by - ay * bx, ax * bx + ay * by);
}

/* How many times the polygon winds round p (every edge strictly left of p): the subtended
 * angles are all positive, so their sum is 2 pi times the winding number. */
static long winding(const gp_vec2 *poly, size_t n, gp_vec2 p)
{
    double s = 0;
    for (size_t k = 0; k < n; k++)
        s += edge_angle(poly[k], poly[(k + 1) % n], p);
    return lround(s / (2.0 * GP_PI));
}

typedef struct halfplane {
    gp_vec2 p, d; /* a point of the line and its unit direction; inside is on the left */
    double ang;
} halfplane;

static double cross2(gp_vec2 a, gp_vec2 b)
{
    return a.x * b.y - a.y * b.x;
}

#define KERNEL_EPS 1e-12 /* in units of the polygon's size: inside-ness and parallelism */

static int hp_out(const halfplane *h, gp_vec2 x)
{
    gp_vec2 v = {x.x - h->p.x, x.y - h->p.y};
    return cross2(h->d, v) < -KERNEL_EPS;
}

static gp_vec2 hp_meet(const halfplane *a, const halfplane *b)
{
    gp_vec2 w = {b->p.x - a->p.x, b->p.y - a->p.y};
    double s = cross2(w, b->d) / cross2(a->d, b->d);
    return (gp_vec2){a->p.x + s * a->d.x, a->p.y + s * a->d.y};
}

static int hp_cmp(const void *x, const void *y)
{
    double a = ((const halfplane *)x)->ang, b = ((const halfplane *)y)->ang;
    return (a > b) - (a < b);
}

/* Half-plane intersection by sorting on direction and sweeping with a deque (the usual
 * O(m log m) "sort and incremental" method): h[0 .. m) sorted in place; dq (capacity m)
 * receives the indices of the half-planes bounding the result, front at dq[*front]. Returns
 * their count (< 3: empty). The tests check it against brute-force clipping. */
static size_t hp_intersect(halfplane *h, size_t m, size_t *dq, size_t *front)
{
    qsort(h, m, sizeof *h, hp_cmp);
    size_t f = 0, len = 0;
    for (size_t i = 0; i < m; i++) {
        while (len > 1 && hp_out(&h[i], hp_meet(&h[dq[f + len - 1]], &h[dq[f + len - 2]])))
            len--;
        while (len > 1 && hp_out(&h[i], hp_meet(&h[dq[f]], &h[dq[f + 1]]))) {
            f++;
            len--;
        }
        if (len > 0) {
            const halfplane *b = &h[dq[f + len - 1]];
            if (fabs(cross2(h[i].d, b->d)) < KERNEL_EPS) {
                if (h[i].d.x * b->d.x + h[i].d.y * b->d.y < 0)
                    return 0; /* opposite parallel lines with nothing between: empty */
                if (!hp_out(&h[i], b->p))
                    continue; /* the one in place is the tighter */
                len--;
            }
        }
        dq[f + len++] = i;
    }
    while (len > 2 && hp_out(&h[dq[f]], hp_meet(&h[dq[f + len - 1]], &h[dq[f + len - 2]])))
        len--;
    while (len > 2 && hp_out(&h[dq[f + len - 1]], hp_meet(&h[dq[f]], &h[dq[f + 1]]))) {
        f++;
        len--;
    }
    *front = f;
    return len;
}

static void set_hp(halfplane *h, gp_vec2 a, gp_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l = hypot(dx, dy);
    h->p = a;
    h->d = (gp_vec2){dx / l, dy / l};
    h->ang = atan2(dy, dx);
}

/* The edges' half-planes in coordinates centred on the bounding box and scaled to its size
 * (so KERNEL_EPS is relative), plus the box's own four (twice its size) so that every
 * intermediate intersection is bounded. */
static void kernel_halfplanes(const gp_vec2 *poly, size_t n, gp_vec2 lo, gp_vec2 hi,
                              halfplane *h, gp_vec2 *o, double *s)
{
    *o = (gp_vec2){0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y)};
    *s = fmax(hi.x - lo.x, hi.y - lo.y);
    for (size_t k = 0; k < n; k++) {
        gp_vec2 a = poly[k], b = poly[(k + 1) % n];
        set_hp(&h[k], (gp_vec2){(a.x - o->x) / *s, (a.y - o->y) / *s},
               (gp_vec2){(b.x - o->x) / *s, (b.y - o->y) / *s});
    }
    const gp_vec2 box[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (size_t k = 0; k < 4; k++)
        set_hp(&h[n + k], box[k], box[(k + 1) % 4]);
}

gp_status gp_outline_kernel(const gp_vec2 *poly, size_t n, gp_vec2 *kernel, size_t *nk,
                            gp_error *err)
{
    if (nk)
        *nk = 0;
    if (!poly || !kernel || !nk || n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "outline kernel: need a polygon of >= 3 points");
    gp_vec2 lo, hi, o;
    double s;
    gp_status st = gp_poly_bbox(poly, n, &lo, &hi, err);
    if (st != GP_OK)
        return st;
    for (size_t k = 0; k < n; k++) {
        if (same(poly[k], poly[(k + 1) % n]))
            return gp_error_set(err, GP_ERR_INVALID, "outline kernel: point %zu is repeated", k);
    }
    size_t m = n + 4, front = 0;
    halfplane *h = malloc(m * sizeof *h);
    size_t *dq = malloc(m * sizeof *dq);
    if (!h || !dq) {
        free(h);
        free(dq);
        return gp_error_set(err, GP_ERR_NOMEM, "outline kernel: out of memory");
    }
    kernel_halfplanes(poly, n, lo, hi, h, &o, &s);
    size_t len = hp_intersect(h, m, dq, &front);
    for (size_t k = 0; len >= 3 && k < len; k++) {
        gp_vec2 v = hp_meet(&h[dq[front + k]], &h[dq[front + (k + 1) % len]]);
        kernel[k] = (gp_vec2){o.x + s * v.x, o.y + s * v.y};
    }
    free(h);
    free(dq);
    if (len >= 3 && gp_poly_signed_area(kernel, len) > 0)
        *nk = len;
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* step 3: radii                                                                               */

gp_status gp_outline_star_radii(const gp_vec2 *poly, size_t n, gp_vec2 pole, size_t np,
                                double *r, gp_error *err)
{
    if (!poly || !r || n < 3 || np < 1)
        return gp_error_set(err, GP_ERR_INVALID, "outline radii: bad arguments");
    size_t bad;
    if (!sees_all_edges(poly, n, pole, &bad))
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "outline radii: edge %zu does not face the pole (%g, %g)", bad,
                            pole.x, pole.y);
    long w = winding(poly, n, pole);
    if (w != 1)
        return gp_error_set(err, GP_ERR_INVALID,
                            "outline radii: the outline winds %ld times round the pole", w);
    /* rays in increasing angle from vertex 0's direction phi0: t_j = theta_{i0 + j} - phi0 */
    double step = 2.0 * GP_PI / (double)np;
    double phi0 = atan2(poly[0].y - pole.y, poly[0].x - pole.x);
    if (phi0 < 0)
        phi0 += 2.0 * GP_PI;
    size_t i0 = (size_t)ceil(phi0 / step);
    size_t k = 0;
    double a_end = edge_angle(poly[0], poly[1 % n], pole); /* vertex angles, relative to phi0 */
    for (size_t j = 0; j < np; j++) {
        size_t i = (i0 + j) % np;
        double t = (double)(i0 + j) * step - phi0;
        while (k + 1 < n && a_end <= t) {
            k++;
            a_end += edge_angle(poly[k], poly[(k + 1) % n], pole);
        }
        /* the ray from the pole along theta_i meets edge k at cross(u_a, u_b) / cross(d, e) */
        gp_vec2 a = poly[k], b = poly[(k + 1) % n];
        gp_vec2 ua = {a.x - pole.x, a.y - pole.y}, ub = {b.x - pole.x, b.y - pole.y};
        gp_vec2 d = {cos(step * (double)i), sin(step * (double)i)};
        gp_vec2 e = {ub.x - ua.x, ub.y - ua.y};
        r[i] = cross2(ua, ub) / cross2(d, e);
    }
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the workspace and one outline                                                               */

gp_outline *gp_outline_create(const gp_outline_params *p, gp_error *err)
{
    gp_outline_params d;
    gp_outline_params_defaults(&d);
    if (!p)
        p = &d;
    if (check_params(p, err) != GP_OK)
        return NULL;
    gp_outline *o = calloc(1, sizeof *o);
    if (!o) {
        gp_error_set(err, GP_ERR_NOMEM, "outline: out of memory");
        return NULL;
    }
    o->p = *p;
    o->f = gp_fourier_create(p->np, err);
    o->r = malloc(p->np * sizeof *o->r);
    o->delta = malloc(p->nmodes * sizeof *o->delta);
    if (!o->f || !o->r || !o->delta) {
        if (o->f)
            gp_error_set(err, GP_ERR_NOMEM, "outline: out of memory");
        gp_outline_destroy(o);
        return NULL;
    }
    return o;
}

void gp_outline_destroy(gp_outline *o)
{
    if (!o)
        return;
    gp_fourier_destroy(o->f);
    free(o->poly);
    free(o->kernel);
    free(o->r);
    free(o->delta);
    free(o);
}

static gp_status reserve(gp_outline *o, size_t n, gp_error *err)
{
    if (n <= o->cap)
        return GP_OK;
    size_t cap = n > 2 * o->cap ? n : 2 * o->cap;
    gp_vec2 *p = realloc(o->poly, cap * sizeof *p);
    if (p)
        o->poly = p;
    gp_vec2 *k = realloc(o->kernel, (cap + 4) * sizeof *k);
    if (k)
        o->kernel = k;
    if (!p || !k)
        return gp_error_set(err, GP_ERR_NOMEM, "outline: out of memory for %zu points", n);
    o->cap = cap;
    return GP_OK;
}

/* Marks info refused with the reason in e, and passes the code on. */
static gp_status refuse(gp_outline_info *info, const gp_error *e, gp_error *err)
{
    info->flags |= GP_OUTLINE_REFUSED;
    info->error = *e;
    if (err)
        *err = *e;
    return e->code;
}

/* Step 2 (local coordinates): *pole = centroid c if it sees every edge, else the kernel's
 * centroid (flag, kernel fraction). */
static gp_status choose_pole(gp_outline *o, size_t n, gp_vec2 c, double area,
                             gp_outline_info *info, gp_vec2 *pole, gp_error *e)
{
    size_t bad;
    *pole = c;
    if (!sees_all_edges(o->poly, n, c, &bad)) {
        size_t nk = 0;
        gp_status st = gp_outline_kernel(o->poly, n, o->kernel, &nk, e);
        if (st != GP_OK)
            return st;
        if (nk == 0 || gp_poly_centroid(o->kernel, nk, pole, NULL) != GP_OK)
            return gp_error_set(e, GP_ERR_NOT_STAR,
                                "outline is not star-shaped: no interior point sees all of it "
                                "(the kernel is empty)");
        if (!sees_all_edges(o->poly, n, *pole, &bad))
            return gp_error_set(e, GP_ERR_NOT_STAR,
                                "outline is not star-shaped: its kernel is too thin to hold a "
                                "pole");
        info->flags |= GP_OUTLINE_POLE_MOVED;
        info->kernel_fraction = gp_poly_area(o->kernel, nk) / area;
    }
    long w = winding(o->poly, n, *pole);
    if (w != 1)
        return gp_error_set(e, GP_ERR_INVALID,
                            "outline crosses itself: it winds %ld times round its pole", w);
    return GP_OK;
}

/* Step 5: the descriptors of the outline's Fourier grain, about its pole. */
static void describe(gp_outline *o, double r0, const double *D, const double *delta,
                     gp_outline_info *info)
{
    gp_shape_curve curve = {{0.0, 0.0}, r0, D, delta, o->p.nmodes};
    gp_shape_result s;
    gp_error e;
    if (gp_shape_describe_fourier(NULL, o->p.np, &curve, NULL, &s, &e) != GP_OK) {
        info->flags |= GP_OUTLINE_NO_DESCRIPTORS;
        info->error = e;
        return;
    }
    info->elongation = s.elongation;
    info->orientation_deg = s.orientation_deg;
    info->roundness = s.roundness;
    info->circularity = s.circularity;
    info->regularity = s.regularity;
}

/* Copies pts into o->poly relative to their bounding-box centre *org (so far-away outlines
 * keep their digits through every later step). */
static gp_status local_copy(gp_outline *o, const gp_vec2 *pts, size_t n, gp_vec2 *org,
                            gp_error *e)
{
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(pts[i].x) || !isfinite(pts[i].y))
            return gp_error_set(e, GP_ERR_INVALID, "outline: point %zu is not finite", i);
    }
    gp_vec2 lo, hi;
    gp_status st = gp_poly_bbox(pts, n, &lo, &hi, e);
    if (st != GP_OK)
        return st;
    *org = (gp_vec2){0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y)};
    for (size_t i = 0; i < n; i++)
        o->poly[i] = (gp_vec2){pts[i].x - org->x, pts[i].y - org->y};
    return GP_OK;
}

/* Steps 1-4 on o->poly (n points, local frame): info's geometry, D and the phases ph. */
static gp_status analyse_local(gp_outline *o, size_t n, double *D, double *ph,
                               gp_outline_info *info, gp_vec2 *c, gp_vec2 *pole, gp_error *e)
{
    size_t m = 0;
    double area = 0, r0 = 0;
    gp_status st = clean_impl(o->poly, n, o->poly, &m, &info->flags, c, &area, e);
    info->ndropped = n - m;
    info->nvertices = m;
    if (st == GP_OK)
        st = choose_pole(o, m, *c, area, info, pole, e);
    if (st == GP_OK)
        st = gp_outline_star_radii(o->poly, m, *pole, o->p.np, o->r, e);
    if (st == GP_OK)
        st = gp_fourier_analyse(o->f, o->r, o->p.nmodes, &r0, D, ph, e);
    if (st != GP_OK)
        return st;
    info->area = area;
    info->r0 = r0;
    info->pole_offset = hypot(pole->x - c->x, pole->y - c->y) / r0;
    return GP_OK;
}

gp_status gp_outline_analyze(gp_outline *o, const gp_vec2 *pts, size_t n, double *D,
                             double *delta, gp_outline_info *info, gp_error *err)
{
    if (!o || !D || !info)
        return gp_error_set(err, GP_ERR_INVALID, "outline: NULL workspace, spectrum or info");
    memset(info, 0, sizeof *info);
    memset(D, 0, o->p.nmodes * sizeof *D);
    gp_error e;
    gp_error_clear(&e);
    if (!pts || n == 0) {
        gp_error_set(&e, GP_ERR_INVALID, "outline: no points");
        return refuse(info, &e, err);
    }
    gp_status st = reserve(o, n, err);
    if (st != GP_OK)
        return st;
    gp_vec2 org = {0, 0}, c = {0, 0}, pole = {0, 0};
    double *ph = delta ? delta : o->delta;
    st = local_copy(o, pts, n, &org, &e);
    if (st == GP_OK)
        st = analyse_local(o, n, D, ph, info, &c, &pole, &e);
    if (st == GP_ERR_NOMEM)
        return gp_error_set(err, st, "%s", e.message);
    if (st != GP_OK) {
        memset(D, 0, o->p.nmodes * sizeof *D);
        return refuse(info, &e, err);
    }
    info->centroid = (gp_vec2){org.x + c.x, org.y + c.y};
    info->pole = (gp_vec2){org.x + pole.x, org.y + pole.y};
    if (o->p.descriptors)
        describe(o, info->r0, D, ph, info);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* a set                                                                                       */

void gp_outline_set_result_free(gp_outline_set_result *res)
{
    if (!res)
        return;
    free(res->mean);
    free(res->sd);
    free(res->cov);
    free(res->spectra);
    free(res->info);
    free(res->refused);
    memset(res, 0, sizeof *res);
}

static gp_status set_alloc(gp_outline_set_result *res, size_t n, size_t nmodes, gp_error *err)
{
    res->n = n;
    res->nmodes = nmodes;
    res->mean = calloc(nmodes, sizeof *res->mean);
    res->sd = calloc(nmodes, sizeof *res->sd);
    res->cov = calloc(nmodes, sizeof *res->cov);
    res->spectra = calloc(n * nmodes, sizeof *res->spectra);
    res->info = calloc(n, sizeof *res->info);
    res->refused = calloc(n, sizeof *res->refused);
    if (!res->mean || !res->sd || !res->cov || !res->spectra || !res->info || !res->refused) {
        gp_outline_set_result_free(res);
        return gp_error_set(err, GP_ERR_NOMEM, "outline set: out of memory for %zu outlines", n);
    }
    return GP_OK;
}

/* mean and sample sd of x[0 .. n) (GSL); sd = 0 below two values */
static gp_outline_stat stat_of(const double *x, size_t n)
{
    gp_outline_stat s = {0, 0};
    if (n == 0)
        return s;
    s.mean = gsl_stats_mean(x, 1, n);
    s.sd = n > 1 ? gsl_stats_sd_m(x, 1, n, s.mean) : 0.0;
    return s;
}

/* The descriptor field at byte offset off of each described outline, into buf. */
static gp_outline_stat descriptor_stat(const gp_outline_set_result *res, size_t off, double *buf)
{
    size_t m = 0;
    for (size_t i = 0; i < res->n; i++) {
        const gp_outline_info *in = &res->info[i];
        if (!(in->flags & (GP_OUTLINE_REFUSED | GP_OUTLINE_NO_DESCRIPTORS)))
            buf[m++] = *(const double *)((const char *)in + off);
    }
    return stat_of(buf, m);
}

/* Spectrum and descriptor statistics over the analysed outlines; buf holds n doubles. */
static void set_stats(gp_outline_set_result *res, int descriptors, double *buf)
{
    for (size_t k = 0; k < res->nmodes; k++) {
        size_t m = 0;
        for (size_t i = 0; i < res->n; i++) {
            if (!(res->info[i].flags & GP_OUTLINE_REFUSED))
                buf[m++] = res->spectra[i * res->nmodes + k];
        }
        gp_outline_stat s = stat_of(buf, m);
        res->mean[k] = s.mean;
        res->sd[k] = s.sd;
        res->cov[k] = s.mean > 0 ? s.sd / s.mean : 0.0;
    }
    if (!descriptors)
        return;
    res->elongation = descriptor_stat(res, offsetof(gp_outline_info, elongation), buf);
    res->roundness = descriptor_stat(res, offsetof(gp_outline_info, roundness), buf);
    res->circularity = descriptor_stat(res, offsetof(gp_outline_info, circularity), buf);
    res->regularity = descriptor_stat(res, offsetof(gp_outline_info, regularity), buf);
}

/* The counts, and the refused indices in ascending order. */
static void set_counts(gp_outline_set_result *res, int descriptors)
{
    for (size_t i = 0; i < res->n; i++) {
        unsigned fl = res->info[i].flags;
        if (fl & GP_OUTLINE_REFUSED) {
            res->refused[res->nrefused++] = i;
            continue;
        }
        res->nanalysed++;
        res->ndescribed += descriptors && !(fl & GP_OUTLINE_NO_DESCRIPTORS);
        res->nreversed += !!(fl & GP_OUTLINE_REVERSED);
        res->npole_moved += !!(fl & GP_OUTLINE_POLE_MOVED);
        res->ndeduped += !!(fl & GP_OUTLINE_DEDUPED);
    }
}

/* GP_ERR_INFEASIBLE naming the first refused outlines and why. */
static gp_status too_few(const gp_outline_set_result *res, size_t need, gp_error *err)
{
    char list[160] = "";
    size_t len = 0;
    for (size_t k = 0; k < res->nrefused && k < 4 && len < sizeof list; k++) {
        size_t i = res->refused[k];
        len += (size_t)snprintf(list + len, sizeof list - len, "%s%zu (%s)", k ? ", " : "", i,
                                gp_status_name(res->info[i].error.code));
    }
    return gp_error_set(err, GP_ERR_INFEASIBLE,
                        "outline set: %zu of %zu outlines analysed, need %zu; refused: %s%s",
                        res->nanalysed, res->n, need, list, res->nrefused > 4 ? ", ..." : "");
}

/* the progress report of outline i of n, every GP_OUTLINE_REPORT_EVERY: 1 = stop */
static int report_progress(const gp_outline_params *p, size_t i, size_t n)
{
    if (!p->progress || i == 0 || i % GP_OUTLINE_REPORT_EVERY) return 0;
    gp_progress r = {.phase = "shape", .phase_fraction = (double)i / (double)n};
    return p->progress(p->progress_user, &r) != 0;
}

gp_status gp_outline_set_analyze(const gp_outline_points *outlines, size_t n,
                                 const gp_outline_params *p, const volatile int *cancel,
                                 gp_outline_set_result *res, gp_error *err)
{
    if (!res)
        return gp_error_set(err, GP_ERR_INVALID, "outline set: NULL result");
    memset(res, 0, sizeof *res);
    if (!outlines || n == 0)
        return gp_error_set(err, GP_ERR_INVALID, "outline set: no outlines");
    gp_outline_params d;
    gp_outline_params_defaults(&d);
    if (!p)
        p = &d;
    gp_outline *o = gp_outline_create(p, err);
    if (!o)
        return err ? err->code : GP_ERR_INVALID;
    gp_status st = set_alloc(res, n, p->nmodes, err);
    for (size_t i = 0; st == GP_OK && i < n; i++) {
        if ((cancel && *cancel) || report_progress(p, i, n))
            st = gp_error_set(err, GP_ERR_CANCELLED, "outline set: cancelled at outline %zu", i);
        else if (gp_outline_analyze(o, outlines[i].pts, outlines[i].n,
                                    res->spectra + i * p->nmodes, NULL, &res->info[i],
                                    err) == GP_ERR_NOMEM)
            st = GP_ERR_NOMEM;
    }
    gp_outline_destroy(o);
    if (st != GP_OK) {
        gp_outline_set_result_free(res);
        return st;
    }
    gp_error_clear(err);
    set_counts(res, p->descriptors);
    if (res->nanalysed < p->min_outlines)
        return too_few(res, p->min_outlines, err);
    double *buf = malloc(n * sizeof *buf);
    if (!buf) {
        gp_outline_set_result_free(res);
        return gp_error_set(err, GP_ERR_NOMEM, "outline set: out of memory");
    }
    set_stats(res, p->descriptors, buf);
    free(buf);
    return GP_OK;
}
