/* gp_sieve.c -- see gp_sieve.h. */
#include "gp_sieve.h"

#include <math.h>
#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

gp_status gp_sieve_validate(const double *d, const double *pw, size_t n, gp_error *err)
{
    if (!d || !pw || n < 2)
        return gp_error_set(err, GP_ERR_INVALID, "sieve: need at least 2 rows");
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(d[k]) || d[k] <= 0)
            return gp_error_set(err, GP_ERR_INVALID, "sieve[%zu]: diameter must be > 0", k);
        if (!isfinite(pw[k]) || pw[k] < 0 || pw[k] > 100)
            return gp_error_set(err, GP_ERR_INVALID, "sieve[%zu]: percent passing must be in [0, 100]", k);
        if (k > 0 && !(d[k] > d[k - 1]))
            return gp_error_set(err, GP_ERR_INVALID, "sieve[%zu]: diameters must increase", k);
        if (k > 0 && pw[k] < pw[k - 1])
            return gp_error_set(err, GP_ERR_INVALID, "sieve[%zu]: percent passing must not decrease", k);
    }
    if (fabs(pw[0]) > 1e-9)
        return gp_error_set(err, GP_ERR_INVALID,
                            "sieve[0]: the first row must pass 0 %% (it gives the smallest grain)");
    if (fabs(pw[n - 1] - 100) > 1e-9)
        return gp_error_set(err, GP_ERR_INVALID,
                            "sieve[%zu]: the last row must pass 100 %% (it gives the largest grain)", n - 1);
    return GP_OK;
}

/* mean of d^3 in bin [a, b] under a rule */
static double bin_cube(double a, double b, gp_sieve_rule rule)
{
    if (rule == GP_SIEVE_MIDBIN) {
        double m = 0.5 * (a + b);
        return m * m * m;
    }
    /* E[d^3] for d uniform in [a, b] = (b^4 - a^4) / (4 (b - a)) */
    return (a + b) * (a * a + b * b) / 4.0;
}

gp_status gp_sieve_weight_to_number(const double *d, const double *pw, size_t n,
                                    gp_sieve_rule rule, double *pn, gp_error *err)
{
    gp_status st = gp_sieve_validate(d, pw, n, err);
    if (st)
        return st;
    double total = 0;
    for (size_t k = 1; k < n; k++)
        total += (pw[k] - pw[k - 1]) / bin_cube(d[k - 1], d[k], rule);
    double acc = 0;
    pn[0] = 0;
    for (size_t k = 1; k < n; k++) {
        acc += (pw[k] - pw[k - 1]) / bin_cube(d[k - 1], d[k], rule);
        pn[k] = 100.0 * acc / total;
    }
    pn[n - 1] = 100.0;
    return GP_OK;
}

double gp_sieve_expected_count(const double *d, const double *pw, size_t n, double solid_volume)
{
    double c = 0;
    for (size_t k = 1; k < n; k++)
        c += (pw[k] - pw[k - 1]) / 100.0 * solid_volume
             / (M_PI / 6.0 * bin_cube(d[k - 1], d[k], GP_SIEVE_UNIFORM));
    return c;
}

/* sum over j of (a + u_j^g (b - a))^3 */
static double warped_cube_sum(const double *u, size_t m, double a, double b, double g)
{
    double s = 0;
    for (size_t j = 0; j < m; j++) {
        double x = a + pow(u[j], g) * (b - a);
        s += x * x * x;
    }
    return s;
}

typedef struct bin_quota {
    size_t k;       /* upper row of the bin */
    double real;    /* real-valued number of grains */
    size_t count;
} bin_quota;

static int cmp_remainder(const void *pa, const void *pb)
{
    const bin_quota *a = pa, *b = pb;
    double ra = a->real - floor(a->real), rb = b->real - floor(b->real);
    if (ra > rb) return -1;
    if (ra < rb) return 1;
    return a->k < b->k ? -1 : (a->k > b->k);
}

gp_status gp_sieve_draw(const double *d, const double *pw, size_t n, double solid_volume,
                        size_t max_count, gp_rng *rng, double **diam, size_t *count,
                        gp_error *err)
{
    *diam = NULL;
    *count = 0;
    gp_status st = gp_sieve_validate(d, pw, n, err);
    if (st)
        return st;
    if (!isfinite(solid_volume) || solid_volume <= 0)
        return gp_error_set(err, GP_ERR_INVALID, "sieve: solid volume must be > 0");
    if (!rng)
        return gp_error_set(err, GP_ERR_INVALID, "sieve: rng is NULL");
    double expected = gp_sieve_expected_count(d, pw, n, solid_volume);
    if (!(expected <= (double)max_count))
        return gp_error_set(err, GP_ERR_INVALID,
                            "sieve: the volume needs about %.0f grains, more than the limit %zu",
                            expected, max_count);

    bin_quota *q = calloc(n, sizeof *q);
    if (!q)
        return gp_error_set(err, GP_ERR_NOMEM, "sieve: out of memory");
    size_t nb = 0, total = 0;
    double real_total = 0;
    for (size_t k = 1; k < n; k++) {
        double w = (pw[k] - pw[k - 1]) / 100.0;
        if (w <= 0)
            continue;
        q[nb].k = k;
        q[nb].real = w * solid_volume / (M_PI / 6.0 * bin_cube(d[k - 1], d[k], GP_SIEVE_UNIFORM));
        q[nb].count = (size_t)floor(q[nb].real);
        total += q[nb].count;
        real_total += q[nb].real;
        nb++;
    }
    /* largest remainder: the total is the nearest integer to the real total (at least 1) */
    size_t want = (size_t)floor(real_total + 0.5);
    if (want < 1)
        want = 1;
    qsort(q, nb, sizeof *q, cmp_remainder);
    for (size_t b = 0; total < want && b < nb; b++, total++)
        q[b].count++;
    /* back to sieve order */
    for (size_t a = 1; a < nb; a++)
        for (size_t b = a; b > 0 && q[b - 1].k > q[b].k; b--) {
            bin_quota t = q[b]; q[b] = q[b - 1]; q[b - 1] = t;
        }

    double *out = malloc((total ? total : 1) * sizeof *out);
    double *u = malloc((total ? total : 1) * sizeof *u);
    if (!out || !u) {
        free(q); free(out); free(u);
        return gp_error_set(err, GP_ERR_NOMEM, "sieve: out of memory (%zu grains)", total);
    }
    /* volume that bins without grains could not take is shared by the others in proportion */
    double w_used = 0;
    for (size_t b = 0; b < nb; b++)
        if (q[b].count)
            w_used += (pw[q[b].k] - pw[q[b].k - 1]) / 100.0;
    size_t pos = 0;
    for (size_t b = 0; b < nb; b++) {
        size_t m = q[b].count, k = q[b].k;
        if (!m)
            continue;
        double a = d[k - 1], c = d[k];
        for (size_t j = 0; j < m; j++)
            u[j] = ((double)j + gp_rng_uniform(rng)) / (double)m;
        for (size_t j = 0; j < m; j++)
            if (u[j] <= 0) u[j] = 0.5 / (double)m / 1024.0;
        /* warp u -> u^g so that the bin holds its share of the volume: sum d^3 = 6 V_k / pi */
        double w = (pw[k] - pw[k - 1]) / 100.0 / w_used;
        double target = 6.0 / M_PI * w * solid_volume;
        double lo = -30, hi = 30; /* ln g; the sum decreases with g */
        if (target >= warped_cube_sum(u, m, a, c, exp(lo)))
            hi = lo;
        else if (target <= warped_cube_sum(u, m, a, c, exp(hi)))
            lo = hi;
        else
            for (int it = 0; it < 200 && hi - lo > 1e-14; it++) {
                double mid = 0.5 * (lo + hi);
                if (warped_cube_sum(u, m, a, c, exp(mid)) > target)
                    lo = mid;
                else
                    hi = mid;
            }
        double g = exp(0.5 * (lo + hi));
        for (size_t j = 0; j < m; j++) {
            double x = a + pow(u[j], g) * (c - a);
            if (x >= c) x = nextafter(c, a);
            if (x < a) x = a;
            out[pos++] = x;
        }
    }
    free(u);
    free(q);
    *diam = out;
    *count = pos;
    return GP_OK;
}

void gp_sieve_passing(const double *diam, size_t count, const double *d, size_t n,
                      double *pw_out, double *pn_out)
{
    double vt = 0;
    for (size_t i = 0; i < count; i++)
        vt += diam[i] * diam[i] * diam[i];
    for (size_t k = 0; k < n; k++) {
        double v = 0;
        size_t c = 0;
        for (size_t i = 0; i < count; i++)
            if (diam[i] < d[k]) {
                v += diam[i] * diam[i] * diam[i];
                c++;
            }
        if (pw_out) pw_out[k] = vt > 0 ? 100.0 * v / vt : 0;
        if (pn_out) pn_out[k] = count ? 100.0 * (double)c / (double)count : 0;
    }
}
