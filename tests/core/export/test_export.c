/* test_export.c -- packs and the export stream on hand-made specimens whose numbers are known:
 * CSV parses back bit for bit, the stream is the same whatever the read size, the 2D LAMMPS
 * densities give each rigid body exactly density * grain area, corrupt packs are refused.
 * (Loading the files into LAMMPS, LIGGGHTS, YADE and VTK is tests/integration/test_exports.py.)
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export.h"
#include "gp_test.h"

/* ---- hand-made specimens ---- */

static double sph[5][4] = {{0.1, 0.2, 0.3, 0.05},
                           {1.0 / 3.0, 0.25, 0.125, 0.01},
                           {0.9, 0.8, 0.7, 0.1},
                           {1e-9, 0.5, 0.5, 1e-3},
                           {0.4, 0.4, 0.4, M_PI / 100}};

static gp_specimen3d make3d(void)
{
    gp_specimen3d s;
    memset(&s, 0, sizeof s);
    s.spheres = &sph[0][0];
    s.count = 5;
    s.box[0] = 1.0;
    s.box[1] = 1.25;
    s.box[2] = 0.75;
    return s;
}

/* Two grains: a unit square (area 1) of two discs, a triangle (area 0.5) of one disc. */
static gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
static gp_vec2 tri[3] = {{2, 0}, {3, 0}, {2, 1}};
static double d0[6] = {0.3, 0.5, 0.3, 0.7, 0.5, 0.3};
static double d1[3] = {2.3, 0.3, 0.29};

static gp_grain2d grain(gp_vec2 *contour, size_t ncontour, double area, double orientation_deg,
                        gp_descriptors descriptors, double *discs, size_t ndiscs)
{
    return (gp_grain2d){.contour = contour, .ncontour = ncontour, .area = area,
                        .orientation_deg = orientation_deg, .descriptors = descriptors,
                        .discs = discs, .ndiscs = ndiscs};
}

static void make2d(gp_specimen2d *s, gp_grain2d g[2], gp_spec2d *spec)
{
    memset(s, 0, sizeof *s);
    g[0] = grain(sq, 4, 1.0, 0, (gp_descriptors){1.0, 0.5, 0.9, 0.1}, d0, 2);
    g[1] = grain(tri, 3, 0.5, 45, (gp_descriptors){0.5, 0.4, 0.8, 0.2}, d1, 1);
    s->grains = g;
    s->ngrains = 2;
    memset(spec, 0, sizeof *spec); /* pack_2d reads the container and the outputs */
    spec->container = GP_CONTAINER_POLYGON;
    static gp_vec2 box[4] = {{-1, -1}, {4, -1}, {4, 2}, {-1, 2}};
    spec->outer.pts = box;
    spec->outer.n = 4;
    spec->outputs = GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS;
}

/* ---- helpers ---- */

typedef struct sink {
    char *p;
    size_t n, cap;
} sink;

static int sink_write(void *user, const char *buf, size_t n)
{
    sink *s = user;
    if (s->n + n + 1 > s->cap) {
        s->cap = (s->n + n + 1) * 2;
        s->p = realloc(s->p, s->cap);
        if (!s->p) return -1;
    }
    memcpy(s->p + s->n, buf, n);
    s->n += n;
    s->p[s->n] = 0;
    return 0;
}

/* The whole export read in pieces of `piece` bytes; NULL on error. */
static char *export_in_pieces(gp_export_format f, const void *pack, size_t len, size_t piece)
{
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *e;
    if (gp_export_open(f, &src, &e, NULL)) return NULL;
    sink s = {0};
    char *buf = malloc(piece);
    for (;;) {
        size_t n;
        if (gp_export_read(e, buf, piece, &n, NULL)) {
            free(s.p);
            s.p = NULL;
            break;
        }
        if (n == 0) break;
        sink_write(&s, buf, n);
    }
    free(buf);
    gp_export_destroy(e);
    return s.p;
}

static int count_lines(const char *t)
{
    int n = 0;
    for (; *t; t++) n += *t == '\n';
    return n;
}

/* the hand-made 2D specimen packed (density 2650) and exported in format f, read in pieces
 * of `piece` bytes (malloc'ed; NULL on failure) */
static char *export2d(gp_export_format f, size_t piece)
{
    gp_specimen2d s;
    gp_grain2d g[2];
    gp_spec2d spec;
    make2d(&s, g, &spec);
    void *pack;
    size_t len;
    CHECK(gp_export_pack_2d(&s, &spec, 2650, &pack, &len, NULL) == GP_OK);
    char *t = export_in_pieces(f, pack, len, piece);
    free(pack);
    return t;
}

/* ---- tests ---- */

static void test_registry(void)
{
    CHECK(gp_export_format_parse("lammps") == GP_EXPORT_LAMMPS);
    CHECK(gp_export_format_parse("csv") == GP_EXPORT_CSV);
    CHECK(gp_export_format_parse("pdf") == -1);
    CHECK(gp_export_format_parse(NULL) == -1);
    CHECK(gp_export_format_supports(GP_EXPORT_LIGGGHTS, 3));
    CHECK(!gp_export_format_supports(GP_EXPORT_LIGGGHTS, 2));
    for (int f = 0; f < GP_EXPORT_NFORMATS; f++) {
        /* every format but stl (the grains of a fv3d pack: test_export_fv3d.c) exists in 3D */
        CHECK(gp_export_format_supports(f, 3) == (f != GP_EXPORT_STL));
        CHECK((strstr(gp_export_format_list(3), gp_export_format_name(f)) != NULL) ==
              (f != GP_EXPORT_STL));
        CHECK(gp_export_format_supports(f, 2) ==
              (strstr(gp_export_format_list(2), gp_export_format_name(f)) != NULL));
    }
}

static void test_csv3d_round_trip(void)
{
    gp_specimen3d s = make3d();
    void *pack;
    size_t len;
    CHECK(gp_export_pack_3d(&s, 2600, &pack, &len, NULL) == GP_OK);
    char *t = export_in_pieces(GP_EXPORT_CSV, pack, len, 65536);
    CHECK(t != NULL);
    if (t) {
        CHECK(!strncmp(t, "x,y,z,r\n", 8));
        char *p = strchr(t, '\n') + 1;
        int rows = 0, exact = 0;
        while (*p) {
            double v[4];
            for (int k = 0; k < 4; k++) {
                v[k] = strtod(p, &p);
                p++; /* ',' or '\n' */
            }
            if (rows < 5 && !memcmp(v, sph[rows], sizeof v)) exact++;
            rows++;
        }
        CHECK(rows == 5);
        CHECK(exact == 5); /* bit for bit */
    }
    free(t);
    free(pack);
}

static void test_pieces_identical(void)
{
    gp_specimen3d s3 = make3d();
    gp_specimen2d s2;
    gp_grain2d g[2];
    gp_spec2d spec;
    make2d(&s2, g, &spec);
    void *p3, *p2;
    size_t n3, n2;
    CHECK(gp_export_pack_3d(&s3, 2600, &p3, &n3, NULL) == GP_OK);
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &p2, &n2, NULL) == GP_OK);
    size_t pieces[3] = {1, 13, 65536};
    for (int dim = 2; dim <= 3; dim++) {
        for (int f = 0; f < GP_EXPORT_NFORMATS; f++) {
            if (!gp_export_format_supports(f, dim)) {
                gp_export_source src = gp_export_memory_source(dim == 2 ? p2 : p3,
                                                                dim == 2 ? n2 : n3);
                gp_export *e = NULL;
                gp_error err;
                CHECK(gp_export_open(f, &src, &e, &err) == GP_ERR_INVALID);
                CHECK(e == NULL && strstr(err.message, "valid: ") != NULL);
                continue;
            }
            if (f == GP_EXPORT_LAMMPS_RELAX) /* a binary tar from a pack with a DEM block: */
                continue;                    /* test_export_relax.c reads it in pieces */
            char *ref = export_in_pieces(f, dim == 2 ? p2 : p3, dim == 2 ? n2 : n3, pieces[2]);
            CHECK(ref != NULL && strlen(ref) > 20);
            for (int k = 0; k < 2 && ref; k++) {
                char *t = export_in_pieces(f, dim == 2 ? p2 : p3, dim == 2 ? n2 : n3, pieces[k]);
                CHECK(t && !strcmp(t, ref));
                free(t);
            }
            free(ref);
        }
    }
    free(p3);
    free(p2);
}

/* The LAMMPS 2D file: molecule ids 1..G, and sum over a grain's discs of
 * (4/3) pi r^3 * density (the mass LAMMPS gives an atom) = 2650 * grain area. */
static void test_lammps2d_masses(void)
{
    char *t = export2d(GP_EXPORT_LAMMPS, 4096);
    CHECK(t != NULL);
    if (t) {
        CHECK(strstr(t, "\n3 atoms\n") != NULL);
        CHECK(strstr(t, "\n-1 4 xlo xhi\n") != NULL);
        CHECK(strstr(t, "\n-1 2 ylo yhi\n") != NULL);
        char *p = strstr(t, "Atoms # hybrid\n\n");
        CHECK(p != NULL);
        double mass[3] = {0, 0, 0};
        int atoms = 0;
        if (p) {
            p += strlen("Atoms # hybrid\n\n");
            while (*p) {
                long id = strtol(p, &p, 10), type = strtol(p, &p, 10);
                double x = strtod(p, &p), y = strtod(p, &p), z = strtod(p, &p);
                double dia = strtod(p, &p), rho = strtod(p, &p);
                long mol = strtol(p, &p, 10);
                if (*p == '\n') p++;
                atoms++;
                CHECK(id == atoms && type == 1 && z == 0);
                CHECK(mol >= 1 && mol <= 2);
                if (mol >= 1 && mol <= 2) mass[mol] += 4.0 / 3.0 * M_PI * pow(dia / 2, 3) * rho;
                (void)x;
                (void)y;
            }
        }
        CHECK(atoms == 3);
        CHECK_REL(mass[1], 2650 * 1.0, 1e-12);
        CHECK_REL(mass[2], 2650 * 0.5, 1e-12);
    }
    free(t);
}

static void test_vtk2d_structure(void)
{
    char *t = export2d(GP_EXPORT_VTK, 100);
    CHECK(t != NULL);
    if (t) {
        CHECK(strstr(t, "POINTS 10 double\n") != NULL);   /* 7 contour points + 3 discs */
        CHECK(strstr(t, "VERTICES 3 6\n1 7\n1 8\n1 9\n") != NULL);
        CHECK(strstr(t, "POLYGONS 2 9\n4 0 1 2 3\n3 4 5 6\n") != NULL);
        CHECK(strstr(t, "CELL_DATA 5\n") != NULL);
        /* grain ids of the cells: discs 0 0 1, then polygons 0 1 */
        CHECK(strstr(t, "SCALARS grain_id int 1\nLOOKUP_TABLE default\n0\n0\n1\n0\n1\n") != NULL);
        CHECK(strstr(t, "SCALARS area double 1\nLOOKUP_TABLE default\n1\n1\n0.5\n1\n0.5\n") != NULL);
        CHECK(strstr(t, "SCALARS regularity double 1") != NULL);
        CHECK(strstr(t, "POINT_DATA 10\nSCALARS radius double 1\nLOOKUP_TABLE default\n"
                        "0\n0\n0\n0\n0\n0\n0\n0.29999999999999999\n0.29999999999999999\n0.28999999999999998\n") != NULL);
        CHECK(count_lines(t) > 40);
    }
    free(t);
}

static void test_refusals(void)
{
    gp_specimen3d s = make3d();
    s.spheres = NULL;
    void *pack = NULL;
    size_t len;
    gp_error err;
    CHECK(gp_export_pack_3d(&s, 2600, &pack, &len, &err) == GP_ERR_INVALID);
    CHECK(strstr(err.message, "\"spheres\"") != NULL);
    s = make3d();
    CHECK(gp_export_pack_3d(&s, -1, &pack, &len, &err) == GP_ERR_INVALID);
    CHECK(gp_export_pack_3d(&s, NAN, &pack, &len, &err) == GP_ERR_INVALID);

    gp_specimen2d s2;
    gp_grain2d g[2];
    gp_spec2d spec;
    make2d(&s2, g, &spec);
    g[1].discs = NULL;
    g[1].ndiscs = 0;
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &pack, &len, &err) == GP_ERR_INVALID);
    CHECK(strstr(err.message, "\"odec\"") != NULL);

    /* corrupt packs: every failure is an error, never a crash or an endless stream */
    make2d(&s2, g, &spec);
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &pack, &len, NULL) == GP_OK);
    unsigned char *p = pack;
    gp_export_source src = gp_export_memory_source(pack, len - 8); /* truncated */
    gp_export *e = NULL;
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_ERR_INVALID);
    src = gp_export_memory_source(pack, 100);
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_ERR_INVALID);
    p[0] ^= 1; /* magic */
    src = gp_export_memory_source(pack, len);
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_ERR_INVALID);
    p[0] ^= 1;
    uint64_t huge = 1ull << 60; /* grain 1's point_first */
    memcpy(p + 128 + 80, &huge, 8);
    CHECK(gp_export_open(GP_EXPORT_VTK, &src, &e, &err) == GP_OK);
    char buf[256];
    size_t n;
    gp_status st = GP_OK;
    for (int k = 0; k < 1000 && !st; k++) {
        st = gp_export_read(e, buf, sizeof buf, &n, &err);
        if (!st && n == 0) break;
    }
    CHECK(st == GP_ERR_INVALID);
    CHECK(strstr(err.message, "grain 1") != NULL);
    gp_export_destroy(e);
    free(pack);
}

int main(void)
{
    test_registry();
    test_csv3d_round_trip();
    test_pieces_identical();
    test_lammps2d_masses();
    test_vtk2d_structure();
    test_refusals();
    return gp_test_summary();
}
