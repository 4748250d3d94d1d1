/* svg_views2d.c -- the map views of the 2D kind (kind_fv2d.c): the packing (grains coloured by
 * area or orientation) and the Voronoi cells with their seeds, read one item at a time in
 * passes (svg_internal.h); beyond INSET_MIN items a detail inset (Mollon & Zhao 2012 Fig. 15a)
 * redraws a window of the map enlarged, from one more pass: no item is kept. The statistics
 * views (size, orientation, descriptors) are in svg_stats2d.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"
#include "svg/svg_views.h"

/* ------------------------------------------------------------------ the container */

/* "x,y x,y ..." of a JSON ring [[x,y],...] (svg_plot_ring_points_xy) */
static size_t ring_points(sb *s, const frame *f, const json_t *ring, double min_px)
{
    svg_item pts = {0};
    size_t w = 0;
    if (svg_items_ring(&pts, ring))
        s->oom = 1;
    else
        w = svg_plot_ring_points_xy(s, f, pts.xy, pts.npts, min_px);
    svg_items_free(&pts);
    return w;
}

/* the container outline (from result.container), as a path */
static void container_outline(sb *s, const frame *f, const json_t *container)
{
    if (!json_is_object(container)) return;
    const json_t *circle = json_object_get(container, "circle");
    if (json_is_object(circle)) {
        const json_t *c = json_object_get(circle, "center");
        double cx = svg_plot_jnum(json_array_get(c, 0), NAN), cy = svg_plot_jnum(json_array_get(c, 1), NAN);
        double r = svg_plot_jnum(json_object_get(circle, "radius"), NAN);
        if (!isfinite(cx) || !isfinite(cy) || !(r > 0)) return;
        double px = svg_plot_fx(f, cx), py = svg_plot_fy(f, cy), pr = svg_plot_fx(f, cx + r) - px;
        svg_plot_sb_printf(s, "<path class=\"container\" d=\"M%.1f %.1fa%.1f %.1f 0 1 0 %.1f 0a%.1f %.1f 0 1 0 %.1f 0z\" "
                     "fill=\"none\" stroke=\"#000000\" stroke-width=\"1.5\"/>\n",
                  px - pr, py, pr, pr, 2 * pr, pr, pr, -2 * pr);
        return;
    }
    const json_t *poly = json_object_get(container, "polygon");
    if (!json_is_array(poly)) return;
    svg_plot_sb_puts(s, "<path class=\"container\" fill=\"none\" stroke=\"#000000\" stroke-width=\"1.5\" d=\"");
    svg_plot_sb_puts(s, "M");
    ring_points(s, f, poly, 0);
    svg_plot_sb_puts(s, "z");
    size_t i;
    const json_t *h;
    json_array_foreach(json_object_get(container, "holes"), i, h) {
        svg_plot_sb_puts(s, " M");
        ring_points(s, f, h, 0);
        svg_plot_sb_puts(s, "z");
    }
    svg_plot_sb_puts(s, "\"/>\n");
}

static void bounds_ring(bounds *b, const json_t *ring)
{
    size_t i;
    const json_t *p;
    json_array_foreach(ring, i, p) {
        svg_plot_bounds_add(b, svg_plot_jnum(json_array_get(p, 0), NAN), svg_plot_jnum(json_array_get(p, 1), NAN));
    }
}

static void container_bounds(bounds *b, const json_t *container)
{
    if (!json_is_object(container)) return;
    const json_t *circle = json_object_get(container, "circle");
    if (circle) {
        const json_t *c = json_object_get(circle, "center");
        double cx = svg_plot_jnum(json_array_get(c, 0), NAN), cy = svg_plot_jnum(json_array_get(c, 1), NAN);
        double r = svg_plot_jnum(json_object_get(circle, "radius"), NAN);
        svg_plot_bounds_add(b, cx - r, cy - r);
        svg_plot_bounds_add(b, cx + r, cy + r);
        return;
    }
    bounds_ring(b, json_object_get(container, "polygon"));
}

/* ------------------------------------------------------------------ the inset's window */

/* the grid cell of a point, -1 outside the grid */
static int grid_cell(const svg_inset *in, double x, double y, int *i, int *j)
{
    const bounds *b = &in->gb;
    double u = (x - b->xmin) / (b->xmax - b->xmin), v = (y - b->ymin) / (b->ymax - b->ymin);
    if (!(u >= 0 && u <= 1 && v >= 0 && v <= 1)) return -1;
    *i = u >= 1 ? INSET_GRID - 1 : (int)(u * INSET_GRID);
    *j = v >= 1 ? INSET_GRID - 1 : (int)(v * INSET_GRID);
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* the items the grid puts in the window centred on (cx, cy) of side w: each grid cell's count
 * by the fraction of it the window covers */
static double grid_count(const svg_inset *in, double cx, double cy, double w)
{
    const bounds *b = &in->gb;
    double gw = (b->xmax - b->xmin) / INSET_GRID, gh = (b->ymax - b->ymin) / INSET_GRID, c = 0;
    for (int i = 0; i < INSET_GRID; i++)
        for (int j = 0; j < INSET_GRID; j++) {
            if (!in->grid[i][j]) continue;
            double x0 = b->xmin + i * gw, y0 = b->ymin + j * gh;
            double ox = fmin(x0 + gw, cx + w / 2) - fmax(x0, cx - w / 2);
            double oy = fmin(y0 + gh, cy + w / 2) - fmax(y0, cy - w / 2);
            if (ox > 0 && oy > 0) c += in->grid[i][j] * ox * oy / (gw * gh);
        }
    return c;
}

/* The window of the inset: a square sized for INSET_TARGET of the n items of b at their mean
 * density, placed on a 17 x 17 lattice of positions: among those the grid counts as full as
 * most (90 % of the 75th percentile of their counts: not a hole, nor a sparse corner of the
 * container -- and not the single fullest, which on a uniform packing is the grid's noise),
 * the nearest to the centre. Deterministic; central on a uniform packing. */
static void inset_window(svg_inset *in, bounds b, size_t n)
{
    enum { NC = 17 };
    double bw = b.xmax - b.xmin, bh = b.ymax - b.ymin;
    double w = fmin(sqrt(INSET_TARGET * bw * bh / (double)n), fmin(bw, bh));
    double cx = (b.xmin + b.xmax) / 2, cy = (b.ymin + b.ymax) / 2, bx = cx, by = cy;
    if (in->grid_on) {
        double cnt[NC * NC], sorted[NC * NC], bestd = INFINITY;
        for (int i = 0; i < NC * NC; i++) {
            double x = b.xmin + w / 2 + (bw - w) * (i % NC) / (NC - 1);
            double y = b.ymin + w / 2 + (bh - w) * (i / NC) / (NC - 1);
            sorted[i] = cnt[i] = grid_count(in, x, y, w);
        }
        qsort(sorted, NC * NC, sizeof *sorted, cmp_double);
        double full = 0.9 * sorted[(NC * NC * 3) / 4];
        for (int i = 0; i < NC * NC; i++) {
            double x = b.xmin + w / 2 + (bw - w) * (i % NC) / (NC - 1);
            double y = b.ymin + w / 2 + (bh - w) * (i / NC) / (NC - 1);
            if (cnt[i] >= full && cnt[i] > 0 && hypot(x - cx, y - cy) < bestd)
                bestd = hypot(x - cx, y - cy), bx = x, by = y;
        }
    }
    in->x0 = bx - w / 2, in->x1 = bx + w / 2;
    in->y0 = by - w / 2, in->y1 = by + w / 2;
}

/* 1 when the bounding box of the item's points meets the window */
static int in_window(const svg_inset *in, const svg_item *c)
{
    bounds ib;
    svg_plot_bounds_init(&ib);
    svg_plot_bounds_xy(&ib, c->xy, c->npts);
    return svg_plot_bounds_ok(&ib) && ib.xmax >= in->x0 && ib.xmin <= in->x1 && ib.ymax >= in->y0 &&
           ib.ymin <= in->y1;
}

/* ------------------------------------------------------------------ maps: packing, cells */

/* The first pass over the items of part (opened for view): the bounds of the items and of the
 * container, the items' count and area range (g->amin, g->amax; 1 when none is positive), and
 * the density grid of the inset over the container's bounds. */
static int map_pass(gp_svg *g, const gp_svg_input *in, gp_svg_part part, const char *view,
                    bounds *b, size_t *n, gpd_err *err)
{
    if (svg_open_part(g, in, part, view, err)) return -1;
    svg_inset *ins = &g->inset;
    svg_plot_bounds_init(b);
    container_bounds(b, json_object_get(in->summary, "container"));
    ins->gb = *b;
    ins->grid_on = svg_plot_bounds_ok(b) && b->xmax > b->xmin && b->ymax > b->ymin;
    double amin = INFINITY, amax = -INFINITY;
    *n = 0;
    int r = svg_pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const svg_item *c = &g->items->cur;
            bounds ib;
            svg_plot_bounds_init(&ib);
            svg_plot_bounds_xy(&ib, c->xy, c->npts);
            (*n)++;
            if (svg_plot_bounds_ok(&ib)) {
                svg_plot_bounds_add(b, ib.xmin, ib.ymin);
                svg_plot_bounds_add(b, ib.xmax, ib.ymax);
                int i, j;
                if (ins->grid_on &&
                    grid_cell(ins, (ib.xmin + ib.xmax) / 2, (ib.ymin + ib.ymax) / 2, &i, &j) == 0)
                    ins->grid[i][j]++;
            }
            if (c->area > 0) amin = fmin(amin, c->area), amax = fmax(amax, c->area);
        }
    if (r < 0) return svg_part_error(err, part);
    if (!svg_plot_bounds_ok(b)) b->xmin = b->ymin = 0, b->xmax = b->ymax = 1;
    if (!(amax >= amin)) amin = amax = 1;
    g->amin = amin;
    g->amax = amax;
    g->min_px = *n > 2000 ? 0.6 : 0.3;
    return 0;
}

/* The head of a map of b: its frame (g->f), the document with its title and axes in metres.
 * A map of more than INSET_MIN items is drawn in the left half, its detail inset (g->inset)
 * in the right half, at a default width of 1200 px instead of 800. */
static void map_head(gp_svg *g, bounds b, size_t n, const gp_svg_options *opt, int width,
                     const char *title)
{
    int height;
    svg_inset *ins = &g->inset;
    ins->on = n > INSET_MIN;
    if (!ins->on) {
        g->f = svg_plot_map_frame(b, width, &height);
    } else {
        if (!opt || opt->width <= 0) width = 1200;
        double pw = (width - 80 - 130 - 50) / 2.0;
        inset_window(ins, b, n);
        g->f = svg_plot_map_frame_in(b, 80, 60, pw, 2 * pw);
        bounds wb = {ins->x0, ins->x1, ins->y0, ins->y1};
        ins->f = svg_plot_map_frame_in(wb, 80 + pw + 50, 60, pw, pw);
        height = (int)ceil(fmax(g->f.h, ins->f.h) + 60 + 60);
    }
    svg_plot_doc_begin(&g->out, width, height, title);
    svg_plot_axes(&g->out, &g->f, "x (m)", "y (m)", 0);
}

/* the colour of a grain or cell of area a: the ramp over g->amin..g->amax (log when
 * g->logscale) */
static void area_color(const gp_svg *g, double a, char *col, size_t n)
{
    double t = 0.5;
    if (isnan(a)) a = g->amin;
    if (g->amax > g->amin)
        t = g->logscale ? log(a / g->amin) / log(g->amax / g->amin)
                        : (a - g->amin) / (g->amax - g->amin);
    svg_plot_ramp(t, col, n);
}

/* the end of a map: the container's outline and a colour bar (cyc: orientations, else the
 * areas g->amin..g->amax, in the unit svg_plot_area_unit picks) into the tail; then the drawing pass
 * begins, by step */
static int map_end(gp_svg *g, const gp_svg_input *in, int cyc, const char *what,
                   int (*step)(gp_svg *g), gpd_err *err)
{
    const frame *f = &g->f, *fr = g->inset.on ? &g->inset.f : &g->f;
    container_outline(&g->tail, f, json_object_get(in->summary, "container"));
    double cbx = fr->x0 + fr->w + 20, cbh = fmin(fmax(f->h, fr->h) - 30, 300);
    if (cyc) {
        svg_plot_colorbar(&g->tail, cbx, f->y0 + 24, cbh, -90, 90, 1, 0, what);
    } else {
        double k;
        char label[96];
        const char *unit = svg_plot_area_unit(g->amax, &k);
        snprintf(label, sizeof label, "%s (%s)", what, unit);
        svg_plot_colorbar(&g->tail, cbx, f->y0 + 24, cbh, g->amin * k, g->amax * k, 0, g->logscale, label);
    }
    svg_plot_doc_end(&g->tail);
    return svg_start_steps(g, step, err);
}

/* ---- the inset's drawing: a third pass over the items (map_inset_*), bounded memory ---- */

/* the window's frame on the map, lines to the inset, and the inset's clipped group (with
 * attrs: the map's own look) */
static void inset_open(gp_svg *g, const char *attrs)
{
    const svg_inset *in = &g->inset;
    sb *s = &g->out;
    const frame *f = &g->f, *fi = &in->f;
    double x0 = svg_plot_fx(f, in->x0), x1 = svg_plot_fx(f, in->x1), y0 = svg_plot_fy(f, in->y1), y1 = svg_plot_fy(f, in->y0);
    svg_plot_sb_printf(s, "<path class=\"inset-link\" fill=\"none\" stroke=\"#888888\" stroke-dasharray=\"3 3\" "
                 "d=\"M%.1f %.1fL%.1f %.1fM%.1f %.1fL%.1f %.1f\"/>\n",
              x1, y0, fi->x0, fi->y0, x1, y1, fi->x0, fi->y0 + fi->h);
    svg_plot_sb_printf(s, "<rect class=\"inset-window\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                 "fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\"/>\n",
              x0, y0, x1 - x0, y1 - y0);
    svg_plot_sb_printf(s, "<g class=\"inset\">\n<desc>detail window: x from %.9g to %.9g m, y from %.9g to %.9g m</desc>\n",
              in->x0, in->x1, in->y0, in->y1);
    svg_plot_sb_printf(s, "<defs><clipPath id=\"inset-clip\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" "
                 "height=\"%.1f\"/></clipPath></defs>\n",
              fi->x0, fi->y0, fi->w, fi->h);
    svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#ffffff\"/>\n",
              fi->x0, fi->y0, fi->w, fi->h);
    svg_plot_sb_printf(s, "<g clip-path=\"url(#inset-clip)\" stroke=\"#222222\" stroke-width=\"0.8\"%s>\n", attrs);
}

/* a scale bar of a round length, about a quarter of the inset wide, at its lower left */
static void scale_bar(sb *s, const frame *fi)
{
    double span = fi->xmax - fi->xmin, len = pow(10, floor(log10(span / 4)));
    if (len * 5 <= span / 4) len *= 5;
    else if (len * 2 <= span / 4) len *= 2;
    double px = len / span * fi->w, x = fi->x0 + 12, y = fi->y0 + fi->h - 14;
    char lab[64];
    if (len >= 1) snprintf(lab, sizeof lab, "%g m", len);
    else snprintf(lab, sizeof lab, "%g mm", len * 1e3);
    svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"24\" fill=\"#ffffff\" fill-opacity=\"0.85\"/>\n",
              x - 6, y - 18, fmax(px, svg_plot_text_w(lab)) + 12);
    svg_plot_sb_printf(s, "<path class=\"scale-bar\" d=\"M%.1f %.1fh%.1f\" stroke=\"#000000\" stroke-width=\"3\"/>\n",
              x, y, px);
    svg_plot_text_at(s, x + px / 2, y - 6, "middle", "font-size=\"11\"", lab);
}

/* after the inset's pass: its frame, scale bar and caption (with the count now known) */
static void inset_close(gp_svg *g, const char *what)
{
    const svg_inset *in = &g->inset;
    const frame *fi = &in->f;
    sb *s = &g->out;
    svg_plot_sb_puts(s, "</g>\n");
    svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
                 "stroke=\"#d62728\" stroke-width=\"2\"/>\n",
              fi->x0, fi->y0, fi->w, fi->h);
    scale_bar(s, fi);
    char cap[200];
    double zoom = (fi->w / (fi->xmax - fi->xmin)) / (g->f.w / (g->f.xmax - g->f.xmin));
    snprintf(cap, sizeof cap, "Detail (\xc3\x97%.3g): %zu %s in the red square", zoom, in->n, what);
    svg_plot_text_at(s, fi->x0 + fi->w / 2, fi->y0 - 8, "middle", "class=\"inset-caption\"", cap);
    svg_plot_sb_puts(s, "</g>\n");
}

/* one item's ring as a path in the inset (paths, not polygons: a picture's <polygon>s are its
 * items, each once) */
static void inset_ring(gp_svg *g, const double *xy, size_t n, const char *col)
{
    svg_plot_sb_printf(&g->out, "<path fill=\"%s\" d=\"M", col);
    svg_plot_ring_points_xy(&g->out, &g->inset.f, xy, n, 0.3);
    svg_plot_sb_puts(&g->out, "z\"/>\n");
}

/* Keeps a ring of n points (n = 0: a seed, the one point at xy) of an item in the window for
 * the inset; past INSET_KEEP points, or out of memory, the inset is left to a pass (full). */
static void inset_keep(svg_inset *in, const double *xy, size_t n, const char *col)
{
    size_t np = n ? n : 1;
    if (in->full || in->kpts + np > INSET_KEEP) {
        in->full = 1;
        return;
    }
    if (in->kpts + np > in->kcap) {
        size_t cap = in->kcap ? in->kcap : 4096;
        while (cap < in->kpts + np) cap *= 2;
        double *q = realloc(in->kxy, 2 * cap * sizeof *q);
        if (!q) {
            in->full = 1;
            return;
        }
        in->kxy = q, in->kcap = cap;
    }
    if (in->nkept == in->kept_cap) {
        size_t cap = in->kept_cap ? 2 * in->kept_cap : 64;
        svg_kept *k = realloc(in->kept, cap * sizeof *k);
        if (!k) {
            in->full = 1;
            return;
        }
        in->kept = k, in->kept_cap = cap;
    }
    memcpy(in->kxy + 2 * in->kpts, xy, 2 * np * sizeof *xy);
    svg_kept *k = &in->kept[in->nkept++];
    k->first = in->kpts, k->n = n;
    snprintf(k->col, sizeof k->col, "%s", col);
    in->kpts += np;
}

static void inset_seed(gp_svg *g, double x, double y);

/* the inset from the kept items, a step at a time: 0 more, 1 drawn */
static int inset_from_kept(gp_svg *g)
{
    svg_inset *in = &g->inset;
    size_t start = g->out.len;
    while (g->out.len - start < STEP_BYTES && in->next < in->nkept) {
        const svg_kept *k = &in->kept[in->next++];
        if (k->n) inset_ring(g, in->kxy + 2 * k->first, k->n, k->col);
        else inset_seed(g, in->kxy[2 * k->first], in->kxy[2 * k->first + 1]);
    }
    return in->next >= in->nkept;
}

/* the end of the map's drawing pass: the inset from its kept items (section 3) or, when they
 * did not all fit, from a pass of its own (section 2); attrs: inset_open's */
static int inset_begin(gp_svg *g, const char *attrs)
{
    inset_open(g, attrs);
    if (!g->inset.full) {
        g->section = 3;
        return 0;
    }
    g->inset.n = 0;
    g->section = 2;
    return svg_pass_begin(g);
}

/* the last section of a map: the inset drawn from what was kept, then the tail (1 when done,
 * 0 while the inset still draws) */
static int finish_inset(gp_svg *g, const char *what)
{
    if (!inset_from_kept(g)) return 0;
    inset_close(g, what);
    svg_plot_sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

/* the packing: grains coloured by area or orientation. Pass 1: bounds, area range, count;
 * then the head; step_packing draws the grains (section 0), the inset (section 2, a pass of
 * its own) and stages the tail. */
static int step_packing(gp_svg *g)
{
    if (g->section == 3) return finish_inset(g, "grains");
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const svg_item *c = &g->items->cur;
        char col[16];
        if (g->by_orient) svg_plot_cyclic(isnan(c->orientation_deg) ? 0 : c->orientation_deg, col, sizeof col);
        else area_color(g, c->area, col, sizeof col);
        int in = g->inset.on && in_window(&g->inset, c);
        if (g->section == 2) {
            if (in) g->inset.n++, inset_ring(g, c->xy, c->npts, col);
            continue;
        }
        svg_plot_sb_printf(&g->out, "<polygon fill=\"%s\" points=\"", col);
        svg_plot_ring_points_xy(&g->out, &g->f, c->xy, c->npts, g->min_px);
        svg_plot_sb_puts(&g->out, "\"/>\n");
        if (in) g->inset.n++, inset_keep(&g->inset, c->xy, c->npts, col);
    }
    if (r < 0) return svg_pass_failed(g);
    if (r > 0) return 0;
    if (g->section == 0) svg_plot_sb_puts(&g->out, "</g>\n");
    if (g->section == 0 && g->inset.on) return inset_begin(g, "");
    if (g->section == 2) inset_close(g, "grains");
    svg_plot_sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

int svg_views2d_packing(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
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
    double sf = svg_plot_jnum(sfj, NAN);
    if (isfinite(sf))
        snprintf(title, sizeof title, "Packing: %zu grains, solid fraction %.3f", ng, sf);
    else
        snprintf(title, sizeof title, "Packing: %zu grains", ng);
    map_head(g, b, ng, opt, width, title);
    svg_plot_sb_puts(&g->out, "<g class=\"grains\" stroke=\"#222222\" stroke-width=\"0.4\">\n");
    g->by_orient = by_orient;
    g->logscale = g->amax > 10 * g->amin;
    g->section = 0;
    return map_end(g, in, by_orient, by_orient ? "orientation (deg)" : "grain area", step_packing,
                   err);
}

/* a cell's colour: the ramp over the areas */
static void cell_color(const gp_svg *g, const svg_item *c, char *col, size_t n)
{
    double a = isnan(c->area) ? g->amin : c->area;
    svg_plot_ramp(g->amax > g->amin ? (a - g->amin) / (g->amax - g->amin) : 0.5, col, n);
}

/* a cell's parts in the map, or (inset) in the inset; keep: kept for the inset too */
static void cell_rings(gp_svg *g, const svg_item *c, int inset, int keep)
{
    char col[16];
    cell_color(g, c, col, sizeof col);
    for (size_t j = 0, k = 0; j < c->nrings; k += c->rings[j], j++) {
        if (keep) inset_keep(&g->inset, c->xy + 2 * k, c->rings[j], col);
        if (inset) {
            inset_ring(g, c->xy + 2 * k, c->rings[j], col);
            continue;
        }
        svg_plot_sb_printf(&g->out, "<polygon fill=\"%s\" points=\"", col);
        svg_plot_ring_points_xy(&g->out, &g->f, c->xy + 2 * k, c->rings[j], g->min_px);
        svg_plot_sb_puts(&g->out, "\"/>\n");
    }
}

/* a seed in the inset: a small square path (the picture's circles are the seeds, each once) */
static void inset_seed(gp_svg *g, double x, double y)
{
    svg_plot_sb_printf(&g->out, "<path fill=\"#d62728\" fill-opacity=\"1\" stroke=\"none\" d=\"M%.1f %.1fh4v4h-4z\"/>\n",
              svg_plot_fx(&g->inset.f, x) - 2, svg_plot_fy(&g->inset.f, y) - 2);
}

/* a cell's seed on the map, or (inset) in the inset */
static void cell_seed(gp_svg *g, const svg_item *c, int inset)
{
    double x = c->seed[0], y = c->seed[1];
    if (!isfinite(x) || !isfinite(y)) return;
    if (inset) inset_seed(g, x, y);
    else svg_plot_sb_printf(&g->out, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\"/>\n", svg_plot_fx(&g->f, x),
                   svg_plot_fy(&g->f, y), g->seed_r);
}

/* the cells and their seeds: pass 1 bounds, area range and count; the head; step_cells draws
 * the polygons (section 0, keeping those in the window), then the seeds (section 1, a second
 * pass), the inset (section 3 from what was kept, or section 2, a third pass), then the tail */
static int step_cells(gp_svg *g)
{
    if (g->section == 3) return finish_inset(g, "cells");
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const svg_item *c = &g->items->cur;
        if (g->section == 1) {
            cell_seed(g, c, 0);
            continue;
        }
        int in = g->inset.on && in_window(&g->inset, c);
        if (g->section == 0) {
            cell_rings(g, c, 0, in);
            if (in && isfinite(c->seed[0]) && isfinite(c->seed[1]))
                inset_keep(&g->inset, c->seed, 0, "");
        } else if (in) {
            cell_rings(g, c, 1, 0);
            cell_seed(g, c, 1);
        }
        g->inset.n += in;
    }
    if (r < 0) return svg_pass_failed(g);
    if (r > 0) return 0;
    if (g->section == 0) {
        svg_plot_sb_puts(&g->out, g->mid.buf ? g->mid.buf : "");
        g->section = 1;
        return svg_pass_begin(g);
    }
    if (g->section == 1) svg_plot_sb_puts(&g->out, "</g>\n"); /* the seeds' */
    if (g->section == 1 && g->inset.on) return inset_begin(g, " fill-opacity=\"0.55\"");
    if (g->section == 2) inset_close(g, "cells");
    svg_plot_sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

int svg_views2d_cells(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                   gpd_err *err)
{
    bounds b;
    size_t nc;
    if (map_pass(g, in, GP_SVG_CELLS, "cells", &b, &nc, err)) return -1;
    char title[160];
    snprintf(title, sizeof title, "Voronoi cells: %zu cells and their seeds", nc);
    map_head(g, b, nc, opt, width, title);
    svg_plot_sb_puts(&g->out, "<g class=\"cells\" stroke=\"#333333\" stroke-width=\"0.5\" fill-opacity=\"0.55\">\n");
    svg_plot_sb_puts(&g->mid, "</g>\n<g class=\"seeds\" fill=\"#d62728\">\n");
    g->seed_r = nc > 2000 ? 0.8 : nc > 200 ? 1.5 : 2.5;
    g->section = 0;
    g->logscale = 0;
    return map_end(g, in, 0, "cell area", step_cells, err);
}
