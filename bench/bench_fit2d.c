/* bench_fit2d.c -- the 2D specimen's cells against their laws by default, speed next to error
 * (issue #33: Neper's accuracy by default at >= 30x its speed).
 *
 * Each row is one case (container, N, lognormal COV of the cell areas, anisotropy of their
 * orientations) built by gp_specimen2d_build with the API's defaults (AD objective at its
 * default threshold, imc.max_steps = gp_spec2d_default_max_steps(N), outputs grains and cells)
 * for three seeds; the grains are filled, so the seconds are the core's end to end.
 * What the cells achieved is measured here from the returned polygons, not read from the
 * specimen's fit report: areas by the shoelace formula, orientations as the direction of the
 * minimum caliper of the seed's part (Mollon & Zhao Fig. 1a), each against its law's CDF.
 * Columns: IMC steps (mean over the seeds), the IMC's error at its end (the largest), seconds end to end (the slowest seed), the cell-area
 * KS distance (largest of the three) and its 5 % critical value 1.36 / sqrt(N), the COV error
 * (sample COV against the target, the three seeds' range), the orientation KS over its
 * critical value (largest), and the IMC's stop reasons. Beside the four cases Neper was run on
 * (issue #33, same machine class: a tessellation fitted to a size law, cells only), its KS and
 * seconds.
 *
 * Usage: bench_fit2d [quick|grid|full] [THRESHOLD] [THREADS]
 *   quick: the four Neper cases and COV 0.05; grid (default): N = 500 and 2,000 on the square x
 *   COV 0.1 .. 1.2 x anisotropy 1, 0.3, 0.1, the L-shape with a hole and the circle at N = 500
 *   and 2,000, and N = 200, 5,000, 20,000 at COV 0.2, 0.8, 1.2; full: every container at every
 *   N. THRESHOLD (> 0) replaces the default AD threshold, THREADS the job's threads (1). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_geom.h"
#include "gp_imc.h"
#include "gp_law.h"
#include "gp_specimen2d.h"

enum { SQUARE, LHOLE, CIRCLE };
static const char *CONTAINER_NAME[] = {"square", "L + hole", "circle"};

static gp_vec2 SQ[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
static gp_vec2 LSH[6] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
static gp_vec2 HOLE[4] = {{0.3, 0.3}, {0.3, 0.6}, {0.6, 0.6}, {0.6, 0.3}};
static gp_ring HOLES[1] = {{HOLE, 4}};

typedef struct fit_case {
    int container;
    size_t n;
    double cov, aniso;
} fit_case;

/* Neper's measured figures (issue #33): KS range and seconds at the same N and COV, isotropic,
 * on the square */
typedef struct peer {
    size_t n;
    double cov, ks, secs_lo, secs_hi;
} peer;
static const peer NEPER[] = {
    {500, 0.2, 0.021, 27, 45}, {500, 0.8, 0.012, 27, 45}, {2000, 0.2, 0.015, 0, 0}, {2000, 0.8, 0.005, 0, 0}};

typedef struct measured {
    double ks, cov_err, ks_orient;
} measured;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double ks_of(double *u, size_t n)
{
    qsort(u, n, sizeof *u, cmp_double);
    double d = 0.0;
    for (size_t i = 0; i < n; i++) d = fmax(d, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
    return d;
}

static double ring_area(const gp_ring *r)
{
    double a = 0.0;
    for (size_t i = 0; i < r->n; i++) {
        const gp_vec2 *p = &r->pts[i], *q = &r->pts[(i + 1) % r->n];
        a += p->x * q->y - q->x * p->y;
    }
    return 0.5 * fabs(a);
}

static double cell_area(const gp_cell2d *c)
{
    double a = 0.0;
    for (size_t k = 0; k < c->npolygons; k++) a += ring_area(&c->polygons[k]);
    return a;
}

/* the part that holds the seed (the cell's orientation is its seed's part's, gp_voronoi.h) */
static const gp_ring *seed_part(const gp_cell2d *c)
{
    for (size_t k = 0; k < c->npolygons; k++) {
        const gp_ring *r = &c->polygons[k];
        int in = 0;
        for (size_t i = 0, j = r->n - 1; i < r->n; j = i++) {
            const gp_vec2 *a = &r->pts[i], *b = &r->pts[j];
            if ((a->y > c->seed.y) != (b->y > c->seed.y) &&
                c->seed.x < (b->x - a->x) * (c->seed.y - a->y) / (b->y - a->y) + a->x)
                in = !in;
        }
        if (in) return r;
    }
    return &c->polygons[0];
}

static int measure(const gp_specimen2d *s, double cov, double aniso, measured *m)
{
    size_t n = s->ncells;
    double *area = malloc(n * sizeof *area), *u = malloc(n * sizeof *u), *w = malloc(n * sizeof *w);
    double total = 0.0;
    int ok = area && u && w;
    for (size_t i = 0; ok && i < n; i++) {
        area[i] = cell_area(&s->cells[i]);
        total += area[i];
        const gp_ring *r = seed_part(&s->cells[i]);
        double width, ang, len;
        ok = gp_min_caliper(r->pts, r->n, &width, &ang, &len, NULL) == GP_OK;
        w[i] = gp_orient_cdf(0.0, aniso, ang * 180.0 / M_PI);
    }
    gp_law *law = ok ? gp_law_create(GP_LAW_LOGNORMAL, total / n, cov, NULL) : NULL;
    if (law) {
        double mu = total / n, s2 = 0.0;
        for (size_t i = 0; i < n; i++) {
            s2 += (area[i] - mu) * (area[i] - mu);
            u[i] = gp_law_cdf(law, area[i]);
        }
        m->ks = ks_of(u, n);
        m->ks_orient = ks_of(w, n);
        m->cov_err = n > 1 ? 100.0 * (sqrt(s2 / (n - 1)) / mu / cov - 1.0) : 0.0;
    }
    gp_law_destroy(law);
    free(area);
    free(u);
    free(w);
    return law != NULL;
}

static void setup(const fit_case *c, uint64_t seed, double threshold, int threads, gp_spec2d *s)
{
    gp_spec2d_defaults(s);
    s->seed = seed;
    if (c->container == CIRCLE) {
        s->container = GP_CONTAINER_CIRCLE;
        s->circle_center = (gp_vec2){0.5, 0.5};
        s->circle_radius = 0.5;
    } else {
        s->outer = c->container == SQUARE ? (gp_ring){SQ, 4} : (gp_ring){LSH, 6};
        s->holes = c->container == LHOLE ? HOLES : NULL;
        s->nholes = c->container == LHOLE ? 1 : 0;
    }
    s->particles = c->n;
    s->cov = c->cov;
    s->anisotropy = c->aniso;
    if (threshold > 0) s->imc_threshold = threshold;
    s->imc_max_steps = gp_spec2d_default_max_steps(c->n);
    s->imc_max_steps_default = 1;
    s->outputs = GP_OUT2_GRAINS | GP_OUT2_CELLS;
    s->threads = threads;
}

static const peer *neper_for(const fit_case *c)
{
    if (c->container != SQUARE || c->aniso != 1.0) return NULL;
    for (size_t i = 0; i < sizeof NEPER / sizeof *NEPER; i++)
        if (NEPER[i].n == c->n && NEPER[i].cov == c->cov) return &NEPER[i];
    return NULL;
}

static void run_case(const fit_case *c, double threshold, int threads)
{
    double steps = 0.0, secs = 0.0, ks = 0.0, ko = 0.0, clo = INFINITY, chi = -INFINITY, err = 0.0;
    char stops[64] = "";
    for (uint64_t seed = 1; seed <= 3; seed++) {
        gp_spec2d spec;
        setup(c, seed, threshold, threads, &spec);
        gp_specimen2d *s = NULL;
        gp_error e;
        measured m;
        if (gp_specimen2d_build(&spec, NULL, NULL, NULL, &s, &e) != GP_OK || !measure(s, c->cov, c->aniso, &m)) {
            printf("| %-8s | %6zu | %4.2f | %4.2f | failed (seed %d): %s |\n", CONTAINER_NAME[c->container], c->n,
                   c->cov, c->aniso, (int)seed, s ? "measure" : e.message);
            gp_specimen2d_destroy(s);
            return;
        }
        steps += s->imc_steps / 3.0;
        err = fmax(err, s->imc_error);
        secs = fmax(secs, s->t_total);
        ks = fmax(ks, m.ks);
        ko = fmax(ko, m.ks_orient);
        clo = fmin(clo, m.cov_err);
        chi = fmax(chi, m.cov_err);
        size_t used = strlen(stops);
        snprintf(stops + used, sizeof stops - used, "%s%.3s", seed > 1 ? "," : "", s->imc_stop_reason);
        gp_specimen2d_destroy(s);
    }
    double crit = 1.36 / sqrt((double)c->n);
    const peer *p = neper_for(c);
    char neper[48] = "";
    if (p && p->secs_hi > 0)
        snprintf(neper, sizeof neper, "%.3f, %.0f-%.0f s", p->ks, p->secs_lo, p->secs_hi);
    else if (p)
        snprintf(neper, sizeof neper, "%.3f", p->ks);
    printf("| %-8s | %6zu | %4.2f | %4.2f | %9.0f | %6.3f | %7.2f | %6.4f | %6.4f | %4.2f | %+5.1f..%+5.1f | %4.2f | %-11s | %s |\n",
           CONTAINER_NAME[c->container], c->n, c->cov, c->aniso, steps, err, secs, ks, crit, ks / crit, clo, chi,
           ko / crit, stops, neper);
    fflush(stdout);
}

static size_t cases_of(const char *mode, fit_case *out)
{
    static const double COVS[] = {0.1, 0.2, 0.5, 0.8, 1.2}, ANISO[] = {1.0, 0.3, 0.1};
    static const size_t NS[] = {500, 2000}, NS_OTHER[] = {200, 5000, 20000};
    size_t k = 0;
    if (!strcmp(mode, "quick")) {
        for (size_t i = 0; i < 4; i++) out[k++] = (fit_case){SQUARE, NEPER[i].n, NEPER[i].cov, 1.0};
        out[k++] = (fit_case){SQUARE, 500, 0.05, 1.0};
        return k;
    }
    int full = !strcmp(mode, "full");
    for (int ct = SQUARE; ct <= CIRCLE; ct++)
        for (size_t in = 0; in < 2; in++)
            for (size_t ic = 0; ic < 5; ic++)
                for (size_t ia = 0; ia < 3; ia++)
                    if (ct == SQUARE || full || (ia == 0 && ic % 2 == 1) || (ia == 1 && ic == 3))
                        out[k++] = (fit_case){ct, NS[in], COVS[ic], ANISO[ia]};
    for (int ct = SQUARE; ct <= (full ? CIRCLE : SQUARE); ct++)
        for (size_t in = 0; in < 3; in++)
            for (size_t ic = 1; ic < 5; ic += (ic == 1 ? 2 : 1))
                for (size_t ia = 0; ia < 2; ia++) out[k++] = (fit_case){ct, NS_OTHER[in], COVS[ic], ANISO[ia]};
    out[k++] = (fit_case){SQUARE, 500, 0.05, 1.0};
    out[k++] = (fit_case){SQUARE, 2000, 0.05, 1.0};
    return k;
}

int main(int argc, char **argv)
{
    const char *mode = argc > 1 ? argv[1] : "grid";
    double threshold = argc > 2 ? atof(argv[2]) : 0.0;
    int threads = argc > 3 ? atoi(argv[3]) : 1;
    static fit_case cases[256];
    size_t n = cases_of(mode, cases);
    printf("2D cells against their laws by default (AD threshold %s%g), 3 seeds a row, %d thread(s)\n\n",
           threshold > 0 ? "" : "default ", threshold > 0 ? threshold : gp_imc_default_threshold(GP_IMC_ERROR_AD),
           threads);
    printf("| container | N | COV | a | steps | error (max) | s (max) | area KS (max) | crit 5 %% | KS/crit | COV err %% | "
           "orient KS/crit | stop | Neper KS, s |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < n; i++) run_case(&cases[i], threshold, threads);
    return 0;
}
