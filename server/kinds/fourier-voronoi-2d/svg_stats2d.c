/* svg_stats2d.c -- the statistics views of the 2D kind (kind_fv2d.c), Mollon & Zhao 2012
 * Fig. 15 d-i:
 *   size         the CDFs of stats.fit (target law dashed, achieved solid, cells and grains) on a
 *                log-area axis, KS and its 5 % critical value in the legend; for a sieve law
 *                also the grains' passing by mass (stats.fit.passing): svg/svg_stats.c, as the
 *                3D kind's; results stored before stats.fit get histograms;
 *   orientation  a rose of the grains' (else the cells') directions, as many classes as N
 *                supports (rose_classes), target cosine law and achieved both as closed step
 *                outlines, rings labelled;
 *   descriptors  one histogram per shape descriptor, zoomed to the data, Freedman-Diaconis
 *                bins, mean and target marked (the panels: svg/svg_stats.c).
 * They read the summary and the items' numbers in light passes (svg_items_fold): memory does
 * not grow with the number of grains. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg/svg_internal.h"
#include "svg/svg_stats.h"
#include "svg/svg_views.h"

#define BLUE "#1f77b4"
#define ORANGE "#ff7f0e"
#define RED "#d62728"

/* ================================================================== size */

/* the size view as histograms (results without stats.fit) */
static int view_size_hist(gp_svg *g, const gp_svg_input *in, int width, gpd_err *err)
{
    const json_t *stats = json_object_get(in->summary, "stats");
    hist h;
    int have = svg_plot_hist_read(json_object_get(stats, "size_histogram"), &h) == 0, cells = 1;
    if (have) {
        hist gh;
        if (svg_plot_hist_read(json_object_get(stats, "grain_size_histogram"), &gh) == 0) {
            if (gh.k == h.k) {
                h.achieved2 = gh.achieved;
                gh.achieved = NULL;
            }
            svg_plot_hist_free(&gh);
        }
    } else {
        size_t n;
        int failed;
        double *v = svg_items_collect(in, GP_SVG_CELLS, 0, &n, &failed);
        if (!v && !failed) {
            v = svg_items_collect(in, GP_SVG_GRAINS, 0, &n, &failed);
            cells = 0;
        }
        if (!v) {
            if (failed) gpd_err_set(err, 500, "cannot read the cells or grains of the result");
            else gpd_err_set(err, 409, "view \"size\" needs stats.size_histogram, cells or grains in the result");
            return -1;
        }
        double lo, hi;
        svg_plot_minmax(v, n, &lo, &hi);
        int ok = svg_plot_hist_from_values(v, n, n < 50 ? 8 : 20, lo, hi, &h) == 0;
        free(v);
        if (!ok) {
            gpd_err_set(err, 500, "out of memory");
            return -1;
        }
    }
    /* the areas in a unit whose labels read as whole numbers */
    double k;
    const char *unit = svg_plot_area_unit(h.edges[h.k], &k);
    for (size_t i = 0; i <= h.k; i++) h.edges[i] *= k;
    char what[64];
    snprintf(what, sizeof what, "%s area (%s)", cells ? "cell" : "grain", unit);
    int height = (int)lround(width * 0.62);
    frame f = svg_plot_hist_frame(80, 40, width - 110, height - 110, &h);
    sb *s = &g->out;
    svg_plot_doc_begin(s, width, height, "Size distribution: target vs achieved");
    svg_plot_axes(s, &f, what, "fraction of cells", 1);
    svg_plot_draw_hist(s, &f, &h, BLUE);
    legend_item it[3];
    int n = 0;
    it[n++] = (legend_item){have ? "achieved (cells)" : "achieved", "bar", BLUE};
    if (h.achieved2) it[n++] = (legend_item){"achieved (grains)", "line", ORANGE};
    if (h.target) it[n++] = (legend_item){"target (lognormal)", "marker", RED};
    svg_plot_legend(s, f.x0 + f.w - svg_plot_legend_w(it, n) - 10, f.y0 + 8, it, n);
    svg_plot_doc_end(s);
    svg_plot_hist_free(&h);
    return 0;
}

/* the size view of the 2D kind: the CDFs of the cells' and grains' areas */
static const svg_stats_size_kind SIZE_2D = {
    "cell_area", "grain_area", "Size distribution: target law vs achieved (CDF)", "area",
    svg_plot_area_unit, "equivalent diameter \xe2\x88\x9a(4A/\xcf\x80) (mm, log scale)",
    " (KS not measured)"};

/* the size view: CDFs from stats.fit when the result has them, else histograms (results stored
 * before stats.fit, or without it) */
int svg_stats2d_size(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                  gpd_err *err)
{
    if (svg_stats_size(&g->out, in->summary, width, &SIZE_2D) == 0) return 0;
    return view_size_hist(g, in, width, err);
}

/* ================================================================== orientation */

#define ROSE_FINE 36 /* 5-degree classes over [-90, 90), merged into the rose's */

/* what the rose draws: the directions' counts, the target law, the fit */
typedef struct rose {
    double fine[ROSE_FINE], n;   /* counts of the items' directions */
    int k;                       /* classes of the rose */
    double edges[ROSE_FINE + 1]; /* degrees, -90..90 */
    double ach[ROSE_FINE], tgt[ROSE_FINE]; /* % per degree */
    int tk;                       /* the target's classes: the rose's, or a stored histogram's */
    double tedges[ROSE_FINE + 1];
    int has_target, from_hist;
    double mean_deg, anis, ks, crit;
    const char *who; /* "grains", "cells" */
} rose;

/* The number of classes of a rose of n directions over 180 degrees: the most of 36, 18, 12,
 * 9, 6 (5 to 30 degrees, each dividing 180 and 36) that leaves 25 directions a class or more
 * on average. A class's count is off by about 1/sqrt(count) of itself: 25 keeps that to 20 %,
 * so that the outline shows the law rather than its sampling noise (at 10 a class, 5-degree
 * classes of 500 grains, every other class looks like a spike or a gap). So 36 classes of 5
 * degrees from N = 900, 18 of 10 from 450 (Mollon & Zhao's 500 grains), 6 of 30 below 225:
 * still 3 classes in the cosine law's half-period -- never the 4-5 classes of the IMC's own
 * histogram at 500, which draw a cosine law as a bow tie. */
static int rose_classes(double n)
{
    static const int ks[5] = {36, 18, 12, 9, 6};
    for (int i = 0; i < 5; i++)
        if (n / ks[i] >= 25) return ks[i];
    return 6;
}

/* the probability of the cosine law (gp_law.h) between t0 and t1 degrees */
static double cosine_mass(double mean, double a, double t0, double t1)
{
    double r = M_PI / 180;
    double m = (1 + a) / 2 * (t1 - t0) * r +
               (1 - a) / 4 * (sin(2 * (t1 - mean) * r) - sin(2 * (t0 - mean) * r));
    return m / ((1 + a) / 2 * M_PI);
}

static void rose_fold(void *user, const svg_item *c)
{
    rose *ro = user;
    double t = c->orientation_deg;
    if (!isfinite(t)) return;
    t = fmod(t + 90, 180);
    if (t < 0) t += 180;
    int i = (int)floor(t / (180.0 / ROSE_FINE));
    ro->fine[i < 0 ? 0 : i >= ROSE_FINE ? ROSE_FINE - 1 : i] += 1;
    ro->n += 1;
}

/* the target law and the KS of stats.fit.<who>_orientation (else the other population's) */
static void rose_fit(rose *ro, const json_t *fit)
{
    const char *keys[2] = {"grain_orientation", "cell_orientation"};
    int first = ro->who && !strcmp(ro->who, "cells");
    for (int j = 0; j < 2; j++) {
        const json_t *b = json_object_get(fit, keys[(first + j) % 2]);
        const json_t *t = json_object_get(b, "target");
        double m = svg_plot_jnum(json_object_get(t, "mean_deg"), NAN), a = svg_plot_jnum(json_object_get(t, "anisotropy"), NAN);
        if (!isfinite(m) || !(a > 0)) continue;
        ro->has_target = 1;
        ro->mean_deg = m;
        ro->anis = a;
        if (j == 0) { /* the KS of the population drawn, not of the other */
            ro->ks = svg_plot_jnum(json_object_get(b, "ks"), NAN);
            ro->crit = svg_plot_jnum(json_object_get(b, "ks_critical"), NAN);
        }
        return;
    }
}

/* the classes of the rose from the fine counts, and the target's densities */
static void rose_bin(rose *ro)
{
    ro->k = rose_classes(ro->n);
    int m = ROSE_FINE / ro->k;
    double w = 180.0 / ro->k;
    for (int i = 0; i < ro->k; i++) {
        double c = 0;
        for (int j = 0; j < m; j++) c += ro->fine[i * m + j];
        ro->edges[i] = -90 + w * i;
        ro->ach[i] = ro->n > 0 ? 100 * c / ro->n / w : 0;
        if (ro->has_target)
            ro->tgt[i] = 100 * cosine_mass(ro->mean_deg, ro->anis, ro->edges[i], ro->edges[i] + w) / w;
    }
    ro->edges[ro->k] = 90;
    if (ro->has_target) {
        ro->tk = ro->k;
        memcpy(ro->tedges, ro->edges, sizeof ro->edges);
    }
}

/* the target of a result without stats.fit: stats.orientation_histogram's, on its classes */
static void rose_hist_target(rose *ro, const json_t *stats)
{
    hist h;
    if (svg_plot_hist_read(json_object_get(stats, "orientation_histogram"), &h)) return;
    if (h.target && h.k <= ROSE_FINE) {
        ro->has_target = 1;
        ro->tk = (int)h.k;
        for (size_t i = 0; i <= h.k; i++) ro->tedges[i] = h.edges[i];
        for (size_t i = 0; i < h.k; i++) {
            double w = h.edges[i + 1] - h.edges[i];
            ro->tgt[i] = w > 0 ? 100 * h.target[i] / w : 0;
        }
    }
    svg_plot_hist_free(&h);
}

/* an old result without items: stats.orientation_histogram's classes (fractions) */
static int rose_from_hist(rose *ro, const json_t *stats)
{
    hist h;
    if (svg_plot_hist_read(json_object_get(stats, "orientation_histogram"), &h) || h.k > ROSE_FINE) {
        if (h.k > ROSE_FINE) svg_plot_hist_free(&h);
        return -1;
    }
    ro->k = ro->tk = (int)h.k;
    ro->from_hist = 1;
    ro->has_target = h.target != NULL;
    for (size_t i = 0; i <= h.k; i++) ro->edges[i] = ro->tedges[i] = h.edges[i];
    for (size_t i = 0; i < h.k; i++) {
        double w = h.edges[i + 1] - h.edges[i];
        ro->ach[i] = w > 0 ? 100 * h.achieved[i] / w : 0;
        ro->tgt[i] = w > 0 && h.target ? 100 * h.target[i] / w : 0;
    }
    svg_plot_hist_free(&h);
    return 0;
}

/* the rose's data: the grains' directions, else the cells', else the stored histogram */
static int rose_read(rose *ro, const gp_svg_input *in, gpd_err *err)
{
    memset(ro, 0, sizeof *ro);
    ro->ks = ro->crit = ro->mean_deg = ro->anis = NAN;
    const json_t *stats = json_object_get(in->summary, "stats");
    static const gp_svg_part parts[2] = {GP_SVG_GRAINS, GP_SVG_CELLS};
    for (int p = 0; p < 2; p++) {
        int failed;
        gp_svg_items *it = svg_items_open_light(in, parts[p], &failed);
        if (failed) {
            gpd_err_set(err, 500, "cannot read the %s of the result", svg_items_part_name[parts[p]]);
            return -1;
        }
        if (!it) continue;
        int r = svg_items_fold(it, rose_fold, ro);
        gp_svg_items_close(it);
        if (r) return svg_part_error(err, parts[p]);
        if (ro->n > 0) {
            ro->who = svg_items_part_name[parts[p]];
            rose_fit(ro, json_object_get(stats, "fit"));
            rose_bin(ro);
            if (!ro->has_target) rose_hist_target(ro, stats);
            return 0;
        }
    }
    if (rose_from_hist(ro, stats) == 0) return 0;
    gpd_err_set(err, 409, "view \"orientation\" needs grains, cells or stats.orientation_histogram in the result");
    return -1;
}

/* The closed step outline of densities d[k] over the classes edges[k+1] (degrees) and their
 * mirror (+180: directions are axial): per class an arc at its radius, radial steps between;
 * scale px per unit of d. */
static void rose_outline(sb *s, double cx, double cy, double scale, const double *edges,
                         const double *d, int k, const char *attrs)
{
    svg_plot_sb_printf(s, "<path %s d=\"", attrs);
    for (int m = 0, first = 1; m < 2; m++)
        for (int i = 0; i < k; i++, first = 0) {
            double r = fmax(0, d[i]) * scale;
            double a0 = (edges[i] + 180 * m) * M_PI / 180, a1 = (edges[i + 1] + 180 * m) * M_PI / 180;
            svg_plot_sb_printf(s, "%s%.2f %.2fA%.2f %.2f 0 0 0 %.2f %.2f", first ? "M" : "L",
                      cx + r * cos(a0), cy - r * sin(a0), r, r, cx + r * cos(a1), cy - r * sin(a1));
        }
    svg_plot_sb_puts(s, "z\"/>\n");
}

/* the grid of the rose: rings at round densities (labelled along the direction the target
 * makes least probable, where the outlines are smallest), spokes every 30 degrees, the angles */
static void rose_grid(sb *s, double cx, double cy, double R, const ticks *t, double rmax,
                      double label_deg)
{
    svg_plot_sb_puts(s, "<g class=\"grid\" fill=\"none\" stroke=\"#cccccc\">\n");
    for (int i = 0; i < t->n; i++) {
        double pr = R * t->v[i] / rmax;
        if (!(pr > 0)) continue;
        svg_plot_sb_printf(s, "<path class=\"ring\" d=\"M%.2f %.2fa%.2f %.2f 0 1 0 %.2f 0a%.2f %.2f 0 1 0 %.2f 0z\"/>\n",
                  cx - pr, cy, pr, pr, 2 * pr, pr, pr, -2 * pr);
    }
    for (int a = 0; a < 360; a += 30) {
        double r = a * M_PI / 180;
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", cx, cy,
                  cx + R * cos(r), cy - R * sin(r));
    }
    svg_plot_sb_puts(s, "</g>\n");
    char lab[64];
    double la = label_deg * M_PI / 180;
    for (int i = 0; i < t->n; i++) {
        double pr = R * t->v[i] / rmax;
        if (!(pr > 0)) continue;
        svg_plot_fmt_tick(lab, sizeof lab, t->v[i], t->step);
        svg_plot_text_at(s, cx + pr * cos(la), cy - pr * sin(la) + 4, "middle",
                "class=\"ring-label\" font-size=\"11\" fill=\"#444444\" stroke=\"#ffffff\" "
                "stroke-width=\"3\" paint-order=\"stroke\"",
                lab);
    }
    for (int a = -90; a <= 90; a += 30) {
        double r = a * M_PI / 180;
        snprintf(lab, sizeof lab, "%d°", a);
        svg_plot_text_at(s, cx + (R + 20) * cos(r), cy - (R + 20) * sin(r) + 4, "middle", NULL, lab);
    }
}

/* the legend lines under the rose */
static void rose_legend(sb *s, const rose *ro, double x, double y)
{
    char a[200], t[160];
    legend_item it[2];
    int n = 0;
    int kl = snprintf(a, sizeof a, "%s, achieved (N = %.0f, %d classes of %.3g°)",
                      ro->who ? ro->who : "achieved", ro->n, ro->k, 180.0 / ro->k);
    if (ro->from_hist) snprintf(a, sizeof a, "achieved (the stored histogram's %d classes)", ro->k);
    else if (isfinite(ro->ks) && isfinite(ro->crit) && kl > 0 && (size_t)kl < sizeof a)
        snprintf(a + kl, sizeof a - (size_t)kl, ": KS %.3g (5 %% critical %.3g)", ro->ks, ro->crit);
    it[n++] = (legend_item){a, "line", BLUE};
    if (ro->has_target) {
        if (!isfinite(ro->anis)) snprintf(t, sizeof t, "target (the stored histogram's classes)");
        else snprintf(t, sizeof t, "target: cosine law, mean %.3g°, anisotropy %.3g", ro->mean_deg,
                      ro->anis);
        it[n++] = (legend_item){t, "dash", RED};
    }
    svg_plot_legend(s, x, y, it, n);
    svg_plot_text_at(s, x, y + 8 + 18 * n + 16, "start", "class=\"caption\" fill=\"#444444\"",
            "radius: probability density (% per degree); directions are axial, drawn at "
            "\xce\xb8 and \xce\xb8 + 180°");
}

int svg_stats2d_orientation(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err)
{
    rose ro;
    if (rose_read(&ro, in, err)) return -1;
    int rose_h = (int)lround(width * 0.72);
    int height = rose_h + 8 + 18 * (ro.has_target ? 2 : 1) + 30;
    double cx = width / 2.0, cy = 40 + (rose_h - 60) / 2.0;
    double R = fmin(width / 2.0 - 70, (rose_h - 100) / 2.0);
    double m = 0;
    for (int i = 0; i < ro.k; i++) m = fmax(m, ro.ach[i]);
    for (int i = 0; ro.has_target && i < ro.tk; i++) m = fmax(m, ro.tgt[i]);
    if (!(m > 0)) m = 1;
    ticks t; /* rings: their labels keep apart along any direction (horizontal widths) */
    svg_plot_lin_ticks(0, m, R, 1, 5, &t);
    double rmax = t.step > 0 ? ceil(m / t.step - 1e-9) * t.step : m;
    if (t.step > 0 && t.v[t.n - 1] < rmax - t.step * 1e-9 && t.n < TICKS_MAX) t.v[t.n++] = rmax;
    sb *s = &g->out;
    svg_plot_doc_begin(s, width, height, "Orientation rose: target vs achieved");
    double label_deg = isfinite(ro.mean_deg) ? ro.mean_deg + 90 : 90;
    label_deg = fmod(fmod(label_deg, 180) + 180, 180) + 7.5; /* between two spokes' labels */
    rose_grid(s, cx, cy, R, &t, rmax, label_deg);
    rose_outline(s, cx, cy, R / rmax, ro.edges, ro.ach, ro.k,
                 "class=\"achieved\" fill=\"#1f77b4\" fill-opacity=\"0.25\" stroke=\"#1f77b4\" "
                 "stroke-width=\"2\"");
    if (ro.has_target)
        rose_outline(s, cx, cy, R / rmax, ro.tedges, ro.tgt, ro.tk,
                     "class=\"target\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" "
                     "stroke-dasharray=\"6 4\"");
    rose_legend(s, &ro, 20, rose_h);
    svg_plot_doc_end(s);
    return 0;
}

/* ================================================================== descriptors */

#define DFINE 1024 /* classes of the quartiles' pass */
#define DMAXBIN 40

/* one descriptor over the passes: moments and range, quartiles from a fine histogram, then
 * the counts in round Freedman-Diaconis bins */
typedef struct dstat {
    double n, sum, sum2, lo, hi;
    unsigned fine[DFINE];
    double x0, step;
    int k;
    double cnt[DMAXBIN];
} dstat;

typedef struct dpass {
    dstat d[4];
    int pass; /* 0 moments, 1 quartiles, 2 bins */
} dpass;

static void desc_fold(void *user, const svg_item *c)
{
    dpass *p = user;
    for (int k = 0; k < 4; k++) {
        double v = c->desc[k];
        dstat *d = &p->d[k];
        if (!isfinite(v)) continue;
        if (p->pass == 0) {
            d->n++, d->sum += v, d->sum2 += v * v;
            d->lo = fmin(d->lo, v), d->hi = fmax(d->hi, v);
        } else if (p->pass == 1 && d->hi > d->lo) {
            long i = (long)floor((v - d->lo) / (d->hi - d->lo) * DFINE);
            d->fine[i < 0 ? 0 : i >= DFINE ? DFINE - 1 : i]++;
        } else if (p->pass == 2 && d->k > 0) {
            long i = (long)floor((v - d->x0) / d->step);
            d->cnt[i < 0 ? 0 : i >= d->k ? d->k - 1 : i] += 1;
        }
    }
}

/* the q-quantile from the fine histogram (linear within its class) */
static double fine_quantile(const dstat *d, double q)
{
    double want = q * d->n, cum = 0, w = (d->hi - d->lo) / DFINE;
    for (int i = 0; i < DFINE; i++) {
        if (cum + d->fine[i] >= want && d->fine[i] > 0)
            return d->lo + w * (i + (want - cum) / d->fine[i]);
        cum += d->fine[i];
    }
    return d->hi;
}

/* the next 1-2-5 x 10^k step above (up > 0) or below st */
static double step_125(double st, int up)
{
    double p = pow(10, floor(log10(st) + 1e-9)), m = st / p;
    if (up) return m < 1.5 ? 2 * p : m < 3.5 ? 5 * p : 10 * p;
    return m > 7 ? 5 * p : m > 3 ? 2 * p : m > 1.5 ? p : p / 2;
}

/* Round bins for d: the Freedman-Diaconis width 2 IQR / n^(1/3) rounded up to a 1-2-5 step,
 * widened or narrowed a step at a time until 8..40 bins cover the data from a multiple of
 * the step. */
static void desc_bins(dstat *d)
{
    double iqr = fine_quantile(d, 0.75) - fine_quantile(d, 0.25);
    double span = d->hi - d->lo;
    double h = iqr > 0 ? 2 * iqr / cbrt(d->n) : span > 0 ? span / 8 : fmax(fabs(d->lo) * 0.01, 1e-3);
    double st = pow(10, ceil(log10(h) - 1e-9));
    while (step_125(st, 0) >= h) st = step_125(st, 0);
    for (int it = 0; it < 40; it++) {
        double x0 = floor(d->lo / st + 1e-9) * st, x1 = ceil(d->hi / st - 1e-9) * st;
        if (x1 <= x0) x1 = x0 + st;
        int k = (int)lround((x1 - x0) / st);
        if (k > DMAXBIN) st = step_125(st, 1);
        else if (k < 8 && span > 0 && it < 39) st = step_125(st, 0);
        else {
            d->x0 = x0, d->step = st, d->k = k;
            return;
        }
    }
    d->x0 = d->lo, d->step = span > 0 ? span / 8 : 1, d->k = 8;
}

/* the three passes over the grains' descriptors; 1 when there are none, -1 when they cannot be
 * read (err) */
static int desc_read(dpass *p, const gp_svg_input *in, gpd_err *err)
{
    int failed;
    gp_svg_items *it = svg_items_open_light(in, GP_SVG_GRAINS, &failed);
    if (!it) {
        if (failed) return svg_part_error(err, GP_SVG_GRAINS);
        return 1;
    }
    for (int k = 0; k < 4; k++) p->d[k].lo = INFINITY, p->d[k].hi = -INFINITY;
    int r = 0, any = 0;
    for (p->pass = 0; p->pass < 3 && r == 0; p->pass++) {
        r = svg_items_fold(it, desc_fold, p);
        for (int k = 0; k < 4 && p->pass == 1; k++)
            if (p->d[k].n > 0) desc_bins(&p->d[k]);
    }
    gp_svg_items_close(it);
    if (r) return svg_part_error(err, GP_SVG_GRAINS);
    for (int k = 0; k < 4; k++) any |= p->d[k].n > 0;
    return any ? 0 : 1;
}

/* a descriptor's histogram from its passes (fractions of the grains) */
static int desc_hist(const dstat *d, hist *h)
{
    memset(h, 0, sizeof *h);
    h->edges = malloc((size_t)(d->k + 1) * sizeof *h->edges);
    h->achieved = malloc((size_t)d->k * sizeof *h->achieved);
    if (!h->edges || !h->achieved) {
        svg_plot_hist_free(h);
        return -1;
    }
    for (int i = 0; i <= d->k; i++) h->edges[i] = d->x0 + d->step * i;
    for (int i = 0; i < d->k; i++) h->achieved[i] = d->cnt[i] / d->n;
    h->k = (size_t)d->k;
    h->mean = d->sum / d->n;
    h->has_mean = 1;
    return 0;
}

/* a stored histogram (stats.descriptors.<name>, a result without grains to read) zoomed to its
 * non-empty classes and one on either side */
static void hist_zoom(hist *h)
{
    size_t a = 0, b = h->k;
    while (a < h->k && !(h->achieved[a] > 0)) a++;
    while (b > a && !(h->achieved[b - 1] > 0)) b--;
    if (a >= b) return;
    a = a > 0 ? a - 1 : 0;
    b = b < h->k ? b + 1 : b;
    memmove(h->edges, h->edges + a, (b - a + 1) * sizeof *h->edges);
    memmove(h->achieved, h->achieved + a, (b - a) * sizeof *h->achieved);
    if (h->target) memmove(h->target, h->target + a, (b - a) * sizeof *h->target);
    h->k = b - a;
}

/* the histogram of descriptor k: from the passes over the grains, else the stored one */
static int desc_of(const dpass *p, int have, const json_t *stored, int k, hist *h, double *sd)
{
    *sd = NAN;
    const dstat *d = &p->d[k];
    if (have && d->n > 0) {
        double m = d->sum / d->n, var = d->sum2 / d->n - m * m;
        *sd = d->n > 1 ? sqrt(fmax(0, var) * d->n / (d->n - 1)) : 0;
        return desc_hist(d, h);
    }
    if (svg_plot_hist_read(stored, h)) return 1;
    hist_zoom(h);
    return 0;
}

static void desc_draw(sb *s, int width, int height, hist *h, const double *sd,
                      const double *target)
{
    svg_plot_doc_begin(s, width, height, "Shape descriptors of the grains");
    int any_target = 0;
    for (int k = 0; k < 4; k++) any_target |= isfinite(target[k]);
    svg_stats_desc d = {svg_items_desc_name, h, sd, target, any_target ? "target" : NULL, 0};
    svg_stats_desc_panels(s, width, &d);
    svg_plot_doc_end(s);
}

int svg_stats2d_descriptors(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err)
{
    const json_t *d = json_object_get(json_object_get(in->summary, "stats"), "descriptors");
    dpass *p = calloc(1, sizeof *p); /* 16 KB of fine classes: not on a worker's stack */
    if (!p) {
        gpd_err_set(err, 500, "out of memory");
        return -1;
    }
    int rc = desc_read(p, in, err);
    if (rc < 0) {
        free(p);
        return -1;
    }
    hist h[4];
    double sd[4], target[4];
    int any = 0, oom = 0;
    for (int k = 0; k < 4; k++) {
        const json_t *o = json_object_get(d, svg_items_desc_name[k]);
        target[k] = svg_plot_jnum(json_object_get(o, "target"), NAN);
        int r = desc_of(p, rc == 0, o, k, &h[k], &sd[k]);
        if (r) memset(&h[k], 0, sizeof h[k]);
        oom |= r < 0;
        any |= r == 0;
    }
    free(p);
    if (any && !oom) desc_draw(&g->out, width, (int)lround(width * 0.75) + 20, h, sd, target);
    for (int k = 0; k < 4; k++) svg_plot_hist_free(&h[k]);
    if (oom) gpd_err_set(err, 500, "out of memory");
    else if (!any)
        gpd_err_set(err, 409, "view \"descriptors\" needs the descriptors: the spec did not ask for output \"descriptors\"");
    return any && !oom ? 0 : -1;
}
