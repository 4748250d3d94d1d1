/* test_svg.c -- the SVG views of a hand-made 2D and 3D result: well-formed XML, one
 * <polygon>/<circle> per grain, cell part, seed or cut sphere, axes and labels, errors for
 * unknown views and missing parts, and a 10,000-grain packing drawn quickly and compactly. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../server/svg.c"
#include "gp_test.h"

static size_t count(const char *hay, const char *needle)
{
    size_t n = 0;
    for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle)) n++;
    return n;
}

static int have_python = -1;

/* well-formed XML whose root is <svg>: python3's parser when there is one, else a tag balance */
static int well_formed(const char *svg, size_t len)
{
    if (have_python < 0) have_python = system("python3 -c 'import xml.etree.ElementTree' 2>/dev/null") == 0;
    if (have_python) {
        char path[] = "/tmp/gp_test_svg_XXXXXX";
        int fd = mkstemp(path);
        if (fd < 0) return 0;
        FILE *f = fdopen(fd, "w");
        fwrite(svg, 1, len, f);
        fclose(f);
        char cmd[512];
        snprintf(cmd, sizeof cmd,
                 "python3 -c \"import sys, xml.etree.ElementTree as E; r = E.parse(sys.argv[1]).getroot(); "
                 "sys.exit(0 if r.tag == '{http://www.w3.org/2000/svg}svg' else 1)\" %s",
                 path);
        int rc = system(cmd);
        unlink(path);
        return rc == 0;
    }
    /* fallback: every <tag> is closed in order */
    const char *stack[64];
    size_t sl[64], depth = 0;
    for (const char *p = strchr(svg, '<'); p; p = strchr(p + 1, '<')) {
        if (p[1] == '?' || p[1] == '!') continue;
        const char *end = strchr(p, '>');
        if (!end) return 0;
        if (p[1] == '/') {
            if (!depth) return 0;
            depth--;
            if (strncmp(p + 2, stack[depth], sl[depth])) return 0;
        } else if (end[-1] != '/') {
            if (depth == 64) return 0;
            stack[depth] = p + 1;
            sl[depth] = strcspn(p + 1, " >");
            depth++;
        }
    }
    return depth == 0;
}

static const char *RESULT_2D =
    "{\"grains\": ["
    " {\"id\": 0, \"cell\": 0, \"contour\": [[0.1,0.1],[0.4,0.1],[0.4,0.4],[0.1,0.4]], \"area\": 0.09, \"orientation_deg\": 10,"
    "  \"descriptors\": {\"elongation\": 0.9, \"roundness\": 0.5, \"circularity\": 0.8, \"regularity\": 3.1}, \"discs\": [[0.25,0.25,0.15]]},"
    " {\"id\": 1, \"cell\": 1, \"contour\": [[0.6,0.1],[0.9,0.1],[0.9,0.3],[0.6,0.3]], \"area\": 0.06, \"orientation_deg\": -45,"
    "  \"descriptors\": {\"elongation\": 0.6, \"roundness\": 0.4, \"circularity\": 0.7, \"regularity\": 2.5}},"
    " {\"id\": 2, \"cell\": 2, \"contour\": [[0.1,0.6],[0.3,0.6],[0.3,0.9],[0.1,0.9]], \"area\": 0.06, \"orientation_deg\": 80,"
    "  \"descriptors\": {\"elongation\": 0.7, \"roundness\": 0.6, \"circularity\": 0.75, \"regularity\": 3.5}},"
    " {\"id\": 3, \"cell\": 3, \"contour\": [[0.6,0.6],[0.9,0.6],[0.75,0.9]], \"area\": 0.045, \"orientation_deg\": 0,"
    "  \"descriptors\": {\"elongation\": 0.8, \"roundness\": 0.3, \"circularity\": 0.6, \"regularity\": 2.0}}],"
    " \"cells\": ["
    " {\"id\": 0, \"seed\": [0.25,0.25], \"polygons\": [[[0,0],[0.5,0],[0.5,0.5],[0,0.5]]], \"area\": 0.25, \"orientation_deg\": 0},"
    " {\"id\": 1, \"seed\": [0.75,0.25], \"polygons\": [[[0.5,0],[1,0],[1,0.5],[0.5,0.5]]], \"area\": 0.25, \"orientation_deg\": 0},"
    " {\"id\": 2, \"seed\": [0.25,0.75], \"polygons\": [[[0,0.5],[0.5,0.5],[0.5,1],[0,1]]], \"area\": 0.25, \"orientation_deg\": 0},"
    " {\"id\": 3, \"seed\": [0.75,0.75], \"polygons\": [[[0.5,0.5],[1,0.5],[1,0.75],[0.5,0.75]], [[0.5,0.75],[1,0.75],[1,1],[0.5,1]]], \"area\": 0.25, \"orientation_deg\": 0}],"
    " \"container\": {\"polygon\": [[0,0],[1,0],[1,1],[0,1]], \"holes\": []},"
    " \"stats\": {\"imc_error\": 0.003, \"imc_steps\": 1200, \"solid_fraction\": 0.255,"
    "  \"size_histogram\": {\"edges\": [0.1, 0.2, 0.3, 0.4], \"target\": [0.2, 0.6, 0.2], \"achieved\": [0.25, 0.5, 0.25]},"
    "  \"grain_size_histogram\": {\"edges\": [0.1, 0.2, 0.3, 0.4], \"achieved\": [0.5, 0.5, 0]},"
    "  \"orientation_histogram\": {\"edges\": [-90, -45, 0, 45, 90], \"target\": [0.25, 0.25, 0.25, 0.25], \"achieved\": [0.1, 0.4, 0.3, 0.2]},"
    "  \"descriptors\": {\"elongation\": {\"mean\": 0.75, \"edges\": [0, 0.5, 1], \"achieved\": [0, 1]},"
    "                  \"roundness\": {\"mean\": 0.45, \"edges\": [0, 0.5, 1], \"counts\": [3, 1]},"
    "                  \"circularity\": {\"mean\": 0.71, \"edges\": [0, 0.5, 1], \"achieved\": [0, 1]},"
    "                  \"regularity\": {\"mean\": 2.8, \"edges\": [2, 3, 4], \"achieved\": [0.5, 0.5]}}}}";

static const char *RESULT_3D =
    "{\"spheres\": [[0.1,0.1,0.25,0.05],[0.3,0.1,0.22,0.04],[0.3,0.3,0.28,0.06],[0.1,0.4,0.25,0.02],"
    "              [0.4,0.4,0.26,0.03],[0.2,0.2,0.05,0.03]],"
    " \"box\": [0.5, 0.5, 0.5],"
    " \"stats\": {\"porosity\": 0.38, \"coordination_number\": 4.2, \"particles\": 6,"
    "  \"psd\": {\"diameters\": [0.01, 0.02, 0.05, 0.08, 0.1],"
    "           \"target_weight\": [0, 2, 50, 95, 100], \"achieved_weight\": [0, 2.7, 52, 94.5, 100],"
    "           \"target_number\": [0, 32.49, 90.11, 99.59, 100], \"achieved_number\": [0, 34.5, 94.4, 99.8, 100]}}}";

static char *render(const json_t *r, const char *kind, const char *view, const gp_svg_options *o,
                    size_t *len, int *status, char *err)
{
    char *s = gp_svg_render(r, kind, view, o, len, status, err, 256);
    if (!s) fprintf(stderr, "render %s: %d %s\n", view, *status, err);
    return s;
}

static void check_common(const char *svg, size_t len)
{
    CHECK(svg != NULL);
    if (!svg) return;
    CHECK(strlen(svg) == len);
    CHECK(strstr(svg, "<svg") != NULL);
    CHECK(strstr(svg, "viewBox=\"0 0 ") != NULL);
    CHECK(strstr(svg, " width=\"") != NULL && strstr(svg, " height=\"") != NULL);
    CHECK(strstr(svg, "<title>") != NULL);
    CHECK(count(svg, "<text") >= 3);
    CHECK(well_formed(svg, len));
    CHECK(strstr(svg, "nan") == NULL && strstr(svg, "inf") == NULL);
}

static void test_2d(void)
{
    json_error_t e;
    json_t *r = json_loads(RESULT_2D, 0, &e);
    CHECK(r != NULL);
    size_t len;
    int status;
    char err[256];

    char *s = render(r, "fourier-voronoi-2d", "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(status == 200);
    CHECK(count(s, "<polygon") == 4);
    CHECK(count(s, "<circle") == 0);
    CHECK(count(s, "<line") >= 6); /* axes and ticks */
    CHECK(strstr(s, "x (m)") && strstr(s, "y (m)"));
    CHECK(strstr(s, "class=\"container\"") != NULL);
    /* y flipped: the grain at y 0.1..0.4 is drawn below (larger pixel y) the one at 0.6..0.9 */
    {
        const char *g0 = strstr(s, "<polygon"), *g2 = strstr(strstr(strstr(g0 + 1, "<polygon") + 1, "<polygon"), "points=\"");
        double x0, y0, x2, y2;
        CHECK(sscanf(strstr(g0, "points=\"") + 8, "%lf,%lf", &x0, &y0) == 2);
        CHECK(sscanf(g2 + 8, "%lf,%lf", &x2, &y2) == 2);
        CHECK(y0 > y2);
    }
    free(s);

    gp_svg_options o = {.color = "orientation"};
    s = render(r, NULL, "packing", &o, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<polygon") == 4 && strstr(s, "orientation (deg)"));
    free(s);
    o.color = "rainbow";
    CHECK(gp_svg_render(r, NULL, "packing", &o, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "size, orientation"));

    s = render(r, "fourier-voronoi-2d", "cells", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<polygon") == 5); /* cell 3 has two parts */
    CHECK(s && count(s, "<circle") == 4);  /* seeds */
    free(s);

    s = render(r, "fourier-voronoi-2d", "size", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<rect") >= 3 + 1);
    CHECK(s && strstr(s, "class=\"target\"") && strstr(s, "target (lognormal)") && strstr(s, "achieved (grains)"));
    free(s);

    s = render(r, "fourier-voronoi-2d", "orientation", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "class=\"target\"") && strstr(s, "90°"));
    CHECK(s && count(s, "<circle") == 0);
    free(s);

    s = render(r, "fourier-voronoi-2d", "descriptors", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "class=\"mean\"") == 4);
    CHECK(s && strstr(s, "elongation") && strstr(s, "roundness") && strstr(s, "circularity") && strstr(s, "regularity"));
    free(s);

    /* unknown view: NULL, 400, the valid views listed */
    CHECK(gp_svg_render(r, "fourier-voronoi-2d", "pie", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(strstr(err, "unknown view \"pie\"") && strstr(err, "packing, cells, size, orientation, descriptors"));
    CHECK(gp_svg_render(r, "fourier-voronoi-2d", "section", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(gp_svg_render(r, "fourier-voronoi-2d", NULL, NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(gp_svg_render(r, "nope", "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(gp_svg_render(NULL, NULL, "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 500);

    /* missing parts: 409 with the output to ask for; stats missing: recomputed */
    json_object_del(r, "cells");
    CHECK(gp_svg_render(r, NULL, "cells", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"cells\""));
    json_object_del(r, "stats");
    s = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(s, len);
    free(s);
    s = render(r, NULL, "orientation", NULL, &len, &status, err);
    check_common(s, len);
    free(s);
    s = render(r, NULL, "descriptors", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "class=\"mean\"") == 4);
    free(s);
    for (size_t i = 0; i < json_array_size(json_object_get(r, "grains")); i++)
        json_object_del(json_array_get(json_object_get(r, "grains"), i), "descriptors");
    CHECK(gp_svg_render(r, NULL, "descriptors", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"descriptors\""));
    json_object_del(r, "grains");
    CHECK(gp_svg_render(r, NULL, "packing", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"grains\""));
    CHECK(gp_svg_render(r, NULL, "size", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409);
    json_decref(r);

    /* the shapes server/result_json.c writes: stats as {"target", "achieved"}, null targets and
     * histograms, descriptor stats with only a mean */
    r = json_loads(RESULT_2D, 0, &e);
    json_t *st = json_object_get(r, "stats");
    json_object_set_new(st, "solid_fraction", json_pack("{s:f, s:f}", "target", 0.65, "achieved", 0.6));
    json_object_set_new(json_object_get(st, "size_histogram"), "target", json_null());
    json_object_set_new(st, "orientation_histogram", json_null());
    json_object_set_new(json_object_get(st, "descriptors"), "elongation", json_pack("{s:f}", "mean", 0.7));
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "solid fraction 0.600"));
    free(s);
    s = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && !strstr(s, "class=\"target\""));
    free(s);
    s = render(r, NULL, "orientation", NULL, &len, &status, err);
    check_common(s, len);
    free(s);
    s = render(r, NULL, "descriptors", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "class=\"mean\"") == 4);
    free(s);
    json_decref(r);

    /* a circle container */
    r = json_loads("{\"grains\": [{\"contour\": [[0,0],[1,0],[0,1]], \"area\": 0.5}],"
                   " \"container\": {\"circle\": {\"center\": [0.3, 0.3], \"radius\": 2}}}", 0, &e);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<polygon") == 1 && strstr(s, "class=\"container\""));
    free(s);
    json_decref(r);
}

static void test_3d(void)
{
    json_error_t e;
    json_t *r = json_loads(RESULT_3D, 0, &e);
    CHECK(r != NULL);
    size_t len;
    int status;
    char err[256];
    char *s = render(r, "spheres-3d", "section", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<circle") == 5); /* the sphere at z = 0.05 is not cut by z = 0.25 */
    CHECK(s && strstr(s, "5 of 6 spheres"));
    CHECK(s && strstr(s, "diameter (mm)"));
    free(s);
    gp_svg_options o = {.has_z = 1, .z = 0.05};
    s = render(r, NULL, "section", &o, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<circle") == 1);
    free(s);
    o.z = 0.7;
    CHECK(gp_svg_render(r, NULL, "section", &o, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "outside"));

    s = render(r, "spheres-3d", "psd", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "log scale") && strstr(s, "percent passing"));
    CHECK(s && strstr(s, "class=\"target_weight\"") && strstr(s, "class=\"achieved_number\""));
    CHECK(s && strstr(s, ">10<") && strstr(s, ">100<")); /* decade ticks in mm */
    free(s);

    CHECK(gp_svg_render(r, "spheres-3d", "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "section, psd"));
    json_object_del(r, "box");
    s = render(r, NULL, "section", NULL, &len, &status, err); /* box from the spheres */
    check_common(s, len);
    free(s);
    json_object_del(r, "spheres");
    CHECK(gp_svg_render(r, "spheres-3d", "section", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 409 && strstr(err, "\"spheres\""));
    json_object_del(r, "stats");
    CHECK(gp_svg_render(r, "spheres-3d", "psd", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 409);
    json_decref(r);
}

/* 10,000 grains of 128 points: fast and bounded */
static void test_large(void)
{
    json_t *r = json_object(), *grains = json_array();
    int n = 100;
    for (int gy = 0; gy < n; gy++)
        for (int gx = 0; gx < n; gx++) {
            json_t *g = json_object(), *c = json_array();
            double cx = (gx + 0.5) / n, cy = (gy + 0.5) / n, rr = 0.4 / n;
            for (int k = 0; k < 128; k++) {
                double t = 2 * M_PI * k / 128;
                json_array_append_new(c, json_pack("[ff]", cx + rr * cos(t), cy + rr * 0.7 * sin(t)));
            }
            json_object_set_new(g, "contour", c);
            json_object_set_new(g, "area", json_real(M_PI * rr * rr * 0.7 * (1 + (gx % 7) * 0.1)));
            json_object_set_new(g, "orientation_deg", json_real(gx % 180 - 90));
            json_array_append_new(grains, g);
        }
    json_object_set_new(r, "grains", grains);
    size_t len;
    int status;
    char err[256];
    clock_t t0 = clock();
    char *s = render(r, "fourier-voronoi-2d", "packing", NULL, &len, &status, err);
    double dt = (double)(clock() - t0) / CLOCKS_PER_SEC;
    printf("10000 grains: %.3f s, %zu bytes\n", dt, len);
    CHECK(s != NULL);
    CHECK(s && count(s, "<polygon") == 10000);
    CHECK(len < 8u * 1024 * 1024);
    CHECK(dt < 5.0);
    CHECK(s && well_formed(s, len));
    free(s);
    json_decref(r);
}

int main(void)
{
    test_2d();
    test_3d();
    test_large();
    return gp_test_summary();
}
