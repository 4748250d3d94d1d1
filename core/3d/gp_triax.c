/* gp_triax.c -- see gp_triax.h.
 *
 * The run: one DEM (gp_dem3d) over the copied spheres, true masses (no density scaling),
 * gravity off, the specimen's contact law and time step rule (GP_SPEC3D_DT_SAFETY and
 * GP_SPEC3D_DT_DAMPING_EXP: the step follows the damping in force), driven in chunks of at
 * most CHUNK steps; between chunks the driver reads the walls, sets the walls' velocities,
 * looks at the stop criteria, reports progress. Code: gp_triax_run() runs start_dem,
 * consolidate and load over one triax_run; measure() takes one point of the curve.
 */
#include "gp_triax.h"

#include "gp_clock.h"
#include "gp_dem3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define CHUNK 100 /* steps between the driver's looks (S_c is measured on a chunk's last step) */
/* Consolidation: every wall a stress servo at sigma3 times its face's current area, its speed
 * capped at CONS_RATE times half its axis' span (the box closes at a strain rate of at most
 * CONS_RATE on each axis), with the gain CONS_GAIN a step (the fraction of Eq. 10's
 * displacement a step applies); loading: the lateral servos with LOAD_GAIN, their cap
 * LOAD_VCAP times the strain rate times half the span (at least CONS_RATE's). The choice and
 * its measurements: docs/design/triax.md. */
#ifndef CONS_RATE
#define CONS_RATE 0.05
#endif
#ifndef CONS_GAIN
#define CONS_GAIN 0.05
#endif
#ifndef LOAD_GAIN
#define LOAD_GAIN 0.25
#endif
#define DEM_SERVO_GAIN 0.25 /* gp_dem3d.c's SERVO_GAIN: the gain is 0.25 dt / dt_ref */
#ifndef LOAD_VCAP
#define LOAD_VCAP 20.0
#endif
/* loading: the strain rate rises linearly from 0 over RAMP_WAVES times the time an elastic
 * wave of the contacts' modulus takes to cross the sample, H0 sqrt(density / E) (about the
 * period of the sample's axial mode), but over no more than 2 RAMP_STRAIN_MAX / rate (so the
 * ramp adds at most RAMP_STRAIN_MAX / rate to the loading's time) */
#ifndef RAMP_WAVES
#define RAMP_WAVES 10.0
#endif
#define RAMP_STRAIN_MAX 0.002
/* the consolidation's share of the steps: CONS_TIME_FRACTION of the loading's time, at least
 * CONS_TIME_MIN seconds, at the run's time step */
#ifndef CONS_TIME_FRACTION
#define CONS_TIME_FRACTION 0.25
#endif
#ifndef CONS_TIME_MIN
#define CONS_TIME_MIN 5.0
#endif
#ifndef SKIN
#define SKIN 1.0 /* the Verlet skin, times the smallest radius (results do not depend on it) */
#endif
#define LOAD_MARGIN 1.05 /* the loading's steps, as planned, times this (cuts of dt) */
#define DILATANCY_WINDOW 0.01 /* axial strain */
#define RISING_WINDOW 0.02    /* axial strain */
#define CONS_WEIGHT 0.1       /* progress: the consolidation's share of the fraction */

void gp_triax_params_defaults(gp_triax_params *p)
{
    memset(p, 0, sizeof *p);
    p->confining = 50e3;
    p->axial_strain = 0.2;
    p->strain_rate = 0.01;
    p->drainage = GP_TRIAX_DRAINED;
    p->stress_tol = 0.01;
    p->stability_tol = 1e-4;
    p->d50 = 0;
    p->max_steps = 0;
    p->samples = 500;
    p->threads = 1;
}

void gp_triax_result_destroy(gp_triax_result *r)
{
    if (!r)
        return;
    free(r->curve);
    free(r->spheres);
    free(r);
}

/* ---- the time step and the plan of steps ---- */

/* the DEM's time step for spheres down to r_min at damping c: the specimen's rule
 * (gp_specimen3d.h), true masses */
static double rule_dt(const gp_material3d *m, double r_min, double c)
{
    double mass = 4.0 / 3.0 * M_PI * r_min * r_min * r_min * m->density;
    double safety = GP_SPEC3D_DT_SAFETY
                    * pow(1 + GP_SPEC3D_RELAX_DAMPING, GP_SPEC3D_DT_DAMPING_EXP);
    return safety * sqrt(mass / (2 * m->young * r_min)) / pow(1 + c, GP_SPEC3D_DT_DAMPING_EXP);
}

/* the loading's longest duration (s): axial_strain / rate, plus half the longest ramp */
static double load_time(const gp_triax_params *p)
{
    return (p->axial_strain + RAMP_STRAIN_MAX) / p->strain_rate;
}

/* the loading's planned steps at time step dt (margin for cuts, one per sample for the
 * rounding where a sample is taken) */
static double load_need(const gp_triax_params *p, double dt)
{
    return ceil(LOAD_MARGIN * load_time(p) / dt) + p->samples + CHUNK;
}

/* the consolidation's share (steps) at its time step dt */
static double cons_allow(const gp_triax_params *p, double dt)
{
    double t = fmax(CONS_TIME_MIN, CONS_TIME_FRACTION * load_time(p));
    return CHUNK * ceil(t / dt / CHUNK);
}

#define STEPS_MAX 1e18 /* plans beyond this are clamped (a long holds 9.2e18) */

long gp_triax_estimate_steps(const gp_material3d *m, double r_min, const gp_triax_params *p)
{
    if (!m || !p || !(r_min > 0) || !(m->density > 0) || !(m->young > 0)
        || !(p->strain_rate > 0) || !(p->axial_strain > 0))
        return 0;
    double dt = rule_dt(m, r_min, m->damping);
    double steps = cons_allow(p, dt) + load_need(p, dt);
    return steps > STEPS_MAX ? (long)STEPS_MAX : (long)steps;
}

/* ---- Mohr-Coulomb ---- */

gp_status gp_triax_mohr_coulomb(const double *sigma3, const double *sigma1, size_t n,
                                double *phi_deg, double *cohesion, double *residual,
                                gp_error *err)
{
    if (!sigma3 || !sigma1 || !phi_deg || !cohesion || !residual)
        return gp_error_set(err, GP_ERR_INVALID, "mohr_coulomb: NULL argument");
    if (n < 1)
        return gp_error_set(err, GP_ERR_INVALID, "mohr_coulomb: need at least one state");
    double ms = 0, mt = 0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(sigma3[i]) || !isfinite(sigma1[i]) || !(sigma3[i] > 0))
            return gp_error_set(err, GP_ERR_INVALID,
                                "mohr_coulomb: state %zu: sigma3 must be finite and > 0", i);
        if (!(sigma1[i] >= sigma3[i]))
            return gp_error_set(err, GP_ERR_INVALID,
                                "mohr_coulomb: state %zu: sigma1 < sigma3", i);
        ms += 0.5 * (sigma1[i] + sigma3[i]);
        mt += 0.5 * (sigma1[i] - sigma3[i]);
    }
    ms /= (double)n;
    mt /= (double)n;
    /* t = a s + b: least squares; b < 0 (or one distinct s) -> the line through 0 */
    double sst = 0, sss = 0;
    for (size_t i = 0; i < n; i++) {
        double s = 0.5 * (sigma1[i] + sigma3[i]) - ms, t = 0.5 * (sigma1[i] - sigma3[i]) - mt;
        sst += s * t;
        sss += s * s;
    }
    double a = 0, b = -1;
    if (n > 1 && sss > 1e-24 * ms * ms) {
        a = sst / sss;
        b = mt - a * ms;
    }
    if (!(b >= 0) || !(a >= 0)) {
        double num = 0, den = 0;
        for (size_t i = 0; i < n; i++) {
            double s = 0.5 * (sigma1[i] + sigma3[i]), t = 0.5 * (sigma1[i] - sigma3[i]);
            num += s * t;
            den += s * s;
        }
        a = num / den; /* in [0, 1): t < s for every state (sigma3 > 0) */
        b = 0;
    }
    double r2 = 0;
    for (size_t i = 0; i < n; i++) {
        double s = 0.5 * (sigma1[i] + sigma3[i]), t = 0.5 * (sigma1[i] - sigma3[i]);
        double e = t - (a * s + b);
        r2 += e * e;
    }
    double phi = asin(a);
    *phi_deg = phi * 180 / M_PI;
    *cohesion = b / cos(phi);
    *residual = sqrt(r2 / (double)n);
    return GP_OK;
}

/* ---- the run ---- */

typedef struct triax_run {
    const gp_material3d *mat;
    const gp_triax_params *P;
    gp_progress_fn progress;
    void *user;
    const volatile int *cancel;
    double last_report;
    gp_error *err;
    size_t n;
    gp_dem3d *dem;
    gp_dem3d_state ds;
    double *xyzr;         /* the spheres at a measure */
    unsigned *cnt;        /* contacts per sphere at a measure */
    gp_triax_result *res;
    double sigma3;
    double dt_load, ramp; /* the loading's time step and ramp (s) */
    long max_steps, cons_share;
    double lo0[3], hi0[3]; /* the walls at the end of consolidation */
    double solid0;         /* the spheres' volume in the box at the start (progress reports) */
} triax_run;


/* the progress callback, paced (gp_progress_pace); non-zero: stop */
static int report(triax_run *R, const char *phase, double fraction, double pf, double porosity,
                  double sc, int force)
{
    gp_progress_pacer pc = {R->progress, R->user, R->cancel, R->last_report};
    gp_progress p = {.phase = phase, .fraction = fraction, .phase_fraction = pf,
                     .steps = R->ds.steps, .porosity = porosity, .stability = sc};
    int stop = gp_progress_pace(&pc, p, force);
    R->last_report = pc.last;
    return stop;
}

static double box_volume(const double lo[3], const double hi[3])
{
    return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
}

static void walls_of(const gp_dem3d *d, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = gp_dem3d_wall(d, 2 * a);
        hi[a] = gp_dem3d_wall(d, 2 * a + 1);
    }
}

/* each wall's stress (Pa, compression positive) over its face's current area, from the
 * forces of the DEM's last step */
static void wall_stresses(const triax_run *R, double s[6])
{
    for (int w = 0; w < 6; w++)
        s[w] = R->ds.wall_force[w] / gp_dem3d_face_area(R->dem, w);
}

/* the largest |stress - sigma3| / sigma3 over the walls of mask (bit w: wall w) */
static double servo_error(const triax_run *R, const double s[6], unsigned mask)
{
    double e = 0;
    for (int w = 0; w < 6; w++)
        if (mask & (1u << w))
            e = fmax(e, fabs(s[w] - R->sigma3) / R->sigma3);
    return e;
}

/* One point of the curve at the DEM's current state (its last step): wall stresses, the
 * Love-Weber tensor S (over the current box), contacts, porosity, S_c, I; the strains from
 * the walls against the consolidation's end (lo0, hi0). mask: the servo walls. */
static gp_status measure(triax_run *R, unsigned mask, gp_triax_point *pt, double S[3][3])
{
    gp_dem3d_get_state(R->dem, &R->ds);
    double lo[3], hi[3], s[6];
    walls_of(R->dem, lo, hi);
    wall_stresses(R, s);
    double V = box_volume(lo, hi);
    memset(pt, 0, sizeof *pt);
    pt->axial_strain = log((R->hi0[2] - R->lo0[2]) / (hi[2] - lo[2]));
    pt->volumetric_strain = log(box_volume(R->lo0, R->hi0) / V);
    pt->sigma1 = 0.5 * (s[4] + s[5]);
    pt->sigma3 = 0.25 * (s[0] + s[1] + s[2] + s[3]);
    pt->q = pt->sigma1 - pt->sigma3;
    pt->p = (pt->sigma1 + 2 * pt->sigma3) / 3;
    pt->ratio = pt->sigma3 > 0 ? pt->sigma1 / pt->sigma3 : 0;
    pt->servo_error = servo_error(R, s, mask);
    pt->stability = isfinite(R->ds.stability) ? R->ds.stability : 0;
    pt->inertial_number = pt->p > 0 ? R->P->strain_rate * R->P->d50 * sqrt(R->mat->density / pt->p)
                                    : 0;
    pt->step = R->ds.steps;
    gp_dem3d_spheres(R->dem, R->xyzr);
    gp_contact3d *c = NULL;
    size_t nc = 0;
    gp_status st = gp_dem3d_contacts(R->dem, &c, &nc, R->err);
    if (st)
        return st;
    gp_dem3d_stress(c, nc, R->xyzr, V, S);
    pt->sigma1_lw = S[2][2];
    pt->sigma3_lw = 0.5 * (S[0][0] + S[1][1]);
    /* Z = 2 C / N; Z_m = 2 C' / N' over the spheres with two contacts or more (walls
     * counted), C' the sphere contacts between two of them */
    memset(R->cnt, 0, R->n * sizeof *R->cnt);
    size_t pairs = 0, pairs_m = 0, nm = 0;
    for (size_t k = 0; k < nc; k++) {
        R->cnt[c[k].i]++;
        if (c[k].j >= 0) {
            R->cnt[c[k].j]++;
            pairs++;
        }
    }
    for (size_t k = 0; k < nc; k++)
        if (c[k].j >= 0 && R->cnt[c[k].i] >= 2 && R->cnt[c[k].j] >= 2)
            pairs_m++;
    for (size_t i = 0; i < R->n; i++)
        nm += R->cnt[i] >= 2;
    free(c);
    pt->coordination = 2.0 * (double)pairs / (double)R->n;
    pt->coordination_mechanical = nm ? 2.0 * (double)pairs_m / (double)nm : 0;
    pt->porosity = 1 - gp_dem3d_solid_volume(R->xyzr, R->n, lo, hi) / V;
    return GP_OK;
}

static gp_status validate(const gp_material3d *m, const double *xyzr, size_t n,
                          const double lo[3], const double hi[3], const gp_triax_params *p,
                          gp_error *err)
{
    if (!m || !xyzr || !lo || !hi || !p)
        return gp_error_set(err, GP_ERR_INVALID, "triax: NULL argument");
    if (n < 1)
        return gp_error_set(err, GP_ERR_INVALID, "triax: no spheres");
    gp_status mst = gp_material3d_check(m, err);
    if (mst)
        return mst;
    for (int a = 0; a < 3; a++)
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || !(hi[a] > lo[a]))
            return gp_error_set(err, GP_ERR_INVALID, "box: axis %d is empty or not finite", a);
    if (!(p->confining > 0) || !(p->confining <= 1e7))
        return gp_error_set(err, GP_ERR_INVALID, "confining must be in (0, 1e7] Pa (got %g)",
                            p->confining);
    if (!(p->axial_strain > 0) || !(p->axial_strain <= 0.5))
        return gp_error_set(err, GP_ERR_INVALID, "axial_strain must be in (0, 0.5] (got %g)",
                            p->axial_strain);
    if (!(p->strain_rate > 0) || !isfinite(p->strain_rate))
        return gp_error_set(err, GP_ERR_INVALID, "strain_rate must be > 0 /s (got %g)",
                            p->strain_rate);
    if (p->drainage != GP_TRIAX_DRAINED && p->drainage != GP_TRIAX_CONSTANT_VOLUME)
        return gp_error_set(err, GP_ERR_INVALID, "drainage must be drained or constant_volume");
    if (!(p->stress_tol > 0) || !(p->stress_tol < 1))
        return gp_error_set(err, GP_ERR_INVALID, "stress_tol must be in (0, 1) (got %g)",
                            p->stress_tol);
    if (!(p->stability_tol > 0) || !(p->stability_tol < 1))
        return gp_error_set(err, GP_ERR_INVALID, "stability_tol must be in (0, 1) (got %g)",
                            p->stability_tol);
    if (!(p->d50 > 0) || !isfinite(p->d50))
        return gp_error_set(err, GP_ERR_INVALID, "d50 must be > 0 m (got %g)", p->d50);
    if (p->max_steps <= 0)
        return gp_error_set(err, GP_ERR_INVALID, "max_steps must be > 0 (got %ld)",
                            p->max_steps);
    if (p->samples < 2 || p->samples > 500)
        return gp_error_set(err, GP_ERR_INVALID, "samples must be in [2, 500] (got %d)",
                            p->samples);
    if (p->threads < 0 || p->threads > 256)
        return gp_error_set(err, GP_ERR_INVALID, "threads must be in [0, 256] (got %d)",
                            p->threads);
    return GP_OK;
}

/* the DEM over the spheres in [lo, hi]: the material, true masses, no gravity, the
 * specimen's time step rule, at the consolidation's damping; the plan of steps */
static gp_status start_dem(triax_run *R, const double *xyzr, const double lo[3],
                           const double hi[3])
{
    const gp_material3d *m = R->mat;
    double r_min = INFINITY;
    for (size_t i = 0; i < R->n; i++)
        r_min = fmin(r_min, xyzr[4 * i + 3]);
    gp_dem3d_params dp;
    gp_dem3d_params_defaults(&dp);
    dp.density = m->density;
    dp.young = m->young;
    dp.ks_kn = m->poisson;
    dp.friction_deg = m->friction_deg;
    dp.damping = m->damping;
    dp.gravity[0] = dp.gravity[1] = dp.gravity[2] = 0;
    dp.dt_safety = GP_SPEC3D_DT_SAFETY * pow(1 + GP_SPEC3D_RELAX_DAMPING, GP_SPEC3D_DT_DAMPING_EXP);
    dp.dt_damping_exp = GP_SPEC3D_DT_DAMPING_EXP;
    dp.scaled_radius = 0;
    dp.skin = r_min > 0 && isfinite(r_min) ? SKIN * r_min : 0;
    dp.threads = R->P->threads > 0 ? R->P->threads : 1;
    gp_status st = gp_dem3d_create(&dp, xyzr, R->n, lo, hi, &R->dem, R->err);
    if (st)
        return st;
    gp_dem3d_set_cancel(R->dem, R->cancel);
    R->dt_load = gp_dem3d_dt(R->dem);
    R->solid0 = gp_dem3d_solid_volume(xyzr, R->n, lo, hi);
    double need = load_need(R->P, R->dt_load);
    if ((double)R->P->max_steps - need < CHUNK)
        return gp_error_set(R->err, GP_ERR_INVALID,
                            "max_steps (%ld) leaves no room for consolidation: the loading alone "
                            "may take %.0f steps", R->P->max_steps, need);
    R->cons_share = R->P->max_steps - (long)need;
    double allow = cons_allow(R->P, R->dt_load);
    if (allow < (double)R->cons_share)
        R->cons_share = (long)allow;
    return GP_OK;
}

/* ---- 1. isotropic consolidation ---- */
static gp_status consolidate(triax_run *R)
{
    const gp_triax_params *P = R->P;
    gp_dem3d *dem = R->dem;
    gp_triax_result *res = R->res;
    double t0 = gp_clock_seconds();
    double lo[3], hi[3];
    walls_of(dem, lo, hi);
    gp_dem3d_set_servo_dt(dem, DEM_SERVO_GAIN * gp_dem3d_dt(dem) / CONS_GAIN);
    for (int w = 0; w < 6; w++)
        gp_dem3d_set_servo_stress(dem, w, R->sigma3, CONS_RATE * 0.5 * (hi[w / 2] - lo[w / 2]));
    double sc0 = -1, pf = 0, err6 = INFINITY, sc = INFINITY;
    for (;;) {
        if (R->ds.steps >= R->cons_share) {
            int e_ok = err6 <= P->stress_tol, s_ok = sc <= P->stability_tol;
            return gp_error_set(R->err, GP_ERR_NOT_CONVERGED,
                                "consolidation: not converged in %ld steps: %s%s%s (wall stress "
                                "error %.3g, tolerance %g; S_c %.3g, tolerance %g)",
                                R->ds.steps, e_ok ? "" : "the wall stresses",
                                !e_ok && !s_ok ? " and " : "", s_ok ? "" : "S_c", err6,
                                P->stress_tol, sc, P->stability_tol);
        }
        gp_status st = gp_dem3d_run(dem, CHUNK, R->err);
        if (st)
            return st;
        gp_dem3d_get_state(dem, &R->ds);
        double s[6];
        wall_stresses(R, s);
        err6 = servo_error(R, s, 0x3f);
        sc = R->ds.stability;
        if (err6 <= P->stress_tol && sc <= P->stability_tol)
            break;
        /* progress: the log of S_c from its first value towards the tolerance (never back) */
        if (sc0 < 0)
            sc0 = fmax(sc, 2 * P->stability_tol);
        double f = fmin(1, log(sc0 / fmax(sc, P->stability_tol)) / log(sc0 / P->stability_tol));
        pf = fmax(pf, f);
        walls_of(dem, lo, hi);
        if (report(R, "consolidation", CONS_WEIGHT * pf, pf, 1 - R->solid0 / box_volume(lo, hi),
                   sc, 0))
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
    }
    res->consolidation_steps = R->ds.steps;
    walls_of(dem, R->lo0, R->hi0);
    gp_triax_point pt;
    double S[3][3];
    gp_status st = measure(R, 0x3f, &pt, S);
    if (st)
        return st;
    double s[6];
    wall_stresses(R, s);
    for (int a = 0; a < 3; a++)
        res->consolidation_wall[a] = 0.5 * (s[2 * a] + s[2 * a + 1]);
    memcpy(res->consolidation_lw, S, sizeof S);
    res->consolidation_porosity = pt.porosity;
    res->consolidation_stability = pt.stability;
    res->height0 = R->hi0[2] - R->lo0[2];
    res->volume0 = box_volume(R->lo0, R->hi0);
    res->curve[0] = pt;
    res->ncurve = 1;
    res->seconds_consolidation = gp_clock_seconds() - t0;
    report(R, "consolidation", CONS_WEIGHT, 1, pt.porosity, pt.stability, 1);
    return GP_OK;
}

/* ---- 2. axial loading ----
 * The axial log strain as a function of the loading's time: its rate rises linearly from 0
 * to strain_rate over the ramp, then stays. */
static double strain_at(const triax_run *R, double t)
{
    double r = R->P->strain_rate, T = R->ramp;
    return t < T ? r * t * t / (2 * T) : r * (t - 0.5 * T);
}

static double time_at(const triax_run *R, double eps)
{
    double r = R->P->strain_rate, T = R->ramp;
    return eps < 0.5 * r * T ? sqrt(2 * T * eps / r) : eps / r + 0.5 * T;
}

static gp_status load(triax_run *R)
{
    const gp_triax_params *P = R->P;
    gp_dem3d *dem = R->dem;
    gp_triax_result *res = R->res;
    double t0 = gp_clock_seconds();
    int cv = P->drainage == GP_TRIAX_CONSTANT_VOLUME;
    unsigned mask = cv ? 0 : 0x0f;
    gp_dem3d_set_servo_dt(dem, DEM_SERVO_GAIN * gp_dem3d_dt(dem) / LOAD_GAIN);
    gp_dem3d_set_wall_velocity(dem, 4, 0);
    double L0[3], c0[3];
    for (int a = 0; a < 3; a++) {
        L0[a] = R->hi0[a] - R->lo0[a];
        c0[a] = 0.5 * (R->hi0[a] + R->lo0[a]);
    }
    for (int w = 0; w < 4 && !cv; w++)
        gp_dem3d_set_servo_stress(dem, w, R->sigma3,
                                  fmax(CONS_RATE, LOAD_VCAP * P->strain_rate) * 0.5 * L0[w / 2]);
    R->ramp = fmin(RAMP_WAVES * L0[2] * sqrt(R->mat->density / R->mat->young),
                   2 * RAMP_STRAIN_MAX / P->strain_rate);
    double t = 0;
    int k = 1, ns = P->samples;
    while (k < ns) {
        double eps_k = P->axial_strain * (double)k / (double)(ns - 1);
        double t_k = time_at(R, eps_k), dt = gp_dem3d_dt(dem);
        double left_d = (t_k - t) / dt;
        long left = left_d < 1 ? 1 : (long)floor(left_d + 0.5);
        long nstep = left > CHUNK ? CHUNK : left;
        int lands = nstep == left;
        double t_end = lands ? t_k : t + (double)nstep * dt;
        double eps_end = lands ? eps_k : strain_at(R, t_end);
        double H = R->hi0[2] - R->lo0[2];
        double Ht = H * exp(-eps_end), span = (double)nstep * dt;
        gp_dem3d_set_wall_velocity(dem, 5, (gp_dem3d_wall(dem, 4) + Ht - gp_dem3d_wall(dem, 5))
                                               / span);
        if (cv) {
            double f = sqrt(H / Ht);
            for (int w = 0; w < 4; w++) {
                int a = w / 2;
                double target = c0[a] + ((w & 1) ? 0.5 : -0.5) * L0[a] * f;
                gp_dem3d_set_wall_velocity(dem, w, (target - gp_dem3d_wall(dem, w)) / span);
            }
        }
        if (R->ds.steps + nstep > R->max_steps)
            return gp_error_set(R->err, GP_ERR_NOT_CONVERGED,
                                "loading: max_steps (%ld) reached at axial strain %.4g of %g",
                                R->max_steps, log(H / (gp_dem3d_wall(dem, 5)
                                                       - gp_dem3d_wall(dem, 4))),
                                P->axial_strain);
        gp_status st = gp_dem3d_run(dem, nstep, R->err);
        if (st)
            return st;
        gp_dem3d_get_state(dem, &R->ds);
        t = t_end;
        double pf = eps_end / P->axial_strain;
        if (lands) {
            double S[3][3];
            gp_triax_point *pt = res->curve + k;
            if ((st = measure(R, mask, pt, S)))
                return st;
            res->ncurve = (size_t)++k;
            if (report(R, "loading", CONS_WEIGHT + (1 - CONS_WEIGHT) * pf, pf, pt->porosity,
                       pt->stability, 0))
                return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
        } else if (report(R, "loading", CONS_WEIGHT + (1 - CONS_WEIGHT) * pf, pf,
                          res->curve[res->ncurve - 1].porosity, R->ds.stability, 0)) {
            return gp_error_set(R->err, GP_ERR_CANCELLED, "cancelled");
        }
    }
    res->dt = gp_dem3d_dt(dem);
    res->seconds_loading = gp_clock_seconds() - t0;
    return GP_OK;
}

/* the value of column y at x on the curve (x increasing), linear between samples, clamped */
static double curve_at(const gp_triax_point *c, size_t n, double x, size_t off_y)
{
#define COL(k) (*(const double *)((const char *)(c + (k)) + off_y))
    if (x <= c[0].axial_strain)
        return COL(0);
    for (size_t k = 1; k < n; k++)
        if (c[k].axial_strain >= x) {
            double x0 = c[k - 1].axial_strain, x1 = c[k].axial_strain;
            return x1 > x0 ? COL(k - 1) + (COL(k) - COL(k - 1)) * (x - x0) / (x1 - x0) : COL(k);
        }
    return COL(n - 1);
#undef COL
}

static double phi_of(double R) { return R > 0 ? asin((R - 1) / (R + 1)) * 180 / M_PI : 0; }

/* the summary of the curve (gp_triax.h) */
static void summarise(gp_triax_result *r)
{
    const gp_triax_point *c = r->curve;
    size_t n = r->ncurve, kp = 0;
    for (size_t k = 1; k < n; k++)
        if (c[k].ratio > c[kp].ratio)
            kp = k;
    r->peak_ratio = c[kp].ratio;
    r->peak_axial_strain = c[kp].axial_strain;
    r->peak_phi_deg = phi_of(r->peak_ratio);
    r->end_ratio = c[n - 1].ratio;
    r->end_phi_deg = phi_of(r->end_ratio);
    /* the largest dilatancy angle: the slope of eps_v over a window of DILATANCY_WINDOW of
     * axial strain centred on each sample (clipped at the ends) */
    double e_end = c[n - 1].axial_strain, psi_max = -90;
    size_t off_v = offsetof(gp_triax_point, volumetric_strain);
    for (size_t k = 0; k < n; k++) {
        double a = fmax(0, c[k].axial_strain - 0.5 * DILATANCY_WINDOW);
        double b = fmin(e_end, c[k].axial_strain + 0.5 * DILATANCY_WINDOW);
        if (!(b - a >= fmin(0.25 * DILATANCY_WINDOW, 0.5 * e_end)) || !(b > a))
            continue;
        double d = (curve_at(c, n, b, off_v) - curve_at(c, n, a, off_v)) / (b - a);
        double s = -d / (2 - d);
        psi_max = fmax(psi_max, asin(fmax(-1, fmin(1, s))) * 180 / M_PI);
    }
    r->dilatancy_deg = psi_max > -90 ? psi_max : 0;
    /* E50: half the peak deviator over the axial strain where q first reaches it */
    double half = 0.5 * c[kp].q;
    r->e50 = 0;
    for (size_t k = 1; k <= kp; k++)
        if (c[k].q >= half) {
            double q0 = c[k - 1].q, e0 = c[k - 1].axial_strain, e1 = c[k].axial_strain;
            double e = c[k].q > q0 ? e0 + (e1 - e0) * (half - q0) / (c[k].q - q0) : e1;
            r->e50 = e > 0 ? half / e : 0;
            break;
        }
    r->inertial_number_max = 0;
    r->servo_error_max = 0;
    for (size_t k = 1; k < n; k++) {
        r->inertial_number_max = fmax(r->inertial_number_max, c[k].inertial_number);
        r->servo_error_max = fmax(r->servo_error_max, c[k].servo_error);
    }
    size_t off_r = offsetof(gp_triax_point, ratio);
    double before = curve_at(c, n, e_end - RISING_WINDOW, off_r);
    r->still_rising = r->end_ratio >= 0.99 * r->peak_ratio && r->end_ratio > before;
}

gp_status gp_triax_run(const gp_material3d *material, const double *xyzr, size_t n,
                       const double lo[3], const double hi[3], const gp_triax_params *params,
                       gp_progress_fn progress, void *user, const volatile int *cancel,
                       gp_triax_result **out, gp_error *err)
{
    if (out)
        *out = NULL;
    if (!out)
        return gp_error_set(err, GP_ERR_INVALID, "triax: NULL argument");
    gp_status st = validate(material, xyzr, n, lo, hi, params, err);
    if (st)
        return st;
    triax_run R;
    memset(&R, 0, sizeof R);
    R.mat = material;
    R.P = params;
    R.progress = progress;
    R.user = user;
    R.cancel = cancel;
    R.err = err;
    R.n = n;
    R.sigma3 = params->confining;
    R.max_steps = params->max_steps;
    R.res = calloc(1, sizeof *R.res);
    R.xyzr = malloc(4 * n * sizeof *R.xyzr);
    R.cnt = malloc(n * sizeof *R.cnt);
    if (R.res)
        R.res->curve = calloc((size_t)params->samples, sizeof *R.res->curve);
    if (!R.res || !R.xyzr || !R.cnt || !R.res->curve) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory (%zu spheres)", n);
        goto done;
    }
    R.res->confining = params->confining;
    if ((st = start_dem(&R, xyzr, lo, hi)))
        goto done;
    if (report(&R, "consolidation", 0, 0, 0, 0, 1)) {
        st = gp_error_set(err, GP_ERR_CANCELLED, "cancelled");
        goto done;
    }
    if ((st = consolidate(&R)) || (st = load(&R)))
        goto done;
    summarise(R.res);
    gp_dem3d_get_state(R.dem, &R.ds);
    R.res->steps = R.ds.steps;
    walls_of(R.dem, R.res->box_lo, R.res->box_hi);
    R.res->spheres = R.xyzr; /* measure() left the last state there */
    R.xyzr = NULL;
    R.res->n = n;
    report(&R, "loading", 1, 1, R.res->curve[R.res->ncurve - 1].porosity,
           R.res->curve[R.res->ncurve - 1].stability, 1);
    *out = R.res;
    R.res = NULL;
done:
    gp_dem3d_destroy(R.dem);
    gp_triax_result_destroy(R.res);
    free(R.xyzr);
    free(R.cnt);
    return st;
}
