/* svg_geostatic.c -- the SVG views of a geostatic-3d result (see svg_geostatic.h). */
#include "kinds/geostatic-3d/svg_geostatic.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"
#include "svg/svg_views.h"

#define SIGMA "\xcf\x83"
#define PHI "\xcf\x86"
#define GAMMA "\xce\xb3"
#define PRIME "\xe2\x80\xb2"
#define MINUS "\xe2\x88\x92"
#define PM "\xc2\xb1"
#define DEG "\xc2\xb0"

#define C_V "#1f77b4"  /* sigma_v */
#define C_H1 "#d62728" /* the first horizontal stress */
#define C_H2 "#2ca02c" /* the second */
#define C_W "#000000"  /* the weight above */
#define C_K0 "#7f7f7f" /* K0 sigma_v, the theory */

/* ------------------------------------------------------------------ reading the summary */

/* the profile's arrays (malloc'ed, n each) */
typedef struct profile {
    size_t n;
    double *depth, *sv, *sh1, *sh2, *weight, *k0;
    int *k0_counted;
    int v;                      /* the vertical axis (0..2) */
    double theory, mean, sd;    /* K0 */
    double max_error;           /* the equilibrium's */
} profile;

static void profile_free(profile *p)
{
    free(p->depth), free(p->sv), free(p->sh1), free(p->sh2), free(p->weight), free(p->k0);
    free(p->k0_counted);
}

/* the vertical axis of the result ("vertical"), z when absent */
static int vertical_of(const json_t *res)
{
    const char *v = json_string_value(json_object_get(res, "vertical"));
    return v && (v[0] == 'x' || v[0] == 'y') && !v[1] ? v[0] - 'x' : 2;
}

static double *column(const json_t *pr, const char *name, size_t n)
{
    size_t m = 0;
    double *a = svg_plot_jarray(json_object_get(pr, name), &m);
    if (a && m == n) return a;
    free(a);
    return NULL;
}

/* 0, or -1 when the result has no profile */
static int profile_read(const json_t *res, profile *p)
{
    static const char *const sig[3] = {"sigma_xx_kpa", "sigma_yy_kpa", "sigma_zz_kpa"};
    memset(p, 0, sizeof *p);
    const json_t *pr = json_object_get(res, "profile");
    p->n = json_array_size(json_object_get(pr, "depth"));
    if (!p->n) return -1;
    p->v = vertical_of(res);
    int h1 = p->v == 0 ? 1 : 0, h2 = p->v == 2 ? 1 : 2;
    p->depth = column(pr, "depth", p->n);
    p->sv = column(pr, sig[p->v], p->n);
    p->sh1 = column(pr, sig[h1], p->n);
    p->sh2 = column(pr, sig[h2], p->n);
    p->weight = column(pr, "weight_kpa", p->n);
    p->k0 = column(pr, "k0", p->n);
    p->k0_counted = calloc(p->n, sizeof *p->k0_counted);
    const json_t *kc = json_object_get(pr, "k0_counted");
    for (size_t i = 0; p->k0_counted && i < p->n; i++)
        p->k0_counted[i] = json_is_true(json_array_get(kc, i));
    const json_t *st = json_object_get(res, "stats"), *k0 = json_object_get(st, "k0");
    p->theory = svg_plot_jnum(json_object_get(k0, "theory"), NAN);
    p->mean = svg_plot_jnum(json_object_get(k0, "mean"), NAN);
    p->sd = svg_plot_jnum(json_object_get(k0, "sd"), NAN);
    p->max_error = svg_plot_jnum(
        json_object_get(json_object_get(st, "equilibrium"), "max_error"), NAN);
    if (p->depth && p->sv && p->sh1 && p->sh2 && p->weight && p->k0 && p->k0_counted) return 0;
    profile_free(p);
    return -1;
}

static int no_profile(const char *view, gpd_err *err)
{
    gpd_err_set(err, 409, "view \"%s\" needs the profile: submit the spec again with "
                          "\"profile\" in outputs", view);
    return -1;
}

/* "K0 0.667 +- 0.112 over 6 slabs (1 - sin phi' = 0.598, phi' 23.7 deg); ..." */
static void k0_line(const json_t *res, const profile *p, char *buf, size_t n)
{
    double phi = svg_plot_jnum(json_object_get(res, "phi_deg"), NAN);
    snprintf(buf, n, "K0 = %.3f " PM " %.3f (1 " MINUS " sin " PHI PRIME " = %.3f, " PHI PRIME
             " = %.1f" DEG "); " SIGMA "v within %.2g %% of the weight above", p->mean, p->sd,
             p->theory, phi, 100 * p->max_error);
}

/* ------------------------------------------------------------------ drawing */

/* a polyline of (x[i], depth[i]) in f, its non-finite points left out; dashed when dash */
static void depth_path(sb *s, const frame *f, const double *x, const double *depth, size_t n,
                       const char *color, int dash)
{
    svg_plot_sb_printf(s, "<path class=\"curve\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s"
                          " d=\"", color, dash ? " stroke-dasharray=\"7 4\"" : "");
    int first = 1;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i]) || !isfinite(depth[i])) continue;
        svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", svg_plot_fx(f, x[i]),
                           svg_plot_fy(f, depth[i]));
        first = 0;
    }
    svg_plot_sb_puts(s, "\"/>\n");
}

static void depth_markers(sb *s, const frame *f, const double *x, const double *depth, size_t n,
                          const char *color)
{
    for (size_t i = 0; i < n; i++)
        if (isfinite(x[i]) && isfinite(depth[i]))
            svg_plot_marker(s, svg_plot_fx(f, x[i]), svg_plot_fy(f, depth[i]), color);
}

/* the depth of the box's bottom: the last slab's mid-plane plus half a slab */
static double bottom_depth(const profile *p)
{
    double d = p->depth[p->n - 1];
    double half = p->n > 1 ? 0.5 * (p->depth[1] - p->depth[0]) : d;
    return d + half;
}

/* ------------------------------------------------------------------ profile */

int svg_geostatic_profile(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                          int width, gpd_err *err)
{
    profile p;
    if (profile_read(in->summary, &p)) return no_profile("profile", err);
    double *k0w = malloc(p.n * sizeof *k0w);
    if (!k0w) {
        profile_free(&p);
        gpd_err_set(err, 500, "out of memory");
        return -1;
    }
    double xmax = 0;
    for (size_t i = 0; i < p.n; i++) {
        k0w[i] = p.theory * p.weight[i];
        double m = fmax(fmax(p.sv[i], p.weight[i]), fmax(p.sh1[i], p.sh2[i]));
        if (isfinite(m)) xmax = fmax(xmax, m);
    }
    double w = width - 110.0, h = round(width * 0.75);
    frame f = {80, 70, w, h, 0, xmax > 0 ? 1.05 * xmax : 1, bottom_depth(&p), 0, 0};
    static const char *const hname[3][2] = {{SIGMA "yy", SIGMA "zz"}, {SIGMA "xx", SIGMA "zz"},
                                            {SIGMA "xx", SIGMA "yy"}};
    static const char *const vname[3] = {SIGMA "xx", SIGMA "yy", SIGMA "zz"};
    sb *s = &g->out;
    char line[300], lv[64], lh1[64], lh2[64];
    svg_plot_doc_begin(s, width, (int)(f.y0 + h + 60), "Geostatic stresses against depth");
    k0_line(in->summary, &p, line, sizeof line);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", line);
    svg_plot_axes(s, &f, "stress (kPa)", "depth below the top of the box (m)", 1);
    depth_path(s, &f, p.weight, p.depth, p.n, C_W, 1);
    depth_path(s, &f, k0w, p.depth, p.n, C_K0, 1);
    const double *cur[3] = {p.sv, p.sh1, p.sh2};
    const char *col[3] = {C_V, C_H1, C_H2};
    for (int c = 0; c < 3; c++) {
        depth_path(s, &f, cur[c], p.depth, p.n, col[c], 0);
        depth_markers(s, &f, cur[c], p.depth, p.n, col[c]);
    }
    snprintf(lv, sizeof lv, "%s (vertical)", vname[p.v]);
    snprintf(lh1, sizeof lh1, "%s", hname[p.v][0]);
    snprintf(lh2, sizeof lh2, "%s", hname[p.v][1]);
    legend_item it[5] = {{lv, "marker", C_V}, {lh1, "marker", C_H1}, {lh2, "marker", C_H2},
                         {GAMMA "z: the weight above / area", "dash", C_W},
                         {"K0 " GAMMA "z, K0 = 1 " MINUS " sin " PHI PRIME, "dash", C_K0}};
    /* top right: the stresses grow with depth, so the curves keep to the left up there */
    svg_plot_legend(s, f.x0 + f.w - svg_plot_legend_w(it, 5) - 10, f.y0 + 8, it, 5);
    svg_plot_doc_end(s);
    free(k0w);
    profile_free(&p);
    return 0;
}

/* ------------------------------------------------------------------ k0 */

/* a vertical line at x over f, dashed */
static void x_line(sb *s, const frame *f, double x, const char *color, const char *dash)
{
    if (!isfinite(x)) return;
    svg_plot_sb_printf(s, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" "
                          "stroke-dasharray=\"%s\" d=\"M%.1f %.1fV%.1f\"/>\n", color, dash,
                       svg_plot_fx(f, x), f->y0, f->y0 + f->h);
}

int svg_geostatic_k0(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err)
{
    profile p;
    if (profile_read(in->summary, &p)) return no_profile("k0", err);
    double xmax = fmax(1, 1.1 * p.theory);
    for (size_t i = 0; i < p.n; i++)
        if (isfinite(p.k0[i]) && p.k0[i] < 5) xmax = fmax(xmax, 1.05 * p.k0[i]);
    double w = width - 110.0, h = round(width * 0.75);
    frame f = {80, 70, w, h, 0, xmax, bottom_depth(&p), 0, 0};
    sb *s = &g->out;
    char line[300];
    svg_plot_doc_begin(s, width, (int)(f.y0 + h + 60), "K0 = " SIGMA "h / " SIGMA "v against "
                                                       "depth");
    k0_line(in->summary, &p, line, sizeof line);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", line);
    svg_plot_axes(s, &f, "K0 = " SIGMA "h / " SIGMA "v", "depth below the top of the box (m)", 1);
    x_line(s, &f, p.theory, C_W, "7 4");
    x_line(s, &f, p.mean, C_V, "2 3");
    depth_path(s, &f, p.k0, p.depth, p.n, C_V, 0);
    for (size_t i = 0; i < p.n; i++)
        if (isfinite(p.k0[i]) && p.k0[i] <= xmax)
            svg_plot_marker(s, svg_plot_fx(&f, p.k0[i]), svg_plot_fy(&f, p.depth[i]),
                            p.k0_counted[i] ? C_V : "#bbbbbb");
    legend_item it[4] = {{"K0 of a slab (its core)", "marker", C_V},
                         {"left out of the mean (top, bottom)", "marker", "#bbbbbb"},
                         {"mean K0", "dash", C_V},
                         {"1 " MINUS " sin " PHI PRIME " (Jaky)", "dash", C_W}};
    svg_plot_legend(s, f.x0 + f.w - svg_plot_legend_w(it, 4) - 10, f.y0 + f.h - 14 - 18.0 * 4,
                    it, 4);
    svg_plot_doc_end(s);
    profile_free(&p);
    return 0;
}

/* ------------------------------------------------------------------ stress-map */

/* the map of the result: its cells (row-major from the top), sizes, tiles */
typedef struct smap {
    size_t nx, nz;
    double dx, dz, tile_h, tile_v;
    double *sv;                 /* nz x nx, kPa */
    char h, v;                  /* the axes' names */
} smap;

static int smap_read(const json_t *res, smap *m)
{
    memset(m, 0, sizeof *m);
    const json_t *o = json_object_get(res, "map"), *rows = json_object_get(o, "sigma_v_kpa");
    m->nx = (size_t)svg_plot_jnum(json_object_get(o, "nx"), 0);
    m->nz = (size_t)svg_plot_jnum(json_object_get(o, "nz"), 0);
    m->dx = svg_plot_jnum(json_object_get(o, "dx"), NAN);
    m->dz = svg_plot_jnum(json_object_get(o, "dz"), NAN);
    const json_t *tile = json_object_get(o, "tile");
    m->tile_h = svg_plot_jnum(json_array_get(tile, 0), NAN);
    m->tile_v = svg_plot_jnum(json_array_get(tile, 1), NAN);
    const char *hs = json_string_value(json_object_get(o, "horizontal"));
    const char *vs = json_string_value(json_object_get(o, "vertical"));
    m->h = hs ? hs[0] : 'x';
    m->v = vs ? vs[0] : 'z';
    if (!m->nx || !m->nz || json_array_size(rows) != m->nz || !(m->dx > 0) || !(m->dz > 0))
        return -1;
    m->sv = malloc(m->nx * m->nz * sizeof *m->sv);
    for (size_t i = 0; m->sv && i < m->nz; i++) {
        const json_t *row = json_array_get(rows, i);
        for (size_t j = 0; j < m->nx; j++)
            m->sv[i * m->nx + j] = svg_plot_jnum(json_array_get(row, j), NAN);
    }
    return m->sv ? 0 : -1;
}

/* the cells of field f (nz x nx) in frame fr, coloured over [lo, hi] */
static void map_cells(sb *s, const frame *fr, const smap *m, const double *f, double lo,
                      double hi)
{
    double H = m->nz * m->dz;
    svg_plot_sb_puts(s, "<g class=\"cells\" stroke=\"none\">\n");
    for (size_t i = 0; i < m->nz; i++)
        for (size_t j = 0; j < m->nx; j++) {
            double v = f[i * m->nx + j];
            char c[16] = "#ffffff";
            if (isfinite(v)) svg_plot_ramp(hi > lo ? (v - lo) / (hi - lo) : 0.5, c, sizeof c);
            double x0 = svg_plot_fx(fr, j * m->dx), x1 = svg_plot_fx(fr, (j + 1) * m->dx);
            double y0 = svg_plot_fy(fr, H - i * m->dz), y1 = svg_plot_fy(fr, H - (i + 1) * m->dz);
            svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                                  "fill=\"%s\"/>\n", x0, y0, x1 - x0 + 0.3, y1 - y0 + 0.3, c);
        }
    svg_plot_sb_puts(s, "</g>\n");
}

/* the tiles' seams over the frame (height above the bottom: seams at multiples of tile_v) */
static void seams(sb *s, const frame *fr, const smap *m)
{
    double W = m->nx * m->dx, H = m->nz * m->dz;
    svg_plot_sb_puts(s, "<g class=\"seams\" stroke=\"#ffffff\" stroke-width=\"1.5\" "
                        "stroke-dasharray=\"4 3\">\n");
    for (double x = m->tile_h; m->tile_h > 0 && x < W - 1e-9 * W; x += m->tile_h)
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n",
                           svg_plot_fx(fr, x), fr->y0, svg_plot_fx(fr, x), fr->y0 + fr->h);
    for (double z = m->tile_v; m->tile_v > 0 && z < H - 1e-9 * H; z += m->tile_v)
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n",
                           fr->x0, svg_plot_fy(fr, z), fr->x0 + fr->w, svg_plot_fy(fr, z));
    svg_plot_sb_puts(s, "</g>\n");
}

/* each cell over the mean of its row (NaN where the row's mean is not positive) */
static double *row_relative(const smap *m)
{
    double *r = malloc(m->nx * m->nz * sizeof *r);
    for (size_t i = 0; r && i < m->nz; i++) {
        double sum = 0;
        size_t k = 0;
        for (size_t j = 0; j < m->nx; j++)
            if (isfinite(m->sv[i * m->nx + j])) sum += m->sv[i * m->nx + j], k++;
        double mean = k ? sum / (double)k : NAN;
        for (size_t j = 0; j < m->nx; j++)
            r[i * m->nx + j] = mean > 0 ? m->sv[i * m->nx + j] / mean : NAN;
    }
    return r;
}

/* one panel: field f in a map frame at x0, its colour bar, its title */
static void map_panel(sb *s, const smap *m, const double *f, double x0, double w, double hmax,
                      const char *title, const char *unit)
{
    bounds b = {0, m->nx * m->dx, 0, m->nz * m->dz};
    frame fr = svg_plot_map_frame_in(b, x0, 90, w, hmax);
    double lo, hi;
    svg_plot_minmax(f, m->nx * m->nz, &lo, &hi);
    map_cells(s, &fr, m, f, lo, hi);
    seams(s, &fr, m);
    svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                          "fill=\"none\" stroke=\"#000000\"/>\n", fr.x0, fr.y0, fr.w, fr.h);
    svg_plot_text_at(s, fr.x0 + fr.w / 2, 80, "middle", NULL, title);
    svg_plot_colorbar(s, fr.x0 + fr.w + 12, fr.y0, fmin(fr.h, 300), lo, hi, 0, 0, unit);
}

int svg_geostatic_stress_map(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                             int width, gpd_err *err)
{
    smap m;
    if (smap_read(in->summary, &m)) {
        free(m.sv);
        gpd_err_set(err, 409, "view \"stress-map\" needs the result's map");
        return -1;
    }
    double *rel = row_relative(&m);
    if (!rel) {
        free(m.sv);
        gpd_err_set(err, 500, "out of memory");
        return -1;
    }
    double pw = (width - 40) / 2.0 - 90, hmax = round(width * 0.8);
    double H = m.nz * m.dz, W = m.nx * m.dx;
    double ph = fmin(hmax, pw * H / W);
    sb *s = &g->out;
    char line[200], t1[64], t2[64];
    svg_plot_doc_begin(s, width, (int)(90 + ph + 40), "Vertical stress over a vertical section");
    snprintf(line, sizeof line, "%c-%c section in cells of %.3g \xc3\x97 %.3g m; the tiles' seams "
             "dashed", m.h, m.v, m.dx, m.dz);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", line);
    snprintf(t1, sizeof t1, SIGMA "v (kPa)");
    snprintf(t2, sizeof t2, SIGMA "v / its row's mean");
    map_panel(s, &m, m.sv, 20, pw, ph, t1, "kPa");
    map_panel(s, &m, rel, 20 + pw + 90, pw, ph, t2, "ratio");
    svg_plot_doc_end(s);
    free(rel);
    free(m.sv);
    return 0;
}
