/* test_svg.c -- the SVG views of a hand-made 2D and 3D result: well-formed XML, one
 * <polygon>/<circle> per grain, cell part, seed or cut sphere, axes and labels, errors for
 * unknown views and missing parts, and a 10,000-grain packing drawn quickly and compactly.
 * The size view from stats.fit (CDF curves, KS lines, warnings), and stats.fit / warnings as
 * server/result_json.c writes them from a specimen, drawn by the size view. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../server/result_json.c"
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

/* ---------------------------------------------------------------- size view from stats.fit */

/* a stats.fit area block with a lognormal-like CDF of n points over [lo, hi] (median mid) */
static json_t *fit_block(double lo, double hi, size_t n, double ks, double crit, int with_cdf)
{
    json_t *x = json_array(), *t = json_array(), *a = json_array();
    double mid = sqrt(lo * hi), sg = log(hi / lo) / 6;
    for (size_t i = 0; i < n; i++) {
        double v = lo * pow(hi / lo, (double)i / (n - 1)), z = log(v / mid) / sg;
        double F = 0.5 * erfc(-z / sqrt(2)), Fa = floor(F * 50 + 0.3) / 50;
        json_array_append_new(x, json_real(v));
        json_array_append_new(t, json_real(F));
        json_array_append_new(a, json_real(Fa > 1 ? 1 : Fa));
    }
    json_t *b = json_pack("{s:s, s:{s:f, s:f}, s:{s:f, s:f}, s:f, s:f, s:f, s:i}", "law",
                          "lognormal", "target", "mean", mid, "cov", 0.8, "achieved", "mean",
                          mid * 1.01, "cov", 0.79, "ks", ks, "ks_critical", crit, "w1", 0.012,
                          "n", 500);
    if (with_cdf)
        json_object_set_new(b, "cdf", json_pack("{s:o, s:o, s:o}", "x", x, "target", t, "achieved", a));
    else
        json_decref(x), json_decref(t), json_decref(a);
    return b;
}

/* the d="..." of the first <path> with this class, or NULL */
static const char *path_d(const char *svg, const char *cls)
{
    char key[96];
    snprintf(key, sizeof key, "class=\"%s\"", cls);
    const char *p = strstr(svg, key);
    return p ? strstr(p, " d=\"") : NULL;
}

static void test_size_fit(void)
{
    json_error_t e;
    json_t *r = json_loads(RESULT_2D, 0, &e);
    json_t *st = json_object_get(r, "stats");
    json_object_set_new(st, "fit", json_pack("{s:o, s:o}", "cell_area",
                                             fit_block(5e-4, 2e-2, 60, 0.021, 0.061, 1),
                                             "grain_area",
                                             fit_block(3e-4, 1.3e-2, 60, 0.09, 0.061, 1)));
    json_object_set_new(r, "warnings",
                        json_pack("[s, s]", "IMC stopped at max_steps: error 0.31 > threshold 0.05",
                                  "grain_area: KS 0.09 is above its 5 % critical value 0.061 "
                                  "(N = 500); the grains do not follow the lognormal law as asked, "
                                  "see stats.fit.grain_area for the achieved mean and COV"));
    size_t len;
    int status;
    char err[256];
    char *s = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(status == 200);
    if (!s) return;
    /* four curves: target (dashed) and achieved for cells and grains, 60 points each */
    static const char *cls[4] = {"cdf-target cells", "cdf-achieved cells", "cdf-target grains",
                                 "cdf-achieved grains"};
    for (int k = 0; k < 4; k++) {
        const char *d = path_d(s, cls[k]);
        CHECK(d != NULL);
        if (!d) continue;
        const char *end = strchr(d + 4, '"');
        size_t segs = 0;
        for (const char *q = d + 4; q < end; q++) segs += *q == 'L';
        CHECK(segs == 59);
        /* a CDF rises: the last point is drawn higher (smaller pixel y) than the first */
        double x0, y0, x1, y1;
        CHECK(sscanf(d + 5, "%lf %lf", &x0, &y0) == 2);
        const char *last = end;
        while (last > d && *last != 'L') last--;
        CHECK(sscanf(last + 1, "%lf %lf", &x1, &y1) == 2 && x1 > x0 && y1 < y0 - 100);
    }
    CHECK(count(s, "stroke-dasharray=\"6 4\"") == 2);
    /* the legend and the KS lines, the grains' one marked as over its critical value */
    CHECK(strstr(s, "cells: target (lognormal)") && strstr(s, "grains: achieved"));
    CHECK(strstr(s, "cells: KS 0.021 (5 % critical 0.061)") != NULL);
    CHECK(strstr(s, "grains: KS 0.09 (5 % critical 0.061)") != NULL);
    CHECK(count(s, "ks-over") == 1);
    CHECK(strstr(s, "COV 0.79 (target 0.8)") != NULL);
    /* log axis: the areas span more than a decade */
    CHECK(strstr(s, "area (m², log scale)") != NULL);
    /* the warnings, the long one wrapped */
    CHECK(strstr(s, "IMC stopped at max_steps: error 0.31 &gt; threshold 0.05") != NULL);
    CHECK(count(s, "class=\"warning\"") >= 3);
    CHECK(strstr(s, "warning: IMC stopped") != NULL);
    /* the histograms are not drawn */
    CHECK(strstr(s, "fraction of cells") == NULL);
    free(s);

    /* no warnings, no grains, a narrow range: no warning line, linear axis, two curves */
    json_object_set_new(r, "warnings", json_array());
    json_object_del(json_object_get(st, "fit"), "grain_area");
    json_object_set_new(json_object_get(st, "fit"), "cell_area", fit_block(1e-3, 4e-3, 30, 0.021, 0.061, 1));
    s = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && !strstr(s, "class=\"warning\"") && !strstr(s, "log scale"));
    CHECK(s && strstr(s, "class=\"cdf-achieved cells\"") && !strstr(s, "grains"));
    CHECK(s && strstr(s, "cells: KS 0.021 (5 % critical 0.061)") && !strstr(s, "ks-over"));
    free(s);

    /* a fit without its curves (or none at all, an old result): the histograms */
    json_object_set_new(json_object_get(st, "fit"), "cell_area", fit_block(1e-3, 4e-3, 30, 0.021, 0.061, 0));
    s = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "target (lognormal)") && strstr(s, "fraction of cells") && !strstr(s, "cdf-"));
    free(s);
    json_decref(r);
}

/* ------------------------------------------- stats.fit and warnings as result_json.c writes them */

static const char *const FIT_KEYS[] = {"law", "target", "achieved", "ks", "ks_critical", "w1",
                                       "n", "range", "cdf"};

static void check_area_block(const json_t *b, int with_cdf)
{
    CHECK(json_is_object(b));
    for (size_t i = 0; i < sizeof FIT_KEYS / sizeof *FIT_KEYS - 1; i++)
        CHECK(json_object_get(b, FIT_KEYS[i]) != NULL);
    CHECK(json_object_size(b) == sizeof FIT_KEYS / sizeof *FIT_KEYS - !with_cdf);
    CHECK(!strcmp(json_string_value(json_object_get(b, "law")), "lognormal"));
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(b, "target"), "cov")), 0.8, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(b, "achieved"), "mean")), 2.02e-3, 0);
    CHECK_NEAR(json_number_value(json_object_get(b, "ks_critical")), 0.061, 0);
    CHECK(json_integer_value(json_object_get(b, "n")) == 500);
    const json_t *rg = json_object_get(b, "range");
    CHECK(json_array_size(json_object_get(rg, "achieved")) == 2);
    CHECK_NEAR(json_number_value(json_array_get(json_object_get(rg, "target_p001_p999"), 1)), 9e-3, 0);
    const json_t *cdf = json_object_get(b, "cdf");
    if (with_cdf)
        CHECK(json_array_size(json_object_get(cdf, "x")) == 3 &&
              json_array_size(json_object_get(cdf, "target")) == 3 &&
              json_array_size(json_object_get(cdf, "achieved")) == 3);
}

static void test_result_fit(void)
{
    static double x[3] = {1e-3, 2e-3, 4e-3}, ft[3] = {0.2, 0.5, 0.8}, fa[3] = {0.25, 0.5, 0.75};
    static double d[2] = {0.02, 0.05}, pt[2] = {10, 100}, pa[2] = {13.1, 100};
    char *warn[1] = {"IMC stopped at max_steps: error 0.31 > threshold 0.05"};
    gp_specimen2d s;
    memset(&s, 0, sizeof s);
    s.fit.cell_area = (gp_fit_area){.present = 1, .law = GP_LAW_LOGNORMAL, .target_mean = 2e-3,
                                    .target_cov = 0.8, .mean = 2.02e-3, .cov = 0.79, .ks = 0.021,
                                    .ks_critical = 0.061, .w1 = 0.012, .min = 2e-4, .max = 1.1e-2,
                                    .q001 = 1e-4, .q999 = 9e-3, .n = 500, .ncurve = 3,
                                    .curve_x = x, .curve_target = ft, .curve_achieved = fa};
    s.fit.cell_orientation = (gp_fit_orient){.present = 1, .target_mean_deg = 30,
                                             .target_anisotropy = 0.5, .ks = 0.03,
                                             .ks_critical = 0.061, .n = 500};
    s.fit.grain_area.present = 0; /* e.g. no grains computed: the block is left out */
    s.warnings = warn;
    s.nwarnings = 1;
    s.imc_error_kind = "AD";
    s.imc_threshold = 0.05;
    s.imc_error = 0.31;
    s.imc_stop_reason = "max_steps";
    gp_spec2d spec;
    memset(&spec, 0, sizeof spec);
    spec.particles = 500;
    spec.imc_error = GP_IMC_E3; /* the core's string wins */
    json_t *sj = json_object();
    json_t *r = gpd_result_2d(&s, &spec, sj);
    CHECK(r != NULL);
    const json_t *st = json_object_get(r, "stats"), *fit = json_object_get(st, "fit");
    CHECK(json_is_object(fit) && json_object_size(fit) == 2);
    check_area_block(json_object_get(fit, "cell_area"), 1);
    const json_t *o = json_object_get(fit, "cell_orientation");
    CHECK(json_object_size(o) == 4 && json_object_get(o, "ks") && json_object_get(o, "n"));
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(o, "target"), "mean_deg")), 30, 0);
    CHECK_NEAR(json_number_value(json_object_get(json_object_get(o, "target"), "anisotropy")), 0.5, 0);
    CHECK(!json_object_get(fit, "grain_area") && !json_object_get(fit, "passing"));
    const json_t *ie = json_object_get(st, "imc_error");
    CHECK(!strcmp(json_string_value(json_object_get(ie, "measure")), "AD"));
    CHECK_NEAR(json_number_value(json_object_get(ie, "target")), 0.05, 0);
    CHECK(!strcmp(json_string_value(json_object_get(ie, "stop_reason")), "max_steps"));
    const json_t *w = json_object_get(r, "warnings");
    CHECK(json_array_size(w) == 1 && !strcmp(json_string_value(json_array_get(w, 0)), warn[0]));

    /* drawn by the size view: one series, its KS line and the warning */
    size_t len;
    int status;
    char err[256];
    char *svg = render(r, NULL, "size", NULL, &len, &status, err);
    check_common(svg, len);
    CHECK(svg && strstr(svg, "class=\"cdf-target cells\"") && strstr(svg, "class=\"cdf-achieved cells\""));
    CHECK(svg && strstr(svg, "cells: KS 0.021 (5 % critical 0.061)") && !strstr(svg, "grains"));
    CHECK(svg && strstr(svg, "error 0.31 &gt; threshold 0.05"));
    free(svg);
    json_decref(r);

    /* the compact summary of a job's progress: no curves; a sieve adds passing; no warnings: [] */
    s.fit.passing = (gp_fit_passing){.n = 2, .diameters = d, .target = pt, .achieved = pa,
                                     .max_error_pp = 3.1};
    json_t *f = gpd_fit_2d(&s.fit, 0);
    check_area_block(json_object_get(f, "cell_area"), 0);
    const json_t *p = json_object_get(f, "passing");
    CHECK(json_object_size(p) == 4 && json_array_size(json_object_get(p, "achieved")) == 2);
    CHECK_NEAR(json_number_value(json_object_get(p, "max_error_pp")), 3.1, 0);
    json_decref(f);
    s.nwarnings = 0;
    s.warnings = NULL;
    r = gpd_result_2d(&s, &spec, sj);
    CHECK(json_is_array(json_object_get(r, "warnings")) && json_array_size(json_object_get(r, "warnings")) == 0);
    json_decref(r);
    json_decref(sj);
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
    test_size_fit();
    test_result_fit();
    test_3d();
    test_large();
    return gp_test_summary();
}
