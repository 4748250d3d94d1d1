/* svg_triax.c -- the SVG views of a triaxial-3d result (see svg_triax.h). */
#include "kinds/triaxial-3d/svg_triax.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"
#include "svg/svg_views.h"

#define SIGMA "\xcf\x83"
#define EPS "\xce\xb5"
#define PHI "\xcf\x86"
#define TAU "\xcf\x84"
#define PRIME "\xe2\x80\xb2"
#define DEG "\xc2\xb0"

#define MAX_CURVES 8 /* colours; a result has at most 5 tests */
static const char *const g_colors[MAX_CURVES] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                                 "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

/* ------------------------------------------------------------------ reading the summary */

/* a curve of the result: its confining stress and two of its arrays (malloc'ed) */
typedef struct xy_curve {
    double confining_kpa;
    double *x, *y;
    size_t n;
    char label[48];
} xy_curve;

static void curves_free(xy_curve *c, int n)
{
    for (int i = 0; i < n; i++) {
        free(c[i].x);
        free(c[i].y);
    }
}

/* the curves' arrays xname and yname (y times yscale); how many, 0 when none */
static int read_curves(const json_t *res, const char *xname, const char *yname, double yscale,
                       xy_curve *c)
{
    const json_t *curves = json_object_get(res, "curves");
    int n = 0;
    for (size_t i = 0; i < json_array_size(curves) && n < MAX_CURVES; i++) {
        const json_t *cu = json_array_get(curves, i);
        xy_curve k = {svg_plot_jnum(json_object_get(cu, "confining_kpa"), NAN), NULL, NULL, 0, ""};
        size_t nx = 0, ny = 0;
        k.x = svg_plot_jarray(json_object_get(cu, xname), &nx);
        k.y = svg_plot_jarray(json_object_get(cu, yname), &ny);
        k.n = nx < ny ? nx : ny;
        for (size_t j = 0; j < k.n; j++) k.x[j] *= 100, k.y[j] *= yscale; /* strains in % */
        snprintf(k.label, sizeof k.label, SIGMA "3 = %g kPa", k.confining_kpa);
        if (k.x && k.y && k.n) c[n++] = k;
        else curves_free(&k, 1);
    }
    return n;
}

/* the range of the finite values of the curves' x (which 0) or y (1) */
static void curves_range(const xy_curve *c, int n, int which, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int i = 0; i < n; i++)
        for (size_t j = 0; j < c[i].n; j++) {
            double v = which ? c[i].y[j] : c[i].x[j];
            if (isfinite(v)) *lo = fmin(*lo, v), *hi = fmax(*hi, v);
        }
    if (!(*hi >= *lo)) *lo = 0, *hi = 1;
    if (*hi - *lo < 1e-12) *lo -= 0.5, *hi += 0.5;
}

/* the path of a curve in f, its non-finite points left out */
static void curve_path(sb *s, const frame *f, const xy_curve *c, const char *color)
{
    svg_plot_sb_printf(s, "<path class=\"curve\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\" "
                          "d=\"", color);
    int first = 1;
    for (size_t j = 0; j < c->n; j++) {
        if (!isfinite(c->x[j]) || !isfinite(c->y[j])) continue;
        svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", svg_plot_fx(f, c->x[j]),
                           svg_plot_fy(f, c->y[j]));
        first = 0;
    }
    svg_plot_sb_puts(s, "\"/>\n");
}

/* the peak of the curve (its largest y) marked */
static void peak_marker(sb *s, const frame *f, const xy_curve *c, const char *color)
{
    size_t kp = 0;
    for (size_t j = 1; j < c->n; j++)
        if (c->y[j] > c->y[kp]) kp = j;
    if (isfinite(c->x[kp]) && isfinite(c->y[kp]))
        svg_plot_marker(s, svg_plot_fx(f, c->x[kp]), svg_plot_fy(f, c->y[kp]), color);
}

/* "drained, 0.01 /s; Mohr-Coulomb phi' 23.7 deg, c' 0 kPa" */
static void test_line(const json_t *res, char *buf, size_t n)
{
    const json_t *mc = json_object_get(json_object_get(res, "stats"), "mohr_coulomb");
    double phi = svg_plot_jnum(json_object_get(mc, "phi_deg"), NAN);
    double c = svg_plot_jnum(json_object_get(mc, "cohesion_kpa"), NAN);
    const char *dr = json_string_value(json_object_get(res, "drainage"));
    int k = snprintf(buf, n, "%s, strain rate %g /s", dr ? dr : "drained",
                     svg_plot_jnum(json_object_get(res, "strain_rate"), NAN));
    if (isfinite(phi) && k > 0 && (size_t)k < n)
        snprintf(buf + k, n - (size_t)k, "; Mohr\xe2\x80\x93" "Coulomb " PHI PRIME " = %.1f" DEG
                 ", c" PRIME " = %.3g kPa", phi, isfinite(c) ? c : 0);
}

/* ------------------------------------------------------------------ stress-strain */

/* one panel: frame f over the curves' x and y ranges (ylo, yhi), axes, curves, peaks */
static void panel(sb *s, frame *f, const xy_curve *c, int n, const char *ylabel, int peaks)
{
    svg_plot_axes(s, f, EPS "a, axial strain (%)", ylabel, 1);
    for (int i = 0; i < n; i++) {
        curve_path(s, f, &c[i], g_colors[i % MAX_CURVES]);
        if (peaks) peak_marker(s, f, &c[i], g_colors[i % MAX_CURVES]);
    }
}

/* sigma1/sigma3 (top) and eps_v (bottom) against eps_a, a curve per confinement */
int svg_triax_stress_strain(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                            int width, gpd_err *err)
{
    xy_curve r[MAX_CURVES], v[MAX_CURVES];
    int nr = read_curves(in->summary, "axial_strain", "stress_ratio", 1, r);
    int nv = read_curves(in->summary, "axial_strain", "volumetric_strain", 100, v);
    if (!nr) {
        curves_free(v, nv);
        gpd_err_set(err, 409, "view \"stress-strain\" needs the curves: submit the spec again "
                              "with \"curves\" in outputs");
        return -1;
    }
    double x0, x1, r0, r1, v0, v1;
    curves_range(r, nr, 0, &x0, &x1);
    curves_range(r, nr, 1, &r0, &r1);
    curves_range(v, nv, 1, &v0, &v1);
    double hr = round(width * 0.4), hv = round(width * 0.25);
    double rlo = fmin(1, floor(10 * r0) / 10);
    frame top = {80, 70, width - 110.0, hr, fmin(0, x0), x1, rlo, r1 + 0.05 * (r1 - rlo), 0};
    frame bot = {80, 70 + hr + 60, width - 110.0, hv, top.xmin, x1, fmin(0, v0), fmax(0, v1), 0};
    int height = (int)(bot.y0 + hv + 60);
    sb *s = &g->out;
    char line[200];
    svg_plot_doc_begin(s, width, height, "Triaxial tests: " SIGMA "1/" SIGMA "3 and " EPS
                                         "v against " EPS "a");
    test_line(in->summary, line, sizeof line);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", line);
    panel(s, &top, r, nr, "stress ratio " SIGMA "1/" SIGMA "3", 1);
    panel(s, &bot, v, nv, EPS "v, volumetric strain (%)", 0);
    legend_item it[MAX_CURVES];
    for (int i = 0; i < nr; i++) it[i] = (legend_item){r[i].label, "line", g_colors[i]};
    svg_plot_legend(s, top.x0 + top.w - svg_plot_legend_w(it, nr) - 10, top.y0 + top.h - 14 -
                    18.0 * nr, it, nr);
    svg_plot_doc_end(s);
    curves_free(r, nr);
    curves_free(v, nv);
    return 0;
}

/* ------------------------------------------------------------------ mohr */

/* the peak states of the tests: sigma3 and sigma1 (kPa); how many */
static int peak_states(const json_t *res, double *s3, double *s1, double *kpa)
{
    const json_t *tests = json_object_get(json_object_get(res, "stats"), "tests");
    int n = 0;
    for (size_t i = 0; i < json_array_size(tests) && n < MAX_CURVES; i++) {
        const json_t *t = json_array_get(tests, i), *pk = json_object_get(t, "peak");
        s3[n] = svg_plot_jnum(json_object_get(pk, "sigma3_kpa"), NAN);
        s1[n] = svg_plot_jnum(json_object_get(pk, "sigma1_kpa"), NAN);
        kpa[n] = svg_plot_jnum(json_object_get(t, "confining_kpa"), NAN);
        if (isfinite(s3[n]) && isfinite(s1[n]) && s1[n] >= s3[n]) n++;
    }
    return n;
}

/* the envelope tau = c + sigma tan(phi), clipped to f */
static void envelope(sb *s, const frame *f, double phi_deg, double c)
{
    double t = tan(phi_deg * M_PI / 180);
    if (!isfinite(t) || !isfinite(c)) return;
    double xe = t > 0 ? fmin(f->xmax, (f->ymax - c) / t) : f->xmax;
    svg_plot_sb_printf(s, "<path class=\"envelope\" fill=\"none\" stroke=\"#000000\" "
                          "stroke-width=\"1.5\" stroke-dasharray=\"7 4\" d=\"M%.1f %.1fL%.1f "
                          "%.1f\"/>\n", svg_plot_fx(f, 0), svg_plot_fy(f, c),
                       svg_plot_fx(f, xe), svg_plot_fy(f, c + t * xe));
}

/* the Mohr circles of the peak states (upper halves) with the envelope, equal scales */
int svg_triax_mohr(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                   gpd_err *err)
{
    double s3[MAX_CURVES], s1[MAX_CURVES], kpa[MAX_CURVES];
    int n = peak_states(in->summary, s3, s1, kpa);
    if (!n) {
        gpd_err_set(err, 409, "view \"mohr\" needs stats.tests[].peak (sigma1_kpa, "
                              "sigma3_kpa) in the result");
        return -1;
    }
    double xmax = 0, rmax = 0;
    for (int i = 0; i < n; i++) xmax = fmax(xmax, s1[i]), rmax = fmax(rmax, 0.5 * (s1[i] - s3[i]));
    xmax = xmax > 0 ? 1.08 * xmax : 1;
    double ymax = rmax > 0 ? 1.3 * rmax : 0.5 * xmax, w = width - 110.0;
    frame f = {80, 70, w, round(w * ymax / xmax), 0, xmax, 0, ymax, 0};
    sb *s = &g->out;
    char line[200];
    svg_plot_doc_begin(s, width, (int)(f.y0 + f.h + 60), "Mohr circles at peak and the "
                                                        "Mohr\xe2\x80\x93" "Coulomb envelope");
    test_line(in->summary, line, sizeof line);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", line);
    svg_plot_axes(s, &f, "normal stress " SIGMA " (kPa)", "shear stress " TAU " (kPa)", 1);
    legend_item it[MAX_CURVES];
    char labels[MAX_CURVES][64];
    for (int i = 0; i < n; i++) {
        double r = 0.5 * (s1[i] - s3[i]) * f.w / f.xmax;
        svg_plot_sb_printf(s, "<path class=\"circle\" fill=\"none\" stroke=\"%s\" "
                              "stroke-width=\"2\" d=\"M%.1f %.1fA%.1f %.1f 0 0 1 %.1f %.1f\"/>\n",
                           g_colors[i], svg_plot_fx(&f, s3[i]), svg_plot_fy(&f, 0), r, r,
                           svg_plot_fx(&f, s1[i]), svg_plot_fy(&f, 0));
        snprintf(labels[i], sizeof labels[i], SIGMA "3 = %g kPa: " SIGMA "1 = %.4g kPa", kpa[i],
                 s1[i]);
        it[i] = (legend_item){labels[i], "line", g_colors[i]};
    }
    const json_t *mc = json_object_get(json_object_get(in->summary, "stats"), "mohr_coulomb");
    envelope(s, &f, svg_plot_jnum(json_object_get(mc, "phi_deg"), NAN),
             svg_plot_jnum(json_object_get(mc, "cohesion_kpa"), NAN));
    svg_plot_legend(s, f.x0 + 10, f.y0 + 8, it, n);
    svg_plot_doc_end(s);
    return 0;
}

/* ------------------------------------------------------------------ section */

/* "the end of the test at 100 kPa (axial strain 0.2): porosity 0.41, of this section 0.45" and
 * the box */
static void section_lines(const json_t *res, double z, double cut_porosity, char *l1, char *l2,
                          size_t n)
{
    const json_t *tests = json_object_get(json_object_get(res, "stats"), "tests");
    const json_t *t = json_array_get(tests, json_array_size(tests) - 1);
    const json_t *end = json_object_get(t, "end");
    double kpa = svg_plot_jnum(json_object_get(t, "confining_kpa"), NAN);
    double ea = svg_plot_jnum(json_object_get(end, "axial_strain"), NAN);
    double por = svg_plot_jnum(json_object_get(end, "porosity"), NAN);
    int k = snprintf(l1, n, "the end of the test at " SIGMA "3 = %g kPa (" EPS "a %.3g): "
                     "porosity %.3f", kpa, ea, por);
    if (isfinite(cut_porosity) && k > 0 && (size_t)k < n)
        snprintf(l1 + k, n - (size_t)k, ", of this section %.3f", cut_porosity);
    const json_t *box = json_object_get(res, "box");
    snprintf(l2, n, "the walls at the end: %.4g \xc3\x97 %.4g \xc3\x97 %.4g m (z from the "
             "bottom wall)", svg_plot_jnum(json_array_get(box, 0), NAN),
             svg_plot_jnum(json_array_get(box, 1), NAN), svg_plot_jnum(json_array_get(box, 2),
                                                                        NAN));
}

int svg_triax_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                      gpd_err *err)
{
    return svg_views3d_section_with(g, in, opt, width, section_lines, err);
}
