/* bench_voronoi3d.c -- the bounded 3D Voronoi tessellation (gp_voronoi3d): one table of full
 * builds of 10^4 and 10^5 random seeds in the unit cube on one thread (seconds, cells/s, and
 * the error |sum of cell volumes - container| / container next to them), voro++ on the same
 * seeds when its reference program is at hand, and the cost of one local move (try_move then
 * commit or rollback, half and half; steps of half a seed spacing) at N = 1,000 and 100,000.
 *
 * Usage: bench_voronoi3d [path of voro_ref]; without it, $GP_VORO_REF, then ../tests/voro_ref
 * next to this program (the build tree's), else the voro++ column says "n/a". voro++'s time
 * is what the reference program measures itself (insertion and cells, not the file I/O). */
#include "gp_clock.h"
#include "gp_voronoi3d.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;

static double u01(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static double *seeds_in_cube(size_t n)
{
    double *s = malloc(3 * n * sizeof(double));
    for (size_t i = 0; s && i < 3 * n; i++) s[i] = u01();
    return s;
}

/* voro++'s seconds on the same seeds through the reference program, or -1. */
static double voro_seconds(const char *ref, const double *s, size_t n)
{
    if (!ref || access(ref, X_OK) != 0) return -1;
    char path[] = "/tmp/gp_bench_voro_XXXXXX", log[64], cmd[4200];
    int fd = mkstemp(path);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f) return -1;
    fprintf(f, "0 0 0 1 1 1\n");
    for (size_t i = 0; i < n; i++) fprintf(f, "%.17g %.17g %.17g\n", s[3 * i], s[3 * i + 1], s[3 * i + 2]);
    fclose(f);
    snprintf(log, sizeof log, "%s.err", path);
    snprintf(cmd, sizeof cmd, "'%s' '%s' > /dev/null 2> '%s'", ref, path, log);
    double t = -1;
    if (system(cmd) == 0 && (f = fopen(log, "r"))) {
        if (fscanf(f, "voro++ seconds %lf", &t) != 1) t = -1;
        fclose(f);
    }
    unlink(path);
    unlink(log);
    return t;
}

static void build_row(size_t n, const char *ref)
{
    double *s = seeds_in_cube(n), best = INFINITY, err = NAN;
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    for (int rep = 0; rep < 2 && s; rep++) {
        double t0 = gp_clock_seconds();
        gp_voronoi3d *v = gp_voronoi3d_create(&c, s, n, NULL);
        double t = gp_clock_seconds() - t0;
        if (!v) break;
        best = fmin(best, t);
        double sum = 0;
        for (size_t i = 0; i < n; i++) sum += gp_voronoi3d_cell_volume(v, i);
        err = fabs(sum - 1.0);
        gp_voronoi3d_destroy(v);
    }
    double tv = voro_seconds(ref, s, n);
    char vs[32] = "n/a";
    if (tv >= 0) snprintf(vs, sizeof vs, "%.3f", tv);
    printf("| build | %7zu | %9.3f s | %9.0f cells/s | %9.2e | %9s s |       |\n", n, best,
           (double)n / best, err, vs);
    free(s);
}

static void move_row(size_t n, int moves)
{
    double *s = seeds_in_cube(n), lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_voronoi3d *v = s ? gp_voronoi3d_create(&c, s, n, NULL) : NULL;
    if (!v) {
        printf("| move  | %7zu | build failed\n", n);
        free(s);
        return;
    }
    double step = 0.5 * cbrt(1.0 / (double)n), t0 = gp_clock_seconds(), changed = 0;
    int done = 0;
    for (int m = 0; m < moves; m++) {
        size_t i = (size_t)(u01() * (double)n);
        double p[3];
        gp_voronoi3d_seed(v, i, p);
        for (int a = 0; a < 3; a++) p[a] = fmin(1, fmax(0, p[a] + step * (2 * u01() - 1)));
        if (gp_voronoi3d_try_move(v, i, p, NULL) != GP_OK) continue;
        changed += (double)gp_voronoi3d_changed(v, NULL);
        if (m & 1) gp_voronoi3d_commit(v);
        else gp_voronoi3d_rollback(v);
        done++;
    }
    double t = gp_clock_seconds() - t0, sum = 0;
    for (size_t i = 0; i < n; i++) sum += gp_voronoi3d_cell_volume(v, i);
    printf("| move  | %7zu | %8.0f us | %9.0f moves/s | %9.2e |             | %5.1f |\n", n,
           1e6 * t / done, done / t, fabs(sum - 1.0), changed / done);
    gp_voronoi3d_destroy(v);
    free(s);
}

int main(int argc, char **argv)
{
    const char *ref = argc > 1 ? argv[1] : getenv("GP_VORO_REF");
    char guess[4096];
    if (!ref) {
        const char *slash = strrchr(argv[0], '/');
        int len = slash ? (int)(slash - argv[0]) : 1;
        snprintf(guess, sizeof guess, "%.*s/../tests/voro_ref", len, slash ? argv[0] : ".");
        ref = guess;
    }
    printf("gp_voronoi3d, one thread, random seeds in the unit cube (error: |sum of cell volumes - "
           "container| / container; time of a move: try_move + commit or rollback; cells: "
           "recomputed per move)\n\n");
    printf("| what  |       N | time        | rate              | error     | voro++      | cells |\n");
    printf("|-------|---------|-------------|-------------------|-----------|-------------|-------|\n");
    build_row(10000, ref);
    build_row(100000, ref);
    move_row(1000, 20000);
    move_row(100000, 20000);
    return 0;
}
