/* test_fill.c -- optimised cell filling (Mollon & Zhao 2012, Sect. 4.1, Eq. 19) against
 * analytic truths: the largest Np-gon of a circle grain inside a square, a hexagon, a
 * triangle (off its centroid) and a 48-edge ellipse (the large-cell LP), exact hits of
 * reachable targets, orientation following the cell, containment in a non-convex cell, the
 * reported rotation and phases reproducing the contour, scale invariance, determinism (also
 * across cells filled with one workspace), the stall stop on a cell that cannot reach F_S, a
 * contour size that is not a multiple of 4 (the shape summed without the quadrant symmetry)
 * and bad input. */
#include "gp_fill.h"
#include "gp_geom.h"
#include "gp_test.h"

#include <string.h>

#define NP 128

static double D[NP / 2];

static gp_fill_workspace *make(double fs, double d2, double d3, double d8, int centre)
{
    memset(D, 0, sizeof D);
    D[0] = 1.0;
    D[2] = d2;
    D[3] = d3;
    for (int n = 4; n < 8; n++) D[n] = d3 * pow(n / 3.0, -2.0);
    D[8] = d8;
    for (int n = 9; n < NP / 2; n++) D[n] = d8 * pow(n / 8.0, -2.0);
    gp_fill_params p;
    gp_fill_params_defaults(&p);
    p.solid_fraction = fs;
    p.D = D;
    p.nmodes = NP / 2;
    p.contour_points = NP;
    p.optimise_centre = centre;
    gp_error e;
    gp_fill_workspace *ws = gp_fill_workspace_create(&p, &e);
    if (!ws) fprintf(stderr, "create: %s\n", e.message);
    return ws;
}

static void phases_fixed(double *ph)
{
    /* deterministic "random" phases for the modes that are not optimised */
    for (int n = 0; n < NP / 2; n++) ph[n] = fmod(n * 2.39996322972865332, 2 * M_PI) - M_PI;
}

static double np_gon_area(double r) { return 0.5 * NP * r * r * sin(2 * M_PI / NP); }

/* distance from q to the nearest edge line of the convex polygon p */
static double edge_clearance(const gp_vec2 *p, size_t n, gp_vec2 q)
{
    double d = INFINITY;
    for (size_t k = 0; k < n; k++)
        d = fmin(d, gp_segment_distance(q, p[k], p[(k + 1) % n]));
    return d;
}

/* largest |contour_i - curve_i| / r0 for the curve the result describes: the caller's
 * phases with res->phases[2..7], turned by res->rotation. r(theta) by the direct cosine sum on
 * purpose, an independent check of the filling's tables */
static double curve_mismatch(const gp_fill_result *r, const double *ph, const gp_vec2 *contour)
{
    double worst = 0.0;
    for (int i = 0; i < NP; i++) {
        double th = 2 * M_PI * i / NP, rho = 1.0;
        for (int n = 1; n < NP / 2; n++) {
            double delta = (n >= 2 && n <= 7) ? r->phases[n] : ph[n];
            rho += D[n] * cos(n * (th - r->rotation) - delta);
        }
        double x = r->centre.x + r->r0 * rho * cos(th), y = r->centre.y + r->r0 * rho * sin(th);
        worst = fmax(worst, hypot(x - contour[i].x, y - contour[i].y) / r->r0);
    }
    return worst;
}

static void rect(gp_vec2 *p, double w, double h, double ang, double cx, double cy)
{
    double c = cos(ang), s = sin(ang);
    double xs[4] = {-w / 2, w / 2, w / 2, -w / 2}, ys[4] = {-h / 2, -h / 2, h / 2, h / 2};
    for (int k = 0; k < 4; k++) {
        p[k].x = cx + c * xs[k] - s * ys[k];
        p[k].y = cy + s * xs[k] + c * ys[k];
    }
}

int main(void)
{
    double ph[NP / 2];
    phases_fixed(ph);
    gp_vec2 contour[NP];
    gp_fill_result r;
    gp_error e;

    /* 1. circle grain, unit square, reachable target: hit exactly */
    gp_vec2 sq[4];
    rect(sq, 1, 1, 0, 0.5, 0.5);
    gp_fill_workspace *ws = make(0.65, 0, 0, 0, 1);
    CHECK(ws != NULL);
    CHECK(gp_fill_cell(ws, sq, 4, ph, contour, &r, &e) == GP_OK);
    CHECK_NEAR(r.fraction, 0.65, 1e-12);
    CHECK(r.target_met);
    CHECK_NEAR(r.centre.x, 0.5, 1e-12);
    CHECK_NEAR(r.centre.y, 0.5, 1e-12);
    CHECK(gp_poly_inside_poly(contour, NP, sq, 4));
    CHECK(gp_poly_signed_area(contour, NP) > 0); /* counter-clockwise */
    gp_fill_workspace_destroy(ws);

    /* 2. circle grain, unreachable target 0.9: the largest is the Np-gon of radius 1/2 */
    ws = make(0.9, 0, 0, 0, 1);
    CHECK(gp_fill_cell(ws, sq, 4, ph, contour, &r, &e) == GP_OK);
    CHECK(!r.target_met);
    CHECK_NEAR(r.fraction, np_gon_area(0.5), 1e-8);
    CHECK_NEAR(r.max_fraction, np_gon_area(0.5), 1e-8);
    CHECK(gp_poly_inside_poly(contour, NP, sq, 4));
    gp_fill_workspace_destroy(ws);

    /* 3. regular hexagon of side 1: largest circle grain has the apothem as radius */
    gp_vec2 hex[6];
    for (int k = 0; k < 6; k++) {
        hex[k].x = cos(M_PI / 6 + k * M_PI / 3);
        hex[k].y = sin(M_PI / 6 + k * M_PI / 3);
    }
    ws = make(0.99, 0, 0, 0, 1);
    CHECK(gp_fill_cell(ws, hex, 6, ph, contour, &r, &e) == GP_OK);
    CHECK_NEAR(r.fraction, np_gon_area(sqrt(3) / 2) / (1.5 * sqrt(3)), 1e-8);
    gp_fill_workspace_destroy(ws);

    /* 4. elongated grain in a rotated 3:1 rectangle: it takes the cell's orientation and
     * fills it better than a round grain could (a disc reaches pi/12 = 0.26 here) */
    for (int deg = -60; deg <= 90; deg += 30) {
        gp_vec2 rc[4];
        double a = deg * M_PI / 180;
        rect(rc, 3, 1, a, 10, -5);
        ws = make(0.6, 0.2, 0.02, 0, 1);
        CHECK(gp_fill_cell(ws, rc, 4, ph, contour, &r, &e) == GP_OK);
        double w, ang, len;
        CHECK(gp_min_caliper(contour, NP, &w, &ang, &len, NULL) == GP_OK);
        double gap = fmod(fabs(ang - a), M_PI);
        if (gap > M_PI / 2) gap = M_PI - gap;
        CHECK(gap < 5 * M_PI / 180);
        CHECK(r.fraction > 0.40);
        CHECK(gp_poly_inside_poly(contour, NP, rc, 4));
        gp_fill_workspace_destroy(ws);
    }

    /* 5. non-convex L-shaped cell: exact containment holds, a fraction is reported */
    gp_vec2 L[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    ws = make(0.65, 0.1, 0.05, 0.02, 1);
    CHECK(gp_fill_cell(ws, L, 6, ph, contour, &r, &e) == GP_OK);
    CHECK(gp_poly_inside_poly(contour, NP, L, 6));
    CHECK(gp_poly_is_simple(contour, NP));
    CHECK(r.fraction > 0.2 && r.fraction <= 0.65 + 1e-12);
    gp_fill_workspace_destroy(ws);

    /* 6. scale invariance: a cell at 1e-6 and one offset by 1e6 fill like the unit cell */
    gp_vec2 tri[3] = {{0, 0}, {1, 0.2}, {0.3, 0.9}}, small[3], big[3];
    for (int k = 0; k < 3; k++) {
        small[k].x = tri[k].x * 1e-6;
        small[k].y = tri[k].y * 1e-6;
        big[k].x = tri[k].x + 1e6;
        big[k].y = tri[k].y - 1e6;
    }
    ws = make(0.7, 0.1, 0.05, 0.0, 1);
    gp_fill_result r1, r2, r3;
    CHECK(gp_fill_cell(ws, tri, 3, ph, contour, &r1, &e) == GP_OK);
    CHECK(gp_fill_cell(ws, small, 3, ph, contour, &r2, &e) == GP_OK);
    CHECK(gp_poly_inside_poly(contour, NP, small, 3));
    CHECK(gp_fill_cell(ws, big, 3, ph, contour, &r3, &e) == GP_OK);
    CHECK(gp_poly_inside_poly(contour, NP, big, 3));
    CHECK_NEAR(r2.fraction, r1.fraction, 1e-6);
    CHECK_NEAR(r3.fraction, r1.fraction, 1e-6);

    /* 7. determinism: the same cell twice gives the same bytes */
    gp_vec2 c2[NP];
    CHECK(gp_fill_cell(ws, tri, 3, ph, contour, &r1, &e) == GP_OK);
    CHECK(gp_fill_cell(ws, tri, 3, ph, c2, &r2, &e) == GP_OK);
    CHECK(memcmp(contour, c2, sizeof c2) == 0);
    gp_fill_workspace_destroy(ws);

    /* 8. circle grain in a flat triangle: the largest is centred on the incentre, not the
     * centroid (r_in = 2 S / perimeter = 0.457 against the centroid's clearance 1/3); an
     * Np-gon of circumradius R fits only if R cos(pi / Np) <= r_in */
    gp_vec2 flat[3] = {{0, 0}, {4, 0}, {0.5, 1}};
    gp_vec2 cen = {1.5, 1.0 / 3};
    double per = 0, S = gp_poly_area(flat, 3);
    for (int k = 0; k < 3; k++)
        per += hypot(flat[(k + 1) % 3].x - flat[k].x, flat[(k + 1) % 3].y - flat[k].y);
    double rin = 2 * S / per;
    ws = make(0.99, 0, 0, 0, 1);
    CHECK(gp_fill_cell(ws, flat, 3, ph, contour, &r, &e) == GP_OK);
    CHECK(r.fraction >= np_gon_area(rin) / S * (1 - 1e-8));
    CHECK(r.fraction <= np_gon_area(rin / cos(M_PI / NP)) / S);
    CHECK(r.fraction > 1.4 * np_gon_area(edge_clearance(flat, 3, cen)) / S);
    CHECK(gp_poly_inside_poly(contour, NP, flat, 3));
    gp_fill_workspace_destroy(ws);

    /* 9. a 48-edge polygonised ellipse (semi-axes 2, 1), solved by the large-cell LP: the
     * largest circle grain is the disc of the centre's clearance, within the strip of width 2 */
    gp_vec2 ell[48];
    for (int k = 0; k < 48; k++) {
        ell[k].x = 5 + 2 * cos(2 * M_PI * k / 48);
        ell[k].y = 3 + sin(2 * M_PI * k / 48);
    }
    double Se = gp_poly_area(ell, 48), dmin = edge_clearance(ell, 48, (gp_vec2){5, 3});
    ws = make(0.99, 0, 0, 0, 1);
    CHECK(gp_fill_cell(ws, ell, 48, ph, contour, &r, &e) == GP_OK);
    CHECK(r.fraction >= np_gon_area(dmin) / Se * (1 - 1e-8));
    CHECK(r.fraction <= np_gon_area(1 / cos(M_PI / NP)) / Se);
    CHECK(gp_poly_inside_poly(contour, NP, ell, 48));
    gp_fill_workspace_destroy(ws);

    /* 10. the result describes the grain: the curve of centre, r0 and the phases (the
     * optimised ones, the caller's above 7) turned by `rotation` is the contour. Elongated
     * cells with a rough spectrum miss F_S, so the search also turns the roughness. */
    ws = make(0.65, 0.1, 0.06, 0.03, 1);
    int turned = 0;
    for (int deg = 0; deg < 180; deg += 20) {
        gp_vec2 rc[4];
        rect(rc, 2.5, 1, deg * M_PI / 180, 1, 2);
        CHECK(gp_fill_cell(ws, rc, 4, ph, contour, &r, &e) == GP_OK);
        CHECK(curve_mismatch(&r, ph, contour) < 1e-9);
        CHECK(gp_poly_inside_poly(contour, NP, rc, 4));
        turned += r.rotation != 0.0;
    }
    CHECK(turned > 0);

    /* 11. one workspace, several cells: a cell's grain does not depend on the ones before */
    gp_vec2 first[NP];
    CHECK(gp_fill_cell(ws, tri, 3, ph, first, &r1, &e) == GP_OK);
    CHECK(gp_fill_cell(ws, ell, 48, ph, contour, &r, &e) == GP_OK);
    CHECK(gp_fill_cell(ws, L, 6, ph, contour, &r, &e) == GP_OK);
    CHECK(gp_fill_cell(ws, tri, 3, ph, contour, &r2, &e) == GP_OK);
    CHECK(memcmp(first, contour, sizeof first) == 0);
    CHECK(r1.evals == r2.evals && r1.rotation == r2.rotation);
    gp_fill_workspace_destroy(ws);

    /* 12. a cell that cannot reach F_S: a circle grain in a 3:1 rectangle turned by 0.3 rad is
     * limited by the width 1: the Np-gon whose vertex nearest the strip's normal (angle
     * 0.3 + pi/2, off a vertex by d) touches, R cos(d) = 1/2 (fraction ~pi/12). The phases
     * change nothing, so every simplex run stalls at once: 324 evaluations in all, where
     * they took 1,104 before runs stopped on a stall. */
    gp_vec2 strip[4];
    rect(strip, 3, 1, 0.3, -2, 7);
    ws = make(0.65, 0, 0, 0, 1);
    CHECK(gp_fill_cell(ws, strip, 4, ph, contour, &r, &e) == GP_OK);
    CHECK(!r.target_met);
    double step = 2 * M_PI / NP, d = fabs(remainder(0.3 + M_PI / 2, step));
    CHECK_NEAR(r.fraction, np_gon_area(0.5 / cos(d)) / 3, 1e-8);
    CHECK(gp_poly_inside_poly(contour, NP, strip, 4));
    CHECK(r.evals < 400);
    gp_fill_workspace_destroy(ws);

    /* 13. Np = 90, not a multiple of 4: the optimised modes are summed ray by ray instead of
     * by the quadrant symmetry; the contour is still the curve the result describes (direct
     * cosine sum), inside its cell, and the elongated grain fills the 3:1 cell as in 4. */
    {
        enum { N90 = 90 };
        double D90[N90 / 2] = {0}, ph90[N90 / 2];
        D90[0] = 1.0, D90[2] = 0.2, D90[3] = 0.02, D90[8] = 0.01;
        for (int n = 0; n < N90 / 2; n++) ph90[n] = fmod(n * 2.39996322972865332, 2 * M_PI) - M_PI;
        gp_fill_params p;
        gp_fill_params_defaults(&p);
        p.solid_fraction = 0.6;
        p.D = D90;
        p.nmodes = N90 / 2;
        p.contour_points = N90;
        gp_fill_workspace *w90 = gp_fill_workspace_create(&p, &e);
        CHECK(w90 != NULL);
        gp_vec2 rc[4], c90[N90];
        rect(rc, 3, 1, 0.5, 3, 1);
        CHECK(gp_fill_cell(w90, rc, 4, ph90, c90, &r, &e) == GP_OK);
        double worst = 0.0;
        for (int i = 0; i < N90; i++) {
            double th = 2 * M_PI * i / N90, rho = 1.0;
            for (int n = 1; n < N90 / 2; n++)
                rho += D90[n] * cos(n * (th - r.rotation) - ((n >= 2 && n <= 7) ? r.phases[n] : ph90[n]));
            worst = fmax(worst, hypot(r.centre.x + r.r0 * rho * cos(th) - c90[i].x,
                                      r.centre.y + r.r0 * rho * sin(th) - c90[i].y) / r.r0);
        }
        CHECK(worst < 1e-9);
        CHECK(gp_poly_inside_poly(c90, N90, rc, 4));
        CHECK(r.fraction > 0.40);
        gp_fill_workspace_destroy(w90);
    }

    /* 14. bad input: errors, no crash */
    ws = make(0.65, 0.1, 0.05, 0.02, 1);
    gp_vec2 line[3] = {{0, 0}, {1, 1}, {2, 2}};
    CHECK(gp_fill_cell(ws, line, 3, ph, contour, &r, &e) == GP_ERR_DEGENERATE);
    CHECK(gp_fill_cell(ws, sq, 2, ph, contour, &r, &e) == GP_ERR_INVALID);
    gp_fill_workspace_destroy(ws);
    CHECK(make(1.5, 0, 0, 0, 1) == NULL);
    CHECK(make(NAN, 0, 0, 0, 1) == NULL);
    CHECK(make(0.5, -0.1, 0, 0, 1) == NULL);
    /* a spectrum that is never star-shaped is reported, not returned as a broken grain */
    ws = make(0.5, 0.9, 0.9, 0.0, 1);
    CHECK(gp_fill_cell(ws, sq, 4, ph, contour, &r, &e) == GP_ERR_NOT_STAR);
    gp_fill_workspace_destroy(ws);

    return gp_test_summary();
}
