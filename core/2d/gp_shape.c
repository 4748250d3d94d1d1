/* gp_shape.c -- see gp_shape.h. */
#include "gp_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define GP_PI 3.14159265358979323846

double gp_shape_regularity(double perimeter, double perimeter_convex, int *capped)
{
    if (capped)
        *capped = 0;
    if (!isfinite(perimeter) || !isfinite(perimeter_convex) || !(perimeter > 0))
        return NAN;
    double d = perimeter - perimeter_convex;
    if (d <= 1e-5 * perimeter) {
        if (capped)
            *capped = 1;
        return GP_SHAPE_REGULARITY_CAP;
    }
    return log10(perimeter / d);
}

static gp_status check_curve(const gp_shape_curve *c, gp_error *err)
{
    if (!c || !c->D || !c->delta)
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve, D or delta is NULL");
    if (!isfinite(c->center.x) || !isfinite(c->center.y))
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve centre is not finite");
    if (!isfinite(c->r0) || !(c->r0 > 0))
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve r0 = %g must be > 0", c->r0);
    if (c->nmodes < 1)
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve needs nmodes >= 1");
    for (size_t n = 1; n < c->nmodes; n++) {
        if (!isfinite(c->D[n]) || !isfinite(c->delta[n]))
            return gp_error_set(err, GP_ERR_INVALID, "shape: curve mode %zu is not finite", n);
    }
    return GP_OK;
}

#if !defined(__SSE2__)
/* The curve's four sums on ray i of the first quadrant (z = e^{i theta_i}, w = z^n by complex
 * products as curve_direct): Ce, Se over the even modes, Co, So over the odd ones of
 * a_n cos(n theta) and b_n sin(n theta) (a_n, b_n = cs[2n], cs[2n + 1]). */
static void ray_sums(const double *cs, size_t nm, double zr, double zi, double out[4])
{
    double wr = 1.0, wi = 0.0, e[2] = {0.0, 0.0}, o[2] = {0.0, 0.0};
    for (size_t n = 1; n < nm; n++) {
        double t = wr * zr - wi * zi;
        wi = wr * zi + wi * zr;
        wr = t;
        double *acc = (n & 1) ? o : e;
        acc[0] += wr * cs[2 * n];
        acc[1] += wi * cs[2 * n + 1];
    }
    out[0] = e[0], out[1] = e[1], out[2] = o[0], out[3] = o[1];
}
#endif

/* r(theta_i) / r0 and the point directions for np a multiple of 4, by the quadrant symmetry
 * of the Fourier basis (as gp_fill.c's shape factor): on ray i of the first quadrant the even
 * and odd modes' cosine and sine parts Ce, Se, Co, So give the four rays i, np/2 - i,
 * np/2 + i, np - i as (Ce + Se) + (Co + So), (Ce - Se) - (Co - So), (Ce + Se) - (Co + So)
 * and (Ce - Se) + (Co - So): np/4 sincos and a quarter of the complex products of
 * curve_direct, two rays at a time (the regularity's 512 points would otherwise be a visible
 * share of a specimen's time: docs/design/geometry.md). ct, st: np each (the directions);
 * s: np. */
static void curve_quadrant(const double *cs, size_t nm, size_t np, double *ct, double *st,
                           double *s)
{
    size_t Q = np / 4;
    for (size_t k = 0; k < Q; k++) { /* the first quadrant, the rest by symmetry */
        double th = 2.0 * GP_PI * (double)k / (double)np, c = cos(th), sn = sin(th);
        ct[k] = c, st[k] = sn;
        ct[Q + k] = -sn, st[Q + k] = c;
        ct[2 * Q + k] = -c, st[2 * Q + k] = -sn;
        ct[3 * Q + k] = sn, st[3 * Q + k] = -c;
    }
    for (size_t i = 0; i <= Q; i++) {
        double v[4];
        size_t i2 = i + 1 <= Q ? i + 1 : i;
#if defined(__SSE2__)
        /* rays i and i + 1 in the two lanes, the same operations as ray_sums */
        double w2[8];
        __m128d zr = _mm_set_pd(ct[i2], ct[i]), zi = _mm_set_pd(st[i2], st[i]);
        __m128d wr = _mm_set1_pd(1.0), wi = _mm_setzero_pd();
        __m128d e0 = _mm_setzero_pd(), e1 = e0, o0 = e0, o1 = e0;
        for (size_t n = 1; n < nm; n++) {
            __m128d t = _mm_sub_pd(_mm_mul_pd(wr, zr), _mm_mul_pd(wi, zi));
            wi = _mm_add_pd(_mm_mul_pd(wr, zi), _mm_mul_pd(wi, zr));
            wr = t;
            __m128d pr = _mm_mul_pd(wr, _mm_set1_pd(cs[2 * n]));
            __m128d pi = _mm_mul_pd(wi, _mm_set1_pd(cs[2 * n + 1]));
            if (n & 1)
                o0 = _mm_add_pd(o0, pr), o1 = _mm_add_pd(o1, pi);
            else
                e0 = _mm_add_pd(e0, pr), e1 = _mm_add_pd(e1, pi);
        }
        _mm_storeu_pd(w2, e0);
        _mm_storeu_pd(w2 + 2, e1);
        _mm_storeu_pd(w2 + 4, o0);
        _mm_storeu_pd(w2 + 6, o1);
        double sums[2][4] = {{w2[0], w2[2], w2[4], w2[6]}, {w2[1], w2[3], w2[5], w2[7]}};
#else
        double sums[2][4];
        ray_sums(cs, nm, ct[i], st[i], sums[0]);
        ray_sums(cs, nm, ct[i2], st[i2], sums[1]);
#endif
        for (size_t r = 0; r < 2 && i + r <= Q; r++) {
            size_t k = i + r;
            memcpy(v, sums[r], sizeof v);
            double ce = v[0], se = v[1], co = v[2], so = v[3];
            if (k < Q) {
                s[k] = 1.0 + ((ce + se) + (co + so));
                s[2 * Q + k] = 1.0 + ((ce + se) - (co + so));
            }
            if (k > 0) {
                s[2 * Q - k] = 1.0 + ((ce - se) - (co - so));
                s[4 * Q - k] = 1.0 + ((ce - se) + (co - so));
            }
        }
        i = i2 > i ? i2 : i;
    }
}

/* The same for any np: per point, w = z^n by complex products. */
static void curve_direct(const double *cs, size_t nm, size_t np, double *ct, double *st,
                         double *s)
{
    for (size_t i = 0; i < np; i++) {
        double th = 2.0 * GP_PI * (double)i / (double)np;
        double zr = cos(th), zi = sin(th);
        /* cos(n th - delta) = cos(n th) cos(delta) + sin(n th) sin(delta); w = z^n */
        double wr = 1.0, wi = 0.0, sum = 1.0;
        for (size_t n = 1; n < nm; n++) {
            double t = wr * zr - wi * zi;
            wi = wr * zi + wi * zr;
            wr = t;
            sum += wr * cs[2 * n] + wi * cs[2 * n + 1];
        }
        ct[i] = zr, st[i] = zi, s[i] = sum;
    }
}

gp_status gp_shape_curve_points(const gp_shape_curve *curve, size_t np, gp_vec2 *pts,
                                gp_error *err)
{
    gp_status st = check_curve(curve, err);
    if (st != GP_OK)
        return st;
    if (!pts || np < 3)
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve points need np >= 3 and an output");
    size_t nm = curve->nmodes;
    double *cs = malloc((2 * nm + 3 * np) * sizeof *cs);
    if (!cs)
        return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
    double *ct = cs + 2 * nm, *sn = ct + np, *s = sn + np;
    for (size_t n = 1; n < nm; n++) {
        cs[2 * n] = curve->D[n] * cos(curve->delta[n]);
        cs[2 * n + 1] = curve->D[n] * sin(curve->delta[n]);
    }
    if (np % 4 == 0)
        curve_quadrant(cs, nm, np, ct, sn, s);
    else
        curve_direct(cs, nm, np, ct, sn, s);
    for (size_t i = 0; i < np; i++) {
        double r = curve->r0 * s[i];
        if (!(r > 0)) {
            double th = 2.0 * GP_PI * (double)i / (double)np, si = s[i];
            free(cs);
            return gp_error_set(err, GP_ERR_NOT_STAR,
                                "shape: the curve is not star-shaped: r = %.3g r0 at theta = %.4f",
                                si, th);
        }
        pts[i].x = curve->center.x + r * ct[i];
        pts[i].y = curve->center.y + r * sn[i];
    }
    free(cs);
    return GP_OK;
}

/* P and P_conv of a point list (contour order). star: p is the curve's points, a polygon
 * star-shaped about the centre (every r > 0): its hull in O(n) without a sort. */
static gp_status perimeters(const gp_vec2 *p, size_t n, int star, double *P, double *Pc,
                            gp_error *err)
{
    gp_vec2 *h = malloc(n * sizeof *h);
    if (!h)
        return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
    size_t nh = star ? gp_convex_hull_star(p, n, h) : gp_convex_hull(p, n, h);
    *P = gp_poly_perimeter(p, n);
    *Pc = nh >= 2 ? gp_poly_perimeter(h, nh) : 0.0;
    free(h);
    return GP_OK;
}

/* the inputs of gp_shape_describe_ex, checked */
static gp_status check_inputs(const gp_vec2 *contour, size_t n, const gp_odec_disc *discs,
                              size_t ndiscs, const gp_shape_curve *curve, gp_error *err)
{
    if (!contour)
        return gp_error_set(err, GP_ERR_INVALID, "shape: contour is NULL");
    if (n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "shape: n = %zu contour points, need >= 3", n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(contour[i].x) || !isfinite(contour[i].y))
            return gp_error_set(err, GP_ERR_INVALID, "shape: contour point %zu is not finite", i);
    }
    for (size_t k = 0; discs && k < ndiscs; k++) {
        if (!(discs[k].r > 0) || !isfinite(discs[k].r))
            return gp_error_set(err, GP_ERR_INVALID, "shape: disc %zu has no radius", k);
    }
    return curve ? check_curve(curve, err) : GP_OK;
}

/* elongation and orientation, by the minimum caliper (star: the contour is star-shaped, its
 * hull is taken in O(n)) */
static gp_status describe_axes(const gp_vec2 *contour, size_t n, int star, gp_shape_result *out,
                               gp_error *err)
{
    double S, ang, L;
    gp_status st = star ? gp_min_caliper_star(contour, n, &S, &ang, &L, err)
                        : gp_min_caliper(contour, n, &S, &ang, &L, err);
    if (st != GP_OK)
        return st;
    if (!(L > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "shape: zero caliper length");
    out->width = S;
    out->length = L;
    out->elongation = S / L;
    double deg = ang * (180.0 / GP_PI);
    if (deg <= -90.0)
        deg += 180.0;
    if (deg > 90.0)
        deg -= 180.0;
    out->orientation_deg = deg;
    return GP_OK;
}

/* The inscribed and enclosing circles and circularity. The largest ODEC disc lies inside the
 * contour: its centre is the inscribed circle's first guess, which lets the search discard
 * most of its grid at once (the result is as exact whatever the guess). */
static gp_status describe_circles(const gp_vec2 *contour, size_t n, double req,
                                  const gp_odec_disc *discs, size_t ndiscs,
                                  gp_shape_result *out, gp_error *err)
{
    size_t big = 0;
    for (size_t k = 1; k < ndiscs; k++)
        if (discs[k].r > discs[big].r)
            big = k;
    gp_vec2 guess = {discs[big].x, discs[big].y};
    gp_status st = gp_max_inscribed_circle_from(contour, n, GP_SHAPE_INSC_TOL * req, &guess,
                                                &out->insc_center, &out->r_insc, err);
    if (st != GP_OK)
        return st;
    st = gp_min_enclosing_circle(contour, n, &out->circ_center, &out->r_circ, err);
    if (st != GP_OK)
        return st;
    if (!(out->r_insc > 0) || !(out->r_circ > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "shape: degenerate inscribed/enclosing circle");
    out->circularity = sqrt(out->r_insc / out->r_circ);
    return GP_OK;
}

/* P and P_conv: of the curve at max(n, GP_SHAPE_PERIMETER_POINTS) angles when there is one,
 * else of the contour; and the regularity */
static gp_status describe_regularity(const gp_vec2 *contour, size_t n,
                                     const gp_shape_curve *curve, gp_shape_result *out,
                                     gp_error *err)
{
    gp_status st;
    if (curve) {
        size_t np = n > GP_SHAPE_PERIMETER_POINTS ? n : GP_SHAPE_PERIMETER_POINTS;
        gp_vec2 *pts = malloc(np * sizeof *pts);
        if (!pts)
            return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
        st = gp_shape_curve_points(curve, np, pts, err);
        if (st == GP_OK)
            st = perimeters(pts, np, 1, &out->perimeter, &out->perimeter_convex, err);
        free(pts);
        out->perimeter_points = np;
    } else {
        st = perimeters(contour, n, 0, &out->perimeter, &out->perimeter_convex, err);
        out->perimeter_points = n;
    }
    if (st != GP_OK)
        return st;
    out->regularity =
        gp_shape_regularity(out->perimeter, out->perimeter_convex, &out->regularity_capped);
    return GP_OK;
}

gp_status gp_shape_describe_ex(const gp_vec2 *contour, size_t n, const gp_odec_params *params,
                               const gp_odec_disc *discs, size_t ndiscs,
                               const gp_shape_curve *curve, gp_shape_result *out,
                               gp_error *err)
{
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "shape: out is NULL");
    memset(out, 0, sizeof *out);
    if (discs && ndiscs == 0)
        discs = NULL;
    gp_status st = check_inputs(contour, n, discs, ndiscs, curve, err);
    if (st != GP_OK)
        return st;
    double area = gp_poly_area(contour, n);
    if (!(area > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "shape: the contour has no area");
    if ((st = describe_axes(contour, n, curve != NULL, out, err)) != GP_OK)
        return st;
    gp_odec_result od;
    memset(&od, 0, sizeof od);
    if (!discs) {
        if ((st = gp_odec_build(contour, n, params, &od, err)) != GP_OK)
            return st;
        discs = od.discs;
        ndiscs = od.ndiscs;
    }
    if (ndiscs == 0)
        st = gp_error_set(err, GP_ERR_DEGENERATE,
                          "shape: no ODEC disc fits the contour (roundness undefined)");
    else
        st = describe_circles(contour, n, sqrt(area / GP_PI), discs, ndiscs, out, err);
    /* roundness (Wadell, by ODEC): the discs' mean radius over the inscribed radius */
    double sr = 0;
    for (size_t k = 0; k < ndiscs; k++)
        sr += discs[k].r;
    gp_odec_result_free(&od);
    if (st != GP_OK)
        return st;
    out->ndiscs = ndiscs;
    out->mean_disc_radius = sr / (double)ndiscs;
    out->roundness = out->mean_disc_radius / out->r_insc;
    return describe_regularity(contour, n, curve, out, err);
}

gp_status gp_shape_describe(const gp_vec2 *contour, size_t n, const gp_odec_params *params,
                            gp_shape_result *out, gp_error *err)
{
    return gp_shape_describe_ex(contour, n, params, NULL, 0, NULL, out, err);
}

gp_status gp_shape_describe_fourier(const gp_vec2 *contour, size_t n, const gp_shape_curve *curve,
                                    const gp_odec_params *params, gp_shape_result *out,
                                    gp_error *err)
{
    if (!curve) {
        if (out)
            memset(out, 0, sizeof *out);
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve is NULL");
    }
    if (contour)
        return gp_shape_describe_ex(contour, n, params, NULL, 0, curve, out, err);
    if (out)
        memset(out, 0, sizeof *out);
    if (n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "shape: n = %zu contour points, need >= 3", n);
    gp_vec2 *pts = malloc(n * sizeof *pts);
    if (!pts)
        return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
    gp_status st = gp_shape_curve_points(curve, n, pts, err);
    if (st == GP_OK)
        st = gp_shape_describe_ex(pts, n, params, NULL, 0, curve, out, err);
    free(pts);
    return st;
}
