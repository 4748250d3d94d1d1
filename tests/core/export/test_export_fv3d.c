/* test_export_fv3d.c -- the exports of a 3D Fourier-Voronoi specimen (gp_export_pack_fv3d and its
 * formats lammps, liggghts, yade, vtk, stl), checked against the specimen itself (gp_fv3d.h): the
 * pack's records read back bit for bit (the placed vertices those of gp_fv3d_grain_vertices);
 * each format's text parsed back -- the lammps tar's members, sizes and checksums, every rigid
 * body's mass, centre of mass and inertia tensor, the atoms' masses summing to each grain's; the
 * LIGGGHTS templates' spheres, masses, tensors and weights; YADE's clumps and "#grain" lines; the
 * VTK and STL meshes, whose enclosed volumes are the grains' to 1e-9 -- the same bytes whatever
 * the read size, a pack without clumps refused by the DEM formats, corrupt and stale packs.
 * (Loading the files into LAMMPS, LIGGGHTS, YADE and VTK is tests/integration/test_export_fv3d.py,
 * which runs this program as `test_export_fv3d --write DIR [N]` for its files.)
 *
 *   test_export_fv3d                  the checks
 *   test_export_fv3d --write DIR [N]  writes a specimen of N grains (30) and its files to DIR:
 *                                     fv3d-lammps.tar, fv3d-liggghts.in, fv3d-yade.txt, fv3d.vtk,
 *                                     fv3d.stl and fv3d.json (the specimen's own values)
 *   test_export_fv3d --bench N [L]    times the pack and every export of N grains at mesh level L
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gp_export.h"
#include "gp_fourier.h"
#include "gp_fv3d.h"
#include "gp_test.h"

#define RHO 2650.5

static double D[16];

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* N grains in a unit box, lognormal COV 0.5 of cells, mesh level `level`, clumps when asked */
static gp_fv3d *specimen(size_t n, unsigned level, int clumps, uint64_t seed)
{
    gp_law *law = gp_law_create(GP_LAW_LOGNORMAL, 1.0 / (double)n, 0.5, NULL);
    gp_fv3d_spec sp;
    gp_fv3d_spec_defaults(&sp);
    sp.particles = n;
    sp.law = law;
    sp.D = D;
    sp.nmodes = 16;
    sp.mesh_level = level;
    sp.seed = seed;
    sp.solid_fraction = 0.4;
    sp.spheres_max = 12;
    sp.outputs = GP_OUT3_GRAINS | (clumps ? GP_OUT3_CLUMPS : 0);
    sp.threads = 2;
    gp_fv3d *s = NULL;
    gp_error e;
    if (gp_fv3d_build(&sp, NULL, NULL, NULL, &s, &e) != GP_OK) {
        fprintf(stderr, "gp_fv3d_build: %s\n", e.message);
        s = NULL;
    }
    gp_law_destroy(law);
    return s;
}

/* ------------------------------------------------------------------ reading an export */

typedef struct text {
    char *p;
    size_t n, cap;
} text;

static void text_add(text *t, const char *buf, size_t n)
{
    if (t->n + n + 1 > t->cap) {
        t->cap = (t->n + n + 1) * 2;
        t->p = realloc(t->p, t->cap);
    }
    memcpy(t->p + t->n, buf, n);
    t->n += n;
    t->p[t->n] = 0;
}

/* the whole export of pack in format f, read in pieces of `piece` bytes (NULL on error, the
 * message in err) */
static char *export_all(gp_export_format f, const void *pack, size_t len, size_t piece, size_t *n,
                        gp_error *err)
{
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *e;
    if (gp_export_open(f, &src, &e, err)) return NULL;
    text t = {0};
    text_add(&t, "", 0);
    char *buf = malloc(piece);
    for (;;) {
        size_t k;
        if (gp_export_read(e, buf, piece, &k, err)) {
            free(t.p);
            t.p = NULL;
            break;
        }
        if (k == 0) break;
        text_add(&t, buf, k);
    }
    free(buf);
    gp_export_destroy(e);
    if (n) *n = t.n;
    return t.p;
}

/* the next line of *s (NUL-terminated in place); NULL at the end */
static char *next_line(char **s)
{
    if (!*s || !**s) return NULL;
    char *l = *s, *nl = strchr(l, '\n');
    if (nl) {
        *nl = 0;
        *s = nl + 1;
    } else {
        *s = l + strlen(l);
    }
    return l;
}

/* parses up to max doubles from line; returns their count */
static int doubles(const char *line, double *v, int max)
{
    int k = 0;
    char *end;
    while (k < max) {
        double x = strtod(line, &end);
        if (end == line) break;
        v[k++] = x;
        line = end;
    }
    return k;
}

/* ------------------------------------------------------------------ the specimen's values */

static void upper(const double I[9], double out[6])
{
    const int u[6] = {0, 4, 8, 1, 2, 5};
    for (int k = 0; k < 6; k++) out[k] = RHO * I[u[k]];
}

/* the volume enclosed by triangles (a, b, c) of vertices x, about origin o */
static double tri_volume(const double *a, const double *b, const double *c, const double o[3])
{
    double p[3], q[3], r[3];
    for (int k = 0; k < 3; k++) {
        p[k] = a[k] - o[k];
        q[k] = b[k] - o[k];
        r[k] = c[k] - o[k];
    }
    return (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
            p[2] * (q[0] * r[1] - q[1] * r[0])) / 6.0;
}

static double total_volume(const gp_fv3d *s)
{
    double v = 0;
    for (size_t g = 0; g < gp_fv3d_count(s); g++) v += gp_fv3d_grain_at(s, g)->volume;
    return v;
}

static size_t total_spheres(const gp_fv3d *s)
{
    size_t n = 0;
    for (size_t g = 0; g < gp_fv3d_count(s); g++) n += gp_fv3d_grain_at(s, g)->nspheres;
    return n;
}

/* ------------------------------------------------------------------ the pack */

static void check_pack(const gp_fv3d *s, const void *pack, size_t len)
{
    const double *dirs;
    const uint32_t *tris;
    size_t n = gp_fv3d_count(s), nd = gp_fv3d_directions(s, &dirs), nt = gp_fv3d_triangles(s, &tris);
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export_reader *r;
    gp_error e;
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    const gp_export_info *in = gp_export_reader_info(r);
    CHECK(in->dim == GP_EXPORT_FV3D && in->nitems == n && in->npoints == nd &&
          in->ntriangles == nt && in->ndiscs == total_spheres(s));
    CHECK(in->flags == GP_EXPORT_HAS_CLUMPS && in->density == RHO);
    CHECK(in->volume == total_volume(s));
    CHECK(in->max_extent > 0 && in->max_extent < 1.8);
    for (int k = 0; k < 3; k++) /* the unit box, from the cells' vertices */
        CHECK(fabs(in->lo[k]) < 1e-12 && fabs(in->hi[k] - 1) < 1e-12);
    double *xyz = malloc(3 * nd * sizeof *xyz), *mine = malloc(3 * nd * sizeof *mine);
    int grains_same = 1, verts_same = 1, spheres_same = 1;
    for (size_t g = 0; g < n; g++) {
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        gp_export_grain3 p;
        CHECK(gp_export_reader_grain3(r, g, &p, &e) == GP_OK);
        double I[6];
        upper(gr->inertia, I);
        grains_same &= p.cell == gr->cell && p.sphere_count == gr->nspheres &&
                       !memcmp(p.centre, gr->centre, sizeof p.centre) &&
                       !memcmp(p.rotation, gr->rotation, sizeof p.rotation) &&
                       p.scale == gr->scale && p.volume == gr->volume &&
                       p.mass == RHO * gr->volume &&
                       !memcmp(p.centroid, gr->centroid, sizeof p.centroid) &&
                       !memcmp(p.inertia, I, sizeof I);
        gp_fv3d_grain_vertices(s, g, xyz);
        CHECK(gp_export_reader_vertices(r, g, mine, &e) == GP_OK);
        verts_same &= !memcmp(xyz, mine, 3 * nd * sizeof *xyz);
        for (size_t k = 0; k < gr->nspheres; k++) {
            double q[4];
            CHECK(gp_export_reader_clump_sphere(r, p.sphere_first + k, q, &e) == GP_OK);
            spheres_same &= !memcmp(q, gr->spheres + 4 * k, sizeof q);
        }
    }
    CHECK(grains_same);
    CHECK(verts_same);
    CHECK(spheres_same);
    int ico_same = 1;
    for (size_t k = 0; k < nd; k++) {
        double d[3];
        CHECK(gp_export_reader_direction(r, k, d, &e) == GP_OK);
        ico_same &= !memcmp(d, dirs + 3 * k, sizeof d);
    }
    for (size_t t = 0; t < nt; t++) {
        uint32_t tri[3];
        CHECK(gp_export_reader_triangle(r, t, tri, &e) == GP_OK);
        ico_same &= !memcmp(tri, tris + 3 * t, sizeof tri);
    }
    CHECK(ico_same);
    /* records the pack does not have */
    double q[4];
    gp_export_grain3 p;
    CHECK(gp_export_reader_grain3(r, n, &p, &e) == GP_ERR_INVALID);
    CHECK(gp_export_reader_sphere(r, 0, q, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "fv3d pack") != NULL);
    CHECK(gp_export_reader_clump_sphere(r, in->ndiscs, q, &e) == GP_ERR_INVALID);
    gp_export_reader_destroy(r);
    free(xyz);
    free(mine);
}

/* ------------------------------------------------------------------ lammps */

typedef struct member {
    char name[101];
    char *body; /* NUL-terminated copy */
    size_t size;
} member;

/* The members of a ustar archive (checksums, sizes, the two zero blocks at its end); returns
 * their count (up to max), -1 when it is not well formed. */
static int untar(const char *t, size_t n, member *m, int max)
{
    size_t at = 0;
    int k = 0;
    while (at + 512 <= n) {
        const unsigned char *h = (const unsigned char *)t + at;
        int zero = 1;
        for (int i = 0; i < 512; i++) zero &= h[i] == 0;
        if (zero) {
            /* the end: a second zero block, nothing after it */
            for (size_t i = at; i < n; i++)
                if (t[i]) return -1;
            return n - at == 1024 ? k : -1;
        }
        unsigned sum = 0;
        for (int i = 0; i < 512; i++) sum += (i >= 148 && i < 156) ? ' ' : h[i];
        if (strtoul((const char *)h + 148, NULL, 8) != sum || memcmp(h + 257, "ustar", 6)) return -1;
        size_t size = strtoull((const char *)h + 124, NULL, 8);
        at += 512;
        if (at + size > n || k >= max) return -1;
        if (h[156] == '0') {
            memcpy(m[k].name, h, 100);
            m[k].name[100] = 0;
            m[k].body = malloc(size + 1);
            memcpy(m[k].body, t + at, size);
            m[k].body[size] = 0;
            m[k].size = size;
            k++;
        }
        at += (size + 511) / 512 * 512;
    }
    return -1;
}

static void check_lammps(const gp_fv3d *s, const char *t, size_t n)
{
    member m[4];
    memset(m, 0, sizeof m);
    int k = untar(t, n, m, 4);
    CHECK(k == 3);
    if (k != 3) return;
    CHECK(!strcmp(m[0].name, "lammps-grains/grains.in") &&
          !strcmp(m[1].name, "lammps-grains/grains.rigid") &&
          !strcmp(m[2].name, "lammps-grains/grains.data"));
    CHECK(strlen(m[0].body) == m[0].size && strlen(m[1].body) == m[1].size &&
          strlen(m[2].body) == m[2].size);
    CHECK(strstr(m[0].body, "\nread_data       grains.data\n") != NULL);
    CHECK(strstr(m[0].body, "fix             grains all rigid/small molecule infile grains.rigid\n") != NULL);
    size_t ng = gp_fv3d_count(s);
    /* grains.rigid: a count, then one body a grain, the specimen's values exactly */
    char *c = m[1].body, *l;
    int count = -1, bodies = 0, exact = 1;
    while ((l = next_line(&c))) {
        if (l[0] == '#' || !l[0]) continue;
        if (count < 0) {
            count = atoi(l);
            continue;
        }
        double v[21];
        int nv = doubles(l, v, 21);
        size_t g = (size_t)v[0] - 1;
        if (nv != 20 || g >= ng) {
            exact = 0;
            continue;
        }
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        double I[6];
        upper(gr->inertia, I);
        exact &= g == (size_t)bodies && v[1] == RHO * gr->volume && !memcmp(v + 2, gr->centroid, 24) &&
                 !memcmp(v + 5, I, sizeof I);
        for (int z = 11; z < 20; z++) exact &= v[z] == 0;
        bodies++;
    }
    CHECK(count == (int)ng && bodies == (int)ng);
    CHECK(exact);
    /* grains.data: the atoms, a grain's weighing its mass */
    c = m[2].body;
    size_t natoms = 0, atoms = 0;
    double *mass = calloc(ng, sizeof *mass);
    int in_atoms = 0, pos_ok = 1;
    size_t first = 0, g_at = 0;
    while ((l = next_line(&c))) {
        if (!in_atoms) {
            if (strstr(l, " atoms") && !natoms) natoms = strtoull(l, NULL, 10);
            if (!strcmp(l, "Atoms # hybrid")) in_atoms = 1;
            continue;
        }
        if (!l[0]) continue;
        double v[9];
        if (doubles(l, v, 9) != 8) {
            pos_ok = 0;
            continue;
        }
        size_t g = (size_t)v[7] - 1, id = (size_t)v[0] - 1;
        if (g >= ng) {
            pos_ok = 0;
            continue;
        }
        if (g != g_at) {
            first += gp_fv3d_grain_at(s, g_at)->nspheres;
            g_at = g;
        }
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        const double *q = gr->spheres + 4 * (id - first);
        pos_ok &= id == atoms && id >= first && id - first < gr->nspheres && v[1] == 1 &&
                  v[2] == q[0] && v[3] == q[1] && v[4] == q[2] && v[5] == 2 * q[3];
        mass[g] += v[6] * 4.0 / 3.0 * M_PI * q[3] * q[3] * q[3];
        atoms++;
    }
    CHECK(natoms == total_spheres(s) && atoms == natoms);
    CHECK(pos_ok);
    double worst = 0;
    for (size_t g = 0; g < ng; g++)
        worst = fmax(worst, fabs(mass[g] / (RHO * gp_fv3d_grain_at(s, g)->volume) - 1));
    CHECK(worst < 1e-13);
    printf("lammps: %zu bodies of %zu atoms, members %zu + %zu + %zu bytes; atom masses per grain "
           "within %.1e\n",
           ng, atoms, m[0].size, m[1].size, m[2].size, worst);
    free(mass);
    for (int i = 0; i < k; i++) free(m[i].body);
}

/* ------------------------------------------------------------------ liggghts */

static void check_liggghts(const gp_fv3d *s, char *t)
{
    size_t ng = gp_fv3d_count(s);
    char *c = t, *l;
    size_t templates = 0, weights = 0, cur = 0, sph = 0;
    int exact = 1, in_template = 0, in_dist = 0;
    double wsum = 0, offset = 0;
    while ((l = next_line(&c))) {
        if (l[0] == '#') continue;
        unsigned long long k, ns;
        double rho;
        if (sscanf(l, "fix gpt%llu all particletemplate/multisphere 15485863 atom_type 1 density "
                      "constant %lf nspheres %llu ntry 1000 spheres &",
                   &k, &rho, &ns) == 3) {
            cur = (size_t)k - 1;
            exact &= cur == templates && cur < ng && rho == RHO &&
                     ns == gp_fv3d_grain_at(s, cur)->nspheres;
            in_template = 1;
            sph = 0;
            templates++;
            continue;
        }
        if (in_template && cur < ng) {
            const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, cur);
            double v[8];
            if (strstr(l, "type ") == l + 4) {
                double I[6];
                upper(gr->inertia, I);
                unsigned long long type;
                double mass, J[6];
                int got = sscanf(l, "    type %llu mass %lf inertia_tensor %lf %lf %lf %lf %lf %lf use_density",
                                 &type, &mass, J, J + 1, J + 2, J + 3, J + 4, J + 5);
                /* Ixx Ixy Ixz Iyy Iyz Izz */
                exact &= got == 8 && type == cur + 1 && mass == RHO * gr->volume && J[0] == I[0] &&
                         J[1] == I[3] && J[2] == I[4] && J[3] == I[1] && J[4] == I[5] && J[5] == I[2];
                exact &= sph == gr->nspheres;
                in_template = 0;
                continue;
            }
            if (doubles(l, v, 8) == 4 && sph < gr->nspheres && l[strlen(l) - 1] == '&') {
                const double *q = gr->spheres + 4 * sph;
                for (int a = 0; a < 3; a++) offset = fmax(offset, fabs(v[a] + gr->centroid[a] - q[a]));
                exact &= v[3] == q[3];
                sph++;
                continue;
            }
            exact = 0;
        }
        if (strstr(l, "fix gpdist all particledistribution/discrete 15485867 ") == l) {
            exact &= strtoull(l + 53, NULL, 10) == ng;
            in_dist = 1;
            continue;
        }
        if (in_dist) {
            unsigned long long k;
            double w;
            if (sscanf(l, "    gpt%llu %lf", &k, &w) == 2) {
                exact &= k == weights + 1 && w == RHO * gp_fv3d_grain_at(s, k - 1)->volume / (RHO * total_volume(s));
                wsum += w;
                weights++;
            } else {
                exact = 0;
            }
        }
    }
    CHECK(templates == ng && weights == ng);
    CHECK(exact);
    CHECK(offset < 1e-15);
    CHECK(fabs(wsum - 1) < 1e-12);
    printf("liggghts: %zu templates, spheres about their centroids to %.1e m, weights sum to 1 %+.1e\n",
           templates, offset, wsum - 1);
}

/* ------------------------------------------------------------------ yade */

static void check_yade(const gp_fv3d *s, char *t)
{
    size_t ng = gp_fv3d_count(s);
    char *c = t, *l;
    size_t grains = 0, spheres = 0, py = 0, in_grain = 0;
    long cur = -1;
    int exact = 1, def = 0;
    while ((l = next_line(&c))) {
        CHECK(l[0] != 0); /* textClumps fails on a blank line */
        if (!strncmp(l, "#py ", 4) || !strcmp(l, "#py")) {
            py++;
            def |= strstr(l, "def grainpack_exact(path, clumps") != NULL;
            continue;
        }
        if (!strncmp(l, "#grain ", 7)) {
            double v[14];
            int nv = doubles(l + 7, v, 14);
            cur = (long)v[0];
            if (nv != 13 || cur != (long)grains || cur >= (long)ng) {
                exact = 0;
                continue;
            }
            const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, (size_t)cur);
            double I[6];
            upper(gr->inertia, I);
            exact &= v[1] == gr->nspheres && v[2] == gr->volume && v[3] == RHO * gr->volume &&
                     !memcmp(v + 4, gr->centroid, 24) && !memcmp(v + 7, I, sizeof I);
            grains++;
            in_grain = 0;
            continue;
        }
        if (l[0] == '#') continue;
        double v[6];
        if (doubles(l, v, 6) != 5 || cur < 0 || v[4] != cur) {
            exact = 0;
            continue;
        }
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, (size_t)cur);
        exact &= in_grain < gr->nspheres && !memcmp(v, gr->spheres + 4 * in_grain, 32);
        in_grain++;
        spheres++;
    }
    CHECK(grains == ng && spheres == total_spheres(s));
    CHECK(exact);
    CHECK(def && py > 20);
}

/* ------------------------------------------------------------------ vtk and stl */

static void check_vtk(const gp_fv3d *s, char *t)
{
    const uint32_t *tris;
    size_t ng = gp_fv3d_count(s), nd = gp_fv3d_directions(s, NULL), nt = gp_fv3d_triangles(s, &tris);
    char *c = t, *l;
    CHECK(!strcmp(next_line(&c), "# vtk DataFile Version 3.0"));
    size_t np = 0, nc = 0;
    double *pts = NULL;
    int exact = 1;
    while ((l = next_line(&c))) {
        unsigned long long a;
        if (sscanf(l, "POINTS %llu double", &a) == 1) {
            np = a;
            pts = malloc(3 * np * sizeof *pts);
            for (size_t k = 0; k < np; k++) {
                l = next_line(&c);
                exact &= l && doubles(l, pts + 3 * k, 3) == 3;
            }
            break;
        }
    }
    CHECK(np == ng * nd);
    double *xyz = malloc(3 * nd * sizeof *xyz);
    for (size_t g = 0; g < ng && pts && np == ng * nd; g++) {
        gp_fv3d_grain_vertices(s, g, xyz);
        exact &= !memcmp(xyz, pts + 3 * g * nd, 3 * nd * sizeof *xyz);
    }
    CHECK(exact);
    /* the triangles: the icosphere's, grain by grain; the volumes they enclose */
    l = next_line(&c);
    unsigned long long a, b;
    CHECK(l && sscanf(l, "POLYGONS %llu %llu", &a, &b) == 2 && a == ng * nt && b == 4 * a);
    nc = (size_t)a;
    double sum = 0, worst = 0, *vol = calloc(ng, sizeof *vol);
    int tri_ok = 1;
    for (size_t k = 0; k < nc && np == ng * nd; k++) {
        l = next_line(&c);
        unsigned long long n3, i, j, m;
        size_t g = k / nt;
        if (!l || sscanf(l, "%llu %llu %llu %llu", &n3, &i, &j, &m) != 4 || n3 != 3 || i >= np ||
            j >= np || m >= np) {
            tri_ok = 0;
            break;
        }
        const uint32_t *tt = tris + 3 * (k % nt);
        tri_ok &= i == g * nd + tt[0] && j == g * nd + tt[1] && m == g * nd + tt[2];
        vol[g] += tri_volume(pts + 3 * i, pts + 3 * j, pts + 3 * m, pts + 3 * g * nd);
    }
    CHECK(tri_ok);
    for (size_t g = 0; g < ng; g++) {
        sum += vol[g];
        worst = fmax(worst, fabs(vol[g] / gp_fv3d_grain_at(s, g)->volume - 1));
    }
    CHECK_REL(sum, total_volume(s), 1e-9);
    CHECK(worst < 1e-9);
    /* cell data: grain_id, cell_id, volume, one value a triangle */
    l = next_line(&c);
    CHECK(l && sscanf(l, "CELL_DATA %llu", &a) == 1 && a == nc);
    const char *names[3] = {"SCALARS grain_id int 1", "SCALARS cell_id int 1", "SCALARS volume double 1"};
    int data_ok = 1;
    for (int arr = 0; arr < 3; arr++) {
        l = next_line(&c);
        data_ok &= l && !strcmp(l, names[arr]);
        l = next_line(&c);
        data_ok &= l && !strcmp(l, "LOOKUP_TABLE default");
        for (size_t k = 0; k < nc && data_ok; k++) {
            const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, k / nt);
            l = next_line(&c);
            double v = l ? strtod(l, NULL) : NAN;
            data_ok &= arr == 0 ? v == (double)(k / nt) : arr == 1 ? v == (double)gr->cell : v == gr->volume;
        }
    }
    CHECK(data_ok);
    CHECK(next_line(&c) == NULL);
    printf("vtk: %zu points, %zu triangles; enclosed volume %.17g (grains %.17g), worst grain %.1e\n",
           np, nc, sum, total_volume(s), worst);
    free(vol);
    free(pts);
    free(xyz);
}

static void check_stl(const gp_fv3d *s, char *t)
{
    size_t ng = gp_fv3d_count(s), nd = gp_fv3d_directions(s, NULL), nt = gp_fv3d_triangles(s, NULL);
    char *c = t, *l;
    size_t solids = 0, facets = 0;
    double sum = 0, worst = 0, normal_gap = 0, *xyz = malloc(3 * nd * sizeof *xyz);
    int ok = 1;
    while ((l = next_line(&c))) {
        unsigned long long g;
        if (sscanf(l, "solid grain_%llu", &g) != 1 || g != solids || g >= ng) {
            ok = 0;
            break;
        }
        gp_fv3d_grain_vertices(s, (size_t)g, xyz);
        double vol = 0;
        size_t f = 0;
        while ((l = next_line(&c)) && strncmp(l, "endsolid", 8)) {
            double n[3], v[3][3];
            ok &= sscanf(l, "facet normal %lf %lf %lf", n, n + 1, n + 2) == 3;
            l = next_line(&c);
            ok &= l && !strcmp(l, " outer loop");
            for (int k = 0; k < 3; k++) {
                l = next_line(&c);
                ok &= l && sscanf(l, "  vertex %lf %lf %lf", v[k], v[k] + 1, v[k] + 2) == 3;
            }
            l = next_line(&c);
            ok &= l && !strcmp(l, " endloop");
            l = next_line(&c);
            ok &= l && !strcmp(l, "endfacet");
            vol += tri_volume(v[0], v[1], v[2], xyz);
            /* the normal: the unit normal of the triangle */
            double u[3], w[3], x[3];
            for (int k = 0; k < 3; k++) {
                u[k] = v[1][k] - v[0][k];
                w[k] = v[2][k] - v[0][k];
            }
            x[0] = u[1] * w[2] - u[2] * w[1];
            x[1] = u[2] * w[0] - u[0] * w[2];
            x[2] = u[0] * w[1] - u[1] * w[0];
            double len = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            for (int k = 0; k < 3; k++) normal_gap = fmax(normal_gap, fabs(x[k] / len - n[k]));
            f++;
        }
        ok &= l && sscanf(l, "endsolid grain_%llu", &g) == 1 && g == solids && f == nt;
        facets += f;
        sum += vol;
        worst = fmax(worst, fabs(vol / gp_fv3d_grain_at(s, solids)->volume - 1));
        solids++;
    }
    CHECK(ok);
    CHECK(solids == ng && facets == ng * nt);
    CHECK_REL(sum, total_volume(s), 1e-9);
    CHECK(worst < 1e-9);
    CHECK(normal_gap < 1e-8);
    printf("stl: %zu solids, %zu facets; enclosed volume %.17g (grains %.17g), worst grain %.1e\n",
           solids, facets, sum, total_volume(s), worst);
    free(xyz);
}

/* ------------------------------------------------------------------ the tests */

static void test_registry(void)
{
    const int fv = GP_EXPORT_FV3D;
    CHECK(gp_export_format_parse("stl") == GP_EXPORT_STL);
    CHECK(!strcmp(gp_export_format_list(fv), "lammps, liggghts, yade, vtk, stl"));
    for (int f = 0; f < GP_EXPORT_NFORMATS; f++)
        CHECK(gp_export_format_supports(f, fv) ==
              (strstr(gp_export_format_list(fv), gp_export_format_name(f)) != NULL));
    CHECK(!gp_export_format_supports(GP_EXPORT_STL, 2) && !gp_export_format_supports(GP_EXPORT_STL, 3));
    CHECK(!gp_export_format_supports(GP_EXPORT_CSV, fv) && !gp_export_format_supports(GP_EXPORT_LAMMPS, 5));
    CHECK(!strcmp(gp_export_format_extension_in(GP_EXPORT_LAMMPS, fv), "tar"));
    CHECK(!strcmp(gp_export_format_mime_in(GP_EXPORT_LAMMPS, fv), "application/x-tar"));
    CHECK(!strcmp(gp_export_format_extension_in(GP_EXPORT_LIGGGHTS, fv), "in"));
    CHECK(!strcmp(gp_export_format_extension_in(GP_EXPORT_LAMMPS, 3), "data"));
    CHECK(!strcmp(gp_export_format_extension_in(GP_EXPORT_STL, fv), "stl"));
    CHECK(!strcmp(gp_export_format_mime_in(GP_EXPORT_STL, fv), "model/stl"));
    CHECK(!strcmp(gp_export_format_mime_in(GP_EXPORT_YADE, fv), gp_export_format_mime(GP_EXPORT_YADE)));
    for (int f = 0; f < GP_EXPORT_NFORMATS; f++) {
        CHECK(gp_export_format_needs_clumps(f, fv) ==
              (f == GP_EXPORT_LAMMPS || f == GP_EXPORT_LIGGGHTS || f == GP_EXPORT_YADE));
        CHECK(!gp_export_format_needs_clumps(f, 2) && !gp_export_format_needs_clumps(f, 3));
    }
}

static const gp_export_format FV3D_FORMATS[] = {GP_EXPORT_LAMMPS, GP_EXPORT_LIGGGHTS, GP_EXPORT_YADE,
                                                GP_EXPORT_VTK, GP_EXPORT_STL};

static void test_formats(const gp_fv3d *s)
{
    void *pack;
    size_t len;
    gp_error e;
    CHECK(gp_export_pack_fv3d(s, RHO, &pack, &len, &e) == GP_OK);
    check_pack(s, pack, len);
    for (size_t i = 0; i < sizeof FV3D_FORMATS / sizeof FV3D_FORMATS[0]; i++) {
        gp_export_format f = FV3D_FORMATS[i];
        size_t n;
        char *t = export_all(f, pack, len, 65536, &n, &e);
        CHECK(t != NULL);
        if (!t) {
            fprintf(stderr, "%s: %s\n", gp_export_format_name(f), e.message);
            continue;
        }
        /* the same bytes whatever the read size */
        const size_t pieces[] = {1, 7, 4096, 1 << 20};
        for (size_t p = 0; p < 4; p++) {
            if (pieces[p] == 1 && n > 4000000) continue;
            size_t m;
            char *u = export_all(f, pack, len, pieces[p], &m, NULL);
            CHECK(u && m == n && !memcmp(u, t, n));
            free(u);
        }
        switch (f) {
        case GP_EXPORT_LAMMPS: check_lammps(s, t, n); break;
        case GP_EXPORT_LIGGGHTS: check_liggghts(s, t); break;
        case GP_EXPORT_YADE: check_yade(s, t); break;
        case GP_EXPORT_VTK: check_vtk(s, t); break;
        default: check_stl(s, t); break;
        }
        free(t);
    }
    /* csv and lammps-relax are not fv3d formats */
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *x;
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &x, &e) == GP_ERR_INVALID && x == NULL);
    CHECK(strstr(e.message, "format csv does not exist in fv3d (valid: lammps, liggghts, yade, vtk, stl)") != NULL);
    CHECK(gp_export_open(GP_EXPORT_LAMMPS_RELAX, &src, &x, &e) == GP_ERR_INVALID);
    free(pack);
}

/* lammps' member sizes: counted when packed; a pack without them is counted at the download
 * and gives the same bytes; a wrong count fails the download rather than make a corrupt tar */
static void test_counts(const gp_fv3d *s)
{
    void *pack;
    size_t len, n, m;
    CHECK(gp_export_pack_fv3d(s, RHO, &pack, &len, NULL) == GP_OK);
    unsigned char *b = pack;
    uint64_t data, rigid;
    uint32_t layout;
    memcpy(&data, b + 128 + 16, 8);
    memcpy(&rigid, b + 128 + 24, 8);
    memcpy(&layout, b + 128 + 32, 4);
    CHECK(data > 0 && rigid > 0 && layout == 1);
    char *t = export_all(GP_EXPORT_LAMMPS, pack, len, 65536, &n, NULL);
    uint64_t zero = 0;
    memcpy(b + 128 + 16, &zero, 8);
    char *u = export_all(GP_EXPORT_LAMMPS, pack, len, 65536, &m, NULL);
    CHECK(t && u && m == n && !memcmp(t, u, n));
    free(u);
    layout = 7; /* another layout: counted again */
    memcpy(b + 128 + 16, &data, 8);
    memcpy(b + 128 + 32, &layout, 4);
    u = export_all(GP_EXPORT_LAMMPS, pack, len, 65536, &m, NULL);
    CHECK(t && u && m == n && !memcmp(t, u, n));
    free(u);
    layout = 1;
    memcpy(b + 128 + 32, &layout, 4);
    uint64_t wrong = data + 1;
    memcpy(b + 128 + 16, &wrong, 8);
    gp_error e;
    u = export_all(GP_EXPORT_LAMMPS, pack, len, 65536, &m, &e);
    CHECK(u == NULL && strstr(e.message, "grains.data is") != NULL);
    if (!u) printf("stale count refused: %s\n", e.message);
    free(u);
    free(t);
    free(pack);
}

/* grains without clumps: vtk and stl, and the DEM formats refused with the reason */
static void test_no_clumps(void)
{
    gp_fv3d *s = specimen(12, 1, 0, 3);
    CHECK(s != NULL);
    if (!s) return;
    void *pack;
    size_t len;
    gp_error e;
    CHECK(gp_export_pack_fv3d(s, RHO, &pack, &len, &e) == GP_OK);
    gp_export_info info;
    gp_export_source src = gp_export_memory_source(pack, len);
    CHECK(gp_export_pack_info(&src, &info, &e) == GP_OK && info.flags == 0 && info.ndiscs == 0);
    for (int f = 0; f < 3; f++) {
        gp_export *x;
        CHECK(gp_export_open(FV3D_FORMATS[f], &src, &x, &e) == GP_ERR_INVALID && x == NULL);
        CHECK(strstr(e.message, "needs the clumps output (outputs must include \"clumps\")") != NULL);
    }
    printf("without clumps: %s\n", e.message);
    char *t = export_all(GP_EXPORT_VTK, pack, len, 65536, NULL, &e);
    CHECK(t != NULL);
    if (t) check_vtk(s, t);
    free(t);
    t = export_all(GP_EXPORT_STL, pack, len, 65536, NULL, &e);
    CHECK(t != NULL);
    if (t) check_stl(s, t);
    free(t);
    free(pack);
    gp_fv3d_destroy(s);
}

static void test_refusals(const gp_fv3d *s)
{
    void *pack;
    size_t len;
    gp_error e;
    CHECK(gp_export_pack_fv3d(NULL, RHO, &pack, &len, &e) == GP_ERR_INVALID && pack == NULL);
    CHECK(gp_export_pack_fv3d(s, 0, &pack, &len, &e) == GP_ERR_INVALID);
    CHECK(gp_export_pack_fv3d(s, NAN, &pack, &len, &e) == GP_ERR_INVALID);
    CHECK(gp_export_pack_fv3d(s, RHO, &pack, &len, &e) == GP_OK);
    unsigned char *b = pack;
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *x;
    gp_export_reader *r;
    /* truncated, a bad block */
    src.size = len - 1;
    CHECK(gp_export_open(GP_EXPORT_VTK, &src, &x, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "size") != NULL);
    src.size = 200;
    CHECK(gp_export_open(GP_EXPORT_VTK, &src, &x, &e) == GP_ERR_INVALID);
    src.size = len;
    b[128] = 'X';
    CHECK(gp_export_open(GP_EXPORT_STL, &src, &x, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "bad fv3d block") != NULL);
    b[128] = 'G';
    /* a triangle past the directions: the download fails */
    const uint32_t *tris;
    size_t n = gp_fv3d_count(s), nd = gp_fv3d_directions(s, NULL), nt = gp_fv3d_triangles(s, &tris);
    size_t off = len - 12 * nt + 4;
    uint32_t big = (uint32_t)nd;
    memcpy(b + off, &big, 4);
    char *t = export_all(GP_EXPORT_STL, pack, len, 4096, NULL, &e);
    CHECK(t == NULL && strstr(e.message, "triangle 0") != NULL);
    free(t);
    memcpy(b + off, tris + 1, 4);
    /* a grain's spheres outside their array: refused by the reader, which stays usable */
    uint64_t first = total_spheres(s);
    memcpy(b + 256 + 176 * (n - 1) + 8, &first, 8);
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    gp_export_grain3 g;
    CHECK(gp_export_reader_grain3(r, n - 1, &g, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "spheres outside their array") != NULL);
    CHECK(gp_export_reader_grain3(r, 0, &g, &e) == GP_OK);
    gp_export_reader_destroy(r);
    t = export_all(GP_EXPORT_YADE, pack, len, 4096, NULL, &e);
    CHECK(t == NULL);
    free(t);
    free(pack);
}

/* ------------------------------------------------------------------ --write and --bench */

static int write_file(const char *dir, const char *name, const void *pack, size_t len,
                      gp_export_format f)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    gp_error e;
    size_t n;
    char *t = export_all(f, pack, len, 1 << 20, &n, &e);
    FILE *fp = fopen(path, "wb");
    if (!t || !fp || fwrite(t, 1, n, fp) != n) {
        fprintf(stderr, "%s: %s\n", path, t ? "cannot write" : e.message);
        if (fp) fclose(fp);
        free(t);
        return -1;
    }
    free(t);
    return fclose(fp);
}

/* the specimen's own values, for the integration test */
static int write_json(const char *dir, const gp_fv3d *s, const void *pack, size_t len)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/fv3d.json", dir);
    FILE *fp = fopen(path, "w");
    if (!fp) return -1;
    gp_export_info in;
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export_pack_info(&src, &in, NULL);
    fprintf(fp, "{\"density\": %.17g, \"volume\": %.17g, \"spheres\": %zu, \"directions\": %zu, "
                "\"triangles\": %zu, \"box_lo\": [%.17g, %.17g, %.17g], \"box_hi\": [%.17g, %.17g, "
                "%.17g], \"max_extent\": %.17g,\n \"grains\": [",
            RHO, total_volume(s), total_spheres(s), gp_fv3d_directions(s, NULL),
            gp_fv3d_triangles(s, NULL), in.lo[0], in.lo[1], in.lo[2], in.hi[0], in.hi[1], in.hi[2],
            in.max_extent);
    for (size_t g = 0; g < gp_fv3d_count(s); g++) {
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        const double *I = gr->inertia;
        fprintf(fp, "%s\n  {\"id\": %zu, \"cell\": %zu, \"nspheres\": %zu, \"volume\": %.17g, "
                    "\"mass\": %.17g, \"centroid\": [%.17g, %.17g, %.17g], \"inertia\": [[%.17g, "
                    "%.17g, %.17g], [%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]]}",
                g ? "," : "", g, gr->cell, gr->nspheres, gr->volume, RHO * gr->volume,
                gr->centroid[0], gr->centroid[1], gr->centroid[2], RHO * I[0], RHO * I[1],
                RHO * I[2], RHO * I[3], RHO * I[4], RHO * I[5], RHO * I[6], RHO * I[7], RHO * I[8]);
    }
    fprintf(fp, "]}\n");
    return fclose(fp);
}

static int write_mode(const char *dir, size_t n)
{
    gp_fv3d *s = specimen(n, 2, 1, 11);
    if (!s) return 1;
    void *pack;
    size_t len;
    gp_error e;
    if (gp_export_pack_fv3d(s, RHO, &pack, &len, &e) != GP_OK) {
        fprintf(stderr, "pack: %s\n", e.message);
        gp_fv3d_destroy(s);
        return 1;
    }
    int rc = write_file(dir, "fv3d-lammps.tar", pack, len, GP_EXPORT_LAMMPS) ||
             write_file(dir, "fv3d-liggghts.in", pack, len, GP_EXPORT_LIGGGHTS) ||
             write_file(dir, "fv3d-yade.txt", pack, len, GP_EXPORT_YADE) ||
             write_file(dir, "fv3d.vtk", pack, len, GP_EXPORT_VTK) ||
             write_file(dir, "fv3d.stl", pack, len, GP_EXPORT_STL) || write_json(dir, s, pack, len);
    printf("wrote %zu grains, %zu spheres to %s\n", gp_fv3d_count(s), total_spheres(s), dir);
    free(pack);
    gp_fv3d_destroy(s);
    return rc ? 1 : 0;
}

static int bench_mode(size_t n, unsigned level)
{
    double t0 = now();
    gp_fv3d *s = specimen(n, level, 1, 5);
    if (!s) return 1;
    double t1 = now();
    void *pack;
    size_t len;
    gp_error e;
    if (gp_export_pack_fv3d(s, RHO, &pack, &len, &e) != GP_OK) {
        fprintf(stderr, "pack: %s\n", e.message);
        return 1;
    }
    double t2 = now();
    printf("%zu grains at mesh level %u (%zu directions, %zu triangles, %zu spheres): build %.2f s, "
           "pack %.3f s (%.1f MB)\n",
           gp_fv3d_count(s), level, gp_fv3d_directions(s, NULL), gp_fv3d_triangles(s, NULL),
           total_spheres(s), t1 - t0, t2 - t1, len / 1e6);
    char *buf = malloc(1 << 16);
    for (size_t i = 0; i < sizeof FV3D_FORMATS / sizeof FV3D_FORMATS[0]; i++) {
        gp_export_source src = gp_export_memory_source(pack, len);
        gp_export *x;
        double a = now();
        if (gp_export_open(FV3D_FORMATS[i], &src, &x, &e)) return 1;
        uint64_t bytes = 0;
        for (;;) {
            size_t k;
            if (gp_export_read(x, buf, 1 << 16, &k, &e)) return 1;
            if (!k) break;
            bytes += k;
        }
        gp_export_destroy(x);
        double dt = now() - a;
        printf("  %-8s %8.3f s  %9.1f MB  %6.1f MB/s\n", gp_export_format_name(FV3D_FORMATS[i]), dt,
               bytes / 1e6, bytes / 1e6 / dt);
    }
    free(buf);
    free(pack);
    gp_fv3d_destroy(s);
    return 0;
}

int main(int argc, char **argv)
{
    if (gp_fourier_spectrum(0.1, 0.05, 0.02, -2, -2, 16, D, NULL) != GP_OK) return 1;
    if (argc >= 3 && !strcmp(argv[1], "--write")) return write_mode(argv[2], argc > 3 ? strtoul(argv[3], NULL, 10) : 30);
    if (argc >= 3 && !strcmp(argv[1], "--bench"))
        return bench_mode(strtoul(argv[2], NULL, 10), argc > 3 ? (unsigned)atoi(argv[3]) : 4);
    test_registry();
    gp_fv3d *s = specimen(30, 2, 1, 7);
    CHECK(s != NULL);
    if (s) {
        printf("specimen: %zu grains, %zu spheres, %zu directions, %zu triangles, volume %.6g\n",
               gp_fv3d_count(s), total_spheres(s), gp_fv3d_directions(s, NULL),
               gp_fv3d_triangles(s, NULL), total_volume(s));
        test_formats(s);
        test_counts(s);
        test_refusals(s);
        gp_fv3d_destroy(s);
    }
    test_no_clumps();
    return gp_test_summary();
}
