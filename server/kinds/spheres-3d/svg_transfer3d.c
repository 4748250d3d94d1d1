/* svg_transfer3d.c -- the "transfer" view of a spheres-3d result (see svg_transfer3d.h). */
#include "kinds/spheres-3d/svg_transfer3d.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"

#define SAMPLE_COLOR "#1f77b4"
#define FINAL_COLOR "#d62728"

/* one curve through the finite points (x[i], y[i]) */
static void rdf_path(sb *s, const frame *f, const char *cls, const char *color, const double *x,
                     const double *y, size_t n, int dashed)
{
    svg_plot_sb_printf(s, "<path class=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s d=\"",
                       cls, color, dashed ? " stroke-dasharray=\"6 4\"" : "");
    int first = 1;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i]) || !isfinite(y[i])) continue;
        svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", svg_plot_fx(f, x[i]),
                           svg_plot_fy(f, fmin(f->ymax, fmax(f->ymin, y[i]))));
        first = 0;
    }
    svg_plot_sb_puts(s, "\"/>\n");
}

/* g(r) of the sample and of the final packing against r / d50, with the largest difference
 * marked by a vertical segment between the two curves */
int svg_transfer3d_rdf(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                       gpd_err *err)
{
    (void)opt;
    const json_t *tr = json_object_get(json_object_get(in->summary, "stats"), "transfer");
    const json_t *rdf = json_object_get(tr, "rdf");
    size_t n = 0, na = 0, nb = 0;
    double *x = svg_plot_jarray(json_object_get(rdf, "r_d50"), &n);
    double *a = svg_plot_jarray(json_object_get(rdf, "sample"), &na);
    double *b = svg_plot_jarray(json_object_get(rdf, "final"), &nb);
    if (!x || !a || !b || na != n || nb != n) {
        free(x);
        free(a);
        free(b);
        gpd_err_set(err, 409, "view \"transfer\" needs stats.transfer.rdf (r_d50, sample, final) "
                              "in the result: only a tiled spheres-3d specimen has it (tiling "
                              "other than [1, 1, 1])");
        return -1;
    }
    double xmax = 0, ymax = 0;
    for (size_t i = 0; i < n; i++) {
        if (isfinite(x[i])) xmax = fmax(xmax, x[i]);
        if (isfinite(a[i])) ymax = fmax(ymax, a[i]);
        if (isfinite(b[i])) ymax = fmax(ymax, b[i]);
    }
    double dr = n > 1 && isfinite(x[1] - x[0]) ? x[1] - x[0] : 0;
    xmax += 0.5 * dr;
    if (!(xmax > 0)) xmax = 1;
    ymax = ymax > 0 ? 1.1 * ymax : 1.5;
    double md = svg_plot_jnum(json_object_get(rdf, "max_difference"), NAN);
    double at = svg_plot_jnum(json_object_get(rdf, "at_r_d50"), NAN);
    double rms = svg_plot_jnum(json_object_get(rdf, "rms"), NAN);
    double d50 = svg_plot_jnum(json_object_get(rdf, "d50"), NAN);
    const char *on = json_string_value(json_object_get(rdf, "measured_on"));
    int height = (int)lround(width * 0.62);
    frame f = {80, 76, width - 110.0, height - 146.0, 0, xmax, 0, ymax, 0};
    sb *s = &g->out;
    svg_plot_doc_begin(s, width, height, "Radial distribution g(r): the sample and the final packing");
    char l1[200], l2[480];
    int k = snprintf(l1, sizeof l1, "largest difference");
    if (isfinite(md) && isfinite(at))
        k += snprintf(l1 + k, sizeof l1 - (size_t)k, " %.3f at r = %.3g d50", md, at);
    if (isfinite(rms) && k > 0 && (size_t)k < sizeof l1)
        k += snprintf(l1 + k, sizeof l1 - (size_t)k, ", rms %.3f", rms);
    if (isfinite(d50) && k > 0 && (size_t)k < sizeof l1)
        snprintf(l1 + k, sizeof l1 - (size_t)k, "; d50 = %.4g mm (the sample's)", d50 * 1e3);
    /* where the final packing's g(r) was measured (stats.transfer.rdf.block) */
    const json_t *blk = json_object_get(rdf, "block"), *bt = json_object_get(blk, "tiles");
    double bs = svg_plot_jnum(json_object_get(blk, "spheres"), NAN);
    double np = svg_plot_jnum(json_object_get(json_object_get(in->summary, "stats"), "particles"),
                              NAN);
    int bn[3];
    for (int a = 0; a < 3; a++) bn[a] = (int)svg_plot_jnum(json_array_get(bt, (size_t)a), 0);
    if (on && !strncmp(on, "the whole tiling", 16) && isfinite(np))
        snprintf(l2, sizeof l2, "final packing: g(r) of the whole tiling, %.0f spheres", np);
    else if (bn[0] > 0 && bn[1] > 0 && bn[2] > 0 && isfinite(bs) && isfinite(np))
        snprintf(l2, sizeof l2, "final packing: g(r) on a block of %d \xc3\x97 %d \xc3\x97 %d "
                 "tiles near its centre, %.0f of its %.0f spheres", bn[0], bn[1], bn[2], bs, np);
    else
        snprintf(l2, sizeof l2, "final packing: g(r) on %s", on ? on : "the tiling");
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", l1);
    svg_plot_text_at(s, width / 2.0, 58, "middle", "class=\"subtitle\" fill=\"#444444\"", l2);
    svg_plot_axes(s, &f, "r / d50", "g(r)", 1);
    /* g = 1, an uncorrelated structure */
    if (ymax > 1)
        svg_plot_sb_printf(s, "<path class=\"unity\" fill=\"none\" stroke=\"#888888\" "
                              "stroke-width=\"1\" stroke-dasharray=\"2 3\" d=\"M%.1f %.1fL%.1f %.1f\"/>\n",
                           svg_plot_fx(&f, 0), svg_plot_fy(&f, 1), svg_plot_fx(&f, xmax),
                           svg_plot_fy(&f, 1));
    rdf_path(s, &f, "sample", SAMPLE_COLOR, x, a, n, 0);
    rdf_path(s, &f, "final", FINAL_COLOR, x, b, n, 1);
    /* the largest difference: the bin at at_r_d50 */
    size_t im = n;
    for (size_t i = 0; i < n && isfinite(at); i++)
        if (isfinite(x[i]) && (im == n || fabs(x[i] - at) < fabs(x[im] - at))) im = i;
    if (im < n && isfinite(a[im]) && isfinite(b[im])) {
        double px = svg_plot_fx(&f, x[im]);
        svg_plot_sb_printf(s, "<path class=\"max-difference\" fill=\"none\" stroke=\"#000000\" "
                              "stroke-width=\"1.5\" d=\"M%.1f %.1fL%.1f %.1fM%.1f %.1fL%.1f %.1fM%.1f "
                              "%.1fL%.1f %.1f\"/>\n",
                           px, svg_plot_fy(&f, a[im]), px, svg_plot_fy(&f, b[im]), px - 5,
                           svg_plot_fy(&f, a[im]), px + 5, svg_plot_fy(&f, a[im]), px - 5,
                           svg_plot_fy(&f, b[im]), px + 5, svg_plot_fy(&f, b[im]));
        char lab[64];
        snprintf(lab, sizeof lab, "\xce\x94g = %.3f", fabs(b[im] - a[im]));
        double ty = 0.5 * (svg_plot_fy(&f, a[im]) + svg_plot_fy(&f, b[im]));
        svg_plot_text_at(s, px + 8, ty + 4, "start", "class=\"max-difference-label\"", lab);
    }
    legend_item it[3] = {{"sample", "line", SAMPLE_COLOR},
                         {"final packing", "dash", FINAL_COLOR},
                         {"largest difference", "line", "#000000"}};
    svg_plot_legend(s, f.x0 + f.w - svg_plot_legend_w(it, 3) - 10, f.y0 + 8, it, 3);
    svg_plot_doc_end(s);
    free(x);
    free(a);
    free(b);
    return 0;
}
