/* svg_views3d.c -- the SVG views of the 3D kind (kind_spheres3d.c): a section of the packing at
 * a height z (the spheres it cuts, coloured by diameter, read one at a time in passes; shared
 * with the other sphere kinds through svg_views3d_section_with) and the grain-size distribution
 * (stats.psd: target and achieved, by weight and by number). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"
#include "svg/svg_views.h"

/* the section at z: pass 1 diameter range, bounds (when the result has no box), count and the
 * spheres cut (once z is known); the head; step_section draws the cut spheres, then the tail */
static int step_section(gp_svg *g)
{
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const double *q = g->items->cur.q;
        double r_ = q[3], dz = q[2] - g->z;
        if (!(r_ > 0) || !(fabs(dz) < r_)) continue;
        double rc = sqrt(r_ * r_ - dz * dz);
        char c[16];
        double t = g->dmax > g->dmin
                       ? (g->logscale ? log(2 * r_ / g->dmin) / log(g->dmax / g->dmin)
                                      : (2 * r_ - g->dmin) / (g->dmax - g->dmin))
                       : 0.5;
        svg_plot_ramp(t, c, sizeof c);
        svg_plot_sb_printf(&g->out, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.2f\" fill=\"%s\"/>\n",
                  svg_plot_fx(&g->f, isnan(q[0]) ? 0 : q[0]), svg_plot_fy(&g->f, isnan(q[1]) ? 0 : q[1]),
                  rc * g->scale, c);
    }
    if (r < 0) return svg_pass_failed(g);
    if (r > 0) return 0;
    svg_plot_sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

/* the box of the result ([bx, by, bz], every side > 0): 1, else 0 */
static int read_box(const json_t *res, double box[3])
{
    const json_t *jb = json_object_get(res, "box");
    int have_box = json_is_array(jb) && json_array_size(jb) == 3;
    for (int a = 0; a < 3; a++) {
        if (have_box) box[a] = svg_plot_jnum(json_array_get(jb, (size_t)a), NAN);
        if (!(box[a] > 0)) have_box = 0;
    }
    return have_box;
}

/* the tiling's count along z (result "tiling": [nx, ny, nz]); 1 when untiled or absent */
static int read_tiles_z(const json_t *res)
{
    double nz = svg_plot_jnum(json_array_get(json_object_get(res, "tiling"), 2), 1);
    return nz >= 1 && nz <= 1e6 ? (int)nz : 1;
}

/* The default cut of a packing of height h from lo, tiled nz times along z: the mid-height of
 * the middle base cell, ((nz - 1) / 2 + 0.5) h / nz. The flip tiling mirrors the sample at
 * every multiple of h / nz (the sample's walls), so a cut there -- the box's middle when nz is
 * even -- shows the same spheres twice, cut at their tips: a grey square. Mid-height of a cell
 * is the farthest a cut can be from every mirror plane, and from the walls' layering. */
static double default_z(double lo, double h, int nz)
{
    return lo + ((nz - 1) / 2 + 0.5) * h / nz;
}

/* the cut asked for (opt->z) when it is in [lo, hi] (400 otherwise); *z unchanged without one */
static int cut_at(const gp_svg_options *opt, double *z, double lo, double hi, gpd_err *err)
{
    if (!opt || !opt->has_z) return 0;
    *z = opt->z;
    if (isfinite(*z) && *z >= lo && *z <= hi) return 0;
    gpd_err_set(err, 400, "z = %g is outside the packing: valid z from %g to %g m", *z, lo, hi);
    return -1;
}

/* what the section needs of the spheres, from a pass over them */
typedef struct sphere_scan {
    size_t n, ncut;                /* spheres, and those cut at z */
    double cut_area;               /* the area of their circles (m²) */
    double dmin, dmax;             /* the diameters' range */
    double bl[3], bh[3];           /* the spheres' bounds */
} sphere_scan;

/* one pass over the spheres: all of sc, or (count_only) only the spheres cut at z */
static int scan_spheres(gp_svg *g, double z, int count_only, sphere_scan *sc)
{
    int r = svg_pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const double *q = g->items->cur.q;
            double rr = q[3], dz = q[2] - z;
            if (rr > 0 && fabs(dz) < rr) sc->ncut++, sc->cut_area += M_PI * (rr * rr - dz * dz);
            if (count_only) continue;
            sc->n++;
            if (!(rr > 0)) continue;
            sc->dmin = fmin(sc->dmin, 2 * rr);
            sc->dmax = fmax(sc->dmax, 2 * rr);
            for (int a = 0; a < 3; a++) {
                sc->bl[a] = fmin(sc->bl[a], q[a] - rr);
                sc->bh[a] = fmax(sc->bh[a], q[a] + rr);
            }
        }
    return r < 0 ? -1 : 0;
}

/* the diameter (m) at p percent passing of a psd curve, log-linear between its sieves; NaN
 * when the curve does not reach p */
static double psd_d(const double *d, const double *c, size_t n, double p)
{
    for (size_t i = 1; i < n; i++) {
        if (!(d[i - 1] > 0) || !(d[i] > 0) || !isfinite(c[i - 1]) || !isfinite(c[i])) continue;
        if (c[i - 1] <= p && c[i] >= p && c[i] > c[i - 1])
            return d[i - 1] * pow(d[i] / d[i - 1], (p - c[i - 1]) / (c[i] - c[i - 1]));
    }
    return NAN;
}

/* "PSD by weight: D50 49.6 mm, Cu = D60/D10 2.3, max error 0.4 pp" from stats.psd; "" when
 * there is none */
static void psd_summary(const json_t *psd, char *buf, size_t len)
{
    size_t n, nt, na;
    double *d = svg_plot_jarray(json_object_get(psd, "diameters"), &n);
    double *t = svg_plot_jarray(json_object_get(psd, "target_weight"), &nt);
    double *a = svg_plot_jarray(json_object_get(psd, "achieved_weight"), &na);
    buf[0] = 0;
    if (d && a && na == n) {
        double d10 = psd_d(d, a, n, 10), d50 = psd_d(d, a, n, 50), d60 = psd_d(d, a, n, 60);
        double err = t && nt == n ? 0 : NAN;
        for (size_t i = 0; t && nt == n && i < n; i++)
            if (isfinite(t[i]) && isfinite(a[i])) err = fmax(err, fabs(a[i] - t[i]));
        int k = snprintf(buf, len, "PSD by weight:");
        if (isfinite(d50) && k > 0 && (size_t)k < len)
            k += snprintf(buf + k, len - (size_t)k, " D50 %.3g mm,", d50 * 1e3);
        if (isfinite(d60 / d10) && k > 0 && (size_t)k < len)
            k += snprintf(buf + k, len - (size_t)k, " Cu = D60/D10 %.3g,", d60 / d10);
        if (isfinite(err) && k > 0 && (size_t)k < len) /* (a fitted curve is exact to 1e-14) */
            k += snprintf(buf + k, len - (size_t)k,
                          err < 0.005 ? " max error < 0.01 pp" : " max error %.2f pp", err);
        if (k > 0 && (size_t)k < len && buf[k - 1] == ',') buf[k - 1] = 0;
        if (!strcmp(buf, "PSD by weight:")) buf[0] = 0;
    }
    free(d);
    free(t);
    free(a);
}

/* the subtitle of the section: porosity of the packing (stats) and of the cut, the PSD, and
 * where the cut lies against the mirror planes of a tiling */
static void section_subtitle(const json_t *res, const sphere_scan *sc, double area, double z,
                             double hz, int nz, char *l1, char *l2, size_t n)
{
    const json_t *po = json_object_get(json_object_get(res, "stats"), "porosity");
    double p = svg_plot_jnum(json_is_object(po) ? json_object_get(po, "achieved") : po, NAN);
    double pt = svg_plot_jnum(json_is_object(po) ? json_object_get(po, "target") : NULL, NAN);
    char psd[160];
    psd_summary(json_object_get(json_object_get(res, "stats"), "psd"), psd, sizeof psd);
    int k = isfinite(p) ? snprintf(l1, n, "porosity %.3f", p) : snprintf(l1, n, "porosity");
    if (isfinite(pt) && k > 0 && (size_t)k < n) k += snprintf(l1 + k, n - (size_t)k, " (target %.3g)", pt);
    if (area > 0 && k > 0 && (size_t)k < n)
        k += snprintf(l1 + k, n - (size_t)k, ", of this section %.3f", 1 - sc->cut_area / area);
    if (psd[0] && k > 0 && (size_t)k < n) snprintf(l1 + k, n - (size_t)k, "; %s", psd);
    if (nz > 1) {
        double cell = hz / nz, dm = fabs(z / cell - floor(z / cell + 0.5)) * cell;
        snprintf(l2, n, "tiled %d\xc3\x97 along z: mirror planes every %.4g m, the nearest %.3g m from the cut",
                 nz, cell, dm);
    } else {
        snprintf(l2, n, "untiled sample");
    }
}

/* the head (title, subtitle, axes, the box) and the tail (a colour bar of the diameters) of
 * the section; its subtitle by sub (NULL: section_subtitle) */
static void section_frame(gp_svg *g, const json_t *res, bounds b, int width,
                          const sphere_scan *sc, double hz, int nz, svg_views3d_subtitle_fn sub)
{
    int height;
    frame f = svg_plot_map_frame(b, width, &height);
    f.y0 += 36; /* room for two subtitle lines */
    height += 36;
    sb *s = &g->out;
    char title[200], l1[320], l2[200];
    snprintf(title, sizeof title, "Section at z = %.4g m: %zu of %zu spheres cut", g->z, sc->ncut,
             sc->n);
    double area = (b.xmax - b.xmin) * (b.ymax - b.ymin);
    if (sub)
        sub(res, g->z, area > 0 ? 1 - sc->cut_area / area : NAN, l1, l2, sizeof l2);
    else
        section_subtitle(res, sc, area, g->z, hz, nz, l1, l2, sizeof l1);
    svg_plot_doc_begin(s, width, height, title);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", l1);
    svg_plot_text_at(s, width / 2.0, 58, "middle", "class=\"subtitle\" fill=\"#444444\"", l2);
    svg_plot_axes(s, &f, "x (m)", "y (m)", 0);
    svg_plot_sb_printf(s, "<rect class=\"box\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f4f4f4\" "
                 "stroke=\"#000000\" stroke-width=\"1.5\"/>\n",
              svg_plot_fx(&f, b.xmin), svg_plot_fy(&f, b.ymax), svg_plot_fx(&f, b.xmax) - svg_plot_fx(&f, b.xmin), svg_plot_fy(&f, b.ymin) - svg_plot_fy(&f, b.ymax));
    svg_plot_sb_puts(s, "<g class=\"spheres\" stroke=\"#222222\" stroke-width=\"0.4\">\n");
    svg_plot_sb_puts(&g->tail, "</g>\n");
    double k = g->dmax < 1 ? 1000 : 1;
    svg_plot_colorbar(&g->tail, f.x0 + f.w + 20, f.y0 + 24, fmin(f.h - 30, 300), g->dmin * k, g->dmax * k,
             0, g->logscale, k > 1 ? "diameter (mm)" : "diameter (m)");
    svg_plot_doc_end(&g->tail);
    g->f = f;
    g->scale = f.w / (f.xmax - f.xmin);
}

/* The section at z (opt->z, else default_z): pass 1 diameter range, bounds (when the result
 * has no box), count and the spheres cut (once z is known); the head; step_section draws the
 * cut spheres, then the tail. */
int svg_views3d_section_with(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                             int width, svg_views3d_subtitle_fn sub, gpd_err *err)
{
    if (svg_open_part(g, in, GP_SVG_SPHERES, "section", err)) return -1;
    double box[3] = {NAN, NAN, NAN}, lo[3] = {0, 0, 0};
    int have_box = read_box(in->summary, box), nz = read_tiles_z(in->summary);
    /* z is known before the pass when the result has its box: check it, count the cut spheres
     * in the same pass */
    double z = have_box ? default_z(0, box[2], nz) : NAN;
    if (have_box && cut_at(opt, &z, 0.0, box[2], err)) return -1;
    sphere_scan sc = {0, 0, 0, INFINITY, -INFINITY, {INFINITY, INFINITY, INFINITY},
                      {-INFINITY, -INFINITY, -INFINITY}};
    if (scan_spheres(g, z, 0, &sc)) return svg_part_error(err, GP_SVG_SPHERES);
    if (!have_box) {
        for (int a = 0; a < 3; a++) {
            lo[a] = sc.bh[a] >= sc.bl[a] ? sc.bl[a] : 0;
            box[a] = sc.bh[a] >= sc.bl[a] ? sc.bh[a] - sc.bl[a] : 1;
        }
        z = default_z(lo[2], box[2], nz);
        if (cut_at(opt, &z, lo[2], lo[2] + box[2], err)) return -1;
        /* a second pass counts the spheres cut */
        sc.ncut = 0;
        sc.cut_area = 0;
        if (scan_spheres(g, z, 1, &sc)) return svg_part_error(err, GP_SVG_SPHERES);
    }
    if (!(sc.dmax >= sc.dmin)) sc.dmin = sc.dmax = 1;
    g->z = z;
    g->dmin = sc.dmin;
    g->dmax = sc.dmax;
    g->logscale = sc.dmax > 4 * sc.dmin;
    bounds b = {lo[0], lo[0] + box[0], lo[1], lo[1] + box[1]};
    section_frame(g, in->summary, b, width, &sc, box[2], nz, sub);
    return svg_start_steps(g, step_section, err);
}

int svg_views3d_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err)
{
    return svg_views3d_section_with(g, in, opt, width, NULL, err);
}

/* the sieve curves of stats.psd: percent passing against the sieve diameter (log scale) */
int svg_views3d_psd(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                 gpd_err *err)
{
    const json_t *res = in->summary;
    const json_t *psd = json_object_get(json_object_get(res, "stats"), "psd");
    static const char *keys[4] = {"target_weight", "achieved_weight", "target_number", "achieved_number"};
    static const char *labels[4] = {"target, by weight", "achieved, by weight", "target, by number",
                                    "achieved, by number"};
    static const char *colors[4] = {"#1f77b4", "#1f77b4", "#d62728", "#d62728"};
    size_t nd = 0, nc[4] = {0};
    double *d = svg_plot_jarray(json_object_get(psd, "diameters"), &nd);
    double *c[4] = {NULL};
    for (int k = 0; k < 4; k++) {
        c[k] = svg_plot_jarray(json_object_get(psd, keys[k]), &nc[k]);
        if (c[k] && nc[k] != nd) {
            free(c[k]);
            c[k] = NULL;
        }
    }
    int any = 0;
    for (int k = 0; k < 4; k++) any |= c[k] != NULL;
    if (!d || !any) {
        free(d);
        for (int k = 0; k < 4; k++) free(c[k]);
        gpd_err_set(err, 409, "view \"psd\" needs stats.psd (diameters with target/achieved curves) in the result");
        return -1;
    }
    double dmin = INFINITY, dmax = -INFINITY;
    for (size_t i = 0; i < nd; i++)
        if (d[i] > 0) dmin = fmin(dmin, d[i]), dmax = fmax(dmax, d[i]);
    if (!(dmax >= dmin)) dmin = 1e-3, dmax = 1e-1;
    double unit = dmax < 1 ? 1000 : 1;
    double xlo = pow(10, floor(log10(dmin * unit) + 1e-9)), xhi = pow(10, ceil(log10(dmax * unit) - 1e-9));
    if (!(xhi > xlo)) xhi = xlo * 10;
    int height = (int)lround(width * 0.62);
    frame f = {80, 40, width - 110.0, height - 110.0, xlo, xhi, 0, 100, 1};
    sb *s = &g->out;
    svg_plot_doc_begin(s, width, height, "Grain-size distribution: target vs achieved");
    svg_plot_axes(s, &f, unit > 1 ? "sieve diameter (mm, log scale)" : "sieve diameter (m, log scale)",
         "percent passing (%)", 1);
    for (int k = 0; k < 4; k++) {
        if (!c[k]) continue;
        int dashed = k % 2 == 0;
        svg_plot_sb_printf(s, "<path class=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s d=\"", keys[k],
                  colors[k], dashed ? " stroke-dasharray=\"6 4\"" : "");
        int first = 1;
        for (size_t i = 0; i < nd; i++) {
            if (!(d[i] > 0) || !isfinite(c[k][i])) continue;
            svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", svg_plot_fx(&f, d[i] * unit), svg_plot_fy(&f, fmax(0, fmin(100, c[k][i]))));
            first = 0;
        }
        svg_plot_sb_puts(s, "\"/>\n");
        if (!dashed)
            for (size_t i = 0; i < nd; i++)
                if (d[i] > 0 && isfinite(c[k][i]))
                    svg_plot_marker(s, svg_plot_fx(&f, d[i] * unit), svg_plot_fy(&f, fmax(0, fmin(100, c[k][i]))), colors[k]);
    }
    legend_item it[4];
    int n = 0;
    for (int k = 0; k < 4; k++)
        if (c[k]) it[n++] = (legend_item){labels[k], k % 2 == 0 ? "dash" : "marker", colors[k]};
    svg_plot_legend(s, f.x0 + 10, f.y0 + 8, it, n);
    svg_plot_doc_end(s);
    free(d);
    for (int k = 0; k < 4; k++) free(c[k]);
    return 0;
}
