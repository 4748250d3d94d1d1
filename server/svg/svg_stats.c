/* svg_stats.c -- the statistics views' parts both Fourier-Voronoi kinds draw (see
 * svg_stats.h). */
#include "svg/svg_stats.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BLUE "#1f77b4"
#define ORANGE "#ff7f0e"
#define RED "#d62728"
#define GREEN "#2ca02c"

/* ================================================================== size */

/* stats.fit.<key> with its "cdf" curves; 0 ok */
static int cdf_read(const json_t *fit, const char *key, const char *name, const char *color,
                    cdf_series *c)
{
    memset(c, 0, sizeof *c);
    const json_t *b = json_object_get(fit, key), *cdf = json_object_get(b, "cdf");
    size_t nt, na;
    c->x = svg_plot_jarray(json_object_get(cdf, "x"), &c->n);
    c->target = svg_plot_jarray(json_object_get(cdf, "target"), &nt);
    c->achieved = svg_plot_jarray(json_object_get(cdf, "achieved"), &na);
    if (!c->x || !c->target || !c->achieved || c->n < 2 || nt != c->n || na != c->n) {
        svg_plot_cdf_free(c);
        return -1;
    }
    c->name = name;
    c->color = color;
    c->law = json_string_value(json_object_get(b, "law"));
    c->ks = svg_plot_jnum(json_object_get(b, "ks"), NAN);
    c->ks_critical = svg_plot_jnum(json_object_get(b, "ks_critical"), NAN);
    c->w1 = svg_plot_jnum(json_object_get(b, "w1"), NAN);
    c->cov = svg_plot_jnum(json_object_get(json_object_get(b, "achieved"), "cov"), NAN);
    c->target_cov = svg_plot_jnum(json_object_get(json_object_get(b, "target"), "cov"), NAN);
    c->count = svg_plot_jnum(json_object_get(b, "n"), NAN);
    return 0;
}

/* the legend label of an achieved curve: "cells: achieved, KS 0.021 (5 % critical 0.061)" */
static void ks_label(char *buf, size_t n, const cdf_series *c, const char *no_ks)
{
    if (isfinite(c->ks) && isfinite(c->ks_critical))
        snprintf(buf, n, "%s: achieved, KS %.3g (5 %% critical %.3g)", c->name, c->ks,
                 c->ks_critical);
    else
        snprintf(buf, n, "%s: achieved%s", c->name, no_ks);
}

/* "cells: N 500, W1 0.012, COV 0.79 (target 0.8)", and " -- KS above its 5 % critical value"
 * when it is; returns 1 then */
static int fit_line(char *buf, size_t n, const cdf_series *c)
{
    int over = isfinite(c->ks) && isfinite(c->ks_critical) && c->ks > c->ks_critical;
    int k = snprintf(buf, n, "%s:", c->name);
    if (isfinite(c->count) && k > 0 && (size_t)k < n)
        k += snprintf(buf + k, n - (size_t)k, " N %.0f,", c->count);
    if (k > 0 && (size_t)k < n && isfinite(c->w1))
        k += snprintf(buf + k, n - (size_t)k, " W1 %.3g,", c->w1);
    if (k > 0 && (size_t)k < n && isfinite(c->cov) && isfinite(c->target_cov))
        k += snprintf(buf + k, n - (size_t)k, " COV %.3g (target %.3g)", c->cov, c->target_cov);
    if (k > 0 && (size_t)k < n && buf[k - 1] == ',') buf[--k] = 0;
    if (k > 0 && (size_t)k < n && over)
        snprintf(buf + k, n - (size_t)k, " -- KS %.3g is above its 5 %% critical value %.3g",
                 c->ks, c->ks_critical);
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
                svg_plot_text_at(s, first ? x : x + 18, y + 16 * lines, "start",
                                 "class=\"warning\" fill=\"#b35c00\" font-weight=\"bold\"", line);
            }
            lines++;
            t += cut;
            while (*t == ' ') t++;
        }
    }
    return lines;
}

/* stats.fit.passing: the grains' percent passing by mass at the sieve diameters (m) */
typedef struct passing {
    double *d, *target, *achieved, max_pp;
    size_t n;
} passing;

static void passing_free(passing *p)
{
    free(p->d);
    free(p->target);
    free(p->achieved);
    memset(p, 0, sizeof *p);
}

/* 0 when the fit has a passing curve of two points or more */
static int passing_read(const json_t *fit, passing *p)
{
    memset(p, 0, sizeof *p);
    const json_t *o = json_object_get(fit, "passing");
    size_t nt, na;
    p->d = svg_plot_jarray(json_object_get(o, "diameters"), &p->n);
    p->target = svg_plot_jarray(json_object_get(o, "target"), &nt);
    p->achieved = svg_plot_jarray(json_object_get(o, "achieved"), &na);
    p->max_pp = svg_plot_jnum(json_object_get(o, "max_error_pp"), NAN);
    if (!p->d || !p->target || !p->achieved || p->n < 2 || nt != p->n || na != p->n) {
        passing_free(p);
        return -1;
    }
    return 0;
}

/* one curve of percent passing against the diameter in mm, with markers at the sieves */
static void passing_curve(sb *s, const frame *f, const passing *p, int achieved)
{
    const double *y = achieved ? p->achieved : p->target;
    const char *color = achieved ? ORANGE : RED;
    svg_plot_sb_printf(s, "<path class=\"passing-%s\" fill=\"none\" stroke=\"%s\" "
                          "stroke-width=\"2\"%s d=\"",
                       achieved ? "achieved" : "target", color,
                       achieved ? "" : " stroke-dasharray=\"6 4\"");
    int first = 1;
    for (size_t i = 0; i < p->n; i++) {
        if (!(p->d[i] > 0) || !isfinite(y[i])) continue;
        svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", svg_plot_fx(f, p->d[i] * 1e3),
                           svg_plot_fy(f, fmax(0, fmin(100, y[i]))));
        first = 0;
    }
    svg_plot_sb_puts(s, "\"/>\n");
    for (size_t i = 0; i < p->n; i++)
        if (p->d[i] > 0 && isfinite(y[i]))
            svg_plot_marker(s, svg_plot_fx(f, p->d[i] * 1e3),
                            svg_plot_fy(f, fmax(0, fmin(100, y[i]))), color);
}

/* the passing panel: target sieve curve and the grains' achieved one, by mass, against the
 * diameter (x axis label xlabel), its legend under the plot */
static void passing_panel(sb *s, const frame *f0, const passing *p, const char *xlabel)
{
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < p->n; i++)
        if (p->d[i] > 0) lo = fmin(lo, p->d[i] * 1e3), hi = fmax(hi, p->d[i] * 1e3);
    if (!(hi > lo)) lo = isfinite(lo) ? lo / 2 : 1, hi = lo * 4;
    frame f = *f0;
    f.xmin = lo;
    f.xmax = hi;
    f.ymin = 0;
    f.ymax = 100;
    f.xlog = 1;
    svg_plot_text_at(s, f.x0 + f.w / 2, f.y0 - 10, "middle", "font-weight=\"bold\"",
                     "Grains passing by mass (sieve law)");
    svg_plot_axes(s, &f, xlabel, "percent passing by mass (%)", 1);
    passing_curve(s, &f, p, 0);
    passing_curve(s, &f, p, 1);
    char lab[96];
    if (isfinite(p->max_pp)) snprintf(lab, sizeof lab, "achieved, max error %.2g pp", p->max_pp);
    else snprintf(lab, sizeof lab, "achieved");
    legend_item it[2] = {{"target (sieve curve)", "dash", RED}, {lab, "marker", ORANGE}};
    svg_plot_legend(s, f.x0, f.y0 + f.h + 50, it, 2);
}

/* The x axis of the CDFs: a log axis when their values are all positive (sizes are read so),
 * in the unit whose labels read as whole numbers: the curves' x and *lo, *hi scaled into it
 * in place; returns the unit's name. */
static const char *cdf_axis(cdf_series *c, int nc, const svg_stats_size_kind *k, double *lo,
                            double *hi, int *xlog)
{
    double f;
    svg_plot_cdf_range(c, nc, 1, lo, hi);
    *xlog = *lo > 0 && *hi > *lo;
    if (!*xlog) svg_plot_cdf_range(c, nc, 0, lo, hi);
    if (!(*hi > *lo)) *lo = isfinite(*lo) ? *lo - 0.5 : 0, *hi = *lo + 1;
    const char *unit = k->unit(*hi, &f);
    for (int j = 0; j < nc; j++)
        for (size_t i = 0; i < c[j].n; i++) c[j].x[i] *= f;
    *lo *= f;
    *hi *= f;
    return unit;
}

/* the CDF panel: both series, and their legend with the KS under the plot (a CDF of a narrow
 * law crosses any corner of it) */
static void cdf_panel(sb *s, const frame *f, const cdf_series *c, int nc, const char *unit,
                      const svg_stats_size_kind *k)
{
    char xl[64];
    snprintf(xl, sizeof xl, "%s (%s%s)", k->measure, unit, f->xlog ? ", log scale" : "");
    svg_plot_axes(s, f, xl, "cumulative fraction (by number)", 1);
    legend_item it[4];
    char names[4][96];
    for (int j = 0; j < nc; j++) {
        svg_plot_cdf_path(s, f, &c[j], 0);
        svg_plot_cdf_path(s, f, &c[j], 1);
        snprintf(names[2 * j], sizeof names[0], "%s: target (%s)", c[j].name,
                 c[j].law ? c[j].law : "law");
        ks_label(names[2 * j + 1], sizeof names[0], &c[j], k->no_ks);
        it[2 * j] = (legend_item){names[2 * j], "dash", c[j].color};
        it[2 * j + 1] = (legend_item){names[2 * j + 1], "line", c[j].color};
    }
    svg_plot_legend(s, f->x0, f->y0 + f->h + 50, it, 2 * nc);
}

/* a line per series from baseline y, 16 px apart (red when its KS is over), then the
 * warnings */
static void fit_lines(sb *s, const cdf_series *c, int nc, const json_t *warnings, double y,
                      size_t maxch)
{
    for (int j = 0; j < nc; j++, y += 16) {
        char line[320];
        int over = fit_line(line, sizeof line, &c[j]);
        svg_plot_text_at(s, 20, y, "start",
                         over ? "class=\"fit ks-over\" fill=\"#d62728\"" : "class=\"fit\"", line);
    }
    warning_lines(s, warnings, 20, y, maxch);
}

/* the picture: from the top the CDFs, their legend, the passing curves (p, when not NULL) and
 * theirs, the fit lines and the warnings */
static void size_draw(sb *s, const json_t *res, cdf_series *c, int nc, const passing *p,
                      int width, const svg_stats_size_kind *k)
{
    double lo, hi;
    int xlog;
    const char *unit = cdf_axis(c, nc, k, &lo, &hi, &xlog);
    const json_t *warnings = json_object_get(res, "warnings");
    size_t maxch = (size_t)((width - 60) / 8 - 12); /* bold 12 px, after "⚠ warning: " */
    int nwarn = warning_lines(NULL, warnings, 0, 0, maxch);
    double cdf_h = lround(width * 0.62) - 110.0, pass_h = lround(width * 0.5) - 110.0;
    double y_pass = 40 + cdf_h + 50 + 8 + 36 * nc + 50;
    double y_lines = p ? y_pass + pass_h + 50 + 44 + 24 : y_pass - 26;
    int height = (int)ceil(y_lines + 16 * (nc + nwarn));
    frame f = {80, 40, width - 110.0, cdf_h, lo, hi, 0, 1, xlog};
    svg_plot_doc_begin(s, width, height, k->title);
    cdf_panel(s, &f, c, nc, unit, k);
    if (p) {
        frame fp = {80, y_pass, width - 110.0, pass_h, 0, 1, 0, 100, 1};
        passing_panel(s, &fp, p, k->diameter);
    }
    fit_lines(s, c, nc, warnings, y_lines, maxch);
    svg_plot_doc_end(s);
}

int svg_stats_size(sb *s, const json_t *res, int width, const svg_stats_size_kind *k)
{
    const json_t *fit = json_object_get(json_object_get(res, "stats"), "fit");
    cdf_series c[2];
    int nc = 0;
    if (cdf_read(fit, k->cell_key, "cells", BLUE, &c[nc]) == 0) nc++;
    if (cdf_read(fit, k->grain_key, "grains", ORANGE, &c[nc]) == 0) nc++;
    if (!nc) return 1;
    passing p;
    int have_p = passing_read(fit, &p) == 0;
    size_draw(s, res, c, nc, have_p ? &p : NULL, width, k);
    for (int j = 0; j < nc; j++) svg_plot_cdf_free(&c[j]);
    passing_free(&p);
    return 0;
}

/* ================================================================== descriptors */

/* a vertical marker line across the frame at x = v */
static void vline(sb *s, const frame *f, double v, const char *cls, const char *style)
{
    double x = svg_plot_fx(f, v);
    svg_plot_sb_printf(s, "<line class=\"%s\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" %s/>\n",
                       cls, x, f->y0, x, f->y0 + f->h, style);
}

/* a panel's title: the name, mean and sd, and the target when asked */
static void desc_title(char *t, size_t n, const char *name, const hist *h, double sd,
                       double target, int asked)
{
    int k = snprintf(t, n, "%s", name);
    if (h->has_mean) k += snprintf(t + k, n - (size_t)k, ": mean %.3g", h->mean);
    if (isfinite(sd)) k += snprintf(t + k, n - (size_t)k, ", sd %.2g", sd);
    if (asked && isfinite(target)) snprintf(t + k, n - (size_t)k, " (asked %.3g)", target);
}

/* one panel: the histogram, the mean (dashed) and the target (red) marked, mean and sd in its
 * title; the x range widened to show a target outside the data */
static void desc_panel(sb *s, double ox, double oy, double pw, double ph, const char *name,
                       const hist *h, double sd, double target, int asked)
{
    frame f = svg_plot_hist_frame(ox + 62, oy + 26, pw - 82, ph - 76, h);
    if (isfinite(target)) {
        double st = (f.xmax - f.xmin) / (double)h->k;
        if (target < f.xmin) f.xmin = floor(target / st) * st;
        if (target > f.xmax) f.xmax = ceil(target / st) * st;
    }
    char t[160];
    desc_title(t, sizeof t, name, h, sd, target, asked);
    svg_plot_text_at(s, f.x0 + f.w / 2, oy + 14, "middle",
                     "class=\"panel-title\" font-weight=\"bold\"", t);
    svg_plot_axes(s, &f, name, "fraction of grains", 0);
    svg_plot_draw_hist(s, &f, h, GREEN);
    if (h->has_mean && h->mean >= f.xmin && h->mean <= f.xmax)
        vline(s, &f, h->mean, "mean",
              "stroke=\"#000000\" stroke-width=\"1.5\" stroke-dasharray=\"5 3\"");
    if (isfinite(target)) vline(s, &f, target, "target", "stroke=\"#d62728\" stroke-width=\"2\"");
}

double svg_stats_desc_panels(sb *s, int width, const svg_stats_desc *d)
{
    legend_item it[3] = {{"achieved (fraction of grains per bin)", "bar", GREEN},
                         {"mean", "dash", "#000000"},
                         {d->target_label, "line", RED}};
    svg_plot_legend_row(s, 40, 44, it, d->target_label ? 3 : 2);
    double pw = (width - 40) / 2.0, ph = (lround(width * 0.75) + 20 - 60) / 2.0;
    for (int k = 0; k < 4; k++) {
        double ox = 20 + (k % 2) * pw, oy = 56 + (k / 2) * ph;
        if (!d->h[k].k) {
            svg_plot_text_at(s, ox + pw / 2, oy + ph / 2, "middle", NULL, "(not in the result)");
            continue;
        }
        desc_panel(s, ox, oy, pw, ph, d->name[k], &d->h[k], d->sd[k], d->target[k], d->asked);
    }
    return 56 + 2 * ph;
}
