/* test_voronoi3d_voro.c -- gp_voronoi3d against voro++ (an independent code), cell by cell, on
 * 1,000 and 10,000 random seeds in a box: volumes within 1e-9 relative, the same number of
 * faces, and the faces' areas (sorted) within 1e-9 of the cell's surface scale.
 *
 * Faces are counted as each code makes them, without any merging: one face per plane that
 * bounds the cell with positive area (gp_voronoi3d.h). voro++ does the same; the two could
 * only disagree on a face whose area is at the level of the tolerances (1e-11 to 1e-12 of the
 * cell), which random seeds do not make -- the test prints the smallest face area on either
 * side so that such a case would show.
 *
 * The reference program (tests/core/3d/voro_ref.cc, built when voro++-dev is installed) comes
 * in as GP_VORO_REF; without it the test fails, saying how to get it. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gp_test.h"
#include "gp_voronoi3d.h"

#ifndef GP_VORO_REF
#define GP_VORO_REF ""
#endif

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double u01(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The areas of cell i's faces, sorted, into a (at most cap); returns the face count. */
static size_t face_areas(const gp_voronoi3d *v, size_t i, double *a, size_t cap)
{
    static double xyz[3 * 4096];
    uint32_t loop[1024];
    size_t nv = gp_voronoi3d_cell_vertices(v, i, xyz, 4096), nf = gp_voronoi3d_cell_face_count(v, i);
    if (nv > 4096) return 0;
    for (size_t f = 0; f < nf && f < cap; f++) {
        size_t m = gp_voronoi3d_cell_face(v, i, f, loop, 1024, NULL);
        double s[3] = {0, 0, 0};
        const double *p0 = xyz + 3 * loop[0];
        for (size_t k = 1; k + 1 < m && m <= 1024; k++) {
            const double *p = xyz + 3 * loop[k], *q = xyz + 3 * loop[k + 1];
            double u[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
            double w[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
            s[0] += u[1] * w[2] - u[2] * w[1];
            s[1] += u[2] * w[0] - u[0] * w[2];
            s[2] += u[0] * w[1] - u[1] * w[0];
        }
        a[f] = 0.5 * sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    }
    qsort(a, nf < cap ? nf : cap, sizeof(double), cmp_double);
    return nf;
}

typedef struct stats {
    double max_rel_vol, max_rel_area, min_area_ours, min_area_ref;
    size_t faces_equal, cells;
} stats;

/* One line of the reference's output against cell i. */
static int compare_line(const gp_voronoi3d *v, size_t i, char *line, stats *st)
{
    char *p = line, *e;
    size_t id = strtoul(p, &e, 10);
    p = e;
    double vol = strtod(p, &e);
    p = e;
    size_t nf = strtoul(p, &e, 10);
    p = e;
    if (id != i || nf > 1024) return 0;
    double ref[1024], ours[1024];
    for (size_t f = 0; f < nf; f++) {
        ref[f] = strtod(p, &e);
        p = e;
    }
    qsort(ref, nf, sizeof(double), cmp_double);
    size_t mf = face_areas(v, i, ours, 1024);
    double mine = gp_voronoi3d_cell_volume(v, i), scale = pow(mine, 2.0 / 3.0);
    st->max_rel_vol = fmax(st->max_rel_vol, fabs(mine - vol) / vol);
    st->cells++;
    if (nf > 0) st->min_area_ref = fmin(st->min_area_ref, ref[0] / scale);
    if (mf > 0) st->min_area_ours = fmin(st->min_area_ours, ours[0] / scale);
    if (mf != nf) return 1;
    st->faces_equal++;
    for (size_t f = 0; f < nf; f++)
        st->max_rel_area = fmax(st->max_rel_area, fabs(ours[f] - ref[f]) / scale);
    return 1;
}

static void compare(size_t n)
{
    const double lo[3] = {0, -1, 2}, hi[3] = {2, 0.5, 3};
    double *s = malloc(3 * n * sizeof(double));
    for (size_t i = 0; i < 3 * n; i++) s[i] = lo[i % 3] + (hi[i % 3] - lo[i % 3]) * u01();
    char path[] = "/tmp/gp_voro_XXXXXX";
    int fd = mkstemp(path);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    CHECK(f != NULL);
    if (!f) return;
    fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g\n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    for (size_t i = 0; i < n; i++) fprintf(f, "%.17g %.17g %.17g\n", s[3 * i], s[3 * i + 1], s[3 * i + 2]);
    fclose(f);
    gp_voronoi3d_container c = gp_voronoi3d_box(lo, hi);
    gp_error err;
    gp_voronoi3d *v = gp_voronoi3d_create(&c, s, n, &err);
    CHECK(v != NULL);
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "'%s' '%s' 2>/dev/null", GP_VORO_REF, path);
    FILE *pipe = v ? popen(cmd, "r") : NULL;
    CHECK(pipe != NULL);
    stats st = {0, 0, INFINITY, INFINITY, 0, 0};
    size_t cap = 1 << 16, lines = 0;
    char *line = malloc(cap);
    int ok = 1;
    while (pipe && fgets(line, (int)cap, pipe)) ok &= compare_line(v, lines++, line, &st);
    CHECK(pipe && pclose(pipe) == 0);
    CHECK(ok);
    CHECK(lines == n);
    printf("voro++ against gp_voronoi3d, %zu seeds: max relative volume difference %.3g; face "
           "counts equal in %zu of %zu cells; max face-area difference %.3g (of vol^(2/3)); "
           "smallest face area %.3g (ours) %.3g (voro++)\n",
           n, st.max_rel_vol, st.faces_equal, st.cells, st.max_rel_area, st.min_area_ours,
           st.min_area_ref);
    CHECK(st.max_rel_vol <= 1e-9);
    CHECK(st.faces_equal == n);
    CHECK(st.max_rel_area <= 1e-9);
    double sum = 0;
    for (size_t i = 0; v && i < n; i++) sum += gp_voronoi3d_cell_volume(v, i);
    CHECK_REL(sum, gp_voronoi3d_container_volume(v), 1e-12);
    free(line);
    gp_voronoi3d_destroy(v);
    unlink(path);
    free(s);
}

int main(void)
{
    if (GP_VORO_REF[0] == '\0' || access(GP_VORO_REF, X_OK) != 0) {
        fprintf(stderr, "test_voronoi3d_voro: the voro++ reference program is missing (%s): "
                        "install voro++-dev (deploy/install-deps.sh --test) and reconfigure\n",
                GP_VORO_REF[0] ? GP_VORO_REF : "not built");
        CHECK(0);
        return gp_test_summary();
    }
    compare(1000);
    compare(10000);
    return gp_test_summary();
}
