/* svg_views2d.c -- the SVG views of the 2D kind (kind_fv2d.c): the packing (grains coloured by
 * area or orientation), the Voronoi cells and their seeds, the size distribution (CDFs of
 * stats.fit, or histograms), the orientation rose and the shape descriptors. The geometry
 * views read the grains or cells one at a time, in passes (svg_internal.h); the statistics views
 * read the summary and fall back to the items where a histogram is missing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg_internal.h"
#include "svg_views.h"

/* ------------------------------------------------------------------ the container */

/* "x,y x,y ..." of a JSON ring [[x,y],...] (ring_points_xy) */
static size_t ring_points(sb *s, const frame *f, const json_t *ring, double min_px)
{
    svg_item pts = {0};
    size_t w = 0;
    if (svg_item_ring(&pts, ring))
        s->oom = 1;
    else
        w = ring_points_xy(s, f, pts.xy, pts.npts, min_px);
    svg_item_free(&pts);
    return w;
}

/* the container outline (from result.container), as a path */
static void container_outline(sb *s, const frame *f, const json_t *container)
{
    if (!json_is_object(container)) return;
    const json_t *circle = json_object_get(container, "circle");
    if (json_is_object(circle)) {
        const json_t *c = json_object_get(circle, "center");
        double cx = jnum(json_array_get(c, 0), NAN), cy = jnum(json_array_get(c, 1), NAN);
        double r = jnum(json_object_get(circle, "radius"), NAN);
        if (!isfinite(cx) || !isfinite(cy) || !(r > 0)) return;
        double px = fx(f, cx), py = fy(f, cy), pr = fx(f, cx + r) - px;
        sb_printf(s, "<path class=\"container\" d=\"M%.1f %.1fa%.1f %.1f 0 1 0 %.1f 0a%.1f %.1f 0 1 0 %.1f 0z\" "
                     "fill=\"none\" stroke=\"#000000\" stroke-width=\"1.5\"/>\n",
                  px - pr, py, pr, pr, 2 * pr, pr, pr, -2 * pr);
        return;
    }
    const json_t *poly = json_object_get(container, "polygon");
    if (!json_is_array(poly)) return;
    sb_puts(s, "<path class=\"container\" fill=\"none\" stroke=\"#000000\" stroke-width=\"1.5\" d=\"");
    sb_puts(s, "M");
    ring_points(s, f, poly, 0);
    sb_puts(s, "z");
    size_t i;
    const json_t *h;
    json_array_foreach(json_object_get(container, "holes"), i, h) {
        sb_puts(s, " M");
        ring_points(s, f, h, 0);
        sb_puts(s, "z");
    }
    sb_puts(s, "\"/>\n");
}

static void bounds_ring(bounds *b, const json_t *ring)
{
    size_t i;
    const json_t *p;
    json_array_foreach(ring, i, p) {
        bounds_add(b, jnum(json_array_get(p, 0), NAN), jnum(json_array_get(p, 1), NAN));
    }
}

static void container_bounds(bounds *b, const json_t *container)
{
    if (!json_is_object(container)) return;
    const json_t *circle = json_object_get(container, "circle");
    if (circle) {
        const json_t *c = json_object_get(circle, "center");
        double cx = jnum(json_array_get(c, 0), NAN), cy = jnum(json_array_get(c, 1), NAN);
        double r = jnum(json_object_get(circle, "radius"), NAN);
        bounds_add(b, cx - r, cy - r);
        bounds_add(b, cx + r, cy + r);
        return;
    }
    bounds_ring(b, json_object_get(container, "polygon"));
}

/* ------------------------------------------------------------------ maps: packing, cells */

/* The first pass over the items of part (opened for view): the bounds of the items and of the
 * container, the items' count and area range (g->amin, g->amax; 1 when none is positive). */
static int map_pass(gp_svg *g, const gp_svg_input *in, gp_svg_part part, const char *view,
                    bounds *b, size_t *n, gpd_err *err)
{
    if (svg_open_part(g, in, part, view, err)) return -1;
    bounds_init(b);
    container_bounds(b, json_object_get(in->summary, "container"));
    double amin = INFINITY, amax = -INFINITY;
    *n = 0;
    int r = svg_pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const svg_item *c = &g->items->cur;
            (*n)++;
            bounds_xy(b, c->xy, c->npts);
            if (c->area > 0) amin = fmin(amin, c->area), amax = fmax(amax, c->area);
        }
    if (r < 0) return svg_part_error(err, part);
    if (!bounds_ok(b)) b->xmin = b->ymin = 0, b->xmax = b->ymax = 1;
    if (!(amax >= amin)) amin = amax = 1;
    g->amin = amin;
    g->amax = amax;
    g->min_px = *n > 2000 ? 0.6 : 0.3;
    return 0;
}

/* the head of a map of b: its frame (g->f), the document with its title and axes in metres */
static void map_head(gp_svg *g, bounds b, int width, const char *title)
{
    int height;
    g->f = map_frame(b, width, &height);
    doc_begin(&g->out, width, height, title);
    axes(&g->out, &g->f, "x (m)", "y (m)", 0);
}

/* the end of a map: the container's outline and a colour bar (cyc: orientations, else the
 * areas g->amin..g->amax) into the tail; then the drawing pass begins, by step */
static int map_end(gp_svg *g, const gp_svg_input *in, int cyc, int logscale, const char *label,
                   int (*step)(gp_svg *g), gpd_err *err)
{
    const frame *f = &g->f;
    container_outline(&g->tail, f, json_object_get(in->summary, "container"));
    double cbx = f->x0 + f->w + 20, cbh = fmin(f->h - 30, 300);
    if (cyc) colorbar(&g->tail, cbx, f->y0 + 24, cbh, -90, 90, 1, 0, label);
    else colorbar(&g->tail, cbx, f->y0 + 24, cbh, g->amin, g->amax, 0, logscale, label);
    doc_end(&g->tail);
    return svg_start_steps(g, step, err);
}

/* the packing: grains coloured by area or orientation. Pass 1: bounds, area range, count;
 * then the head; step_packing draws the grains and stages the tail. */
static int step_packing(gp_svg *g)
{
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const svg_item *c = &g->items->cur;
        char col[16];
        if (g->by_orient) {
            cyclic(isnan(c->orientation_deg) ? 0 : c->orientation_deg, col, sizeof col);
        } else {
            double a = isnan(c->area) ? g->amin : c->area, t;
            if (g->amax > g->amin)
                t = g->logscale ? log(a / g->amin) / log(g->amax / g->amin)
                                : (a - g->amin) / (g->amax - g->amin);
            else t = 0.5;
            ramp(t, col, sizeof col);
        }
        sb_printf(&g->out, "<polygon fill=\"%s\" points=\"", col);
        ring_points_xy(&g->out, &g->f, c->xy, c->npts, g->min_px);
        sb_puts(&g->out, "\"/>\n");
    }
    if (r < 0) return svg_pass_failed(g);
    if (r > 0) return 0;
    sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

int svg_view_packing(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err)
{
    const char *color = opt && opt->color && *opt->color ? opt->color : "size";
    int by_orient = !strcmp(color, "orientation");
    if (!by_orient && strcmp(color, "size") != 0) {
        gpd_err_set(err, 400, "unknown color \"%s\"; valid: size, orientation", color);
        return -1;
    }
    bounds b;
    size_t ng;
    if (map_pass(g, in, GP_SVG_GRAINS, "packing", &b, &ng, err)) return -1;
    char title[160];
    const json_t *sfj = json_object_get(json_object_get(in->summary, "stats"), "solid_fraction");
    if (json_is_object(sfj)) sfj = json_object_get(sfj, "achieved"); /* {"target", "achieved"} */
    double sf = jnum(sfj, NAN);
    if (isfinite(sf))
        snprintf(title, sizeof title, "Packing: %zu grains, solid fraction %.3f", ng, sf);
    else
        snprintf(title, sizeof title, "Packing: %zu grains", ng);
    map_head(g, b, width, title);
    sb_puts(&g->out, "<g class=\"grains\" stroke=\"#222222\" stroke-width=\"0.4\">\n");
    sb_puts(&g->tail, "</g>\n");
    g->by_orient = by_orient;
    g->logscale = g->amax > 10 * g->amin;
    return map_end(g, in, by_orient, g->logscale, by_orient ? "orientation (deg)" : "area (m²)",
                   step_packing, err);
}

/* the cells and their seeds: pass 1 bounds, area range and count; the head; step_cells draws
 * the polygons (section 0), then the seeds (section 1, a second pass), then the tail */
static int step_cells(gp_svg *g)
{
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const svg_item *c = &g->items->cur;
        if (g->section == 0) {
            double a = isnan(c->area) ? g->amin : c->area;
            char col[16];
            ramp(g->amax > g->amin ? (a - g->amin) / (g->amax - g->amin) : 0.5, col, sizeof col);
            for (size_t j = 0, k = 0; j < c->nrings; k += c->rings[j], j++) {
                sb_printf(&g->out, "<polygon fill=\"%s\" points=\"", col);
                ring_points_xy(&g->out, &g->f, c->xy + 2 * k, c->rings[j], g->min_px);
                sb_puts(&g->out, "\"/>\n");
            }
        } else {
            double x = c->seed[0], y = c->seed[1];
            if (!isfinite(x) || !isfinite(y)) continue;
            sb_printf(&g->out, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\"/>\n", fx(&g->f, x),
                      fy(&g->f, y), g->seed_r);
        }
    }
    if (r < 0) return svg_pass_failed(g);
    if (r > 0) return 0;
    if (g->section == 0) {
        sb_puts(&g->out, g->mid.buf ? g->mid.buf : "");
        g->section = 1;
        return svg_pass_begin(g);
    }
    sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

int svg_view_cells(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                   gpd_err *err)
{
    bounds b;
    size_t nc;
    if (map_pass(g, in, GP_SVG_CELLS, "cells", &b, &nc, err)) return -1;
    char title[160];
    snprintf(title, sizeof title, "Voronoi cells: %zu cells and their seeds", nc);
    map_head(g, b, width, title);
    sb_puts(&g->out, "<g class=\"cells\" stroke=\"#333333\" stroke-width=\"0.5\" fill-opacity=\"0.55\">\n");
    sb_puts(&g->mid, "</g>\n<g class=\"seeds\" fill=\"#d62728\">\n");
    sb_puts(&g->tail, "</g>\n");
    g->seed_r = nc > 2000 ? 0.8 : nc > 200 ? 1.5 : 2.5;
    g->section = 0;
    return map_end(g, in, 0, 0, "cell area (m²)", step_cells, err);
}

/* ------------------------------------------------------------------ statistics */

/* the size view as histograms (results without stats.fit) */
static int view_size_hist(gp_svg *g, const gp_svg_input *in, int width, gpd_err *err)
{
    const json_t *res = in->summary;
    const json_t *stats = json_object_get(res, "stats");
    hist h;
    const char *what = "cell area (m²)";
    int have = hist_read(json_object_get(stats, "size_histogram"), &h) == 0;
    if (have) {
        hist gh;
        if (hist_read(json_object_get(stats, "grain_size_histogram"), &gh) == 0) {
            if (gh.k == h.k) {
                h.achieved2 = gh.achieved;
                gh.achieved = NULL;
            }
            hist_free(&gh);
        }
    } else {
        size_t n;
        int failed;
        double *v = svg_collect_items(in, GP_SVG_CELLS, 0, &n, &failed);
        if (!v && !failed) {
            v = svg_collect_items(in, GP_SVG_GRAINS, 0, &n, &failed);
            what = "grain area (m²)";
        }
        if (!v) {
            if (failed) gpd_err_set(err, 500, "cannot read the cells or grains of the result");
            else gpd_err_set(err, 409, "view \"size\" needs stats.size_histogram, cells or grains in the result");
            return -1;
        }
        double lo, hi;
        minmax(v, n, &lo, &hi);
        int ok = hist_from_values(v, n, n < 50 ? 8 : 20, lo, hi, &h) == 0;
        free(v);
        if (!ok) {
            gpd_err_set(err, 500, "out of memory");
            return -1;
        }
    }
    int height = (int)lround(width * 0.62);
    frame f = hist_frame(80, 40, width - 110, height - 110, &h);
    sb *s = &g->out;
    doc_begin(s, width, height, "Size distribution: target vs achieved");
    axes(s, &f, what, "fraction of cells", 1);
    draw_hist(s, &f, &h, "#1f77b4");
    legend_item it[3];
    int n = 0;
    it[n++] = (legend_item){have ? "achieved (cells)" : "achieved", "bar", "#1f77b4"};
    if (h.achieved2) it[n++] = (legend_item){"achieved (grains)", "line", "#ff7f0e"};
    if (h.target) it[n++] = (legend_item){"target (lognormal)", "marker", "#d62728"};
    legend(s, f.x0 + f.w - 190, f.y0 + 8, it, n);
    doc_end(s);
    hist_free(&h);
    return 0;
}

/* stats.fit.<key> with its "cdf" curves; 0 ok */
static int cdf_read(const json_t *fit, const char *key, const char *name, const char *color,
                    cdf_series *c)
{
    memset(c, 0, sizeof *c);
    const json_t *b = json_object_get(fit, key), *cdf = json_object_get(b, "cdf");
    size_t nt, na;
    c->x = jarray(json_object_get(cdf, "x"), &c->n);
    c->target = jarray(json_object_get(cdf, "target"), &nt);
    c->achieved = jarray(json_object_get(cdf, "achieved"), &na);
    if (!c->x || !c->target || !c->achieved || c->n < 2 || nt != c->n || na != c->n) {
        cdf_free(c);
        return -1;
    }
    c->name = name;
    c->color = color;
    c->law = json_string_value(json_object_get(b, "law"));
    c->ks = jnum(json_object_get(b, "ks"), NAN);
    c->ks_critical = jnum(json_object_get(b, "ks_critical"), NAN);
    c->w1 = jnum(json_object_get(b, "w1"), NAN);
    c->cov = jnum(json_object_get(json_object_get(b, "achieved"), "cov"), NAN);
    c->target_cov = jnum(json_object_get(json_object_get(b, "target"), "cov"), NAN);
    return 0;
}

/* "cells: KS 0.021 (5 % critical 0.061), W1 0.012, COV 0.79 (target 0.8)"; 1 when KS is over */
static int fit_line(char *buf, size_t n, const cdf_series *c)
{
    int over = c->ks > c->ks_critical;
    if (!isfinite(c->ks) || !isfinite(c->ks_critical)) {
        snprintf(buf, n, "%s: KS not measured", c->name);
        return 0;
    }
    int k = snprintf(buf, n, "%s: KS %.3g (5 %% critical %.3g)", c->name, c->ks, c->ks_critical);
    if (k > 0 && (size_t)k < n && isfinite(c->w1))
        k += snprintf(buf + k, n - (size_t)k, ", W1 %.3g", c->w1);
    if (k > 0 && (size_t)k < n && isfinite(c->cov) && isfinite(c->target_cov))
        k += snprintf(buf + k, n - (size_t)k, ", COV %.3g (target %.3g)", c->cov, c->target_cov);
    if (k > 0 && (size_t)k < n && over)
        snprintf(buf + k, n - (size_t)k, " -- above its critical value");
    return over;
}

/* Draws (s != NULL) or counts the lines of the result's warnings, wrapped at maxch bytes on
 * spaces (never inside a UTF-8 character), from baseline y, 16 px apart. */
static int warning_lines(sb *s, const json_t *warnings, double x, double y, size_t maxch)
{
    int lines = 0;
    size_t i;
    const json_t *w;
    json_array_foreach(warnings, i, w) {
        const char *t = json_string_value(w);
        for (int first = 1; t && *t; first = 0) {
            size_t len = strlen(t), cut = len;
            if (len > maxch) {
                cut = maxch;
                while (cut > maxch / 2 && t[cut] != ' ') cut--;
                if (t[cut] != ' ') /* no space: cut a long word, at a character's start */
                    for (cut = maxch; cut > 1 && ((unsigned char)t[cut] & 0xC0) == 0x80;) cut--;
            }
            if (s) {
                char line[512];
                snprintf(line, sizeof line, "%s%.*s", first ? "\xe2\x9a\xa0 warning: " : "",
                         (int)(cut < 400 ? cut : 400), t);
                text_at(s, first ? x : x + 18, y + 16 * lines, "start",
                        "class=\"warning\" fill=\"#b35c00\" font-weight=\"bold\"", line);
            }
            lines++;
            t += cut;
            while (*t == ' ') t++;
        }
    }
    return lines;
}

static int view_size_fit(gp_svg *g, const json_t *res, cdf_series *c, int nc, int width)
{
    double lo, hi;
    cdf_range(c, nc, 1, &lo, &hi);
    int xlog = hi > 10 * lo && lo > 0;
    if (!xlog) cdf_range(c, nc, 0, &lo, &hi);
    if (!(hi > lo)) lo = isfinite(lo) ? lo - 0.5 : 0, hi = lo + 1;
    const json_t *warnings = json_object_get(res, "warnings");
    size_t maxch = (size_t)((width - 60) / 8 - 12); /* bold 12 px, after "⚠ warning: " */
    int nwarn = warning_lines(NULL, warnings, 0, 0, maxch);
    int plot_h = (int)lround(width * 0.62);
    int height = plot_h + 10 + 16 * (nc + nwarn);
    frame f = {80, 40, width - 110.0, plot_h - 110.0, lo, hi, 0, 1, xlog};
    sb *s = &g->out;
    doc_begin(s, width, height, "Size distribution: target law vs achieved (CDF)");
    axes(s, &f, xlog ? "area (m², log scale)" : "area (m²)", "cumulative fraction (by number)",
         1);
    legend_item it[4];
    char names[4][64];
    for (int k = 0; k < nc; k++) {
        cdf_path(s, &f, &c[k], 0);
        cdf_path(s, &f, &c[k], 1);
        snprintf(names[2 * k], sizeof names[0], "%s: target (%s)", c[k].name,
                 c[k].law ? c[k].law : "law");
        snprintf(names[2 * k + 1], sizeof names[0], "%s: achieved", c[k].name);
        it[2 * k] = (legend_item){names[2 * k], "dash", c[k].color};
        it[2 * k + 1] = (legend_item){names[2 * k + 1], "line", c[k].color};
    }
    legend(s, f.x0 + 10, f.y0 + 8, it, 2 * nc);
    double y = plot_h + 6;
    for (int k = 0; k < nc; k++, y += 16) {
        char line[256];
        int over = fit_line(line, sizeof line, &c[k]);
        text_at(s, 20, y, "start",
                over ? "class=\"fit ks-over\" fill=\"#d62728\"" : "class=\"fit\"", line);
    }
    warning_lines(s, warnings, 20, y, maxch);
    doc_end(s);
    return 0;
}

/* the size view: CDFs from stats.fit when the result has them, else histograms (results stored
 * before stats.fit, or without it) */
int svg_view_size(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                  gpd_err *err)
{
    const json_t *res = in->summary;
    const json_t *fit = json_object_get(json_object_get(res, "stats"), "fit");
    cdf_series c[2];
    int nc = 0;
    if (cdf_read(fit, "cell_area", "cells", "#1f77b4", &c[nc]) == 0) nc++;
    if (cdf_read(fit, "grain_area", "grains", "#ff7f0e", &c[nc]) == 0) nc++;
    if (!nc) return view_size_hist(g, in, width, err);
    int rc = view_size_fit(g, res, c, nc, width);
    for (int k = 0; k < nc; k++) cdf_free(&c[k]);
    return rc;
}

int svg_view_orientation(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err)
{
    const json_t *res = in->summary;
    hist h;
    int have = hist_read(json_object_get(json_object_get(res, "stats"), "orientation_histogram"), &h) == 0;
    if (!have) {
        size_t n;
        int failed;
        double *v = svg_collect_items(in, GP_SVG_GRAINS, 1, &n, &failed);
        if (!v && !failed) v = svg_collect_items(in, GP_SVG_CELLS, 1, &n, &failed);
        if (!v) {
            if (failed) {
                gpd_err_set(err, 500, "cannot read the grains or cells of the result");
                return -1;
            }
            gpd_err_set(err, 409, "view \"orientation\" needs stats.orientation_histogram, grains or cells in the result");
            return -1;
        }
        int ok = hist_from_values(v, n, 18, -90, 90, &h) == 0;
        free(v);
        if (!ok) {
            gpd_err_set(err, 500, "out of memory");
            return -1;
        }
    }
    int height = (int)lround(width * 0.75);
    double cx = width / 2.0, cy = 40 + (height - 80) / 2.0, R = fmin(width / 2.0 - 60, (height - 100) / 2.0);
    double m = 0;
    for (size_t i = 0; i < h.k; i++) {
        m = fmax(m, h.achieved[i]);
        if (h.target) m = fmax(m, h.target[i]);
    }
    if (!(m > 0)) m = 1;
    double st = nice_step(0, m, 4), rmax = ceil(m / st - 1e-9) * st;
    sb *s = &g->out;
    doc_begin(s, width, height, "Orientation rose: target vs achieved (axial, degrees)");
    /* grid: rings and spokes */
    sb_puts(s, "<g class=\"grid\" fill=\"none\" stroke=\"#cccccc\">\n");
    char lab[64];
    for (double r = st; r <= rmax + st * 1e-9; r += st) {
        double pr = R * r / rmax;
        sb_printf(s, "<path d=\"M%.1f %.1fa%.1f %.1f 0 1 0 %.1f 0a%.1f %.1f 0 1 0 %.1f 0z\"/>\n",
                  cx - pr, cy, pr, pr, 2 * pr, pr, pr, -2 * pr);
    }
    for (int a = 0; a < 360; a += 30) {
        double t = a * M_PI / 180;
        sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", cx, cy,
                  cx + R * cos(t), cy - R * sin(t));
    }
    sb_puts(s, "</g>\n");
    for (double r = st; r <= rmax + st * 1e-9; r += st) {
        fmt_label(lab, sizeof lab, r);
        text_at(s, cx + R * r / rmax * cos(M_PI / 12) + 2, cy - R * r / rmax * sin(M_PI / 12), "start",
                "fill=\"#666666\" font-size=\"10\"", lab);
    }
    for (int a = -90; a <= 90; a += 30) {
        double t = a * M_PI / 180;
        snprintf(lab, sizeof lab, "%d°", a);
        text_at(s, cx + (R + 18) * cos(t), cy - (R + 18) * sin(t) + 4, "middle", NULL, lab);
    }
    /* achieved: wedges for each class and its mirror (axial data) */
    sb_puts(s, "<g class=\"achieved\" fill=\"#1f77b4\" fill-opacity=\"0.6\" stroke=\"#1f77b4\">\n");
    for (size_t i = 0; i < h.k; i++) {
        double pr = R * fmin(h.achieved[i], rmax) / rmax;
        if (!(pr > 0)) continue;
        for (int mirror = 0; mirror < 2; mirror++) {
            double a0 = (h.edges[i] + 180 * mirror) * M_PI / 180, a1 = (h.edges[i + 1] + 180 * mirror) * M_PI / 180;
            sb_printf(s, "<path d=\"M%.1f %.1fL%.1f %.1fA%.1f %.1f 0 0 0 %.1f %.1fz\"/>\n", cx, cy,
                      cx + pr * cos(a0), cy - pr * sin(a0), pr, pr, cx + pr * cos(a1), cy - pr * sin(a1));
        }
    }
    sb_puts(s, "</g>\n");
    if (h.target) {
        sb_puts(s, "<path class=\"target\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" d=\"");
        for (int mirror = 0, first = 1; mirror < 2; mirror++)
            for (size_t i = 0; i < h.k; i++) {
                double a = (0.5 * (h.edges[i] + h.edges[i + 1]) + 180 * mirror) * M_PI / 180;
                double pr = R * fmin(h.target[i], rmax) / rmax;
                sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", cx + pr * cos(a), cy - pr * sin(a));
                first = 0;
            }
        sb_puts(s, "z\"/>\n");
        for (int mirror = 0; mirror < 2; mirror++)
            for (size_t i = 0; i < h.k; i++) {
                double a = (0.5 * (h.edges[i] + h.edges[i + 1]) + 180 * mirror) * M_PI / 180;
                double pr = R * fmin(h.target[i], rmax) / rmax;
                marker(s, cx + pr * cos(a), cy - pr * sin(a), "#d62728");
            }
    }
    legend_item it[2] = {{"achieved (fraction per class)", "bar", "#1f77b4"},
                         {"target", "marker", "#d62728"}};
    legend(s, 10, height - 56, it, h.target ? 2 : 1);
    doc_end(s);
    hist_free(&h);
    return 0;
}

int svg_view_descriptors(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err)
{
    const char *const *names = SVG_DESC_NAME;
    const json_t *d = json_object_get(json_object_get(in->summary, "stats"), "descriptors");
    hist h[4];
    int ok = 1, any = 0;
    for (int k = 0; k < 4; k++) {
        if (hist_read(json_object_get(d, names[k]), &h[k]) == 0) {
            any = 1;
            continue;
        }
        size_t n;
        int failed;
        double *v = svg_collect_items(in, GP_SVG_GRAINS, 2 + k, &n, &failed);
        if (failed) ok = 0;
        if (v) {
            double lo, hi;
            minmax(v, n, &lo, &hi);
            if (k != 3) lo = fmin(lo, 0), hi = fmax(hi, 1); /* ratios in [0, 1] */
            if (hist_from_values(v, n, 20, lo, hi, &h[k]) == 0) any = 1;
            else ok = 0;
            free(v);
        } else {
            memset(&h[k], 0, sizeof h[k]);
        }
    }
    if (!any || !ok) {
        for (int k = 0; k < 4; k++) hist_free(&h[k]);
        if (!ok) gpd_err_set(err, 500, "out of memory or the grains cannot be read");
        else gpd_err_set(err, 409, "view \"descriptors\" needs the descriptors: the spec did not ask for output \"descriptors\"");
        return -1;
    }
    int height = (int)lround(width * 0.75);
    sb *s = &g->out;
    doc_begin(s, width, height, "Shape descriptors of the grains");
    double pw = (width - 40) / 2.0, ph = (height - 50) / 2.0;
    for (int k = 0; k < 4; k++) {
        double ox = 20 + (k % 2) * pw, oy = 40 + (k / 2) * ph;
        if (!h[k].k) {
            text_at(s, ox + pw / 2, oy + ph / 2, "middle", NULL, "(not in the result)");
            continue;
        }
        frame f = hist_frame(ox + 62, oy + 22, pw - 82, ph - 72, &h[k]);
        axes(s, &f, names[k], "fraction of grains", 0);
        draw_hist(s, &f, &h[k], "#2ca02c");
        /* mean marker: a vertical dashed line with its value */
        if (h[k].has_mean && h[k].mean >= f.xmin && h[k].mean <= f.xmax) {
            double x = fx(&f, h[k].mean);
            sb_printf(s, "<line class=\"mean\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#000000\" stroke-width=\"1.5\" stroke-dasharray=\"5 3\"/>\n",
                      x, f.y0, x, f.y0 + f.h);
            char lab[64];
            snprintf(lab, sizeof lab, "mean %.3g", h[k].mean);
            text_at(s, x + 4, f.y0 + 10, "start", "font-size=\"11\"", lab);
        }
        char t[64];
        snprintf(t, sizeof t, "%s", names[k]);
        text_at(s, f.x0 + f.w / 2, oy + 14, "middle", "font-weight=\"bold\"", t);
    }
    doc_end(s);
    for (int k = 0; k < 4; k++) hist_free(&h[k]);
    return 0;
}
