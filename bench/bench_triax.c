/* bench_triax.c -- the drained triaxial test of Dang & Meguid (2010, "Triaxial Tests", Fig. 7)
 * on the paper's S0 (0.5 m cube, Tables 1 and 2, porosity 0.38, built by gp_specimen3d_build
 * with the API defaults and the given seed), one confining stress, timed: one markdown table
 * (spheres, steps, dt, seconds of consolidation and loading, steps/s, the peak, the volumetric
 * strain at 5/10/20 % axial strain, the largest inertial number and servo error, and how the
 * wall and Love-Weber stresses agree at the end of consolidation).
 *
 * Usage: bench_triax [SEED] [--confining KPA] [--rate 1/S] [--strain E] [--threads N]
 *                    [--box M] [--porosity P] [--json FILE] [--export DIR]
 * Defaults: seed 7, 50 kPa, 0.01 /s, axial strain 0.2, one thread, the 0.5 m cube at 0.38.
 * --json FILE: the settings, the consolidation, the summary and the curves, with the column
 * names of bench/peers/yade_triaxial.py's out.json where they mean the same (axial_strain,
 * volumetric_strain, sigma1_kpa, sigma3_kpa, q_kpa, p_kpa, stress_ratio, porosity, stability,
 * inertial_number, servo_error, coordination_spheres, iter; compression positive) and names
 * of their own where they do not (its "definitions" say), so that a script can set the two
 * codes' curves side by side.
 * --export DIR: the specimen as yade_triaxial.py reads it: DIR/spheres.txt ("x y z r" a line,
 * %.17g, SI) and DIR/box.json ({"lo", "hi", "box"}), the sample as its build ended.
 *
 * The study (did the flip tiling keep the sample's strength?), on when --seeds or --tiling is
 * given or --confining lists more than one stress:
 *   bench_triax --seeds 7,8,9 --tiling 2 --confining 50,100 [--rate 1/S] [--strain E]
 *               [--threads N] [--box M] [--porosity P] [--parts s0,tiled]
 * Each seed's specimen is built once (tiling {N, N, N}); at each confining stress the sample
 * S0 (sample_spheres) and, with N > 1, the tiled packing (spheres) are tested (--parts keeps
 * one of them); then the Mohr-Coulomb envelope (gp_triax_mohr_coulomb, the peak states'
 * sigma3 and sigma1) of each over the stresses, per seed. One line per run goes to stderr as
 * it ends; at the end one markdown table to stdout: per seed and stress the peak, phi_peak, its
 * axial strain, the largest I, seconds (wall) and steps of each run; per seed the envelopes;
 * the mean and sample standard deviation (n - 1) over the seeds of S0's phi_peak and phi' and
 * of the tiling's, and whether each tiled phi lies within S0's mean +- 2 sd. A run that fails
 * is reported and left out. --json and --export are for the single run only. */
#include "gp_clock.h"
#include "gp_specimen3d.h"
#include "gp_triax.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* the median diameter by mass of the n spheres */
static double d50_by_mass(const double *s, size_t n)
{
    double *d = malloc(n * sizeof *d), tot = 0, acc = 0, r = 0;
    if (!d)
        return 0;
    for (size_t i = 0; i < n; i++) {
        d[i] = 2 * s[4 * i + 3];
        tot += d[i] * d[i] * d[i];
    }
    qsort(d, n, sizeof *d, cmp_double);
    for (size_t i = 0; i < n; i++) {
        acc += d[i] * d[i] * d[i];
        if (acc >= 0.5 * tot) {
            r = d[i];
            break;
        }
    }
    free(d);
    return r;
}

/* the value of eps_v at axial strain x (linear between samples); NAN beyond the curve */
static double ev_at(const gp_triax_result *r, double x)
{
    const gp_triax_point *c = r->curve;
    for (size_t k = 1; k < r->ncurve; k++)
        if (c[k].axial_strain >= x - 1e-12) {
            double x0 = c[k - 1].axial_strain, x1 = c[k].axial_strain;
            return c[k - 1].volumetric_strain
                   + (c[k].volumetric_strain - c[k - 1].volumetric_strain) * (x - x0) / (x1 - x0);
        }
    return NAN;
}

static void pct(char *buf, size_t n, double v)
{
    if (isnan(v))
        snprintf(buf, n, "-");
    else
        snprintf(buf, n, "%+.3f %%", 100 * v);
}

#define COLUMN(name, expr, scale)                                                      \
    do {                                                                               \
        fprintf(f, "%s  \"%s\": [", first ? "" : ",\n", name);                        \
        first = 0;                                                                     \
        for (size_t k = 0; k < r->ncurve; k++)                                         \
            fprintf(f, "%s%.10g", k ? ", " : "", (double)(r->curve[k].expr) * (scale)); \
        fprintf(f, "]");                                                               \
    } while (0)

static int write_json(const char *path, const gp_triax_result *r, const gp_triax_params *p,
                      unsigned long long seed, size_t n, double lw_err, double wall_clock,
                      double cpu)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f, "{\"code\": \"grainpack\", \"status\": \"done\",\n");
    fprintf(f, " \"settings\": {\"seed\": %llu, \"confining_kpa\": %.10g, \"axial_strain\": %.10g, "
               "\"strain_rate\": %.10g, \"drainage\": \"%s\", \"threads\": %d, \"dt\": %.10g, "
               "\"d50\": %.10g, \"samples\": %d},\n",
            seed, p->confining / 1e3, p->axial_strain, p->strain_rate,
            p->drainage == GP_TRIAX_DRAINED ? "drained" : "constant_volume", p->threads, r->dt,
            p->d50, p->samples);
    fprintf(f, " \"spheres\": %zu,\n", n);
    fprintf(f, " \"consolidation\": {\"steps\": %ld, \"wall_kpa\": [%.10g, %.10g, %.10g], "
               "\"love_weber_kpa\": [[%.10g, %.10g, %.10g], [%.10g, %.10g, %.10g], [%.10g, %.10g, "
               "%.10g]], \"love_weber_vs_wall_max\": %.6g, \"porosity\": %.10g, \"stability\": "
               "%.6g, \"height\": %.10g, \"volume\": %.10g, \"wall_clock_s\": %.4g},\n",
            r->consolidation_steps, r->consolidation_wall[0] / 1e3, r->consolidation_wall[1] / 1e3,
            r->consolidation_wall[2] / 1e3, r->consolidation_lw[0][0] / 1e3,
            r->consolidation_lw[0][1] / 1e3, r->consolidation_lw[0][2] / 1e3,
            r->consolidation_lw[1][0] / 1e3, r->consolidation_lw[1][1] / 1e3,
            r->consolidation_lw[1][2] / 1e3, r->consolidation_lw[2][0] / 1e3,
            r->consolidation_lw[2][1] / 1e3, r->consolidation_lw[2][2] / 1e3, lw_err,
            r->consolidation_porosity, r->consolidation_stability, r->height0, r->volume0,
            r->seconds_consolidation);
    fprintf(f, " \"peak\": {\"stress_ratio\": %.10g, \"axial_strain\": %.10g, "
               "\"phi_deg\": %.10g},\n",
            r->peak_ratio, r->peak_axial_strain, r->peak_phi_deg);
    fprintf(f, " \"end\": {\"stress_ratio\": %.10g, \"phi_deg\": %.10g, \"axial_strain\": %.10g, "
               "\"volumetric_strain\": %.10g},\n",
            r->end_ratio, r->end_phi_deg, r->curve[r->ncurve - 1].axial_strain,
            r->curve[r->ncurve - 1].volumetric_strain);
    fprintf(f, " \"volumetric_strain_at\": {");
    const double at[3] = {0.05, 0.1, 0.2};
    for (int k = 0; k < 3; k++) {
        double v = ev_at(r, at[k]);
        if (isnan(v))
            fprintf(f, "%s\"%g\": null", k ? ", " : "", at[k]);
        else
            fprintf(f, "%s\"%g\": %.10g", k ? ", " : "", at[k], v);
    }
    fprintf(f, "},\n \"dilatancy_deg\": {\"max\": %.10g, \"definition\": \"sin psi = -(d eps_v/d "
               "eps_a) / (2 - d eps_v/d eps_a), compression positive, slope over +-0.5 %% axial "
               "strain\"},\n \"e50_mpa\": %.10g, \"inertial_number_max\": %.6g, "
               "\"servo_error_max\": %.6g, \"still_rising\": %d,\n",
            r->dilatancy_deg, r->e50 / 1e6, r->inertial_number_max, r->servo_error_max,
            r->still_rising);
    fprintf(f, " \"definitions\": {\"coordination_spheres\": \"2 sphere-sphere contacts / "
               "spheres (yade_triaxial.py's coordination_spheres)\", "
               "\"coordination_mechanical_rattlers_removed\": \"2 C' / N', N' the spheres with "
               "two contacts or more (walls counted), C' the sphere-sphere contacts between two of "
               "them (not yade_triaxial.py's Thornton coordination_mechanical)\", \"e50_mpa\": "
               "\"q_peak / 2 over the axial strain where q first reaches it\", \"iter\": \"DEM "
               "steps since the loading began\", \"porosity\": \"1 - solid / box, the spheres "
               "clipped at the walls\"},\n");
    fprintf(f, " \"steps\": %ld, \"dt\": %.10g, \"wall_clock_s\": %.4g, \"cpu_s\": %.4g,\n",
            r->steps, r->dt, wall_clock, cpu);
    fprintf(f, " \"curves\": {\n");
    int first = 1;
    COLUMN("axial_strain", axial_strain, 1);
    COLUMN("volumetric_strain", volumetric_strain, 1);
    COLUMN("sigma1_kpa", sigma1, 1e-3);
    COLUMN("sigma3_kpa", sigma3, 1e-3);
    COLUMN("sigma1_lw_kpa", sigma1_lw, 1e-3);
    COLUMN("sigma3_lw_kpa", sigma3_lw, 1e-3);
    COLUMN("q_kpa", q, 1e-3);
    COLUMN("p_kpa", p, 1e-3);
    COLUMN("stress_ratio", ratio, 1);
    COLUMN("coordination_spheres", coordination, 1);
    COLUMN("coordination_mechanical_rattlers_removed", coordination_mechanical, 1);
    COLUMN("porosity", porosity, 1);
    COLUMN("stability", stability, 1);
    COLUMN("inertial_number", inertial_number, 1);
    COLUMN("servo_error", servo_error, 1);
    COLUMN("iter", step - r->consolidation_steps, 1);
    fprintf(f, "\n }\n}\n");
    return fclose(f) != 0;
}

static int export_specimen(const char *dir, const gp_specimen3d *sp)
{
    mkdir(dir, 0777);
    char path[4096];
    snprintf(path, sizeof path, "%s/spheres.txt", dir);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f, "# x y z r (m): grainpack's sample S0, bench_triax\n");
    for (size_t i = 0; i < sp->stats.sample_particles; i++) {
        const double *s = sp->sample_spheres + 4 * i;
        fprintf(f, "%.17g %.17g %.17g %.17g\n", s[0], s[1], s[2], s[3]);
    }
    int bad = fclose(f) != 0;
    snprintf(path, sizeof path, "%s/box.json", dir);
    if (!(f = fopen(path, "w"))) {
        perror(path);
        return 1;
    }
    const double *b = sp->sample_box;
    fprintf(f, "{\"lo\": [0, 0, 0], \"hi\": [%.17g, %.17g, %.17g], \"box\": [%.17g, %.17g, %.17g], "
               "\"axial_axis\": 2, \"grainpack\": {\"particles\": %zu, \"porosity\": %.17g, "
               "\"stability\": %.6g}}\n",
            b[0], b[1], b[2], b[0], b[1], b[2], sp->stats.sample_particles,
            sp->stats.sample_porosity, sp->stats.stability);
    return (fclose(f) != 0) | bad;
}

/* ------------------------------------------------------------------ the study */

#define MAX_LIST 16

/* a comma-separated list of numbers into v (at most MAX_LIST); the count, 0 if malformed */
static int parse_list(const char *a, double *v)
{
    int n = 0;
    const char *q = a;
    while (*q) {
        char *end;
        double x = strtod(q, &end);
        if (end == q || n == MAX_LIST)
            return 0;
        v[n++] = x;
        if (*end == ',')
            q = end + 1;
        else if (*end == '\0')
            q = end;
        else
            return 0;
    }
    return n;
}

typedef struct study_run {
    int ok;
    double peak, phi, eps_peak, imax, servo, seconds, cpu, sigma1, sigma3, dt;
    long steps, consolidation_steps;
    size_t spheres;
} study_run;

typedef struct study_mc {
    int ok;
    double phi, c, residual;
} study_mc;

static void study_one(const gp_spec3d *spec, const double *xyzr, size_t n, const double *hi,
                      double confining_kpa, double rate, double strain, int threads,
                      study_run *out)
{
    memset(out, 0, sizeof *out);
    out->spheres = n;
    gp_triax_params p;
    gp_triax_params_defaults(&p);
    p.confining = confining_kpa * 1e3;
    p.strain_rate = rate;
    p.axial_strain = strain;
    p.threads = threads;
    p.d50 = d50_by_mass(xyzr, n);
    p.max_steps = gp_triax_estimate_steps(&spec->material, 0.5 * spec->sieve[0].diameter, &p);
    const double lo[3] = {0, 0, 0};
    gp_triax_result *r = NULL;
    gp_error e;
    double c0 = cpu_seconds(), t0 = gp_clock_seconds();
    gp_status st = gp_triax_run(&spec->material, xyzr, n, lo, hi, &p, NULL, NULL, NULL, &r, &e);
    out->seconds = gp_clock_seconds() - t0;
    out->cpu = cpu_seconds() - c0;
    if (st != GP_OK) {
        fprintf(stderr, "  triax failed: %s\n", e.message);
        return;
    }
    size_t kp = 0; /* the peak's sample, for its stresses (as the kind's envelope takes them) */
    for (size_t k = 1; k < r->ncurve; k++)
        if (r->curve[k].ratio > r->curve[kp].ratio)
            kp = k;
    out->ok = 1;
    out->peak = r->peak_ratio;
    out->phi = r->peak_phi_deg;
    out->eps_peak = r->peak_axial_strain;
    out->imax = r->inertial_number_max;
    out->servo = r->servo_error_max;
    out->sigma1 = r->curve[kp].sigma1;
    out->sigma3 = r->curve[kp].sigma3;
    out->steps = r->steps;
    out->consolidation_steps = r->consolidation_steps;
    out->dt = r->dt;
    if (r->still_rising)
        fprintf(stderr, "  warning: still rising at the end of the loading\n");
    gp_triax_result_destroy(r);
}

static void study_envelope(const study_run *runs, int npress, study_mc *mc)
{
    double s3[MAX_LIST], s1[MAX_LIST];
    int k = 0;
    memset(mc, 0, sizeof *mc);
    for (int j = 0; j < npress; j++)
        if (runs[j].ok) {
            s3[k] = runs[j].sigma3;
            s1[k] = runs[j].sigma1;
            k++;
        }
    if (k < 2) /* one test is its own phi: no envelope */
        return;
    gp_error e;
    mc->ok = gp_triax_mohr_coulomb(s3, s1, (size_t)k, &mc->phi, &mc->c, &mc->residual, &e)
             == GP_OK;
    if (!mc->ok)
        fprintf(stderr, "  Mohr-Coulomb: %s\n", e.message);
}

/* mean and sample standard deviation (n - 1) of the x[i] with ok[i]; the count */
static int mean_sd(const double *x, const int *ok, int n, double *mean, double *sd)
{
    int k = 0;
    double s = 0, ss = 0;
    for (int i = 0; i < n; i++)
        if (ok[i]) {
            s += x[i];
            k++;
        }
    *mean = k ? s / k : NAN;
    for (int i = 0; i < n; i++)
        if (ok[i])
            ss += (x[i] - *mean) * (x[i] - *mean);
    *sd = k > 1 ? sqrt(ss / (k - 1)) : NAN;
    return k;
}

static void run_cells(char *b, size_t n, const study_run *r)
{
    if (!r->ok)
        snprintf(b, n, "failed | - | - | - | %.1f / -", r->seconds);
    else
        snprintf(b, n, "%.4f | %.2f | %.2f %% | %.2e | %.1f / %ld + %ld", r->peak, r->phi,
                 100 * r->eps_peak, r->imax, r->seconds, r->consolidation_steps,
                 r->steps - r->consolidation_steps);
}

static int study(const gp_spec3d *base, const double *seeds, int nseeds, const double *press,
                 int npress, int tiling, int parts, double rate, double strain, int threads)
{
    /* [seed][pressure][0 = S0, 1 = tiled] */
    static study_run runs[MAX_LIST][MAX_LIST][2];
    static study_mc mc[MAX_LIST][2];
    const char *name[2] = {"S0", "tiled"};
    double t_all = gp_clock_seconds();
    size_t nsample = 0, ntiled = 0;
    for (int i = 0; i < nseeds; i++) {
        gp_spec3d spec = *base;
        spec.seed = (uint64_t)seeds[i];
        spec.tiling[0] = spec.tiling[1] = spec.tiling[2] = tiling;
        gp_specimen3d *sp = NULL;
        gp_error e;
        double t0 = gp_clock_seconds();
        gp_status st = gp_specimen3d_build(&spec, NULL, NULL, NULL, &sp, &e);
        if (st != GP_OK) {
            fprintf(stderr, "seed %llu: specimen: %s\n", (unsigned long long)spec.seed, e.message);
            gp_specimen3d_destroy(sp);
            for (int j = 0; j < npress; j++)
                runs[i][j][0].ok = runs[i][j][1].ok = 0;
            continue;
        }
        nsample = sp->stats.sample_particles;
        ntiled = sp->count;
        fprintf(stderr, "seed %llu: specimen built in %.2f s: sample %zu spheres (porosity %.4f), "
                        "tiled %zu (porosity %.4f)\n",
                (unsigned long long)spec.seed, gp_clock_seconds() - t0, nsample,
                sp->stats.sample_porosity, ntiled, sp->stats.porosity);
        for (int j = 0; j < npress; j++)
            for (int w = 0; w < 2; w++) {
                study_run *r = &runs[i][j][w];
                memset(r, 0, sizeof *r);
                if (!(parts & (1 << w)) || (w == 1 && tiling < 2))
                    continue;
                if (w == 0)
                    study_one(&spec, sp->sample_spheres, nsample, sp->sample_box, press[j], rate,
                              strain, threads, r);
                else
                    study_one(&spec, sp->spheres, sp->count, sp->box, press[j], rate, strain,
                              threads, r);
                fprintf(stderr, "seed %llu %s %g kPa: %s peak %.4f at %.2f %%, phi %.2f deg, "
                                "I max %.2e, servo error max %.2e, %ld + %ld steps, dt %.2f us, "
                                "%.1f s wall, %.1f s CPU (all %.0f s)\n",
                        (unsigned long long)spec.seed, name[w], press[j],
                        r->ok ? "ok" : "FAILED", r->peak, 100 * r->eps_peak, r->phi, r->imax,
                        r->servo, r->consolidation_steps, r->steps - r->consolidation_steps,
                        1e6 * r->dt, r->seconds, r->cpu, gp_clock_seconds() - t_all);
            }
        gp_specimen3d_destroy(sp);
        for (int w = 0; w < 2; w++) {
            study_run col[MAX_LIST];
            for (int j = 0; j < npress; j++)
                col[j] = runs[i][j][w];
            study_envelope(col, npress, &mc[i][w]);
        }
    }
    int tiled = tiling > 1 && (parts & 2);
    /* the scatter of S0 over the seeds */
    double m_phi[MAX_LIST], s_phi[MAX_LIST], m_t[MAX_LIST], s_t[MAX_LIST], m_mc[2], s_mc[2];
    int k_phi[MAX_LIST], k_t[MAX_LIST], k_mc[2];
    for (int j = 0; j < npress; j++) {
        double x[MAX_LIST], y[MAX_LIST];
        int ok[MAX_LIST], oky[MAX_LIST];
        for (int i = 0; i < nseeds; i++) {
            x[i] = runs[i][j][0].phi, ok[i] = runs[i][j][0].ok;
            y[i] = runs[i][j][1].phi, oky[i] = runs[i][j][1].ok;
        }
        k_phi[j] = mean_sd(x, ok, nseeds, &m_phi[j], &s_phi[j]);
        k_t[j] = mean_sd(y, oky, nseeds, &m_t[j], &s_t[j]);
    }
    for (int w = 0; w < 2; w++) {
        double x[MAX_LIST];
        int ok[MAX_LIST];
        for (int i = 0; i < nseeds; i++)
            x[i] = mc[i][w].phi, ok[i] = mc[i][w].ok;
        k_mc[w] = mean_sd(x, ok, nseeds, &m_mc[w], &s_mc[w]);
    }
    char tn[32];
    snprintf(tn, sizeof tn, "%dx%dx%d", tiling, tiling, tiling);
    printf("\nS0: %zu spheres; %s tiling: %zu spheres; rate %g /s to axial strain %g, drained, "
           "%d thread%s; wall time %.0f s in all\n\n",
           nsample, tn, ntiled, rate, strain, threads, threads == 1 ? "" : "s",
           gp_clock_seconds() - t_all);
    printf("| seed | sigma3 (kPa) | S0 peak sigma1/sigma3 | S0 phi_peak (deg) | S0 eps_a at peak | "
           "S0 I max | S0 s / steps (consolidation + loading) | %s peak sigma1/sigma3 | %s "
           "phi_peak (deg) | %s eps_a at peak | %s I max | %s s / steps (consolidation + "
           "loading) | %s phi_peak within S0 mean +- 2 sd |\n",
           tn, tn, tn, tn, tn, tn);
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < nseeds; i++)
        for (int j = 0; j < npress; j++) {
            char a[160], b[160], in[96] = "-";
            run_cells(a, sizeof a, &runs[i][j][0]);
            if (tiled)
                run_cells(b, sizeof b, &runs[i][j][1]);
            else
                snprintf(b, sizeof b, "- | - | - | - | -");
            if (tiled && runs[i][j][1].ok && k_phi[j] > 1) {
                double d = (runs[i][j][1].phi - m_phi[j]) / s_phi[j];
                snprintf(in, sizeof in, "%s (%+.2f sd)", fabs(d) <= 2 ? "yes" : "NO", d);
            }
            printf("| %.0f | %g | %s | %s | %s |\n", seeds[i], press[j], a, b, in);
        }
    for (int i = 0; i < nseeds; i++) {
        char a[96] = "-", b[96] = "-", in[96] = "-";
        if (mc[i][0].ok)
            snprintf(a, sizeof a, "phi' %.2f deg (c' %.2f kPa)", mc[i][0].phi, mc[i][0].c / 1e3);
        if (tiled && mc[i][1].ok)
            snprintf(b, sizeof b, "phi' %.2f deg (c' %.2f kPa)", mc[i][1].phi, mc[i][1].c / 1e3);
        if (tiled && mc[i][1].ok && k_mc[0] > 1) {
            double d = (mc[i][1].phi - m_mc[0]) / s_mc[0];
            snprintf(in, sizeof in, "%s (%+.2f sd)", fabs(d) <= 2 ? "yes" : "NO", d);
        }
        printf("| %.0f | Mohr-Coulomb | | %s | | | | | %s | | | | %s |\n", seeds[i], a, b, in);
    }
    for (int j = 0; j < npress; j++) {
        char b[96] = "-";
        if (tiled && k_t[j])
            snprintf(b, sizeof b, "%.2f +- %.2f (n %d)", m_t[j], s_t[j], k_t[j]);
        printf("| mean +- sd | %g | | %.2f +- %.2f (n %d; 2 sd band %.2f-%.2f) | | | | | %s | | "
               "| | |\n",
               press[j], m_phi[j], s_phi[j], k_phi[j], m_phi[j] - 2 * s_phi[j],
               m_phi[j] + 2 * s_phi[j], b);
    }
    {
        char b[96] = "-";
        if (tiled && k_mc[1])
            snprintf(b, sizeof b, "phi' %.2f +- %.2f (n %d)", m_mc[1], s_mc[1], k_mc[1]);
        printf("| mean +- sd | Mohr-Coulomb | | phi' %.2f +- %.2f (n %d; 2 sd band %.2f-%.2f) | | "
               "| | | %s | | | | |\n",
               m_mc[0], s_mc[0], k_mc[0], m_mc[0] - 2 * s_mc[0], m_mc[0] + 2 * s_mc[0], b);
    }
    return 0;
}

int main(int argc, char **argv)
{
    unsigned long long seed = 7;
    double confining_kpa = 50, rate = 0.01, strain = 0.2, box = 0.5, porosity = 0.38;
    int threads = 1;
    const char *json = NULL, *export_dir = NULL;
    double seeds[MAX_LIST], press[MAX_LIST] = {50};
    int nseeds = 0, npress = 1, tiling = 0, parts = 3, bad_list = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--confining") && v) {
            npress = parse_list(argv[++i], press);
            bad_list |= !npress;
            confining_kpa = press[0];
        }
        else if (!strcmp(a, "--seeds") && v) bad_list |= !(nseeds = parse_list(argv[++i], seeds));
        else if (!strcmp(a, "--tiling") && v) bad_list |= (tiling = atoi(argv[++i])) < 1;
        else if (!strcmp(a, "--parts") && v) {
            const char *q = argv[++i];
            parts = (strstr(q, "s0") ? 1 : 0) | (strstr(q, "tiled") ? 2 : 0);
            bad_list |= !parts;
        }
        else if (!strcmp(a, "--rate") && v) rate = atof(argv[++i]);
        else if (!strcmp(a, "--strain") && v) strain = atof(argv[++i]);
        else if (!strcmp(a, "--threads") && v) threads = atoi(argv[++i]);
        else if (!strcmp(a, "--box") && v) box = atof(argv[++i]);
        else if (!strcmp(a, "--porosity") && v) porosity = atof(argv[++i]);
        else if (!strcmp(a, "--json") && v) json = argv[++i];
        else if (!strcmp(a, "--export") && v) export_dir = argv[++i];
        else if (a[0] != '-') seed = strtoull(a, NULL, 10);
        else
            bad_list = 1;
    }
    int is_study = nseeds > 0 || tiling > 0 || npress > 1;
    if (bad_list || (is_study && (json || export_dir))) {
        fprintf(stderr, "usage: bench_triax [SEED] [--confining KPA] [--rate 1/S] "
                        "[--strain E] [--threads N] [--box M] [--porosity P] [--json FILE] "
                        "[--export DIR]\n"
                        "       bench_triax --seeds S,S,... [--tiling N] [--confining KPA,KPA,...] "
                        "[--parts s0,tiled] [--rate 1/S] [--strain E] [--threads N] [--box M] "
                        "[--porosity P]\n");
        return 2;
    }
    gp_spec3d spec;
    gp_spec3d_defaults(&spec);
    spec.seed = seed;
    spec.box[0] = spec.box[1] = spec.box[2] = box;
    spec.porosity = porosity;
    if (is_study) {
        if (!nseeds)
            seeds[nseeds++] = (double)seed;
        spec.threads = threads;
        return study(&spec, seeds, nseeds, press, npress, tiling ? tiling : 1, parts, rate,
                     strain, threads);
    }
    gp_specimen3d *sp = NULL;
    gp_error e;
    double t0 = gp_clock_seconds();
    gp_status st = gp_specimen3d_build(&spec, NULL, NULL, NULL, &sp, &e);
    double t_build = gp_clock_seconds() - t0;
    if (st != GP_OK) {
        fprintf(stderr, "specimen: %s\n", e.message);
        gp_specimen3d_destroy(sp);
        return 1;
    }
    size_t n = sp->stats.sample_particles;
    if (export_dir && export_specimen(export_dir, sp))
        return 1;
    gp_triax_params p;
    gp_triax_params_defaults(&p);
    p.confining = confining_kpa * 1e3;
    p.strain_rate = rate;
    p.axial_strain = strain;
    p.threads = threads;
    p.d50 = d50_by_mass(sp->sample_spheres, n);
    double r_min = 0.5 * spec.sieve[0].diameter; /* the sieve's smallest grain, as a plan has it */
    p.max_steps = gp_triax_estimate_steps(&spec.material, r_min, &p);
    const double lo[3] = {0, 0, 0};
    gp_triax_result *r = NULL;
    double c0 = cpu_seconds();
    t0 = gp_clock_seconds();
    st = gp_triax_run(&spec.material, sp->sample_spheres, n, lo, sp->sample_box, &p, NULL, NULL,
                      NULL, &r, &e);
    double wall = gp_clock_seconds() - t0, cpu = cpu_seconds() - c0;
    if (st != GP_OK) {
        fprintf(stderr, "triax: %s\n", e.message);
        gp_specimen3d_destroy(sp);
        return 1;
    }
    double lw_err = 0; /* the largest |Love-Weber - wall| / wall of the three axes */
    for (int a = 0; a < 3; a++)
        lw_err = fmax(lw_err, fabs(r->consolidation_lw[a][a] - r->consolidation_wall[a])
                                  / r->consolidation_wall[a]);
    double cons_err = 0; /* the walls against sigma3 */
    for (int a = 0; a < 3; a++)
        cons_err = fmax(cons_err, fabs(r->consolidation_wall[a] - p.confining) / p.confining);
    long load_steps = r->steps - r->consolidation_steps;
    char ev5[32], ev10[32], ev20[32];
    pct(ev5, sizeof ev5, ev_at(r, 0.05));
    pct(ev10, sizeof ev10, ev_at(r, 0.10));
    pct(ev20, sizeof ev20, ev_at(r, 0.20));
    printf("| seed | spheres | sigma3 (kPa) | rate (1/s) | axial strain | steps (consolidation + "
           "loading) | estimate | dt (us) | s consolidation | s loading | CPU s | steps/s (wall, "
           "CPU) | peak sigma1/sigma3 | strain at peak | phi peak (deg) | eps_v at 5 / 10 / 20 %% "
           "| I max | servo error max | wall vs Love-Weber at consolidation | walls vs sigma3 |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    printf("| %llu | %zu | %g | %g | %g | %ld + %ld | %ld | %.2f | %.2f | %.2f | %.2f | %.0f, %.0f "
           "| %.4f | %.4f | %.2f | %s / %s / %s | %.2e | %.2e | %.2e | %.2e |\n",
           seed, n, confining_kpa, rate, strain, r->consolidation_steps, load_steps, p.max_steps,
           1e6 * r->dt, r->seconds_consolidation, r->seconds_loading, cpu,
           (double)r->steps / (r->seconds_consolidation + r->seconds_loading),
           (double)r->steps / cpu, r->peak_ratio,
           r->peak_axial_strain, r->peak_phi_deg, ev5, ev10, ev20, r->inertial_number_max,
           r->servo_error_max, lw_err, cons_err);
    fprintf(stderr, "specimen built in %.2f s (porosity %.4f); triaxial %.2f s wall, %.2f s CPU; "
                    "end ratio %.4f, dilatancy %.2f deg, E50 %.2f MPa, still rising %d\n",
            t_build, sp->stats.porosity, wall, cpu, r->end_ratio, r->dilatancy_deg, r->e50 / 1e6,
            r->still_rising);
    int bad = json ? write_json(json, r, &p, seed, n, lw_err, wall, cpu) : 0;
    gp_triax_result_destroy(r);
    gp_specimen3d_destroy(sp);
    return bad;
}
