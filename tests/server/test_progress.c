/* test_progress.c -- the progress model (server/jobs/progress.h) on runs played with a made-up clock:
 * phases that take what their plan says, or twice as long (a loaded machine), a phase run again
 * (the 2D refill), a phase whose own rate slows (a converging error), a name the plan does not
 * have (the core's "done"), and the result phase: the fraction never goes down, stays below 1
 * while running and follows elapsed / total; the ETA is never 0 before the end and follows the
 * time really left. */
#include <string.h>

#include "gp_test.h"
#include "jobs/progress.h"

#define DT 0.05 /* seconds between the core's reports */

typedef struct run {
    double t, total;
    double max_dev, max_eta_err; /* |fraction - t / total|, |eta - (total - t)| / total */
    double last_f;
    int down, eta_zero, f_one;
} run;

/* one estimate at r->t, checked and scored */
static void look(gpd_progress_model *m, run *r)
{
    double f, eta;
    gpd_progress_estimate(m, r->t, &f, &eta);
    if (f < r->last_f) r->down++;
    if (!(eta > 0)) r->eta_zero++;
    if (f >= 1) r->f_one++;
    r->last_f = f;
    double dev = fabs(f - r->t / r->total), err = fabs(eta - (r->total - r->t)) / r->total;
    if (dev > r->max_dev) r->max_dev = dev;
    if (err > r->max_eta_err) r->max_eta_err = err;
}

/* A phase of d seconds whose fraction goes as pf(s) = (s / d)^shape (shape 1: linear). */
static void phase(gpd_progress_model *m, run *r, const char *name, double d, double shape)
{
    double t0 = r->t;
    for (double s = 0; s < d; s += DT) {
        r->t = t0 + s;
        gpd_progress_report(m, name, pow(s / d, shape), r->t);
        look(m, r);
    }
    r->t = t0 + d;
}

static void result_phase(gpd_progress_model *m, run *r, double cost, double d)
{
    double t0 = r->t;
    gpd_progress_result(m, cost, t0);
    for (double s = 0; s < d; s += DT) {
        r->t = t0 + s;
        look(m, r);
    }
    r->t = t0 + d;
}

/* a 3D-like plan whose phases all take `slow` times their plan */
static void test_on_plan(double slow, double max_dev)
{
    gpd_phase plan[] = {{"deposition", 2, 1}, {"compaction", 6, 0}, {"relaxation", 2, 0},
                        {"tiling", 0.5, 1}, {"result", 3, 1}};
    gpd_progress_model m;
    gpd_progress_init(&m, plan, 5, 0);
    CHECK(!strcmp(gpd_progress_phase(&m), "starting"));
    run r = {.total = slow * 13.5};
    phase(&m, &r, "deposition", 2 * slow, 1);
    CHECK(!strcmp(gpd_progress_phase(&m), "deposition"));
    phase(&m, &r, "compaction", 6 * slow, 1);
    phase(&m, &r, "relaxation", 2 * slow, 1);
    phase(&m, &r, "tiling", 0.5 * slow, 1);
    gpd_progress_report(&m, "done", 1, r.t); /* not in the plan: stays */
    CHECK(!strcmp(gpd_progress_phase(&m), "tiling"));
    result_phase(&m, &r, 3, 3 * slow);
    CHECK(!strcmp(gpd_progress_phase(&m), "result"));
    CHECK(r.down == 0 && r.eta_zero == 0 && r.f_one == 0);
    printf("on plan x%g: max |fraction - elapsed/total| %.3f, max |eta error| / total %.3f\n", slow,
           r.max_dev, r.max_eta_err);
    CHECK(r.max_dev <= max_dev);
}

/* 2D-like: the IMC converges more slowly than planned (its rate falls), the fill runs again */
static void test_refill_and_slow_convergence(void)
{
    gpd_phase plan[] = {{"tessellation", 0.2, 1}, {"imc", 2, 0},  {"fill", 10, 1},
                        {"fill", 4, 0},           {"odec", 3, 1}, {"result", 3, 1}};
    gpd_progress_model m;
    gpd_progress_init(&m, plan, 6, 0);
    run r = {.total = 0.2 + 4 + 10 + 4 + 2 + 3 + 3};
    phase(&m, &r, "tessellation", 0.2, 1);
    phase(&m, &r, "imc", 4, 0.5); /* fast at first, then slower */
    phase(&m, &r, "fill", 10, 1);
    phase(&m, &r, "fill", 4, 1);  /* the refill: the plan's second "fill" */
    phase(&m, &r, "fill", 2, 1);  /* once more than planned */
    phase(&m, &r, "odec", 3, 1);
    result_phase(&m, &r, 3, 3);
    CHECK(r.down == 0 && r.eta_zero == 0 && r.f_one == 0);
    printf("refill, slow IMC: max |fraction - elapsed/total| %.3f, max |eta error| / total "
           "%.3f\n", r.max_dev, r.max_eta_err);
    CHECK(r.max_dev <= 0.15);
}

/* a result phase that takes longer than planned: the ETA stays above 0 and grows with it */
static void test_result_overrun(void)
{
    gpd_phase plan[] = {{"fill", 1, 1}};
    gpd_progress_model m;
    gpd_progress_init(&m, plan, 1, 0); /* "result" appended */
    run r = {.total = 11};
    phase(&m, &r, "fill", 1, 1);
    result_phase(&m, &r, 1, 10);
    CHECK(r.down == 0 && r.eta_zero == 0 && r.f_one == 0);
    double f, eta;
    gpd_progress_estimate(&m, 11, &f, &eta);
    CHECK(eta >= 0.1 * 10 - 1e-9); /* a tenth of the time the phase has taken */
}

int main(void)
{
    test_on_plan(1, 0.03);
    test_on_plan(2, 0.05); /* a machine twice as slow: the speed is measured */
    test_refill_and_slow_convergence();
    test_result_overrun();
    return gp_test_summary();
}
