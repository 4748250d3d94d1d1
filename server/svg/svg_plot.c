/* svg_plot.c -- the plot kit of the SVG views (see svg_plot.h). */
#include "svg/svg_plot.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ the XML writer */

void svg_plot_sb_printf(sb *s, const char *fmt, ...)
{
    if (s->oom) return;
    va_list ap;
    va_start(ap, fmt);
    char tmp[512];
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof tmp) {
        gpd_buf_add(s, tmp, (size_t)n);
        return;
    }
    if (gpd_buf_reserve(s, (size_t)n)) return;
    va_start(ap, fmt);
    vsnprintf(s->buf + s->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    s->len += (size_t)n;
}

void svg_plot_sb_puts(sb *s, const char *str) { gpd_buf_add(s, str, strlen(str)); }

/* The rounding is done on v * 10 unless that lies within 1e-6 of a half, where snprintf
 * decides (its exact decimal rounding), so the text is always printf's. */
int svg_plot_fmt_f1(char *buf, double v)
{
    double t = v * 10.0;
    if (!(fabs(t) < 1e15)) return snprintf(buf, F1_MAX, "%.1f", v);
    double fl = floor(t), fr = t - fl;
    if (fabs(fr - 0.5) < 1e-6) return snprintf(buf, F1_MAX, "%.1f", v);
    long long q = (long long)fl + (fr > 0.5);
    int neg = signbit(v) != 0;
    unsigned long long a = (unsigned long long)(q < 0 ? -q : q);
    char tmp[24];
    int n = 0;
    tmp[n++] = (char)('0' + a % 10);
    tmp[n++] = '.';
    a /= 10;
    do {
        tmp[n++] = (char)('0' + a % 10);
        a /= 10;
    } while (a);
    int k = 0;
    if (neg) buf[k++] = '-';
    while (n) buf[k++] = tmp[--n];
    buf[k] = 0;
    return k;
}

/* text content with XML escaping */
void svg_plot_sb_text(sb *s, const char *str)
{
    for (; *str; str++) {
        switch (*str) {
        case '<': svg_plot_sb_puts(s, "&lt;"); break;
        case '>': svg_plot_sb_puts(s, "&gt;"); break;
        case '&': svg_plot_sb_puts(s, "&amp;"); break;
        case '"': svg_plot_sb_puts(s, "&quot;"); break;
        default: gpd_buf_add(s, str, 1);
        }
    }
}

void svg_plot_text_at(sb *s, double x, double y, const char *anchor, const char *extra,
                    const char *str)
{
    svg_plot_sb_printf(s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\"%s%s>", x, y, anchor,
              extra && *extra ? " " : "", extra ? extra : "");
    svg_plot_sb_text(s, str);
    svg_plot_sb_puts(s, "</text>\n");
}

void svg_plot_text_up(sb *s, double x, double y, const char *str)
{
    svg_plot_sb_printf(s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f %.1f)\">",
              x, y, x, y);
    svg_plot_sb_text(s, str);
    svg_plot_sb_puts(s, "</text>\n");
}

void svg_plot_doc_begin(sb *s, int w, int h, const char *title)
{
    svg_plot_sb_puts(s, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    svg_plot_sb_printf(s,
              "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%d\" height=\"%d\" "
              "viewBox=\"0 0 %d %d\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n",
              w, h, w, h);
    svg_plot_sb_puts(s, "<title>");
    svg_plot_sb_text(s, title);
    svg_plot_sb_puts(s, "</title>\n");
    svg_plot_sb_printf(s, "<rect x=\"0\" y=\"0\" width=\"%d\" height=\"%d\" fill=\"#ffffff\"/>\n", w, h);
    svg_plot_text_at(s, w / 2.0, 22, "middle", "font-size=\"15\" font-weight=\"bold\"", title);
}

void svg_plot_doc_end(sb *s) { svg_plot_sb_puts(s, "</svg>\n"); }

/* ------------------------------------------------------------------ labels and colours */

void svg_plot_fmt_label(char *buf, size_t n, double v)
{
    if (fabs(v) < 1e-12) v = 0;
    snprintf(buf, n, "%.4g", v);
}

/* "m×10ᵏ" (m left out when 1), the exponent in superscript digits */
static void fmt_pow10(char *buf, size_t n, double v)
{
    static const char *const sup[10] = {"⁰", "¹", "²", "³", "⁴",
                                        "⁵", "⁶", "⁷", "⁸", "⁹"};
    int e = (int)floor(log10(fabs(v)) + 1e-9);
    double m = v / pow(10, e);
    char digits[16], out[96];
    int k = 0;
    if (fabs(fabs(m) - 1) > 1e-9) k = snprintf(out, sizeof out, "%.3g×", m);
    else if (m < 0) out[k++] = '-', out[k] = 0;
    k += snprintf(out + k, sizeof out - (size_t)k, "10%s", e < 0 ? "⁻" : "");
    snprintf(digits, sizeof digits, "%d", abs(e));
    for (const char *d = digits; *d && (size_t)k + 4 < sizeof out; d++)
        k += snprintf(out + k, sizeof out - (size_t)k, "%s", sup[*d - '0']);
    snprintf(buf, n, "%s", out);
}

void svg_plot_fmt_tick(char *buf, size_t n, double v, double step)
{
    step = fabs(step) > 0 ? fabs(step) : fabs(v);
    if (fabs(v) < step * 1e-9 || v == 0) {
        snprintf(buf, n, "0");
        return;
    }
    if (fabs(v) < 1e-4 || fabs(v) >= 1e6) {
        fmt_pow10(buf, n, v);
        return;
    }
    /* decimals of the step: 0.002 -> 3, 0.5 -> 1, 20 -> 0 (1-2-5 steps need no more) */
    int dec = (int)ceil(-log10(step) - 1e-9);
    if (dec < 0) dec = 0;
    if (dec > 12) dec = 12;
    snprintf(buf, n, "%.*f", dec, v);
}

double svg_plot_text_w(const char *str)
{
    double w = 0;
    for (const unsigned char *p = (const unsigned char *)str; *p; p++)
        if ((*p & 0xC0) != 0x80) w += 7; /* one per character, not per UTF-8 byte */
    return w;
}

/* ------------------------------------------------------------------ ticks */

/* 1 when the labels of t, at positions pos[] px along the axis, keep apart */
static int ticks_fit(const ticks *t, const double *pos, int horiz)
{
    double wprev = 0;
    for (int i = 0; i < t->n; i++) {
        char lab[64];
        svg_plot_fmt_tick(lab, sizeof lab, t->v[i], t->step);
        double w = svg_plot_text_w(lab);
        if (i > 0) {
            double need = horiz ? (w + wprev) / 2 + 6 : 16;
            if (fabs(pos[i] - pos[i - 1]) < need) return 0;
        }
        wprev = w;
    }
    return 1;
}

void svg_plot_lin_ticks(double lo, double hi, double px, int horiz, int nmax, ticks *t)
{
    t->n = 0;
    t->step = 0;
    if (!isfinite(lo) || !isfinite(hi)) return;
    if (!(hi > lo) || fabs(lo) / (hi - lo) > 1e12) { /* one value, or beyond doubles' steps */
        t->v[t->n++] = lo;
        if (hi > lo) t->v[t->n++] = hi;
        return;
    }
    if (nmax < 1) nmax = 1;
    double span = hi - lo, pos[TICKS_MAX];
    int e0 = (int)floor(log10(span / (nmax + 1)));
    static const double mant[3] = {1, 2, 5};
    for (int e = e0; e <= e0 + 3; e++)
        for (int i = 0; i < 3; i++) {
            double st = mant[i] * pow(10, e);
            double a = ceil(lo / st - 1e-9), b = floor(hi / st + 1e-9);
            if (b - a + 1 > nmax + 1 || b - a + 1 > TICKS_MAX || b < a) continue;
            t->n = 0;
            t->step = st;
            for (double k = a; k <= b; k++) {
                t->v[t->n] = k * st;
                pos[t->n] = (k * st - lo) / span * px;
                t->n++;
            }
            if (ticks_fit(t, pos, horiz) || t->n <= 1) return;
        }
}

void svg_plot_log_ticks(double lo, double hi, double px, int horiz, ticks *t)
{
    static const int sets[4][10] = {
        {1, 2, 3, 4, 5, 6, 7, 8, 9, 0}, {1, 2, 3, 5, 0}, {1, 2, 5, 0}, {1, 0}};
    static const int stride[9] = {1, 1, 1, 1, 2, 3, 5, 10, 20};
    t->n = 0;
    t->step = 0;
    if (!(lo > 0) || !(hi > lo) || !isfinite(hi)) {
        svg_plot_lin_ticks(lo, hi, px, horiz, 5, t);
        return;
    }
    int d0 = (int)floor(log10(lo) + 1e-9), d1 = (int)ceil(log10(hi) - 1e-9);
    double L = log10(hi / lo), pos[TICKS_MAX];
    for (int c = 0; c < 9; c++) {
        const int *m = sets[c < 3 ? c : 3];
        t->n = 0;
        for (int d = d0; d <= d1 && t->n < TICKS_MAX; d++) {
            if (((d % stride[c]) + stride[c]) % stride[c]) continue;
            for (int i = 0; m[i] && t->n < TICKS_MAX; i++) {
                double v = m[i] * pow(10, d);
                if (v < lo * (1 - 1e-9) || v > hi * (1 + 1e-9)) continue;
                pos[t->n] = log10(v / lo) / L * px;
                t->v[t->n++] = v;
            }
        }
        if (c == 0 && t->n < 2) break; /* less than two round values: linear ones */
        if (t->n >= 2 && ticks_fit(t, pos, horiz)) return;
        if (t->n < 2) break; /* sparser sets only lose more: linear ones */
    }
    svg_plot_lin_ticks(lo, hi, px, horiz, 4, t);
}

const char *svg_plot_area_unit(double hi, double *factor)
{
    if (!(hi < 0.1)) {
        *factor = 1;
        return "m²";
    }
    if (hi >= 1e-7) {
        *factor = 1e6;
        return "mm²";
    }
    *factor = 1e12;
    return "µm²";
}

/* viridis-like colour ramp, t in [0, 1] */
void svg_plot_ramp(double t, char *buf, size_t n)
{
    static const double st[6][3] = {{68, 1, 84},    {65, 68, 135},  {42, 120, 142},
                                    {34, 168, 132}, {122, 209, 81}, {253, 231, 37}};
    if (!(t >= 0)) t = 0;
    if (t > 1) t = 1;
    double u = t * 5;
    int k = (int)u;
    if (k > 4) k = 4;
    double f = u - k;
    int rgb[3];
    for (int c = 0; c < 3; c++) rgb[c] = (int)lround(st[k][c] + f * (st[k + 1][c] - st[k][c]));
    snprintf(buf, n, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
}

/* cyclic colour for an axial orientation in degrees (period 180) */
void svg_plot_cyclic(double deg, char *buf, size_t n)
{
    double h = fmod(deg + 90.0, 180.0);
    if (h < 0) h += 180;
    h *= 2; /* hue 0..360 */
    double c = 0.75, x = c * (1 - fabs(fmod(h / 60.0, 2) - 1)), m = 0.15;
    double r = 0, g = 0, b = 0;
    if (h < 60) { r = c; g = x; }
    else if (h < 120) { r = x; g = c; }
    else if (h < 180) { g = c; b = x; }
    else if (h < 240) { g = x; b = c; }
    else if (h < 300) { r = x; b = c; }
    else { r = c; b = x; }
    snprintf(buf, n, "#%02x%02x%02x", (int)lround((r + m) * 255), (int)lround((g + m) * 255),
             (int)lround((b + m) * 255));
}

/* ------------------------------------------------------------------ JSON numbers */

double svg_plot_jnum(const json_t *v, double dflt)
{
    return json_is_number(v) ? json_number_value(v) : dflt;
}

/* reads a numeric array (NULL-safe); returns a malloc'ed copy and its length, NULL if absent */
double *svg_plot_jarray(const json_t *a, size_t *n)
{
    *n = 0;
    if (!json_is_array(a) || json_array_size(a) == 0) return NULL;
    size_t m = json_array_size(a);
    double *v = malloc(m * sizeof *v);
    if (!v) return NULL;
    for (size_t i = 0; i < m; i++) v[i] = svg_plot_jnum(json_array_get(a, i), NAN);
    *n = m;
    return v;
}

/* ------------------------------------------------------------------ frames and axes */

/* "nice" tick step for about n ticks over [lo, hi] */
double svg_plot_nice_step(double lo, double hi, int n)
{
    double span = hi - lo;
    if (!(span > 0)) return 1;
    double raw = span / n, p = pow(10, floor(log10(raw))), f = raw / p;
    double nf = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
    return nf * p;
}

double svg_plot_fx(const frame *f, double x)
{
    if (f->xlog) return f->x0 + (log10(x) - log10(f->xmin)) / (log10(f->xmax) - log10(f->xmin)) * f->w;
    return f->x0 + (x - f->xmin) / (f->xmax - f->xmin) * f->w;
}

double svg_plot_fy(const frame *f, double y)
{
    return f->y0 + f->h - (y - f->ymin) / (f->ymax - f->ymin) * f->h;
}

/* a grid line across the frame at x (vertical) or y */
static void grid_line(sb *s, const frame *f, double at, int vertical)
{
    if (vertical)
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#dddddd\"/>\n", at,
                  f->y0, at, f->y0 + f->h);
    else
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#dddddd\"/>\n",
                  f->x0, at, f->x0 + f->w, at);
}

/* the x axis' ticks: round values labelled (ticks.h), on a log axis the other m x 10^k as
 * short unlabelled ticks where a decade is wide enough to show them */
static void x_ticks(sb *s, const frame *f, int grid)
{
    ticks t;
    if (f->xlog) svg_plot_log_ticks(f->xmin, f->xmax, f->w, 1, &t);
    else svg_plot_lin_ticks(f->xmin, f->xmax, f->w, 1, 7, &t);
    double yb = f->y0 + f->h;
    if (f->xlog && f->w / log10(f->xmax / f->xmin) >= 40) {
        int d0 = (int)floor(log10(f->xmin)), d1 = (int)ceil(log10(f->xmax));
        for (int d = d0; d <= d1; d++)
            for (int m = 1; m <= 9; m++) {
                double v = m * pow(10, d);
                if (v < f->xmin * (1 - 1e-9) || v > f->xmax * (1 + 1e-9)) continue;
                double x = svg_plot_fx(f, v);
                svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", x, yb,
                          x, yb + 3);
            }
    }
    for (int i = 0; i < t.n; i++) {
        double x = svg_plot_fx(f, t.v[i]);
        char lab[64];
        if (grid) grid_line(s, f, x, 1);
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", x, yb, x,
                  yb + 6);
        svg_plot_fmt_tick(lab, sizeof lab, t.v[i], t.step);
        svg_plot_text_at(s, x, yb + 19, "middle", "class=\"xtick\" stroke=\"none\"", lab);
    }
}

/* the y axis' ticks; returns the width of the widest label */
static double y_ticks(sb *s, const frame *f, int grid)
{
    ticks t;
    svg_plot_lin_ticks(fmin(f->ymin, f->ymax), fmax(f->ymin, f->ymax), f->h, 0, 6, &t);
    double wmax = 0;
    for (int i = 0; i < t.n; i++) {
        double y = svg_plot_fy(f, t.v[i]);
        char lab[64];
        if (grid) grid_line(s, f, y, 0);
        svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0 - 6, y,
                  f->x0, y);
        svg_plot_fmt_tick(lab, sizeof lab, t.v[i], t.step);
        wmax = fmax(wmax, svg_plot_text_w(lab));
        svg_plot_text_at(s, f->x0 - 9, y + 4, "end", "class=\"ytick\" stroke=\"none\"", lab);
    }
    return wmax;
}

/* axes with ticks and labels; grid lines when grid. The y label stands clear of the widest
 * tick label. */
void svg_plot_axes(sb *s, const frame *f, const char *xlabel, const char *ylabel, int grid)
{
    svg_plot_sb_puts(s, "<g class=\"axes\" stroke=\"#000000\" stroke-width=\"1\">\n");
    svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0, f->y0 + f->h,
              f->x0 + f->w, f->y0 + f->h);
    svg_plot_sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0, f->y0, f->x0,
              f->y0 + f->h);
    svg_plot_sb_puts(s, "</g>\n<g class=\"ticks\" stroke=\"#000000\">\n");
    x_ticks(s, f, grid);
    double wy = y_ticks(s, f, grid);
    svg_plot_sb_puts(s, "</g>\n");
    svg_plot_text_at(s, f->x0 + f->w / 2, f->y0 + f->h + 38, "middle", NULL, xlabel);
    svg_plot_text_up(s, f->x0 - 9 - wy - 10, f->y0 + f->h / 2, ylabel);
}

/* a legend item's symbol, 22 px wide from x, for a label on baseline yy */
static void legend_symbol(sb *s, double x, double yy, const legend_item *it)
{
    if (!strcmp(it->style, "bar"))
        svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"22\" height=\"10\" fill=\"%s\" "
                     "fill-opacity=\"0.7\" stroke=\"%s\"/>\n",
                  x, yy - 9, it->color, it->color);
    else
        svg_plot_sb_printf(s, "<path d=\"M%.1f %.1fh22\" stroke=\"%s\" stroke-width=\"2\"%s/>\n", x, yy - 4,
                  it->color, !strcmp(it->style, "dash") ? " stroke-dasharray=\"5 3\"" : "");
    if (!strcmp(it->style, "marker"))
        svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"6\" height=\"6\" fill=\"%s\"/>\n", x + 8,
                  yy - 7, it->color);
}

double svg_plot_legend_row(sb *s, double x, double y, const legend_item *it, int n)
{
    double x0 = x;
    svg_plot_sb_puts(s, "<g class=\"legend\">\n");
    for (int i = 0; i < n; i++) {
        legend_symbol(s, x, y, &it[i]);
        svg_plot_text_at(s, x + 28, y, "start", NULL, it[i].label);
        x += 28 + svg_plot_text_w(it[i].label) + 20;
    }
    svg_plot_sb_puts(s, "</g>\n");
    return x - x0 - 20;
}

double svg_plot_legend_w(const legend_item *it, int n)
{
    double w = 0;
    for (int i = 0; i < n; i++) w = fmax(w, svg_plot_text_w(it[i].label));
    return w + 46;
}

void svg_plot_legend(sb *s, double x, double y, const legend_item *it, int n)
{
    double w = svg_plot_legend_w(it, n) - 46;
    svg_plot_sb_printf(s, "<g class=\"legend\">\n<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%d\" "
                 "fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#999999\"/>\n",
              x, y, w + 46, 8 + 18 * n);
    for (int i = 0; i < n; i++) {
        double yy = y + 16 + 18 * i;
        legend_symbol(s, x + 8, yy, &it[i]);
        svg_plot_text_at(s, x + 38, yy, "start", NULL, it[i].label);
    }
    svg_plot_sb_puts(s, "</g>\n");
}

/* a marker as a small square path (not a <circle>, see the conventions above) */
void svg_plot_marker(sb *s, double x, double y, const char *color)
{
    svg_plot_sb_printf(s, "<path d=\"M%.1f %.1fh6v6h-6z\" fill=\"%s\"/>\n", x - 3, y - 3, color);
}

/* the colour bar's ticks: every 45 degrees for orientations, else round values */
static void colorbar_ticks(double lo, double hi, double h, int cyc, int logscale, ticks *t)
{
    if (cyc) {
        t->n = 5;
        t->step = 45;
        for (int k = 0; k < 5; k++) t->v[k] = -90 + 45 * k;
    } else if (logscale && lo > 0) {
        svg_plot_log_ticks(lo, hi, h, 0, t);
    } else {
        svg_plot_lin_ticks(lo, hi, h, 0, 6, t);
    }
}

void svg_plot_colorbar(sb *s, double x, double y, double h, double lo, double hi, int cyc,
                     int logscale, const char *label)
{
    svg_plot_sb_puts(s, "<defs><linearGradient id=\"cbar\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">\n");
    for (int k = 0; k <= 10; k++) {
        char c[16];
        if (cyc) svg_plot_cyclic(-90 + 18.0 * k, c, sizeof c);
        else svg_plot_ramp(k / 10.0, c, sizeof c);
        svg_plot_sb_printf(s, "<stop offset=\"%.1f\" stop-color=\"%s\"/>\n", k / 10.0, c);
    }
    svg_plot_sb_puts(s, "</linearGradient></defs>\n");
    svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"16\" height=\"%.1f\" fill=\"url(#cbar)\" stroke=\"#000000\"/>\n",
              x, y, h);
    if (cyc) lo = -90, hi = 90;
    ticks t;
    colorbar_ticks(lo, hi, h, cyc, logscale, &t);
    int lg = logscale && !cyc && lo > 0;
    double wmax = 0;
    for (int k = 0; k < t.n; k++) {
        double u = !(hi > lo) ? 0.5 : lg ? log(t.v[k] / lo) / log(hi / lo) : (t.v[k] - lo) / (hi - lo);
        double yy = y + h - u * h;
        char lab[64];
        svg_plot_fmt_tick(lab, sizeof lab, t.v[k], t.step);
        svg_plot_sb_printf(s, "<line class=\"cbar-tick\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000000\"/>\n",
                  x + 16, yy, x + 21, yy);
        svg_plot_text_at(s, x + 25, yy + 4, "start", "class=\"cbar-label\"", lab);
        wmax = fmax(wmax, svg_plot_text_w(lab));
    }
    svg_plot_text_up(s, x + 25 + wmax + 14, y + h / 2, label);
}

/* ------------------------------------------------------------------ maps */

void svg_plot_bounds_init(bounds *b)
{
    b->xmin = b->ymin = INFINITY;
    b->xmax = b->ymax = -INFINITY;
}

/* (comparisons, not fmin/fmax: these see every point of every pass, and the finite test
 * already keeps NaN out) */
void svg_plot_bounds_add(bounds *b, double x, double y)
{
    if (!isfinite(x) || !isfinite(y)) return;
    if (x < b->xmin) b->xmin = x;
    if (x > b->xmax) b->xmax = x;
    if (y < b->ymin) b->ymin = y;
    if (y > b->ymax) b->ymax = y;
}

void svg_plot_bounds_xy(bounds *b, const double *xy, size_t n)
{
    bounds r = *b;
    for (size_t i = 0; i < n; i++) {
        double x = xy[2 * i], y = xy[2 * i + 1];
        if (!isfinite(x) || !isfinite(y)) continue;
        if (x < r.xmin) r.xmin = x;
        if (x > r.xmax) r.xmax = x;
        if (y < r.ymin) r.ymin = y;
        if (y > r.ymax) r.ymax = y;
    }
    *b = r;
}

int svg_plot_bounds_ok(const bounds *b) { return b->xmax >= b->xmin && b->ymax >= b->ymin; }

/* a map frame with equal scales on both axes, fitting width px */
frame svg_plot_map_frame(bounds b, int width, int *height)
{
    double dx = b.xmax - b.xmin, dy = b.ymax - b.ymin;
    double d = fmax(dx, dy);
    if (!(d > 0)) d = 1;
    if (!(dx > 0)) { b.xmin -= d / 2; b.xmax += d / 2; dx = d; }
    if (!(dy > 0)) { b.ymin -= d / 2; b.ymax += d / 2; dy = d; }
    frame f;
    f.x0 = 80;
    f.y0 = 40;
    f.w = width - 80 - 130; /* room for the colour bar on the right */
    f.h = f.w * dy / dx;
    if (f.h > 2.0 * width) {
        f.h = 2.0 * width;
        f.w = f.h * dx / dy;
    }
    if (f.h < 120) f.h = 120, f.w = fmin(width - 210.0, f.h * dx / dy);
    f.xmin = b.xmin;
    f.xmax = b.xmin + dx * 1.0;
    f.ymin = b.ymin;
    f.ymax = b.ymax;
    /* keep the scales equal: widen the data range to the pixel aspect */
    double sx = f.w / dx, sy = f.h / dy, sc = fmin(sx, sy);
    double cx = (b.xmin + b.xmax) / 2, cy = (b.ymin + b.ymax) / 2;
    f.xmin = cx - f.w / sc / 2;
    f.xmax = cx + f.w / sc / 2;
    f.ymin = cy - f.h / sc / 2;
    f.ymax = cy + f.h / sc / 2;
    f.xlog = 0;
    *height = (int)ceil(f.y0 + f.h + 60);
    return f;
}

frame svg_plot_map_frame_in(bounds b, double x0, double y0, double w, double hmax)
{
    double dx = b.xmax - b.xmin, dy = b.ymax - b.ymin;
    if (!(dx > 0)) dx = dy > 0 ? dy : 1;
    if (!(dy > 0)) dy = dx;
    double sc = fmin(w / dx, hmax / dy);
    double cx = (b.xmin + b.xmax) / 2, cy = (b.ymin + b.ymax) / 2;
    frame f = {x0, y0, dx * sc, dy * sc, cx - dx / 2, cx + dx / 2, cy - dy / 2, cy + dy / 2, 0};
    return f;
}

/* "x,y x,y ..." of a ring of n points (xy: x0 y0 x1 y1 ...), decimated to min_px (a point
 * within min_px of the last one written, in both directions, is dropped, but a ring keeps at
 * least 3 points); returns points written */
size_t svg_plot_ring_points_xy(sb *s, const frame *f, const double *xy, size_t n, double min_px)
{
    size_t written = 0;
    double lx = NAN, ly = NAN;
    for (size_t i = 0; i < n; i++) {
        double x = svg_plot_fx(f, xy[2 * i]), y = svg_plot_fy(f, xy[2 * i + 1]);
        if (!isfinite(x) || !isfinite(y)) continue;
        int last = i + 1 == n;
        if (written && !last && fabs(x - lx) < min_px && fabs(y - ly) < min_px) continue;
        if (written && last && fabs(x - lx) < min_px && fabs(y - ly) < min_px && written >= 3) continue;
        char pt[2 * F1_MAX + 4];
        int k = 0;
        if (written) pt[k++] = ' ';
        k += svg_plot_fmt_f1(pt + k, x);
        pt[k++] = ',';
        k += svg_plot_fmt_f1(pt + k, y);
        gpd_buf_add(s, pt, (size_t)k);
        lx = x;
        ly = y;
        written++;
    }
    return written;
}

/* ------------------------------------------------------------------ histograms */

void svg_plot_hist_free(hist *h)
{
    free(h->edges);
    free(h->target);
    free(h->achieved);
    free(h->achieved2);
    memset(h, 0, sizeof *h);
}

/* reads {"edges", "target", "achieved"|"counts", "mean"}; 0 ok */
int svg_plot_hist_read(const json_t *o, hist *h)
{
    memset(h, 0, sizeof *h);
    if (!json_is_object(o)) return -1;
    size_t ne, nt, na;
    h->edges = svg_plot_jarray(json_object_get(o, "edges"), &ne);
    const json_t *a = json_object_get(o, "achieved");
    if (!a) a = json_object_get(o, "counts");
    h->achieved = svg_plot_jarray(a, &na);
    h->target = svg_plot_jarray(json_object_get(o, "target"), &nt);
    if (!h->edges || !h->achieved || ne != na + 1 || ne < 2) {
        svg_plot_hist_free(h);
        return -1;
    }
    if (h->target && nt != na) {
        free(h->target);
        h->target = NULL;
    }
    /* counts -> fractions */
    if (!json_object_get(o, "achieved")) {
        double sum = 0;
        for (size_t i = 0; i < na; i++) sum += h->achieved[i];
        if (sum > 0) for (size_t i = 0; i < na; i++) h->achieved[i] /= sum;
    }
    h->k = na;
    const json_t *m = json_object_get(o, "mean");
    if (json_is_number(m)) h->mean = json_number_value(m), h->has_mean = 1;
    return 0;
}

/* k equal classes over [lo, hi] of values; fractions */
int svg_plot_hist_from_values(const double *v, size_t n, size_t k, double lo, double hi, hist *h)
{
    memset(h, 0, sizeof *h);
    if (!n) return -1;
    if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
    h->edges = malloc((k + 1) * sizeof *h->edges);
    h->achieved = calloc(k, sizeof *h->achieved);
    if (!h->edges || !h->achieved) {
        svg_plot_hist_free(h);
        return -1;
    }
    for (size_t i = 0; i <= k; i++) h->edges[i] = lo + (hi - lo) * i / k;
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i])) continue;
        long c = (long)floor((v[i] - lo) / (hi - lo) * k);
        if (c < 0) c = 0;
        if (c >= (long)k) c = (long)k - 1;
        h->achieved[c] += 1;
        sum += v[i];
    }
    for (size_t i = 0; i < k; i++) h->achieved[i] /= n;
    h->k = k;
    h->mean = sum / n;
    h->has_mean = 1;
    return 0;
}

void svg_plot_minmax(const double *v, size_t n, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (isfinite(v[i])) *lo = fmin(*lo, v[i]), *hi = fmax(*hi, v[i]);
}

/* bars of h->achieved (and h->achieved2 as outlines) and h->target as a line with markers */
void svg_plot_draw_hist(sb *s, const frame *f, const hist *h, const char *bar_color)
{
    svg_plot_sb_printf(s, "<g class=\"bars\" fill=\"%s\" fill-opacity=\"0.7\" stroke=\"%s\">\n", bar_color, bar_color);
    for (size_t i = 0; i < h->k; i++) {
        double x0 = svg_plot_fx(f, h->edges[i]), x1 = svg_plot_fx(f, h->edges[i + 1]);
        double y = svg_plot_fy(f, fmax(f->ymin, fmin(f->ymax, h->achieved[i]))), y0 = svg_plot_fy(f, f->ymin);
        if (!isfinite(y)) continue;
        svg_plot_sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/>\n", x0 + 0.5, y,
                  fmax(0, x1 - x0 - 1), fmax(0, y0 - y));
    }
    svg_plot_sb_puts(s, "</g>\n");
    if (h->achieved2) {
        svg_plot_sb_puts(s, "<path class=\"achieved2\" fill=\"none\" stroke=\"#ff7f0e\" stroke-width=\"2\" d=\"");
        for (size_t i = 0; i < h->k; i++) {
            double x0 = svg_plot_fx(f, h->edges[i]), x1 = svg_plot_fx(f, h->edges[i + 1]);
            double y = svg_plot_fy(f, fmax(f->ymin, fmin(f->ymax, h->achieved2[i])));
            svg_plot_sb_printf(s, "%s%.1f %.1fH%.1f", i ? "L" : "M", x0, y, x1);
        }
        svg_plot_sb_puts(s, "\"/>\n");
    }
    if (h->target) {
        svg_plot_sb_puts(s, "<path class=\"target\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" d=\"");
        for (size_t i = 0; i < h->k; i++) {
            double xc = svg_plot_fx(f, 0.5 * (h->edges[i] + h->edges[i + 1]));
            svg_plot_sb_printf(s, "%s%.1f %.1f", i ? "L" : "M", xc, svg_plot_fy(f, fmin(f->ymax, h->target[i])));
        }
        svg_plot_sb_puts(s, "\"/>\n");
        for (size_t i = 0; i < h->k; i++)
            svg_plot_marker(s, svg_plot_fx(f, 0.5 * (h->edges[i] + h->edges[i + 1])), svg_plot_fy(f, fmin(f->ymax, h->target[i])),
                   "#d62728");
    }
}

static double hist_ymax(const hist *h)
{
    double m = 0;
    for (size_t i = 0; i < h->k; i++) {
        m = fmax(m, h->achieved[i]);
        if (h->target) m = fmax(m, h->target[i]);
        if (h->achieved2) m = fmax(m, h->achieved2[i]);
    }
    return m > 0 ? m * 1.1 : 1;
}

frame svg_plot_hist_frame(double x0, double y0, double w, double h, const hist *hs)
{
    frame f = {x0, y0, w, h, hs->edges[0], hs->edges[hs->k], 0, hist_ymax(hs), 0};
    if (!(f.xmax > f.xmin)) f.xmax = f.xmin + 1;
    return f;
}

/* ------------------------------------------------------------------ cumulative distributions */

void svg_plot_cdf_free(cdf_series *c)
{
    free(c->x);
    free(c->target);
    free(c->achieved);
    c->x = c->target = c->achieved = NULL;
    c->n = 0;
}

/* the x range of the curves (positive values only when for_log) */
void svg_plot_cdf_range(const cdf_series *c, int n, int for_log, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int k = 0; k < n; k++)
        for (size_t i = 0; i < c[k].n; i++)
            if (isfinite(c[k].x[i]) && (!for_log || c[k].x[i] > 0))
                *lo = fmin(*lo, c[k].x[i]), *hi = fmax(*hi, c[k].x[i]);
}

/* one curve: the target dashed, the achieved solid (the empirical CDF at the same points: its
 * jumps fall between them, so it is joined by lines as the target is) */
void svg_plot_cdf_path(sb *s, const frame *f, const cdf_series *c, int achieved)
{
    const double *y = achieved ? c->achieved : c->target;
    svg_plot_sb_printf(s, "<path class=\"cdf-%s %s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s d=\"",
              achieved ? "achieved" : "target", c->name, c->color,
              achieved ? "" : " stroke-dasharray=\"6 4\"");
    int first = 1;
    for (size_t i = 0; i < c->n; i++) {
        if (!isfinite(c->x[i]) || !isfinite(y[i]) || (f->xlog && !(c->x[i] > 0))) continue;
        double px = svg_plot_fx(f, c->x[i]), py = svg_plot_fy(f, fmax(0, fmin(1, y[i])));
        svg_plot_sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", px, py);
        first = 0;
    }
    svg_plot_sb_puts(s, "\"/>\n");
}
