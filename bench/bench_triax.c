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
 * %.17g, SI) and DIR/box.json ({"lo", "hi", "box"}), the sample as its build ended. */
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

int main(int argc, char **argv)
{
    unsigned long long seed = 7;
    double confining_kpa = 50, rate = 0.01, strain = 0.2, box = 0.5, porosity = 0.38;
    int threads = 1;
    const char *json = NULL, *export_dir = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--confining") && v) confining_kpa = atof(argv[++i]);
        else if (!strcmp(a, "--rate") && v) rate = atof(argv[++i]);
        else if (!strcmp(a, "--strain") && v) strain = atof(argv[++i]);
        else if (!strcmp(a, "--threads") && v) threads = atoi(argv[++i]);
        else if (!strcmp(a, "--box") && v) box = atof(argv[++i]);
        else if (!strcmp(a, "--porosity") && v) porosity = atof(argv[++i]);
        else if (!strcmp(a, "--json") && v) json = argv[++i];
        else if (!strcmp(a, "--export") && v) export_dir = argv[++i];
        else if (a[0] != '-') seed = strtoull(a, NULL, 10);
        else {
            fprintf(stderr, "usage: bench_triax [SEED] [--confining KPA] [--rate 1/S] "
                            "[--strain E] [--threads N] [--box M] [--porosity P] [--json FILE] "
                            "[--export DIR]\n");
            return 2;
        }
    }
    gp_spec3d spec;
    gp_spec3d_defaults(&spec);
    spec.seed = seed;
    spec.box[0] = spec.box[1] = spec.box[2] = box;
    spec.porosity = porosity;
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
