/* gp_fourier.c -- see gp_fourier.h. */
#include "gp_fourier.h"

#include <fftw3.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define GP_PI 3.14159265358979323846

struct gp_fourier {
    size_t np;       /* samples */
    size_t npf;      /* fine samples for the star check: 4 np */
    double *r;       /* np, fftw_malloc */
    fftw_complex *c; /* np/2 + 1 */
    double *rf;      /* npf */
    fftw_complex *cf;/* npf/2 + 1 */
    double *delta;   /* max_modes, scratch for contour_random with delta_out == NULL */
    double *ray;     /* np, scratch radii for analyse_polygon */
    fftw_plan c2r, r2c, c2r_fine;
};

static pthread_once_t planner_once = PTHREAD_ONCE_INIT;

static void make_planner_thread_safe(void)
{
    fftw_make_planner_thread_safe();
}

size_t gp_fourier_max_modes(size_t np)
{
    return (np + 1) / 2;
}

size_t gp_fourier_np(const gp_fourier *f)
{
    return f ? f->np : 0;
}

gp_status gp_fourier_spectrum(double D2, double D3, double D8, double alpha, double beta,
                              size_t nmodes, double *D, gp_error *err)
{
    if (!D)
        return gp_error_set(err, GP_ERR_INVALID, "spectrum: D is NULL");
    if (nmodes < 1)
        return gp_error_set(err, GP_ERR_INVALID, "spectrum: nmodes must be >= 1");
    if (!isfinite(D2) || !isfinite(D3) || !isfinite(D8) || !isfinite(alpha) || !isfinite(beta))
        return gp_error_set(err, GP_ERR_INVALID,
                            "spectrum: D2, D3, D8, alpha, beta must be finite numbers");
    if (D2 < 0 || D3 < 0 || D8 < 0)
        return gp_error_set(err, GP_ERR_INVALID,
                            "spectrum: D2 = %g, D3 = %g, D8 = %g must be >= 0", D2, D3, D8);
    for (size_t n = 0; n < nmodes; n++) {
        double v;
        if (n == 0)
            v = 1.0;
        else if (n == 1)
            v = 0.0;
        else if (n == 2)
            v = D2;
        else if (n == 3)
            v = D3;
        else if (n < 8)
            v = D3 * pow((double)n / 3.0, alpha);
        else if (n == 8)
            v = D8;
        else
            v = D8 * pow((double)n / 8.0, beta);
        if (!isfinite(v) || v < 0)
            return gp_error_set(err, GP_ERR_INVALID,
                                "spectrum: D_%zu = %g is not a finite amplitude (alpha = %g, "
                                "beta = %g)", n, v, alpha, beta);
        D[n] = v;
    }
    return GP_OK;
}

gp_status gp_fourier_spectrum_check(const double *D, size_t nmodes, gp_error *err)
{
    if (!D)
        return gp_error_set(err, GP_ERR_INVALID, "spectrum: D is NULL");
    if (nmodes < 1)
        return gp_error_set(err, GP_ERR_INVALID, "spectrum: needs at least D0");
    if (!(fabs(D[0] - 1.0) <= 1e-9))
        return gp_error_set(err, GP_ERR_INVALID,
                            "spectrum: D0 = %g must be 1 (normalised amplitudes)", D[0]);
    for (size_t n = 1; n < nmodes; n++) {
        if (!isfinite(D[n]) || D[n] < 0)
            return gp_error_set(err, GP_ERR_INVALID,
                                "spectrum: D_%zu = %g must be finite and >= 0", n, D[n]);
    }
    return GP_OK;
}

gp_fourier *gp_fourier_create(size_t np, gp_error *err)
{
    if (np < GP_FOURIER_NP_MIN) {
        gp_error_set(err, GP_ERR_INVALID, "fourier: np = %zu contour points, must be >= %d",
                     np, GP_FOURIER_NP_MIN);
        return NULL;
    }
    if (np > (size_t)1 << 24) {
        gp_error_set(err, GP_ERR_INVALID, "fourier: np = %zu contour points is too many", np);
        return NULL;
    }
    pthread_once(&planner_once, make_planner_thread_safe);

    gp_fourier *f = calloc(1, sizeof *f);
    if (!f) {
        gp_error_set(err, GP_ERR_NOMEM, "fourier: out of memory");
        return NULL;
    }
    f->np = np;
    f->npf = 4 * np;
    f->r = fftw_alloc_real(np);
    f->c = fftw_alloc_complex(np / 2 + 1);
    f->rf = fftw_alloc_real(f->npf);
    f->cf = fftw_alloc_complex(f->npf / 2 + 1);
    f->delta = malloc(gp_fourier_max_modes(np) * sizeof *f->delta);
    f->ray = malloc(np * sizeof *f->ray);
    if (!f->r || !f->c || !f->rf || !f->cf || !f->delta || !f->ray) {
        gp_fourier_destroy(f);
        gp_error_set(err, GP_ERR_NOMEM, "fourier: out of memory for np = %zu", np);
        return NULL;
    }
    /* FFTW_ESTIMATE: no timing measurements, so the plan (and the bytes it produces) does not
     * depend on machine load. */
    f->c2r = fftw_plan_dft_c2r_1d((int)np, f->c, f->r, FFTW_ESTIMATE);
    f->r2c = fftw_plan_dft_r2c_1d((int)np, f->r, f->c, FFTW_ESTIMATE);
    f->c2r_fine = fftw_plan_dft_c2r_1d((int)f->npf, f->cf, f->rf, FFTW_ESTIMATE);
    if (!f->c2r || !f->r2c || !f->c2r_fine) {
        gp_fourier_destroy(f);
        gp_error_set(err, GP_ERR_INTERNAL, "fourier: FFTW planning failed for np = %zu", np);
        return NULL;
    }
    return f;
}

void gp_fourier_destroy(gp_fourier *f)
{
    if (!f)
        return;
    if (f->c2r)
        fftw_destroy_plan(f->c2r);
    if (f->r2c)
        fftw_destroy_plan(f->r2c);
    if (f->c2r_fine)
        fftw_destroy_plan(f->c2r_fine);
    fftw_free(f->r);
    fftw_free(f->c);
    fftw_free(f->rf);
    fftw_free(f->cf);
    free(f->delta);
    free(f->ray);
    free(f);
}

gp_status gp_fourier_random_phases(size_t nmodes, gp_fourier_u01_fn u01, void *state,
                                   double *delta, gp_error *err)
{
    if (!u01 || !delta)
        return gp_error_set(err, GP_ERR_INVALID, "random phases: NULL generator or output");
    if (nmodes < 1)
        return gp_error_set(err, GP_ERR_INVALID, "random phases: nmodes must be >= 1");
    delta[0] = 0.0;
    for (size_t n = 1; n < nmodes; n++) {
        double u = u01(state);
        if (!(u >= 0.0 && u <= 1.0))
            return gp_error_set(err, GP_ERR_INVALID,
                                "random phases: generator returned %g, not in [0, 1]", u);
        delta[n] = -GP_PI + 2.0 * GP_PI * u;
    }
    return GP_OK;
}

/* Checks the common arguments of the synthesis calls. */
static gp_status check_synthesis(const gp_fourier *f, double r0, const double *D,
                                 const double *delta, size_t nmodes, gp_error *err)
{
    if (!f)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: NULL plan object");
    if (!isfinite(r0) || r0 <= 0)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: r0 = %g must be finite and > 0", r0);
    if (nmodes > gp_fourier_max_modes(f->np))
        return gp_error_set(err, GP_ERR_INVALID,
                            "fourier: %zu modes cannot be represented on %zu points (at most "
                            "%zu: modes n < Np/2)", nmodes, f->np, gp_fourier_max_modes(f->np));
    gp_status s = gp_fourier_spectrum_check(D, nmodes, err);
    if (s != GP_OK)
        return s;
    if (!delta)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: phases array is NULL");
    for (size_t n = 1; n < nmodes; n++) {
        if (!isfinite(delta[n]))
            return gp_error_set(err, GP_ERR_INVALID, "fourier: phase delta_%zu = %g is not finite",
                                n, delta[n]);
    }
    return GP_OK;
}

/* Half-spectrum of r(theta): X_0 = r0, X_n = (r0 D_n / 2) e^{-i delta_n}, zero above nmodes.
 * c2r then gives sum_k X_k e^{+i k theta_j} over the Hermitian extension = r(theta_j). */
static void fill_half_spectrum(fftw_complex *c, size_t nc, double r0, const double *D,
                               const double *delta, size_t nmodes)
{
    memset(c, 0, nc * sizeof *c);
    c[0][0] = r0;
    for (size_t n = 1; n < nmodes && n < nc; n++) {
        double a = 0.5 * r0 * D[n];
        c[n][0] = a * cos(delta[n]);
        c[n][1] = -a * sin(delta[n]);
    }
}

/* The smallest of a[0 .. n) (n >= 1) and, in *at, the first index where it is. */
static double min_at(const double *a, size_t n, size_t *at)
{
    double m = a[0];
    *at = 0;
    for (size_t i = 1; i < n; i++) {
        if (a[i] < m) {
            m = a[i];
            *at = i;
        }
    }
    return m;
}

/* Star check (see header). Runs c2r into f->r; returns GP_OK if r > 0 on the continuous curve. */
static gp_status synthesise(gp_fourier *f, double r0, const double *D, const double *delta,
                            size_t nmodes, gp_error *err)
{
    size_t nc = f->np / 2 + 1;
    fill_half_spectrum(f->c, nc, r0, D, delta, nmodes);
    fftw_execute(f->c2r);

    size_t imin;
    double rmin = min_at(f->r, f->np, &imin);
    if (!(rmin > 0))
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "fourier: spectrum is not star-shaped with these phases: r = %.3g r0 "
                            "at theta = %.4f rad", rmin / r0, 2.0 * GP_PI * (double)imin /
                                                               (double)f->np);
    double sum = 0, sum2 = 0;
    for (size_t n = 1; n < nmodes; n++) {
        sum += D[n];
        sum2 += (double)n * (double)n * D[n];
    }
    if (sum < 1.0 - 1e-9)
        return GP_OK; /* r >= r0 (1 - sum D_n) > 0 */

    size_t ncf = f->npf / 2 + 1;
    fill_half_spectrum(f->cf, ncf, r0, D, delta, nmodes);
    fftw_execute(f->c2r_fine);
    size_t jmin;
    double fmin = min_at(f->rf, f->npf, &jmin);
    double h = 2.0 * GP_PI / (double)f->npf;
    /* the true minimum is within h/2 of a fine sample, where r' = 0: Taylor bound */
    double bound = fmin - 0.5 * r0 * sum2 * (0.5 * h) * (0.5 * h) - 1e-12 * r0 * (1.0 + sum);
    if (!(bound > 0))
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "fourier: spectrum is not star-shaped with these phases: r falls to "
                            "%.3g r0 (lower bound %.3g r0) near theta = %.4f rad",
                            fmin / r0, bound / r0, h * (double)jmin);
    return GP_OK;
}

gp_status gp_fourier_radii(gp_fourier *f, double r0, const double *D, const double *delta,
                           size_t nmodes, double *r, gp_error *err)
{
    gp_status s = check_synthesis(f, r0, D, delta, nmodes, err);
    if (s != GP_OK)
        return s;
    if (!r)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: output radii array is NULL");
    s = synthesise(f, r0, D, delta, nmodes, err);
    if (s != GP_OK)
        return s;
    memcpy(r, f->r, f->np * sizeof *r);
    return GP_OK;
}

gp_status gp_fourier_contour(gp_fourier *f, gp_vec2 center, double r0, const double *D,
                             const double *delta, size_t nmodes, gp_vec2 *pts, double *r,
                             gp_error *err)
{
    gp_status s = check_synthesis(f, r0, D, delta, nmodes, err);
    if (s != GP_OK)
        return s;
    if (!pts)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: output points array is NULL");
    if (!isfinite(center.x) || !isfinite(center.y))
        return gp_error_set(err, GP_ERR_INVALID, "fourier: centre is not finite");
    s = synthesise(f, r0, D, delta, nmodes, err);
    if (s != GP_OK)
        return s;
    double step = 2.0 * GP_PI / (double)f->np;
    for (size_t i = 0; i < f->np; i++) {
        double th = step * (double)i;
        double ri = f->r[i];
        pts[i].x = center.x + ri * cos(th);
        pts[i].y = center.y + ri * sin(th);
        if (r)
            r[i] = ri;
    }
    return GP_OK;
}

gp_status gp_fourier_contour_random(gp_fourier *f, gp_vec2 center, double r0, const double *D,
                                    size_t nmodes, gp_fourier_u01_fn u01, void *state,
                                    double *delta_out, gp_vec2 *pts, double *r, gp_error *err)
{
    if (!f)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: NULL plan object");
    if (nmodes > gp_fourier_max_modes(f->np))
        return gp_error_set(err, GP_ERR_INVALID,
                            "fourier: %zu modes cannot be represented on %zu points (at most %zu)",
                            nmodes, f->np, gp_fourier_max_modes(f->np));
    double *delta = delta_out ? delta_out : f->delta;
    gp_status s = gp_fourier_random_phases(nmodes, u01, state, delta, err);
    if (s != GP_OK)
        return s;
    return gp_fourier_contour(f, center, r0, D, delta, nmodes, pts, r, err);
}

gp_status gp_fourier_analyse(gp_fourier *f, const double *r, size_t nmodes, double *r0,
                             double *D, double *delta, gp_error *err)
{
    if (!f || !r || !r0)
        return gp_error_set(err, GP_ERR_INVALID, "fourier analysis: NULL argument");
    if (nmodes < 1 || nmodes > gp_fourier_max_modes(f->np))
        return gp_error_set(err, GP_ERR_INVALID,
                            "fourier analysis: nmodes = %zu must be in [1, %zu] for %zu points",
                            nmodes, gp_fourier_max_modes(f->np), f->np);
    for (size_t i = 0; i < f->np; i++) {
        if (!isfinite(r[i]))
            return gp_error_set(err, GP_ERR_INVALID, "fourier analysis: r[%zu] is not finite", i);
    }
    memcpy(f->r, r, f->np * sizeof *r);
    fftw_execute(f->r2c);
    double N = (double)f->np;
    double m = f->c[0][0] / N;
    if (!(m > 0))
        return gp_error_set(err, GP_ERR_INVALID,
                            "fourier analysis: mean radius %g is not positive", m);
    *r0 = m;
    if (D)
        D[0] = 1.0;
    if (delta)
        delta[0] = 0.0;
    for (size_t n = 1; n < nmodes; n++) {
        double re = f->c[n][0], im = f->c[n][1];
        if (D)
            D[n] = 2.0 * hypot(re, im) / (N * m);
        if (delta)
            delta[n] = atan2(-im, re);
    }
    return GP_OK;
}

gp_status gp_fourier_polygon_radii(const gp_vec2 *poly, size_t n, gp_vec2 center, size_t np,
                                   double *r, int *star, gp_error *err)
{
    if (!poly || !r)
        return gp_error_set(err, GP_ERR_INVALID, "polygon radii: NULL argument");
    if (n < 3)
        return gp_error_set(err, GP_ERR_INVALID, "polygon radii: n = %zu vertices, need >= 3", n);
    if (np < 1)
        return gp_error_set(err, GP_ERR_INVALID, "polygon radii: np must be >= 1");
    if (!isfinite(center.x) || !isfinite(center.y))
        return gp_error_set(err, GP_ERR_INVALID, "polygon radii: centre is not finite");
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(poly[k].x) || !isfinite(poly[k].y))
            return gp_error_set(err, GP_ERR_INVALID, "polygon radii: vertex %zu is not finite", k);
    }
    int all_star = 1;
    size_t first_bad = 0;
    double step = 2.0 * GP_PI / (double)np;
    for (size_t i = 0; i < np; i++) {
        double th = step * (double)i;
        double dx = cos(th), dy = sin(th);
        /* side of each vertex w.r.t. the ray's line: c = d x (v - centre); an edge crosses the
         * line when (c_a > 0) != (c_b > 0) (half-open rule: a vertex on the line counts once) */
        size_t count = 0;
        double tmin = INFINITY;
        int on_boundary = 0;
        gp_vec2 a = poly[n - 1];
        double ca = dx * (a.y - center.y) - dy * (a.x - center.x);
        for (size_t k = 0; k < n; k++) {
            gp_vec2 b = poly[k];
            double cb = dx * (b.y - center.y) - dy * (b.x - center.x);
            if ((ca > 0) != (cb > 0)) {
                double s = ca / (ca - cb);
                double px = a.x + s * (b.x - a.x) - center.x;
                double py = a.y + s * (b.y - a.y) - center.y;
                double t = px * dx + py * dy;
                if (t > 0) {
                    count++;
                    if (t < tmin)
                        tmin = t;
                } else if (t == 0) {
                    on_boundary = 1;
                }
            }
            a = b;
            ca = cb;
        }
        if (on_boundary || count % 2 == 0)
            return gp_error_set(err, GP_ERR_INVALID,
                                "polygon radii: centre (%g, %g) is not strictly inside the polygon",
                                center.x, center.y);
        if (count > 1 && all_star) {
            all_star = 0;
            first_bad = i;
        }
        r[i] = tmin;
    }
    if (star) {
        *star = all_star;
    } else if (!all_star) {
        return gp_error_set(err, GP_ERR_NOT_STAR,
                            "polygon radii: the polygon is not star-shaped from (%g, %g): the ray "
                            "at theta = %.4f rad crosses its boundary more than once",
                            center.x, center.y, step * (double)first_bad);
    }
    return GP_OK;
}

gp_status gp_fourier_analyse_polygon(gp_fourier *f, const gp_vec2 *poly, size_t n,
                                     gp_vec2 center, size_t nmodes, double *r0, double *D,
                                     double *delta, int *star, gp_error *err)
{
    if (!f)
        return gp_error_set(err, GP_ERR_INVALID, "fourier: NULL plan object");
    gp_status s = gp_fourier_polygon_radii(poly, n, center, f->np, f->ray, star, err);
    if (s != GP_OK)
        return s;
    return gp_fourier_analyse(f, f->ray, nmodes, r0, D, delta, err);
}
