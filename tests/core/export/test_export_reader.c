/* test_export_reader.c -- the public reader of an export pack (gp_export_reader): the records of packs made here read back exactly (3D spheres, 2D grains with their contour points and discs, with and without descriptors), and a wrong record kind, an index past its count or a corrupt pack refused. A view pack (gp_export_pack_2d_view: grains without discs) reads back its grains, says what it is (gp_export_pack_info) and is refused by every export format. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export.h"
#include "gp_test.h"

static double sph[5][4] = {{0.1, 0.2, 0.3, 0.05}, {1.0 / 3.0, 0.25, 0.125, 0.01},
                           {0.9, 0.8, 0.7, 0.1}, {1e-9, 0.5, 0.5, 1e-3}, {0.4, 0.4, 0.4, M_PI / 100}};
static gp_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
static gp_vec2 tri[3] = {{2, 0}, {3, 0}, {2, 1}};
static double d0[6] = {0.3, 0.5, 0.3, 0.7, 0.5, 0.3};
static double d1[3] = {2.3, 0.3, 0.29};

/* a specimen of two grains, a square (two discs, first orientation orient0) and a triangle (one
 * disc if second_discs), in a 5 x 3 box, asking for outputs */
static void two_grains(gp_grain2d gr[2], gp_specimen2d *s2, gp_spec2d *spec, double orient0,
                       int second_discs, unsigned outputs)
{
    static gp_vec2 box[4] = {{-1, -1}, {4, -1}, {4, 2}, {-1, 2}};
    memset(gr, 0, 2 * sizeof *gr);
    gr[0] = (gp_grain2d){.contour = sq, .ncontour = 4, .area = 1, .orientation_deg = orient0,
                         .descriptors = {1.0, 0.5, 0.9, 0.1}, .discs = d0, .ndiscs = 2};
    gr[1] = (gp_grain2d){.contour = tri, .ncontour = 3, .area = 0.5, .orientation_deg = 45,
                         .descriptors = {0.5, 0.4, 0.8, 0.2}, .discs = second_discs ? d1 : NULL,
                         .ndiscs = second_discs ? 1 : 0};
    memset(s2, 0, sizeof *s2);
    s2->grains = gr;
    s2->ngrains = 2;
    memset(spec, 0, sizeof *spec);
    spec->container = GP_CONTAINER_POLYGON;
    spec->outer.pts = box;
    spec->outer.n = 4;
    spec->outputs = outputs;
}

static void test_reader(int with_desc)
{
    gp_error e;
    /* 3D */
    gp_specimen3d s3;
    memset(&s3, 0, sizeof s3);
    s3.spheres = &sph[0][0];
    s3.count = 5;
    s3.box[0] = 1.0; s3.box[1] = 1.25; s3.box[2] = 0.75;
    void *pack; size_t len;
    CHECK(gp_export_pack_3d(&s3, 2600, &pack, &len, &e) == GP_OK);
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export_reader *r;
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    const gp_export_info *in = gp_export_reader_info(r);
    CHECK(in->dim == 3 && in->nitems == 5 && in->density == 2600 && in->hi[1] == 1.25);
    for (uint64_t i = 0; i < 5; i++) {
        double q[4];
        CHECK(gp_export_reader_sphere(r, i, q, &e) == GP_OK);
        CHECK(memcmp(q, sph[i], sizeof q) == 0);
    }
    double q[4];
    gp_export_grain g;
    CHECK(gp_export_reader_sphere(r, 5, q, &e) == GP_ERR_INVALID);
    CHECK(gp_export_reader_grain(r, 0, &g, &e) == GP_ERR_INVALID);
    printf("%s\n", e.message);
    CHECK(gp_export_reader_sphere(r, 4, q, NULL) == GP_OK && q[3] == M_PI / 100);
    gp_export_reader_destroy(r);
    free(pack);
    /* 2D */
    gp_grain2d gr[2];
    gp_specimen2d s2;
    gp_spec2d spec;
    two_grains(gr, &s2, &spec, 0, 1, GP_OUT2_ODEC | (with_desc ? GP_OUT2_DESCRIPTORS : 0));
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &pack, &len, &e) == GP_OK);
    src = gp_export_memory_source(pack, len);
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    in = gp_export_reader_info(r);
    CHECK(in->dim == 2 && in->nitems == 2 && in->npoints == 7 && in->ndiscs == 3);
    CHECK(!!(in->flags & GP_EXPORT_HAS_DESCRIPTORS) == with_desc);
    for (uint64_t k = 0; k < 2; k++) {
        CHECK(gp_export_reader_grain(r, k, &g, &e) == GP_OK);
        CHECK(g.point_count == gr[k].ncontour && g.disc_count == gr[k].ndiscs);
        CHECK(g.area == gr[k].area && g.orientation_deg == gr[k].orientation_deg);
        CHECK(with_desc ? g.roundness == gr[k].descriptors.roundness : isnan(g.roundness));
        for (uint64_t i = 0; i < g.point_count; i++) {
            double p[2];
            CHECK(gp_export_reader_point(r, g.point_first + i, p, &e) == GP_OK);
            CHECK(p[0] == gr[k].contour[i].x && p[1] == gr[k].contour[i].y);
        }
        for (uint64_t i = 0; i < g.disc_count; i++) {
            double d[3];
            CHECK(gp_export_reader_disc(r, g.disc_first + i, d, &e) == GP_OK);
            CHECK(memcmp(d, gr[k].discs + 3 * i, sizeof d) == 0);
        }
    }
    double p[2];
    CHECK(gp_export_reader_point(r, 7, p, &e) == GP_ERR_INVALID);
    CHECK(gp_export_reader_sphere(r, 0, q, &e) == GP_ERR_INVALID);
    CHECK(gp_export_reader_grain(r, 2, &g, &e) == GP_ERR_INVALID);
    /* a corrupt grain record: refused, and the reader stays usable */
    unsigned char *b = pack;
    uint64_t big = 1000;
    memcpy(b + 128 + 80 + 8, &big, 8);
    CHECK(gp_export_reader_grain(r, 1, &g, &e) == GP_OK); /* cached before the change? */
    gp_export_reader_destroy(r);
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    CHECK(gp_export_reader_grain(r, 1, &g, &e) == GP_ERR_INVALID);
    printf("%s\n", e.message);
    CHECK(gp_export_reader_grain(r, 0, &g, &e) == GP_OK && g.point_count == 4);
    gp_export_reader_destroy(r);
    /* not a pack */
    b[0] = 'X';
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_ERR_INVALID && r == NULL);
    printf("%s\n", e.message);
    src.size = 10;
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_ERR_INVALID && r == NULL);
    CHECK(gp_export_reader_open(NULL, &r, &e) == GP_ERR_INVALID && r == NULL);
    gp_export_reader_destroy(NULL);
    free(pack);
}

/* a view pack: the grains' records and contours, no discs even where the specimen has them,
 * and no file written from it */
static void test_view_pack(void)
{
    gp_grain2d gr[2];
    gp_specimen2d s2;
    gp_spec2d spec;
    two_grains(gr, &s2, &spec, 10, 0, GP_OUT2_GRAINS | GP_OUT2_DESCRIPTORS);
    void *pack;
    size_t len;
    gp_error e;
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &pack, &len, &e) == GP_ERR_INVALID);
    CHECK(gp_export_pack_2d_view(&s2, &spec, &pack, &len, &e) == GP_OK);
    CHECK(len == 128 + 2 * 80 + 7 * 16);
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export_info info;
    CHECK(gp_export_pack_info(&src, &info, &e) == GP_OK);
    CHECK(info.dim == 2 && info.nitems == 2 && info.npoints == 7 && info.ndiscs == 0);
    CHECK(info.flags == (GP_EXPORT_VIEW_ONLY | GP_EXPORT_HAS_DESCRIPTORS));
    gp_export_reader *r;
    CHECK(gp_export_reader_open(&src, &r, &e) == GP_OK);
    for (uint64_t k = 0; k < 2; k++) {
        gp_export_grain g;
        CHECK(gp_export_reader_grain(r, k, &g, &e) == GP_OK);
        CHECK(g.point_count == gr[k].ncontour && g.disc_count == 0);
        CHECK(g.area == gr[k].area && g.regularity == gr[k].descriptors.regularity);
        for (uint64_t i = 0; i < g.point_count; i++) {
            double p[2];
            CHECK(gp_export_reader_point(r, g.point_first + i, p, &e) == GP_OK);
            CHECK(p[0] == gr[k].contour[i].x && p[1] == gr[k].contour[i].y);
        }
    }
    double d[3];
    CHECK(gp_export_reader_disc(r, 0, d, &e) == GP_ERR_INVALID);
    gp_export_reader_destroy(r);
    for (int f = 0; f < GP_EXPORT_NFORMATS; f++) {
        gp_export *x = NULL;
        CHECK(gp_export_open((gp_export_format)f, &src, &x, &e) == GP_ERR_INVALID && x == NULL);
    }
    CHECK(strstr(e.message, "\"odec\"") != NULL);
    /* an export pack is no view pack */
    free(pack);
    gr[1].discs = d1;
    gr[1].ndiscs = 1;
    CHECK(gp_export_pack_2d(&s2, &spec, 2650, &pack, &len, &e) == GP_OK);
    src = gp_export_memory_source(pack, len);
    CHECK(gp_export_pack_info(&src, &info, &e) == GP_OK && !(info.flags & GP_EXPORT_VIEW_ONLY));
    free(pack);
}

int main(void)
{
    test_reader(1);
    test_reader(0);
    test_view_pack();
    return gp_test_summary();
}
