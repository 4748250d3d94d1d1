/* test_svg.c -- the SVG views of a hand-made 2D and 3D result: well-formed XML, one
 * <polygon>/<circle> per grain, cell part, seed or cut sphere, axes and labels, no two texts
 * overlapping (every picture drawn here), errors for unknown views and missing parts, and a
 * 10,000-grain packing drawn compactly.
 * Geometry against the tests' own truth: the rose's classes (18 at Mollon & Zhao's 500 grains)
 * and its achieved and target radii recomputed from the test's directions and a numerical
 * integral of the cosine law; colour-bar ticks round (1-2-5 steps) and 12 px apart; the
 * section's default z half a base cell from every mirror plane of a tiled result, its title's
 * cut count, porosity of the cut and D50/Cu; the detail inset's window (central on a uniform
 * packing, where the grains are on a half-empty one) and the grains drawn in it; the
 * descriptor histograms' Freedman-Diaconis bins, bar heights, mean and target.
 * The size view from stats.fit (CDF curves, KS lines, warnings), and stats.fit / warnings as
 * server/jobs/result_json.c writes them from a specimen, drawn by the size view.
 * Compact reading (what GET /svg does): server/util/json_scan.c (member spans, array walks, the
 * summary of a result, cut texts refused), the element parser against jansson and its
 * numbers against strtod, the fast "%.1f", and every view drawn as a pull stream from a summary plus an export pack or the
 * scanned result text, in pieces of 7 bytes to 1 MiB, byte for byte as gp_svg_render draws
 * the whole result; a source failing anywhere fails the picture (500 or a read error). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "gp_test.h"
#include "util/json_scan.h"
#include "kinds/fourier-voronoi-2d/kind_fv2d.h"
#include "svg/svg.h"
#include "svg/svg_internal.h" /* the element parsers, the fast "%.1f" */

#define KIND_2D "fourier-voronoi-2d"
#define KIND_3D "spheres-3d"

static size_t count(const char *hay, const char *needle)
{
    size_t n = 0;
    for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle)) n++;
    return n;
}

/* gp_svg_render and gp_svg_open with the status (200 on success) and message in plain
 * variables, as the checks read them */
static char *render_st(const json_t *r, const char *kind, const char *view,
                       const gp_svg_options *o, size_t *len, int *status, char *err, size_t n)
{
    gpd_err e = {0, ""};
    char *s = gp_svg_render(r, kind, view, o, len, &e);
    *status = s ? 200 : e.status;
    snprintf(err, n, "%s", e.msg);
    return s;
}

static gp_svg *open_st(const gp_svg_input *in, const char *view, const gp_svg_options *o,
                       int *status, char *err, size_t n)
{
    gpd_err e = {0, ""};
    gp_svg *g = gp_svg_open(in, view, o, &e);
    *status = g ? 200 : e.status;
    snprintf(err, n, "%s", e.msg);
    return g;
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
    char *s = render_st(r, kind, view, o, len, status, err, 256);
    if (!s) fprintf(stderr, "render %s: %d %s\n", view, *status, err);
    return s;
}

/* ---- reading a picture back: attributes, <text> boxes ---- */

/* the number of attribute attr (e.g. "x") of the element that starts at el; NAN without it */
static double attr_num(const char *el, const char *attr)
{
    const char *end = strchr(el, '>');
    char key[48];
    snprintf(key, sizeof key, " %s=\"", attr);
    const char *p = strstr(el, key);
    if (!p || (end && p > end)) return NAN;
    return strtod(p + strlen(key), NULL);
}

/* the content of the <text> element that starts at el, entities and tags kept, into buf */
static void text_of(const char *el, char *buf, size_t n)
{
    const char *a = strchr(el, '>'), *b = a ? strstr(a, "</text>") : NULL;
    size_t k = a && b ? (size_t)(b - a - 1) : 0;
    if (k >= n) k = n - 1;
    memcpy(buf, a ? a + 1 : "", k);
    buf[k] = 0;
}

/* characters of a text as drawn: UTF-8 characters, an entity as one */
static double text_chars(const char *t)
{
    double n = 0;
    for (const unsigned char *p = (const unsigned char *)t; *p; p++) {
        if (*p == '&') {
            while (p[1] && *p != ';') p++;
        } else if ((*p & 0xC0) == 0x80) {
            continue;
        }
        n++;
    }
    return n;
}

typedef struct tbox {
    double x0, y0, x1, y1;
    char s[128];
} tbox;

/* the box of every <text>: 0.55 em a character (Helvetica's average; digits 0.56), from 0.75
 * em above the baseline to 0.2 em below; anchors and a -90 rotation taken into account */
static size_t text_boxes(const char *svg, tbox *b, size_t max)
{
    size_t n = 0;
    for (const char *p = strstr(svg, "<text "); p && n < max; p = strstr(p + 1, "<text ")) {
        double x = attr_num(p, "x"), y = attr_num(p, "y"), fs = attr_num(p, "font-size");
        if (isnan(fs)) fs = 12;
        text_of(p, b[n].s, sizeof b[n].s);
        double w = 0.55 * fs * text_chars(b[n].s), lo = x;
        const char *end = strchr(p, '>');
        const char *anc = strstr(p, "text-anchor=\"");
        if (anc && anc < end && !strncmp(anc + 13, "middle", 6)) lo = x - w / 2;
        else if (anc && anc < end && !strncmp(anc + 13, "end", 3)) lo = x - w;
        const char *rot = strstr(p, "rotate(-90");
        if (rot && rot < end) /* along -y from the anchor, glyphs towards -x */
            b[n] = (tbox){x - 0.75 * fs, y - (lo - x) - w, x + 0.2 * fs, y - (lo - x), ""},
            text_of(p, b[n].s, sizeof b[n].s);
        else
            b[n].x0 = lo, b[n].x1 = lo + w, b[n].y0 = y - 0.75 * fs, b[n].y1 = y + 0.2 * fs;
        n++;
    }
    return n;
}

/* no two texts of the picture overlap (by more than half a pixel each way) */
static int texts_apart(const char *svg)
{
    enum { MAXT = 4000 };
    tbox *b = malloc(MAXT * sizeof *b);
    size_t n = text_boxes(svg, b, MAXT);
    int ok = 1;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            double ox = fmin(b[i].x1, b[j].x1) - fmax(b[i].x0, b[j].x0);
            double oy = fmin(b[i].y1, b[j].y1) - fmax(b[i].y0, b[j].y0);
            if (ox > 0.5 && oy > 0.5) {
                fprintf(stderr, "texts overlap: \"%s\" and \"%s\"\n", b[i].s, b[j].s);
                ok = 0;
            }
        }
    free(b);
    return ok;
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
    CHECK(texts_apart(svg));
}

/* a result from its text (NULL, counted as a failed check, when it is not JSON) */
static json_t *load(const char *text)
{
    json_error_t e;
    json_t *r = json_loads(text, 0, &e);
    CHECK(r != NULL);
    if (!r) fprintf(stderr, "not JSON: %s\n", e.text);
    return r;
}

/* draws view of r (the kind from the result): a well-formed picture; returns how many times
 * needle is in it (0 when nothing is drawn) */
static size_t drawn(const json_t *r, const char *view, const char *needle)
{
    size_t len, n = 0;
    int status;
    char err[256];
    char *s = render(r, NULL, view, NULL, &len, &status, err);
    check_common(s, len);
    if (s && needle) n = count(s, needle);
    free(s);
    return n;
}

static void test_2d(void)
{
    json_t *r = load(RESULT_2D);
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
    CHECK(render_st(r, NULL, "packing", &o, &len, &status, err, sizeof err) == NULL);
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
    CHECK(render_st(r, "fourier-voronoi-2d", "pie", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(strstr(err, "unknown view \"pie\"") && strstr(err, "packing, cells, size, orientation, descriptors"));
    CHECK(render_st(r, "fourier-voronoi-2d", "section", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(render_st(r, "fourier-voronoi-2d", NULL, NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400);
    CHECK(render_st(r, "nope", "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(render_st(NULL, NULL, "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 500);

    /* missing parts: 409 with the output to ask for; stats missing: recomputed */
    json_object_del(r, "cells");
    CHECK(render_st(r, NULL, "cells", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"cells\""));
    json_object_del(r, "stats");
    drawn(r, "size", NULL);
    drawn(r, "orientation", NULL);
    CHECK(drawn(r, "descriptors", "class=\"mean\"") == 4);
    for (size_t i = 0; i < json_array_size(json_object_get(r, "grains")); i++)
        json_object_del(json_array_get(json_object_get(r, "grains"), i), "descriptors");
    CHECK(render_st(r, NULL, "descriptors", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"descriptors\""));
    json_object_del(r, "grains");
    CHECK(render_st(r, NULL, "packing", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409 && strstr(err, "\"grains\""));
    CHECK(render_st(r, NULL, "size", NULL, &len, &status, err, 256) == NULL);
    CHECK(status == 409);
    json_decref(r);

    /* the shapes server/jobs/result_json.c writes: stats as {"target", "achieved"}, null targets and
     * histograms, descriptor stats with only a mean */
    r = load(RESULT_2D);
    json_t *st = json_object_get(r, "stats");
    json_object_set_new(st, "solid_fraction", json_pack("{s:f, s:f}", "target", 0.65, "achieved", 0.6));
    json_object_set_new(json_object_get(st, "size_histogram"), "target", json_null());
    json_object_set_new(st, "orientation_histogram", json_null());
    json_object_set_new(json_object_get(st, "descriptors"), "elongation", json_pack("{s:f}", "mean", 0.7));
    CHECK(drawn(r, "packing", "solid fraction 0.600") >= 1);
    CHECK(drawn(r, "size", "class=\"target\"") == 0);
    drawn(r, "orientation", NULL);
    CHECK(drawn(r, "descriptors", "class=\"mean\"") == 4);
    json_decref(r);

    /* a circle container */
    r = load("{\"grains\": [{\"contour\": [[0,0],[1,0],[0,1]], \"area\": 0.5}],"
             " \"container\": {\"circle\": {\"center\": [0.3, 0.3], \"radius\": 2}}}");
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && count(s, "<polygon") == 1 && strstr(s, "class=\"container\""));
    free(s);
    json_decref(r);
}

static void test_3d(void)
{
    json_t *r = load(RESULT_3D);
    char err[256];
    size_t len;
    int status;
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
    CHECK(render_st(r, NULL, "section", &o, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "outside"));

    s = render(r, "spheres-3d", "psd", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "log scale") && strstr(s, "percent passing"));
    CHECK(s && strstr(s, "class=\"target_weight\"") && strstr(s, "class=\"achieved_number\""));
    CHECK(s && strstr(s, ">10<") && strstr(s, ">100<")); /* decade ticks in mm */
    free(s);

    CHECK(render_st(r, "spheres-3d", "packing", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "section, psd"));
    json_object_del(r, "box");
    s = render(r, NULL, "section", NULL, &len, &status, err); /* box from the spheres */
    check_common(s, len);
    free(s);
    json_object_del(r, "spheres");
    CHECK(render_st(r, "spheres-3d", "section", NULL, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 409 && strstr(err, "\"spheres\""));
    json_object_del(r, "stats");
    CHECK(render_st(r, "spheres-3d", "psd", NULL, &len, &status, err, sizeof err) == NULL);
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
    json_t *r = load(RESULT_2D);
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
    CHECK(strstr(s, "cells: achieved, KS 0.021 (5 % critical 0.061)") != NULL);
    CHECK(strstr(s, "grains: achieved, KS 0.09 (5 % critical 0.061)") != NULL);
    CHECK(count(s, "ks-over") == 1);
    CHECK(strstr(s, "KS 0.09 is above its 5 % critical value 0.061") != NULL);
    CHECK(strstr(s, "cells: N 500, W1 0.012, COV 0.79 (target 0.8)") != NULL);
    CHECK(strstr(s, "COV 0.79 (target 0.8)") != NULL);
    /* log axis: the areas span more than a decade */
    CHECK(strstr(s, "area (mm², log scale)") != NULL); /* 0.5 to 20,000 mm², not 5e-4 m² */
    CHECK(strstr(s, ">1000<") && strstr(s, ">10000<") && !strstr(s, "e-0"));
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
    CHECK(s && !strstr(s, "class=\"warning\"") && strstr(s, "log scale")); /* less than a decade */
    CHECK(s && strstr(s, ">1000<") && strstr(s, ">2000<") && strstr(s, ">3000<"));
    CHECK(s && strstr(s, "class=\"cdf-achieved cells\"") && !strstr(s, "grains"));
    CHECK(s && strstr(s, "cells: achieved, KS 0.021 (5 % critical 0.061)") && !strstr(s, "ks-over"));
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
    json_t *r = gpd_result_2d(&s, &spec, sj, NULL);
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
    CHECK(svg && strstr(svg, "cells: achieved, KS 0.021 (5 % critical 0.061)") && !strstr(svg, "grains"));
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
    r = gpd_result_2d(&s, &spec, sj, NULL);
    CHECK(json_is_array(json_object_get(r, "warnings")) && json_array_size(json_object_get(r, "warnings")) == 0);
    json_decref(r);
    json_decref(sj);
}

/* ---------------------------------------------------------------- the orientation rose */

/* a fixed generator for the tests' data: uniform in [0, 1) */
static double lcg(unsigned *x)
{
    *x = *x * 1103515245u + 12345u;
    return ((*x >> 8) & 0xFFFFFF) / 16777216.0;
}

/* the cosine law of api.md (any scale) */
static double cos_law(double t, double mean, double a)
{
    return (1 + a) / 2 + (1 - a) / 2 * cos(2 * (t - mean) * M_PI / 180);
}

/* its probability between t0 and t1 degrees, by Simpson's rule (not the view's closed form) */
static double cos_prob(double t0, double t1, double mean, double a)
{
    double in[2] = {0, 0}, lim[2][2] = {{t0, t1}, {-90, 90}};
    for (int k = 0; k < 2; k++) {
        int m = 400;
        double h = (lim[k][1] - lim[k][0]) / m;
        for (int i = 0; i <= m; i++)
            in[k] += (i == 0 || i == m ? 1 : i % 2 ? 4 : 2) * cos_law(lim[k][0] + i * h, mean, a);
        in[k] *= h / 3;
    }
    return in[0] / in[1];
}

/* n grains whose directions follow the law (rejection sampling), with their fit block */
static json_t *rose_result(int n, double mean, double a)
{
    json_t *grains = json_array();
    unsigned x = 11;
    for (int i = 0; i < n; i++) {
        double t;
        do t = lcg(&x) * 180 - 90;
        while (lcg(&x) > cos_law(t, mean, a));
        json_array_append_new(grains, json_pack("{s:f, s:f}", "orientation_deg", t, "area", 1.0));
    }
    json_t *fit = json_pack("{s:{s:{s:f, s:f}, s:f, s:f, s:i}}", "grain_orientation", "target",
                            "mean_deg", mean, "anisotropy", a, "ks", 0.03, "ks_critical",
                            1.36 / sqrt(n), "n", n);
    return json_pack("{s:s, s:o, s:{s:o}}", "kind", KIND_2D, "grains", grains, "stats", "fit", fit);
}

/* the radii of the arcs of the path of class cls; their count */
static int arc_radii(const char *svg, const char *cls, double *r, int max)
{
    const char *d = path_d(svg, cls);
    if (!d) return 0;
    const char *end = strchr(d + 4, '"');
    int n = 0;
    for (const char *q = strchr(d + 4, 'A'); q && q < end && n < max; q = strchr(q + 1, 'A'))
        r[n++] = strtod(q + 1, NULL);
    return n;
}

/* px per unit of density: each ring's radius over its label's value, the same for all */
static double ring_scale(const char *svg, int *rings)
{
    double scale = NAN;
    *rings = 0;
    const char *p = strstr(svg, "class=\"ring\""), *l = strstr(svg, "class=\"ring-label\"");
    for (; p && l; p = strstr(p + 1, "class=\"ring\""), l = strstr(l + 1, "class=\"ring-label\"")) {
        double cx, cy, pr;
        char lab[32];
        CHECK(sscanf(strstr(p, " d=\"") + 4, "M%lf %lfa%lf", &cx, &cy, &pr) == 3);
        text_of(l, lab, sizeof lab);
        double v = strtod(lab, NULL), sc = pr / v;
        if (*rings) CHECK_NEAR(sc, scale, 0.02 * (1 + scale) / v);
        else scale = sc;
        (*rings)++;
    }
    return scale;
}

static void check_rose(int n, double mean, double a, int classes)
{
    json_t *r = rose_result(n, mean, a);
    size_t len;
    int status;
    char err[256];
    char *s = render(r, NULL, "orientation", NULL, &len, &status, err);
    check_common(s, len);
    if (!s) return;
    double ra[80], rt[80], w = 180.0 / classes;
    int rings;
    double scale = ring_scale(s, &rings);
    CHECK(rings >= 3 && isfinite(scale));
    /* classes x 2 arcs (axial: each class and its mirror), the same drawing for both curves */
    CHECK(arc_radii(s, "achieved", ra, 80) == 2 * classes);
    CHECK(arc_radii(s, "target", rt, 80) == 2 * classes);
    /* the achieved radii are the test's own counts of its directions (% per degree) */
    double cnt[40] = {0};
    const json_t *g;
    size_t i;
    json_array_foreach(json_object_get(r, "grains"), i, g) {
        int c = (int)floor((json_number_value(json_object_get(g, "orientation_deg")) + 90) / w);
        cnt[c >= classes ? 0 : c]++;
    }
    for (int c = 0; c < classes; c++) {
        CHECK_NEAR(ra[c], scale * 100 * cnt[c] / n / w, 0.02 + 0.002 * ra[c]);
        CHECK_NEAR(ra[c + classes], ra[c], 0);
        double t0 = -90 + w * c;
        CHECK_NEAR(rt[c], scale * 100 * cos_prob(t0, t0 + w, mean, a) / w, 0.02 + 0.002 * rt[c]);
    }
    char want[160];
    snprintf(want, sizeof want, "(N = %d, %d classes of %g°): KS 0.03 (5 %% critical %.3g)", n,
             classes, w, 1.36 / sqrt(n));
    CHECK(strstr(s, want) != NULL);
    snprintf(want, sizeof want, "target: cosine law, mean %g°, anisotropy %g", mean, a);
    CHECK(strstr(s, want) != NULL);
    CHECK(strstr(s, "% per degree") != NULL);
    free(s);
    json_decref(r);
}

static void test_rose(void)
{
    check_rose(500, 0, 0.1, 18); /* Mollon & Zhao's Example 2: 10-degree classes, not 4 */
    check_rose(500, 30, 0.5, 18);
    check_rose(1000, -60, 0.3, 36);
    check_rose(300, 0, 1, 12);
    check_rose(100, 45, 0.2, 6);
}

/* ---------------------------------------------------------------- colour bars */

/* n square grains, 4 a row, their areas from amin to amax (m²) */
static json_t *squares_result(int n, double amin, double amax)
{
    json_t *grains = json_array();
    for (int i = 0; i < n; i++) {
        double a = amin + (amax - amin) * i / (n - 1), h = sqrt(a) / 2, cx = 0.4 * (i % 4);
        double cy = 0.4 * (i / 4);
        json_array_append_new(grains, json_pack("{s:[[f,f],[f,f],[f,f],[f,f]], s:f, s:f}", "contour",
                                                cx - h, cy - h, cx + h, cy - h, cx + h, cy + h, cx - h, cy + h,
                                                "area", a, "orientation_deg", 0.0));
    }
    return json_pack("{s:s, s:o}", "kind", KIND_2D, "grains", grains);
}

/* the colour bar's ticks and labels: labels keep 12 px (the font) apart and right of their
 * ticks, round values (linear: multiples of a 1-2-5 x 10^k step; log: m x 10^k, m whole),
 * within lo..hi (the bar's unit); their count */
static int check_colorbar(const char *svg, int logscale, double lo, double hi)
{
    double v[64], y[64];
    int n = 0;
    const char *t = strstr(svg, "class=\"cbar-tick\"");
    for (const char *l = strstr(svg, "class=\"cbar-label\""); l && n < 64;
         l = strstr(l + 1, "class=\"cbar-label\""), n++) {
        const char *el = l;
        while (el > svg && strncmp(el, "<text", 5)) el--;
        char lab[32];
        text_of(el, lab, sizeof lab);
        v[n] = strtod(lab, NULL);
        y[n] = attr_num(el, "y");
        CHECK(t != NULL);
        if (!t) break;
        const char *tl = t;
        while (tl > svg && strncmp(tl, "<line", 5)) tl--;
        CHECK(attr_num(el, "x") > attr_num(tl, "x2")); /* the label starts right of its tick */
        CHECK_NEAR(attr_num(tl, "y1") + 4, y[n], 0.11);  /* and is centred on it */
        t = strstr(t + 1, "class=\"cbar-tick\"");
        CHECK(v[n] >= lo * (1 - 1e-9) && v[n] <= hi * (1 + 1e-9));
        if (logscale) {
            double m = v[n] / pow(10, floor(log10(v[n]) + 1e-9));
            CHECK_NEAR(m, round(m), 1e-9);
        }
    }
    for (int i = 1; i < n; i++) CHECK(fabs(y[i] - y[i - 1]) >= 12);
    if (!logscale && n >= 2) {
        double st = v[1] - v[0], m = st / pow(10, floor(log10(st) + 1e-9));
        CHECK(fabs(m - 1) < 1e-6 || fabs(m - 2) < 1e-6 || fabs(m - 5) < 1e-6);
        for (int i = 0; i < n; i++) CHECK_NEAR(v[i] / st, round(v[i] / st), 1e-6);
        for (int i = 1; i < n; i++) CHECK_NEAR(v[i] - v[i - 1], st, st * 1e-6);
    }
    return n;
}

static void test_colorbar(void)
{
    size_t len;
    int status;
    char err[256];
    /* linear (areas within a factor 10): mm², 1-2-5 steps -- not 0.001798 m² */
    json_t *r = squares_result(12, 0.0011, 0.0034);
    char *s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "grain area (mm²)") && check_colorbar(s, 0, 1100, 3400) >= 3);
    free(s);
    json_decref(r);
    /* log (a factor 150) */
    r = squares_result(12, 2e-5, 3e-3);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && check_colorbar(s, 1, 20, 3000) >= 3);
    free(s);
    json_decref(r);
    /* small values keep their digits: 1-2-5 steps of 10^-5 m² would read 0.00001 */
    r = squares_result(12, 0.101, 0.1013);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "grain area (m²)") && check_colorbar(s, 0, 0.101, 0.1013) >= 2);
    free(s);
    json_decref(r);
    /* the fixed-decimals label of a tick, and powers of ten beyond */
    char b[64];
    svg_plot_fmt_tick(b, sizeof b, 0.3000000000000001, 0.1);
    CHECK(!strcmp(b, "0.3"));
    svg_plot_fmt_tick(b, sizeof b, 2e-5, 0);
    CHECK(!strcmp(b, "2×10⁻⁵"));
    svg_plot_fmt_tick(b, sizeof b, 1e7, 0);
    CHECK(!strcmp(b, "10⁷"));
    svg_plot_fmt_tick(b, sizeof b, -1e-17, 0.5);
    CHECK(!strcmp(b, "0"));
}

/* ---------------------------------------------------------------- the 3D section */

static void test_section_z(void)
{
    json_t *r = load(RESULT_3D);
    /* tiled 2 x 2 x 4: a box 2 m high, mirror planes every 0.5 m */
    json_object_set_new(r, "box", json_pack("[f, f, f]", 1.0, 1.0, 2.0));
    json_object_set_new(r, "tiling", json_pack("[i, i, i]", 2, 2, 4));
    json_object_set_new(json_object_get(r, "stats"), "porosity",
                        json_pack("{s:f, s:f}", "target", 0.38, "achieved", 0.377));
    json_t *sp = json_object_get(r, "spheres");
    for (int i = 0; i < 40; i++) /* spheres about every height */
        json_array_append_new(sp, json_pack("[f, f, f, f]", 0.1 + 0.02 * i, 0.5, 0.05 * i, 0.04));
    size_t len;
    int status;
    char err[256];
    char *s = render(r, NULL, "section", NULL, &len, &status, err);
    check_common(s, len);
    double z = NAN;
    CHECK(s && sscanf(strstr(s, "Section at z = ") + 15, "%lf", &z) == 1);
    double base = 2.0 / 4, off = fabs(z / base - round(z / base)) * base;
    CHECK(off > 0.01 * base);    /* not on a mirror plane */
    CHECK_NEAR(off, base / 2, 1e-9); /* as far from them as a cut can be */
    /* the spheres it cuts and their area, counted here */
    int cut = 0;
    double area = 0;
    const json_t *q;
    size_t i;
    json_array_foreach(sp, i, q) {
        double zz = json_number_value(json_array_get(q, 2)), rr = json_number_value(json_array_get(q, 3));
        if (fabs(zz - z) < rr) cut++, area += M_PI * (rr * rr - (zz - z) * (zz - z));
    }
    char want[200];
    snprintf(want, sizeof want, ": %d of %zu spheres cut", cut, json_array_size(sp));
    CHECK(s && strstr(s, want));
    snprintf(want, sizeof want, "porosity 0.377 (target 0.38), of this section %.3f", 1 - area / 1.0);
    CHECK(s && strstr(s, want));
    /* the PSD summary, from the achieved curve by weight (log-linear between sieves) */
    double d50 = 0.02 * pow(2.5, (50 - 2.7) / (52 - 2.7)), d10 = 0.02 * pow(2.5, (10 - 2.7) / (52 - 2.7));
    double d60 = 0.05 * pow(1.6, (60 - 52) / (94.5 - 52));
    snprintf(want, sizeof want, "D50 %.3g mm, Cu = D60/D10 %.3g, max error 2.00 pp", d50 * 1e3, d60 / d10);
    CHECK(s && strstr(s, want));
    CHECK(s && strstr(s, "mirror planes every 0.5 m, the nearest 0.25 m from the cut"));
    free(s);
    /* z asked for: outside the packing, a 400 naming z and the range */
    gp_svg_options o = {.has_z = 1, .z = 2.5};
    CHECK(render_st(r, NULL, "section", &o, &len, &status, err, sizeof err) == NULL);
    CHECK(status == 400 && strstr(err, "z = 2.5") && strstr(err, "valid z from 0 to 2 m"));
    o.z = 1.0; /* on a mirror plane, when asked */
    s = render(r, NULL, "section", &o, &len, &status, err);
    CHECK(s && strstr(s, "Section at z = 1 m") && strstr(s, "the nearest 0 m from the cut"));
    free(s);
    /* a curve that starts above 10 %: no D10, so no Cu (and no "nan") */
    json_t *aw = json_object_get(json_object_get(json_object_get(r, "stats"), "psd"), "achieved_weight");
    json_array_set_new(aw, 0, json_real(15));
    json_array_set_new(aw, 1, json_real(20));
    s = render(r, NULL, "section", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "PSD by weight: D50 ") && !strstr(s, "Cu =") && strstr(s, "max error 18.00 pp"));
    free(s);
    /* an odd tiling: the middle cell's middle, which is the box's */
    json_object_set_new(r, "box", json_pack("[f, f, f]", 1.0, 1.0, 1.5));
    json_object_set_new(r, "tiling", json_pack("[i, i, i]", 1, 1, 3));
    s = render(r, NULL, "section", NULL, &len, &status, err);
    CHECK(s && strstr(s, "Section at z = 0.75 m"));
    free(s);
    json_decref(r);
}

/* ---------------------------------------------------------------- the detail inset */

/* n x m grains (polygons of np points, radius rad) on a grid over [x0, x1] x [0, 1], in a
 * container [0, cw] x [0, 1] */
static json_t *grid_result_np(int n, int m, double x0, double x1, double rad, double cw, int np)
{
    json_t *grains = json_array();
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) {
            double cx = x0 + (x1 - x0) * (i + 0.5) / n, cy = (j + 0.5) / m;
            json_t *c = json_array();
            for (int k = 0; k < np; k++)
                json_array_append_new(c, json_pack("[f, f]", cx + rad * cos(k * 2 * M_PI / np),
                                                   cy + rad * sin(k * 2 * M_PI / np)));
            json_array_append_new(grains, json_pack("{s:o, s:f, s:f}", "contour", c, "area",
                                                    2.83 * rad * rad * (1 + (i % 5) * 0.1),
                                                    "orientation_deg", 0.0));
        }
    return json_pack("{s:s, s:o, s:{s:[[i,i],[f,i],[f,i],[i,i]]}}", "kind", KIND_2D, "grains",
                     grains, "container", "polygon", 0, 0, cw, 0, cw, 1, 0, 1);
}

static json_t *grid_result(int n, int m, double x0, double x1, double rad, double cw)
{
    return grid_result_np(n, m, x0, x1, rad, cw, 8);
}

/* the inset of a packing: its window (desc), the paths drawn in it, the test's own count of
 * the grains whose bounding box meets the window; returns that count */
static int check_inset(const char *s, const json_t *r, double win[4])
{
    const char *d = strstr(s, "<desc>detail window: x from ");
    CHECK(d && sscanf(d + 28, "%lf to %lf m, y from %lf to %lf", &win[0], &win[1], &win[2], &win[3]) == 4);
    if (!d) return -1;
    CHECK_NEAR(win[1] - win[0], win[3] - win[2], 1e-8); /* square */
    const char *a = strstr(d, "<g clip-path"), *b = strstr(a, "</g>");
    int drawn = 0, own = 0;
    for (const char *p = strstr(a, "<path"); p && p < b; p = strstr(p + 1, "<path")) drawn++;
    const json_t *g;
    size_t i;
    json_array_foreach(json_object_get(r, "grains"), i, g) {
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        const json_t *pt;
        size_t k;
        json_array_foreach(json_object_get(g, "contour"), k, pt) for (int c = 0; c < 2; c++) {
            lo[c] = fmin(lo[c], json_number_value(json_array_get(pt, (size_t)c)));
            hi[c] = fmax(hi[c], json_number_value(json_array_get(pt, (size_t)c)));
        }
        own += hi[0] >= win[0] && lo[0] <= win[1] && hi[1] >= win[2] && lo[1] <= win[3];
    }
    CHECK(drawn == own);
    char cap[96];
    snprintf(cap, sizeof cap, "): %d grains in the red square", own);
    CHECK(strstr(s, cap) != NULL);
    CHECK(count(s, "<polygon") == json_array_size(json_object_get(r, "grains"))); /* each once */
    return own;
}

static void test_inset(void)
{
    size_t len;
    int status;
    char err[256];
    double w[4];
    /* 55 x 55 grains, uniform: a central window of about INSET_TARGET grains */
    json_t *r = grid_result(55, 55, 0, 1, 0.006, 1);
    char *s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    int in = s ? check_inset(s, r, w) : -1;
    CHECK(in >= 100 && in <= 300);
    CHECK_NEAR((w[0] + w[1]) / 2, 0.5, 1e-9);
    CHECK_NEAR((w[2] + w[3]) / 2, 0.5, 1e-9);
    CHECK(s && strstr(s, "width=\"1200\"") && count(s, "class=\"inset-window\"") == 1);
    free(s);
    gp_svg_options o = {.width = 900};
    s = render(r, NULL, "packing", &o, &len, &status, err);
    check_common(s, len);
    CHECK(s && strstr(s, "width=\"900\"") && check_inset(s, r, w) == in);
    free(s);
    json_decref(r);
    /* grains in the right half of a 2 x 1 container only: the window is where they are */
    r = grid_result(50, 50, 1, 2, 0.004, 2);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    in = s ? check_inset(s, r, w) : -1;
    CHECK(in >= 100 && w[0] >= 1 - 0.1 * (w[1] - w[0]) && w[1] <= 2 + 1e-9);
    free(s);
    json_decref(r);
    /* grains of 600 points: the window's (some 100,000 points) are not kept from the map's
     * pass, the inset reads them again -- the same picture */
    r = grid_result_np(46, 46, 0, 1, 0.007, 1, 600);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    in = s ? check_inset(s, r, w) : -1;
    CHECK(in >= 100 && in <= 300 && in * 600 > INSET_KEEP);
    free(s);
    json_decref(r);
    /* 2,000 grains or fewer: no inset */
    r = grid_result(40, 50, 0, 1, 0.004, 1);
    s = render(r, NULL, "packing", NULL, &len, &status, err);
    check_common(s, len);
    CHECK(s && !strstr(s, "class=\"inset") && strstr(s, "width=\"800\""));
    free(s);
    json_decref(r);
}

/* ---------------------------------------------------------------- descriptor histograms */

/* px = a + b v from the labelled x ticks between p and end */
static int xmap(const char *p, const char *end, double *a, double *b)
{
    double px[64], v[64];
    int n = 0;
    for (const char *t = strstr(p, "class=\"xtick\""); t && t < end && n < 64; t = strstr(t + 1, "class=\"xtick\"")) {
        const char *el = t;
        while (strncmp(el, "<text", 5)) el--;
        char lab[32];
        text_of(el, lab, sizeof lab);
        px[n] = attr_num(el, "x");
        v[n++] = strtod(lab, NULL);
    }
    if (n < 2) return -1;
    *b = (px[n - 1] - px[0]) / (v[n - 1] - v[0]);
    *a = px[0] - *b * v[0];
    for (int i = 0; i < n; i++) CHECK_NEAR(px[i], *a + *b * v[i], 0.11);
    return 0;
}

/* the elongation panel of the descriptors view against the test's own values */
static void check_desc_panel(const char *s, const double *v, int n, double target)
{
    const char *p = strstr(s, "class=\"panel-title\""), *end = strstr(p + 1, "class=\"panel-title\"");
    double a = NAN, b = NAN, mean = 0, sd = 0, lo = INFINITY, hi = -INFINITY;
    CHECK(xmap(p, end, &a, &b) == 0);
    for (int i = 0; i < n; i++) mean += v[i] / n, lo = fmin(lo, v[i]), hi = fmax(hi, v[i]);
    for (int i = 0; i < n; i++) sd += (v[i] - mean) * (v[i] - mean) / (n - 1);
    sd = sqrt(sd);
    char t[128];
    snprintf(t, sizeof t, "elongation: mean %.3g, sd %.2g", mean, sd);
    CHECK(strstr(s, t) != NULL);
    /* the bars: edges on a 1-2-5 step, 8..40 of them covering the data and no more */
    double e[48], frac[48], y0 = NAN, ymap;
    int k = 0;
    const char *bars = strstr(p, "<g class=\"bars\"");
    for (const char *r = strstr(bars, "<rect"); r && r < strstr(bars, "</g>") && k < 47; r = strstr(r + 1, "<rect")) {
        e[k] = (attr_num(r, "x") - 0.5 - a) / b;
        e[k + 1] = (attr_num(r, "x") + attr_num(r, "width") + 0.5 - a) / b;
        frac[k++] = attr_num(r, "height");
        y0 = attr_num(r, "y") + attr_num(r, "height");
    }
    CHECK(k >= 8 && k <= 40);
    double st = (e[k] - e[0]) / k, p10 = pow(10, floor(log10(st) + 1e-3)), m = st / p10;
    CHECK(fabs(m - 1) < 0.01 || fabs(m - 2) < 0.02 || fabs(m - 5) < 0.05);
    if (!(fabs(m - 1) < 0.01 || fabs(m - 2) < 0.02 || fabs(m - 5) < 0.05))
        fprintf(stderr, "descriptor bins: %d from %g to %g\n", k, e[0], e[k]);
    /* the exact edges: the round step from multiples of it (the pixels are rounded) */
    st = round(m) * p10;
    e[0] = round(e[0] / st) * st;
    for (int i = 1; i <= k; i++) e[i] = e[0] + st * i;
    CHECK(e[0] <= lo && e[0] > lo - st && e[k] >= hi && e[k] < hi + st);
    /* Freedman-Diaconis: the step is the round one at or just above 2 IQR / n^(1/3) */
    double *sv = malloc((size_t)n * sizeof *sv);
    memcpy(sv, v, (size_t)n * sizeof *sv);
    for (int i = 1; i < n; i++) /* insertion sort: n is small */
        for (int j = i; j > 0 && sv[j - 1] > sv[j]; j--) { double x = sv[j]; sv[j] = sv[j - 1]; sv[j - 1] = x; }
    double fd = 2 * (sv[3 * n / 4] - sv[n / 4]) / cbrt(n);
    free(sv);
    CHECK(st >= fd * 0.97 && st <= fd * 2.6);
    /* heights: the test's own fractions, on the y axis' scale (the y ticks) */
    const char *yt = strstr(p, "class=\"ytick\""), *yt2 = strstr(yt + 1, "class=\"ytick\"");
    const char *e1 = yt, *e2 = yt2;
    while (strncmp(e1, "<text", 5)) e1--;
    while (strncmp(e2, "<text", 5)) e2--;
    char l1[32], l2[32];
    text_of(e1, l1, sizeof l1);
    text_of(e2, l2, sizeof l2);
    ymap = (attr_num(e1, "y") - attr_num(e2, "y")) / (strtod(l2, NULL) - strtod(l1, NULL));
    CHECK_NEAR(attr_num(e1, "y") - 4, y0, 0.11); /* the first y tick is 0, at the bars' base */
    for (int i = 0; i < k; i++) {
        int c = 0;
        for (int j = 0; j < n; j++) c += v[j] >= e[i] - st * 1e-6 && (v[j] < e[i + 1] - st * 1e-6 || (i == k - 1 && v[j] <= e[k]));
        CHECK_NEAR(frac[i] / ymap, (double)c / n, 0.2 / ymap + 0.002 * c / n); /* 0.1 px */
    }
    /* the mean and the target, where they are */
    CHECK_NEAR(attr_num(strstr(p, "class=\"mean\"") - 6, "x1"), a + b * mean, 0.11);
    CHECK_NEAR(attr_num(strstr(p, "class=\"target\"") - 6, "x1"), a + b * target, 0.11);
}

static void test_descriptors_zoom(void)
{
    enum { N = 500 };
    json_t *grains = json_array();
    double el[N];
    unsigned x = 3;
    for (int i = 0; i < N; i++) {
        el[i] = 0.62 + 0.1 * (lcg(&x) + lcg(&x) + lcg(&x)) / 3;
        double ro = 0.4 + 0.01 * lcg(&x), ci = 0.85 + 0.003 * lcg(&x), re = 1.2 + 0.2 * lcg(&x);
        json_array_append_new(grains, json_pack("{s:{s:f, s:f, s:f, s:f}, s:f}", "descriptors",
                                                "elongation", el[i], "roundness", ro, "circularity",
                                                ci, "regularity", re, "area", 1.0));
    }
    json_t *r = json_pack("{s:s, s:o, s:{s:{s:{s:f}, s:{s:f}}}}", "kind", KIND_2D, "grains", grains,
                          "stats", "descriptors", "elongation", "target", 0.66, "roundness",
                          "target", 0.3);
    size_t len;
    int status;
    char err[256];
    char *s = render(r, NULL, "descriptors", NULL, &len, &status, err);
    check_common(s, len);
    if (s) check_desc_panel(s, el, N, 0.66);
    /* a target outside the data widens the axis to show it: roundness 0.3, data 0.40-0.41 */
    CHECK(s && count(s, "class=\"target\"") == 2);
    free(s);
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
    /* (its speed is measured by bench/bench_svg.py, not asserted here) */
    char *s = render(r, "fourier-voronoi-2d", "packing", NULL, &len, &status, err);
    CHECK(s != NULL);
    CHECK(s && count(s, "<polygon") == 10000);
    CHECK(len < 8u * 1024 * 1024);
    CHECK(s && well_formed(s, len));
    free(s);
    json_decref(r);
}

/* ---- compact reading: json_scan, the item sources, the pull stream ---- */

static void test_json_scan(void)
{
    const char *t = "{\"a\":\"x]\\\"}\" , \"grains\":[{\"k\":\"]\"},[1,2],3],\"b\":[1,2,{\"c\":null}],"
                    "\"n\":-1.5e3,\"cells\":[],\"z\":true}";
    js_source src = json_scan_memory_source(t, strlen(t));
    static const char *const skip[] = {"grains", "cells", "spheres", NULL};
    uint64_t sp[3][2];
    size_t len;
    char *w = json_scan_object_without(&src, skip, &len, sp);
    CHECK(w && !strcmp(w, "{\"a\":\"x]\\\"}\",\"b\":[1,2,{\"c\":null}],\"n\":-1.5e3,\"z\":true}"));
    CHECK(w && len == strlen(w));
    CHECK(sp[0][0] > 0 && !strncmp(t + sp[0][0], "[{\"k\"", 5) && t[sp[0][1] - 1] == ']');
    CHECK(sp[1][1] == sp[1][0] + 2 && sp[2][0] == 0 && sp[2][1] == 0);
    /* the elements of the grains array, one at a time */
    js_scan *s = json_scan_open(&src);
    CHECK(s && json_scan_array_begin(s, sp[0][0]) == 0);
    uint64_t a, b;
    int n = 0;
    while (json_scan_array_next(s, &a, &b) > 0) {
        json_t *e = json_scan_load(s, a, b);
        CHECK(e != NULL);
        if (n == 0) CHECK(!strcmp(json_string_value(json_object_get(e, "k")), "]"));
        if (n == 2) CHECK(json_integer_value(e) == 3);
        json_decref(e);
        n++;
    }
    CHECK(n == 3);
    CHECK(json_scan_array_begin(s, sp[1][0]) == 0 && json_scan_array_next(s, &a, &b) == 0); /* [] */
    CHECK(json_scan_array_begin(s, 0) == -1);                                        /* not an array */
    json_scan_close(s);
    free(w);
    /* every cut of the text is refused, never read past */
    for (size_t k = 0; k < strlen(t); k++) {
        char *cut = strndup(t, k);
        js_source cs = json_scan_memory_source(cut, k);
        char *x = json_scan_object_without(&cs, skip, NULL, NULL);
        CHECK(x == NULL);
        free(x);
        free(cut);
    }
    js_source bad = json_scan_memory_source("[1,2]", 5);
    CHECK(json_scan_object_without(&bad, skip, NULL, NULL) == NULL);
    /* across cache windows: a string of 200,000 bytes with escapes, then an array */
    size_t big = 200000;
    char *bt = malloc(big + big / 1000 + 64);
    size_t k = (size_t)sprintf(bt, "{\"s\":\"");
    for (size_t i = 0; i < big; i++) {
        if (i % 1000 == 999) bt[k++] = '\\', bt[k++] = '"';
        else bt[k++] = (char)('a' + i % 26);
    }
    k += (size_t)sprintf(bt + k, "\",\"grains\":[[1],[2]]}");
    js_source bs = json_scan_memory_source(bt, k);
    w = json_scan_object_without(&bs, skip, &len, sp);
    CHECK(w && len == k - strlen(",\"grains\":[[1],[2]]") && sp[0][1] == k - 1);
    free(w);
    free(bt);
}

/* reads a stream in pieces of cap bytes */
static char *read_all(gp_svg *g, size_t cap, size_t *len)
{
    size_t n = 0, room = 1 << 16;
    char *out = malloc(room), *buf = malloc(cap);
    for (;;) {
        size_t got;
        if (gp_svg_read(g, buf, cap, &got)) {
            free(out);
            free(buf);
            return NULL;
        }
        if (!got) break;
        if (n + got + 1 > room) out = realloc(out, room = 2 * (n + got + 1));
        memcpy(out + n, buf, got);
        n += got;
    }
    out[n] = 0;
    free(buf);
    *len = n;
    return out;
}

/* what grainpackd's svg_job does: a summary, grains/spheres from a pack, the rest scanned */
typedef struct src_ctx {
    const void *pack;
    size_t pack_len;
    const char *text;
    uint64_t spans[3][2];
    int fail_after; /* reads the scan source allows (0 = any) */
    int reads;
} src_ctx;

static int counting_read(void *user, uint64_t off, void *dst, size_t n)
{
    src_ctx *c = user;
    if (c->fail_after && ++c->reads > c->fail_after) return -1;
    memcpy(dst, c->text + off, n);
    return 0;
}

static gp_svg_items *test_open(void *user, gp_svg_part part, int *failed)
{
    src_ctx *c = user;
    *failed = 0;
    if (c->pack && part != GP_SVG_CELLS) {
        gp_export_source ps = gp_export_memory_source(c->pack, c->pack_len);
        gp_svg_items *it = gp_svg_items_pack(&ps, part);
        if (it) return it;
    }
    if (c->spans[part][1] <= c->spans[part][0]) return NULL;
    js_source ts = {counting_read, c, strlen(c->text)};
    return gp_svg_items_scan(&ts, c->spans[part][0], part);
}

static void check_stream_equal(json_t *result, const char *kind, const char *view,
                               const gp_svg_options *o, src_ctx *ctx, const json_t *summary)
{
    size_t rlen;
    int st;
    char err[256];
    char *ref = render_st(result, kind, view, o, &rlen, &st, err, sizeof err);
    CHECK(ref != NULL);
    if (!ref) {
        fprintf(stderr, "%s: %s\n", view, err);
        return;
    }
    gp_svg_input in = {kind, summary, test_open, ctx};
    size_t caps[3] = {7, 4096, 1 << 20};
    for (int k = 0; k < 3; k++) {
        gp_svg *g = open_st(&in, view, o, &st, err, sizeof err);
        CHECK(g != NULL && st == 200);
        if (!g) continue;
        size_t len;
        char *s = read_all(g, caps[k], &len);
        CHECK(s && len == rlen && !memcmp(s, ref, rlen));
        if (s && (len != rlen || memcmp(s, ref, rlen)))
            fprintf(stderr, "%s (pieces of %zu): the stream differs from gp_svg_render\n", view, caps[k]);
        free(s);
        gp_svg_close(g);
    }
    free(ref);
}

static void set_spans(src_ctx *c)
{
    static const char *const skip[] = {"grains", "cells", "spheres", NULL};
    js_source s = json_scan_memory_source(c->text, strlen(c->text));
    free(json_scan_object_without(&s, skip, NULL, c->spans));
}

static void test_compact_2d(void)
{
    enum { NG = 12, NP = 24 };
    gp_specimen2d s;
    memset(&s, 0, sizeof s);
    gp_grain2d grains[NG];
    gp_vec2 contours[NG][NP];
    double discs[NG][6];
    gp_cell2d cells[NG];
    gp_ring rings[NG][2];
    gp_vec2 cpts[NG][2][4];
    memset(grains, 0, sizeof grains);
    memset(cells, 0, sizeof cells);
    for (int g = 0; g < NG; g++) {
        double cx = 0.125 + 0.25 * (g % 4), cy = 0.12 + 0.23 * (g / 4), r = 0.05 + 0.004 * g;
        for (int k = 0; k < NP; k++) {
            double t = 2 * M_PI * k / NP;
            contours[g][k] = (gp_vec2){cx + r * cos(t) * (1 + 0.2 * sin(3 * t)), cy + 0.7 * r * sin(t)};
        }
        if (g == 5) contours[g][3].x = NAN; /* a point the JSON writes as null */
        grains[g].cell = (size_t)g;
        grains[g].contour = contours[g];
        grains[g].ncontour = NP;
        grains[g].area = g == 7 ? NAN : M_PI * r * r * 0.7;
        grains[g].orientation_deg = g == 8 ? NAN : -80 + 15.3 * g;
        grains[g].descriptors = (gp_descriptors){0.5 + 0.03 * g, 0.4 + 0.02 * g, 0.7 + 0.01 * g, 2 + 0.1 * g};
        discs[g][0] = cx, discs[g][1] = cy, discs[g][2] = r * 0.5;
        discs[g][3] = cx + r * 0.3, discs[g][4] = cy, discs[g][5] = r * 0.3;
        grains[g].discs = discs[g];
        grains[g].ndiscs = 2;
        double x0 = 0.25 * (g % 4), y0 = 0.23 * (g / 4);
        int parts = g == 3 ? 2 : 1;
        for (int p = 0; p < parts; p++) {
            double h = 0.23 / parts;
            cpts[g][p][0] = (gp_vec2){x0, y0 + p * h};
            cpts[g][p][1] = (gp_vec2){x0 + 0.25, y0 + p * h};
            cpts[g][p][2] = (gp_vec2){x0 + 0.25, y0 + (p + 1) * h};
            cpts[g][p][3] = (gp_vec2){x0, y0 + (p + 1) * h};
            rings[g][p] = (gp_ring){cpts[g][p], 4};
        }
        cells[g].seed = (gp_vec2){x0 + 0.12, y0 + 0.11};
        cells[g].polygons = rings[g];
        cells[g].npolygons = (size_t)parts;
        cells[g].area = 0.25 * 0.23 * (1 + 0.01 * g);
        cells[g].orientation_deg = 10.0 * g - 60;
    }
    s.grains = grains;
    s.ngrains = NG;
    s.cells = cells;
    s.ncells = NG;
    gp_spec2d spec;
    memset(&spec, 0, sizeof spec);
    gp_vec2 outer[4] = {{0, 0}, {1, 0}, {1, 0.69}, {0, 0.69}};
    spec.container = GP_CONTAINER_POLYGON;
    spec.outer = (gp_ring){outer, 4};
    spec.particles = NG;
    spec.outputs = GP_OUT2_GRAINS | GP_OUT2_ODEC | GP_OUT2_DESCRIPTORS | GP_OUT2_CELLS;
    json_error_t e;
    json_t *sj = json_loads("{\"container\": {\"polygon\": [[0,0],[1,0],[1,0.69],[0,0.69]]}}", 0, &e);
    json_t *r = gpd_result_2d(&s, &spec, sj, NULL);
    CHECK(r != NULL);
    char *text = json_dumps(r, JSON_COMPACT | JSON_REAL_PRECISION(17));
    void *pack = NULL;
    size_t pack_len = 0;
    gp_error perr;
    CHECK(gp_export_pack_2d(&s, &spec, 2650, &pack, &pack_len, &perr) == GP_OK);
    void *view = NULL; /* what a job without output odec stores */
    size_t view_len = 0;
    CHECK(gp_export_pack_2d_view(&s, &spec, &view, &view_len, &perr) == GP_OK);
    /* the summary: the result without its arrays */
    static const char *const skip[] = {"grains", "cells", "spheres", "contacts", NULL};
    js_source ts = json_scan_memory_source(text, strlen(text));
    char *sum_text = json_scan_object_without(&ts, skip, NULL, NULL);
    json_t *summary = sum_text ? json_loads(sum_text, 0, &e) : NULL;
    CHECK(summary && !json_object_get(summary, "grains") && !json_object_get(summary, "cells"));
    json_t *copy = json_deep_copy(r);
    json_object_del(copy, "grains");
    json_object_del(copy, "cells");
    CHECK(json_equal(copy, summary));
    json_decref(copy);
    /* every view, from the scanned text only, from the export pack or the view pack and the
     * scanned text, as the result in memory draws it (the statistics here have no histograms:
     * the size, orientation and descriptors views fall back to the items) */
    const char *views[5] = {"packing", "cells", "size", "orientation", "descriptors"};
    gp_svg_options og = {.color = "orientation"}, ow = {.width = 1500};
    for (int with_pack = 0; with_pack < 3; with_pack++) {
        src_ctx ctx = {with_pack == 1 ? pack : with_pack == 2 ? view : NULL,
                       with_pack == 1 ? pack_len : view_len, text, {{0}}, 0, 0};
        set_spans(&ctx);
        for (int v = 0; v < 5; v++) check_stream_equal(r, KIND_2D, views[v], NULL, &ctx, summary);
        check_stream_equal(r, KIND_2D, "packing", &og, &ctx, summary);
        check_stream_equal(r, KIND_2D, "packing", &ow, &ctx, summary);
    }
    /* without the part: 409, as from the result */
    {
        src_ctx ctx = {NULL, 0, text, {{0}}, 0, 0};
        gp_svg_input in = {KIND_2D, summary, test_open, &ctx};
        int st = 0;
        char err[256];
        CHECK(open_st(&in, "cells", NULL, &st, err, sizeof err) == NULL && st == 409);
    }
    json_decref(summary);
    free(sum_text);
    free(pack);
    free(view);
    free(text);
    json_decref(r);
    json_decref(sj);
}

static void test_compact_3d(void)
{
    json_t *r = load(RESULT_3D);
    const json_t *sp = json_object_get(r, "spheres");
    size_t n = json_array_size(sp);
    double *q = malloc(4 * n * sizeof *q);
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 4; a++) q[4 * i + a] = json_number_value(json_array_get(json_array_get(sp, i), (size_t)a));
    gp_specimen3d s;
    memset(&s, 0, sizeof s);
    s.spheres = q;
    s.count = n;
    s.box[0] = s.box[1] = s.box[2] = 0.5;
    void *pack = NULL;
    size_t pack_len = 0;
    gp_error perr;
    CHECK(gp_export_pack_3d(&s, 2650, &pack, &pack_len, &perr) == GP_OK);
    char *text = json_dumps(r, JSON_COMPACT | JSON_REAL_PRECISION(17));
    json_t *summary = json_deep_copy(r);
    json_object_del(summary, "spheres");
    gp_svg_options oz = {.has_z = 1, .z = 0.05}, obad = {.has_z = 1, .z = 0.7};
    for (int with_pack = 0; with_pack < 2; with_pack++) {
        src_ctx ctx = {with_pack ? pack : NULL, pack_len, text, {{0}}, 0, 0};
        set_spans(&ctx);
        check_stream_equal(r, KIND_3D, "section", NULL, &ctx, summary);
        check_stream_equal(r, KIND_3D, "section", &oz, &ctx, summary);
        check_stream_equal(r, KIND_3D, "psd", NULL, &ctx, summary);
        gp_svg_input in = {KIND_3D, summary, test_open, &ctx};
        int st = 0;
        char err[256];
        CHECK(open_st(&in, "section", &obad, &st, err, sizeof err) == NULL && st == 400 &&
              strstr(err, "outside"));
    }
    /* a 2D pack is no source of spheres, a 3D one none of grains or cells */
    gp_export_source ps = gp_export_memory_source(pack, pack_len);
    CHECK(gp_svg_items_pack(&ps, GP_SVG_GRAINS) == NULL && gp_svg_items_pack(&ps, GP_SVG_CELLS) == NULL);
    gp_svg_items *it = gp_svg_items_pack(&ps, GP_SVG_SPHERES);
    CHECK(it != NULL);
    gp_svg_items_close(it);
    json_decref(summary);
    free(text);
    free(pack);
    free(q);
    json_decref(r);
}

/* a source failing anywhere: a 500 from gp_svg_open or -1 from gp_svg_read, never a short
 * picture (3,000 cells: a text of several cache windows, read in three passes) */
static void test_failing_source(void)
{
    json_t *r = json_object(), *cells = json_array();
    for (int i = 0; i < 3000; i++) {
        double x = (i % 60) / 60.0, y = (i / 60) / 50.0;
        json_array_append_new(cells, json_pack("{s:i, s:[f,f], s:[[[f,f],[f,f],[f,f]]], s:f, s:f}",
                                               "id", i, "seed", x + 0.005, y + 0.005, "polygons",
                                               x, y, x + 1 / 60.0, y, x, y + 0.02, "area",
                                               1e-4 * (1 + i % 5), "orientation_deg", 0.0));
    }
    json_object_set_new(r, "kind", json_string(KIND_2D));
    json_object_set_new(r, "cells", cells);
    char *text = json_dumps(r, JSON_COMPACT | JSON_REAL_PRECISION(17));
    CHECK(strlen(text) > 4 * 65536);
    json_t *summary = json_pack("{s:s}", "kind", KIND_2D);
    src_ctx ctx = {NULL, 0, text, {{0}}, 0, 0};
    set_spans(&ctx);
    check_stream_equal(r, KIND_2D, "cells", NULL, &ctx, summary);
    /* the reads a whole picture takes */
    ctx.reads = 0;
    ctx.fail_after = 1000000;
    gp_svg_input in = {KIND_2D, summary, test_open, &ctx};
    int st = 0;
    char err[256];
    size_t len;
    gp_svg *g = open_st(&in, "cells", NULL, &st, err, sizeof err);
    char *x = g ? read_all(g, 4096, &len) : NULL;
    CHECK(x != NULL);
    free(x);
    gp_svg_close(g);
    int total = ctx.reads, at_open = 0, mid = 0;
    CHECK(total > 6);
    for (int fail = 1; fail < total; fail++) { /* reads after the first `fail` fail */
        ctx.reads = 0;
        ctx.fail_after = fail;
        g = open_st(&in, "cells", NULL, &st, err, sizeof err);
        if (!g) {
            CHECK(st == 500);
            at_open++;
            continue;
        }
        x = read_all(g, 4096, &len);
        CHECK(x == NULL && strstr(gp_svg_error(g), "cells"));
        mid += x == NULL;
        free(x);
        gp_svg_close(g);
    }
    CHECK(at_open > 0 && mid > 0);
    json_decref(summary);
    free(text);
    json_decref(r);
}

/* the element parser of the scan source reads what the JSON tree gives, odd elements too */
static void test_item_parse(void)
{
    const char *grains[] = {
        "{\"id\":1,\"contour\":[[1,2],[3.5,-4e-3],null,[5],\"x\",[6,7,8]],\"area\":null,"
        "\"orientation_deg\":\"no\",\"descriptors\":{\"roundness\":0.25,\"x\":{\"y\":\"]}\"},"
        "\"regularity\":3},\"discs\":[[1,2,3]]}",
        "{\"contour\":5,\"area\":1e-3,\"k\\\"ey\":[\"]\"],\"descriptors\":[1,2]}",
        "[1,2]",
        "{ \"contour\" : [ [ 0 , 1 ] ] , \"area\" : 2 }",
    };
    const char *cells[] = {
        "{\"seed\":[0.5,null],\"polygons\":[[[0,0],[1,0],[1,1]],7,[]],\"area\":0.5,\"orientation_deg\":-3}",
        "{\"seed\":3,\"polygons\":{}}",
    };
    const char *spheres[] = {"[1,2,3,4]", "[1,null,3]", "{\"x\":1}", "[1,2,3,4,5,[6]]"};
    struct { gp_svg_part part; const char *const *t; int n; } sets[3] = {
        {GP_SVG_GRAINS, grains, 4}, {GP_SVG_CELLS, cells, 2}, {GP_SVG_SPHERES, spheres, 4}};
    svg_item a = {0}, b = {0};
    for (int s = 0; s < 3; s++)
        for (int i = 0; i < sets[s].n; i++) {
            const char *t = sets[s].t[i];
            json_error_t e;
            json_t *j = json_loads(t, JSON_DECODE_ANY, &e);
            CHECK(j != NULL);
            CHECK(svg_items_from_json(sets[s].part, &a, j) == 0);
            CHECK(svg_items_parse(sets[s].part, &b, t, strlen(t)) == 0);
            int same = a.npts == b.npts && a.nrings == b.nrings;
            for (size_t k = 0; same && k < 2 * a.npts; k++)
                same = (isnan(a.xy[k]) && isnan(b.xy[k])) || a.xy[k] == b.xy[k];
            for (size_t k = 0; same && k < a.nrings; k++) same = a.rings[k] == b.rings[k];
            double va[13] = {a.area, a.orientation_deg, a.desc[0], a.desc[1], a.desc[2], a.desc[3],
                             a.seed[0], a.seed[1], a.q[0], a.q[1], a.q[2], a.q[3], 0};
            double vb[13] = {b.area, b.orientation_deg, b.desc[0], b.desc[1], b.desc[2], b.desc[3],
                             b.seed[0], b.seed[1], b.q[0], b.q[1], b.q[2], b.q[3], 0};
            for (int k = 0; same && k < 13; k++) same = (isnan(va[k]) && isnan(vb[k])) || va[k] == vb[k];
            CHECK(same);
            if (!same) fprintf(stderr, "item_parse differs on %s\n", t);
            json_decref(j);
        }
    /* malformed text is refused */
    /* (values that are skipped are only matched bracket to bracket, not checked) */
    const char *bad[] = {"{\"contour\":[[1,2]", "{\"area\":}", "{\"area\" 1}",
                         "{\"contour\":[[1,,2]]}", "{\"contour\":[[1,2],]}"};
    for (int i = 0; i < 5; i++) CHECK(svg_items_parse(GP_SVG_GRAINS, &b, bad[i], strlen(bad[i])) == -1);
    CHECK(svg_items_parse(GP_SVG_SPHERES, &b, "[1,2", 4) == -1);
    free(a.xy);
    free(a.rings);
    free(b.xy);
    free(b.rings);
}

/* one number as a sphere's first value, bit for bit as strtod reads it; 0 when it differs */
static int number_same(const char *num)
{
    char t[128];
    snprintf(t, sizeof t, "[%s,0,0,0]", num);
    svg_item c = {0};
    int ok = svg_items_parse(GP_SVG_SPHERES, &c, t, strlen(t)) == 0;
    double want = strtod(num, NULL);
    ok = ok && memcmp(&c.q[0], &want, sizeof want) == 0;
    if (!ok) fprintf(stderr, "the element parser reads %s as %.17g, strtod as %.17g\n", num, c.q[0], want);
    return ok;
}

/* The element parser's numbers (its own fast path, strtod's fallback) are strtod's, bit for
 * bit: midpoints between two doubles, the edges of the fast path (19 digits, 10^+-27,
 * subnormals), forms JSON does not have, and random doubles written at 6 to 20 digits. */
static void test_item_numbers(void)
{
    const char *lit[] = {"0", "-0", "0.0", "-0.0", "1", "-1", "0.5", "1e23", "8.589973e9",
                         "9007199254740993", "9007199254740995", "9007199254740993.5",
                         "4503599627370497.5", "1234567890123456789", "12345678901234567890",
                         "0.1", "0.30000000000000004", "1e-27", "1e27", "1e-28", "1e28",
                         "9.9999999999999999e26", "2.2250738585072011e-308", "4.9e-324",
                         "1.7976931348623157e308", "1e400", "1E5", "1e+5", "1.e5", "0x10",
                         "00012.5", "-0.000000000000000000000000001234",
                         "0.011144915524144993", "5e-324", "1.5e-30"};
    int bad = 0;
    for (size_t i = 0; i < sizeof lit / sizeof *lit; i++) bad += !number_same(lit[i]);
    unsigned x = 2024;
    for (int i = 0; i < 300000; i++) {
        uint64_t bits = 0;
        for (int k = 0; k < 4; k++) {
            x = x * 1103515245u + 12345u;
            bits = bits << 16 | (x >> 16);
        }
        double mant = (double)(bits >> 11) / 9007199254740992.0; /* 53 random bits */
        double d = ldexp(0.5 + mant / 2, (int)(bits % 200) - 100) * (bits >> 63 ? -1 : 1);
        static const int digits[] = {6, 15, 16, 17, 20};
        char num[64];
        snprintf(num, sizeof num, "%.*g", digits[i % 5], d);
        bad += !number_same(num);
    }
    CHECK(bad == 0);
}

/* printf's "%.1f" exactly, halves included */
static void test_fmt_f1(void)
{
    double v[] = {0, -0.0, 0.05, 0.25, -0.25, 0.15, 1.05, 2.5, -0.04, 99.95, 12345.65, 0.35,
                  1e14, -3e15, 1e300, 799.95, 123.449999999};
    int bad = 0;
    for (size_t i = 0; i < sizeof v / sizeof *v; i++) {
        char a[400], b[400];
        snprintf(a, sizeof a, "%.1f", v[i]);
        svg_plot_fmt_f1(b, v[i]);
        bad += strcmp(a, b) != 0;
    }
    unsigned x = 12345;
    for (int i = 0; i < 2000000; i++) {
        x = x * 1103515245u + 12345u;
        double d = (i % 2) ? (x % 400000) / 20.0 - 1000 : (double)x / 7919.0 - 3000;
        char a[64], b[64];
        snprintf(a, sizeof a, "%.1f", d);
        svg_plot_fmt_f1(b, d);
        bad += strcmp(a, b) != 0;
    }
    CHECK(bad == 0);
}

int main(void)
{
    test_2d();
    test_size_fit();
    test_result_fit();
    test_3d();
    test_rose();
    test_colorbar();
    test_section_z();
    test_inset();
    test_descriptors_zoom();
    test_large();
    test_json_scan();
    test_item_parse();
    test_item_numbers();
    test_fmt_f1();
    test_compact_2d();
    test_compact_3d();
    test_failing_source();
    return gp_test_summary();
}
