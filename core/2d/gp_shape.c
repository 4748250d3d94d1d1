/* gp_shape.c -- see gp_shape.h. */
#include "gp_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

gp_status gp_shape_curve_points(const gp_shape_curve *curve, size_t np, gp_vec2 *pts,
                                gp_error *err)
{
    gp_status st = check_curve(curve, err);
    if (st != GP_OK)
        return st;
    if (!pts || np < 3)
        return gp_error_set(err, GP_ERR_INVALID, "shape: curve points need np >= 3 and an output");
    size_t nm = curve->nmodes;
    double *cs = malloc(2 * (nm ? nm : 1) * sizeof *cs);
    if (!cs)
        return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
    for (size_t n = 1; n < nm; n++) {
        cs[2 * n] = curve->D[n] * cos(curve->delta[n]);
        cs[2 * n + 1] = curve->D[n] * sin(curve->delta[n]);
    }
    for (size_t i = 0; i < np; i++) {
        double th = 2.0 * GP_PI * (double)i / (double)np;
        double zr = cos(th), zi = sin(th);
        /* cos(n th - delta) = cos(n th) cos(delta) + sin(n th) sin(delta); w = z^n */
        double wr = 1.0, wi = 0.0, s = 1.0;
        for (size_t n = 1; n < nm; n++) {
            double t = wr * zr - wi * zi;
            wi = wr * zi + wi * zr;
            wr = t;
            s += wr * cs[2 * n] + wi * cs[2 * n + 1];
        }
        double r = curve->r0 * s;
        if (!(r > 0)) {
            free(cs);
            return gp_error_set(err, GP_ERR_NOT_STAR,
                                "shape: the curve is not star-shaped: r = %.3g r0 at theta = %.4f",
                                s, th);
        }
        pts[i].x = curve->center.x + r * zr;
        pts[i].y = curve->center.y + r * zi;
    }
    free(cs);
    return GP_OK;
}

/* P and P_conv of a point list (contour order) */
static gp_status perimeters(const gp_vec2 *p, size_t n, double *P, double *Pc, gp_error *err)
{
    gp_vec2 *h = malloc(n * sizeof *h);
    if (!h)
        return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
    size_t nh = gp_convex_hull(p, n, h);
    *P = gp_poly_perimeter(p, n);
    *Pc = nh >= 2 ? gp_poly_perimeter(h, nh) : 0.0;
    free(h);
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
    if (!contour)
        return gp_error_set(err, GP_ERR_INVALID, "shape: contour is NULL");
    if (n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "shape: n = %zu contour points, need >= 3", n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(contour[i].x) || !isfinite(contour[i].y))
            return gp_error_set(err, GP_ERR_INVALID, "shape: contour point %zu is not finite", i);
    }
    if (discs && ndiscs == 0)
        discs = NULL;
    if (discs) {
        for (size_t k = 0; k < ndiscs; k++) {
            if (!(discs[k].r > 0) || !isfinite(discs[k].r))
                return gp_error_set(err, GP_ERR_INVALID, "shape: disc %zu has no radius", k);
        }
    }
    if (curve) {
        gp_status st = check_curve(curve, err);
        if (st != GP_OK)
            return st;
    }
    double area = gp_poly_area(contour, n);
    if (!(area > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "shape: the contour has no area");
    double req = sqrt(area / GP_PI);

    /* elongation, orientation */
    double S, ang, L;
    gp_status st = gp_min_caliper(contour, n, &S, &ang, &L, err);
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

    /* circles */
    st = gp_max_inscribed_circle(contour, n, GP_SHAPE_INSC_TOL * req, &out->insc_center,
                                 &out->r_insc, err);
    if (st != GP_OK)
        return st;
    st = gp_min_enclosing_circle(contour, n, &out->circ_center, &out->r_circ, err);
    if (st != GP_OK)
        return st;
    if (!(out->r_insc > 0) || !(out->r_circ > 0))
        return gp_error_set(err, GP_ERR_DEGENERATE, "shape: degenerate inscribed/enclosing circle");
    out->circularity = sqrt(out->r_insc / out->r_circ);

    /* roundness */
    gp_odec_result od;
    memset(&od, 0, sizeof od);
    if (!discs) {
        st = gp_odec_build(contour, n, params, &od, err);
        if (st != GP_OK)
            return st;
        discs = od.discs;
        ndiscs = od.ndiscs;
    }
    double sr = 0;
    for (size_t k = 0; k < ndiscs; k++)
        sr += discs[k].r;
    gp_odec_result_free(&od);
    if (ndiscs == 0)
        return gp_error_set(err, GP_ERR_DEGENERATE,
                            "shape: no ODEC disc fits the contour (roundness undefined)");
    out->ndiscs = ndiscs;
    out->mean_disc_radius = sr / (double)ndiscs;
    out->roundness = out->mean_disc_radius / out->r_insc;

    /* regularity */
    if (curve) {
        size_t np = n > GP_SHAPE_PERIMETER_POINTS ? n : GP_SHAPE_PERIMETER_POINTS;
        gp_vec2 *pts = malloc(np * sizeof *pts);
        if (!pts)
            return gp_error_set(err, GP_ERR_NOMEM, "shape: out of memory");
        st = gp_shape_curve_points(curve, np, pts, err);
        if (st == GP_OK)
            st = perimeters(pts, np, &out->perimeter, &out->perimeter_convex, err);
        free(pts);
        if (st != GP_OK)
            return st;
        out->perimeter_points = np;
    } else {
        st = perimeters(contour, n, &out->perimeter, &out->perimeter_convex, err);
        if (st != GP_OK)
            return st;
        out->perimeter_points = n;
    }
    out->regularity =
        gp_shape_regularity(out->perimeter, out->perimeter_convex, &out->regularity_capped);
    return GP_OK;
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
