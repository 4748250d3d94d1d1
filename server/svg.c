/* svg.c -- SVG pictures of a result. See svg.h for the views and the result fields read.
 *
 * Conventions: pixel coordinates printed with one or two decimals (bounded output), y axis of
 * data flipped so that up is up, legends and colour bars drawn with <rect>/<line>/<path> only so
 * that the <polygon> / <circle> elements of a picture are exactly its grains, cells, seeds or
 * sphere sections. Contours are decimated to about half a pixel (a 10,000-grain packing stays a
 * few MB). */
#include "svg.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export_internal.h" /* the pack's record readers (gp_xr_grain, gp_xr_point, ...) */

#define KIND_2D "fourier-voronoi-2d"
#define KIND_3D "spheres-3d"
#define VIEWS_2D "packing, cells, size, orientation, descriptors"
#define VIEWS_3D "section, psd"

/* ------------------------------------------------------------------------------------------ */
/* string builder */

typedef struct sb {
    char *buf;
    size_t len, cap;
    int oom;
} sb;

static void sb_grow(sb *s, size_t need)
{
    if (s->oom || s->len + need + 1 <= s->cap) return;
    size_t cap = s->cap ? s->cap : 4096;
    while (cap < s->len + need + 1) cap *= 2;
    char *b = realloc(s->buf, cap);
    if (!b) {
        s->oom = 1;
        return;
    }
    s->buf = b;
    s->cap = cap;
}

static void sb_printf(sb *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void sb_printf(sb *s, const char *fmt, ...)
{
    if (s->oom) return;
    va_list ap;
    va_start(ap, fmt);
    char tmp[512];
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof tmp) {
        sb_grow(s, (size_t)n);
        if (s->oom) return;
        memcpy(s->buf + s->len, tmp, (size_t)n + 1);
        s->len += (size_t)n;
        return;
    }
    sb_grow(s, (size_t)n);
    if (s->oom) return;
    va_start(ap, fmt);
    vsnprintf(s->buf + s->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    s->len += (size_t)n;
}

static void sb_puts(sb *s, const char *str)
{
    size_t n = strlen(str);
    sb_grow(s, n);
    if (s->oom) return;
    memcpy(s->buf + s->len, str, n + 1);
    s->len += n;
}

/* printf's "%.1f" of v, quickly (the points of a large picture are most of its time): the
 * rounding is done on v * 10 unless that lies within 1e-6 of a half, where snprintf decides
 * (its exact decimal rounding), so the text is always printf's. buf has F1_MAX bytes; returns
 * the length. */
#define F1_MAX 320 /* "%.1f" of -DBL_MAX is 312 bytes */
static int fmt_f1(char *buf, double v)
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

static void sb_mem(sb *s, const char *p, size_t n)
{
    sb_grow(s, n);
    if (s->oom) return;
    memcpy(s->buf + s->len, p, n);
    s->len += n;
    s->buf[s->len] = 0;
}

/* text content with XML escaping */
static void sb_text(sb *s, const char *str)
{
    for (; *str; str++) {
        switch (*str) {
        case '<': sb_puts(s, "&lt;"); break;
        case '>': sb_puts(s, "&gt;"); break;
        case '&': sb_puts(s, "&amp;"); break;
        case '"': sb_puts(s, "&quot;"); break;
        default: {
            char c[2] = {*str, 0};
            sb_puts(s, c);
        }
        }
    }
}

static void text_at(sb *s, double x, double y, const char *anchor, const char *extra,
                    const char *str)
{
    sb_printf(s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\"%s%s>", x, y, anchor,
              extra && *extra ? " " : "", extra ? extra : "");
    sb_text(s, str);
    sb_puts(s, "</text>\n");
}

/* ------------------------------------------------------------------------------------------ */
/* small helpers */

static void seterr(char *errbuf, size_t errlen, int *status, int code, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

static void seterr(char *errbuf, size_t errlen, int *status, int code, const char *fmt, ...)
{
    if (status) *status = code;
    if (!errbuf || !errlen) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(errbuf, errlen, fmt, ap);
    va_end(ap);
}

static double jnum(const json_t *v, double dflt)
{
    return json_is_number(v) ? json_number_value(v) : dflt;
}

/* reads a numeric array (NULL-safe); returns a malloc'ed copy and its length, NULL if absent */
static double *jarray(const json_t *a, size_t *n)
{
    *n = 0;
    if (!json_is_array(a) || json_array_size(a) == 0) return NULL;
    size_t m = json_array_size(a);
    double *v = malloc(m * sizeof *v);
    if (!v) return NULL;
    for (size_t i = 0; i < m; i++) v[i] = jnum(json_array_get(a, i), NAN);
    *n = m;
    return v;
}

static void fmt_label(char *buf, size_t n, double v)
{
    if (fabs(v) < 1e-12) v = 0;
    snprintf(buf, n, "%.4g", v);
}

/* viridis-like colour ramp, t in [0, 1] */
static void ramp(double t, char *buf, size_t n)
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
static void cyclic(double deg, char *buf, size_t n)
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

/* "nice" tick step for about n ticks over [lo, hi] */
static double nice_step(double lo, double hi, int n)
{
    double span = hi - lo;
    if (!(span > 0)) return 1;
    double raw = span / n, p = pow(10, floor(log10(raw))), f = raw / p;
    double nf = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
    return nf * p;
}

/* ------------------------------------------------------------------------------------------ */
/* plot frames */

typedef struct frame {
    double x0, y0, w, h;            /* pixels: left, top, width, height */
    double xmin, xmax, ymin, ymax;  /* data */
    int xlog;
} frame;

static double fx(const frame *f, double x)
{
    if (f->xlog) return f->x0 + (log10(x) - log10(f->xmin)) / (log10(f->xmax) - log10(f->xmin)) * f->w;
    return f->x0 + (x - f->xmin) / (f->xmax - f->xmin) * f->w;
}

static double fy(const frame *f, double y)
{
    return f->y0 + f->h - (y - f->ymin) / (f->ymax - f->ymin) * f->h;
}

static void doc_begin(sb *s, int w, int h, const char *title)
{
    sb_puts(s, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    sb_printf(s,
              "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%d\" height=\"%d\" "
              "viewBox=\"0 0 %d %d\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n",
              w, h, w, h);
    sb_puts(s, "<title>");
    sb_text(s, title);
    sb_puts(s, "</title>\n");
    sb_printf(s, "<rect x=\"0\" y=\"0\" width=\"%d\" height=\"%d\" fill=\"#ffffff\"/>\n", w, h);
    text_at(s, w / 2.0, 22, "middle", "font-size=\"15\" font-weight=\"bold\"", title);
}

static void doc_end(sb *s) { sb_puts(s, "</svg>\n"); }

/* axes with ticks and labels; grid lines when grid */
static void axes(sb *s, const frame *f, const char *xlabel, const char *ylabel, int grid)
{
    sb_puts(s, "<g class=\"axes\" stroke=\"#000000\" stroke-width=\"1\">\n");
    sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0, f->y0 + f->h,
              f->x0 + f->w, f->y0 + f->h);
    sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0, f->y0, f->x0,
              f->y0 + f->h);
    sb_puts(s, "</g>\n<g class=\"ticks\" stroke=\"#000000\">\n");
    char lab[64];
    /* x ticks */
    if (f->xlog) {
        int d0 = (int)floor(log10(f->xmin) + 1e-9), d1 = (int)ceil(log10(f->xmax) - 1e-9);
        for (int d = d0; d <= d1; d++)
            for (int m = 1; m <= 9; m++) {
                double v = m * pow(10, d);
                if (v < f->xmin * (1 - 1e-9) || v > f->xmax * (1 + 1e-9)) continue;
                double x = fx(f, v);
                int major = m == 1, labelled = m == 1 || m == 2 || m == 5;
                if (grid && major)
                    sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#dddddd\"/>\n",
                              x, f->y0, x, f->y0 + f->h);
                sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", x,
                          f->y0 + f->h, x, f->y0 + f->h + (major ? 6 : 3));
                if (labelled) {
                    fmt_label(lab, sizeof lab, v);
                    text_at(s, x, f->y0 + f->h + 19, "middle", "stroke=\"none\"", lab);
                }
            }
    } else {
        double st = nice_step(f->xmin, f->xmax, 6);
        for (double v = ceil(f->xmin / st - 1e-9) * st; v <= f->xmax + st * 1e-9; v += st) {
            double x = fx(f, v);
            if (grid)
                sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#dddddd\"/>\n",
                          x, f->y0, x, f->y0 + f->h);
            sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", x,
                      f->y0 + f->h, x, f->y0 + f->h + 6);
            fmt_label(lab, sizeof lab, v);
            text_at(s, x, f->y0 + f->h + 19, "middle", "stroke=\"none\"", lab);
        }
    }
    /* y ticks */
    double st = nice_step(f->ymin, f->ymax, 5);
    for (double v = ceil(f->ymin / st - 1e-9) * st; v <= f->ymax + st * 1e-9; v += st) {
        double y = fy(f, v);
        if (grid)
            sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#dddddd\"/>\n",
                      f->x0, y, f->x0 + f->w, y);
        sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", f->x0 - 6, y,
                  f->x0, y);
        fmt_label(lab, sizeof lab, v);
        text_at(s, f->x0 - 9, y + 4, "end", "stroke=\"none\"", lab);
    }
    sb_puts(s, "</g>\n");
    text_at(s, f->x0 + f->w / 2, f->y0 + f->h + 38, "middle", NULL, xlabel);
    sb_printf(s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f %.1f)\">",
              f->x0 - 52, f->y0 + f->h / 2, f->x0 - 52, f->y0 + f->h / 2);
    sb_text(s, ylabel);
    sb_puts(s, "</text>\n");
}

typedef struct legend_item {
    const char *label;
    const char *style; /* "bar", "line", "dash", "marker" */
    const char *color;
} legend_item;

static void legend(sb *s, double x, double y, const legend_item *it, int n)
{
    double w = 0;
    for (int i = 0; i < n; i++) w = fmax(w, 7.0 * strlen(it[i].label));
    sb_printf(s, "<g class=\"legend\">\n<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%d\" "
                 "fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#999999\"/>\n",
              x, y, w + 46, 8 + 18 * n);
    for (int i = 0; i < n; i++) {
        double yy = y + 16 + 18 * i;
        if (!strcmp(it[i].style, "bar"))
            sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"22\" height=\"10\" fill=\"%s\" "
                         "fill-opacity=\"0.7\" stroke=\"%s\"/>\n",
                      x + 8, yy - 9, it[i].color, it[i].color);
        else
            sb_printf(s, "<path d=\"M%.1f %.1fh22\" stroke=\"%s\" stroke-width=\"2\"%s/>\n", x + 8,
                      yy - 4, it[i].color,
                      !strcmp(it[i].style, "dash") ? " stroke-dasharray=\"5 3\"" : "");
        if (!strcmp(it[i].style, "marker"))
            sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"6\" height=\"6\" fill=\"%s\"/>\n",
                      x + 16, yy - 7, it[i].color);
        text_at(s, x + 38, yy, "start", NULL, it[i].label);
    }
    sb_puts(s, "</g>\n");
}

/* a marker as a small square path (not a <circle>, see the conventions above) */
static void marker(sb *s, double x, double y, const char *color)
{
    sb_printf(s, "<path d=\"M%.1f %.1fh6v6h-6z\" fill=\"%s\"/>\n", x - 3, y - 3, color);
}

/* ------------------------------------------------------------------------------------------ */
/* 2D geometry */

typedef struct bounds {
    double xmin, xmax, ymin, ymax;
} bounds;

static void bounds_init(bounds *b)
{
    b->xmin = b->ymin = INFINITY;
    b->xmax = b->ymax = -INFINITY;
}

static void bounds_add(bounds *b, double x, double y)
{
    if (!isfinite(x) || !isfinite(y)) return;
    b->xmin = fmin(b->xmin, x);
    b->xmax = fmax(b->xmax, x);
    b->ymin = fmin(b->ymin, y);
    b->ymax = fmax(b->ymax, y);
}

static void bounds_ring(bounds *b, const json_t *ring)
{
    size_t i;
    const json_t *p;
    json_array_foreach(ring, i, p) {
        bounds_add(b, jnum(json_array_get(p, 0), NAN), jnum(json_array_get(p, 1), NAN));
    }
}

static void bounds_xy(bounds *b, const double *xy, size_t n)
{
    for (size_t i = 0; i < n; i++) bounds_add(b, xy[2 * i], xy[2 * i + 1]);
}

static int bounds_ok(const bounds *b) { return b->xmax >= b->xmin && b->ymax >= b->ymin; }

/* a map frame with equal scales on both axes, fitting width px */
static frame map_frame(bounds b, int width, int *height)
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

/* "x,y x,y ..." of a ring of n points (xy: x0 y0 x1 y1 ...), decimated to min_px (a point
 * within min_px of the last one written, in both directions, is dropped, but a ring keeps at
 * least 3 points); returns points written */
static size_t ring_points_xy(sb *s, const frame *f, const double *xy, size_t n, double min_px)
{
    size_t written = 0;
    double lx = NAN, ly = NAN;
    for (size_t i = 0; i < n; i++) {
        double x = fx(f, xy[2 * i]), y = fy(f, xy[2 * i + 1]);
        if (!isfinite(x) || !isfinite(y)) continue;
        int last = i + 1 == n;
        if (written && !last && fabs(x - lx) < min_px && fabs(y - ly) < min_px) continue;
        if (written && last && fabs(x - lx) < min_px && fabs(y - ly) < min_px && written >= 3) continue;
        char pt[2 * F1_MAX + 4];
        int k = 0;
        if (written) pt[k++] = ' ';
        k += fmt_f1(pt + k, x);
        pt[k++] = ',';
        k += fmt_f1(pt + k, y);
        sb_mem(s, pt, (size_t)k);
        lx = x;
        ly = y;
        written++;
    }
    return written;
}

/* the same for a JSON ring [[x,y],...] */
static size_t ring_points(sb *s, const frame *f, const json_t *ring, double min_px)
{
    size_t n = json_array_size(ring);
    if (!n) return 0;
    double *xy = malloc(2 * n * sizeof *xy);
    if (!xy) {
        s->oom = 1;
        return 0;
    }
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(ring, i);
        xy[2 * i] = jnum(json_array_get(p, 0), NAN);
        xy[2 * i + 1] = jnum(json_array_get(p, 1), NAN);
    }
    size_t w = ring_points_xy(s, f, xy, n, min_px);
    free(xy);
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

/* vertical colour bar with a gradient; cyc = orientation colours */
static void colorbar(sb *s, double x, double y, double h, double lo, double hi, int cyc,
                     int logscale, const char *label)
{
    sb_puts(s, "<defs><linearGradient id=\"cbar\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">\n");
    for (int k = 0; k <= 10; k++) {
        char c[16];
        if (cyc) cyclic(-90 + 18.0 * k, c, sizeof c);
        else ramp(k / 10.0, c, sizeof c);
        sb_printf(s, "<stop offset=\"%.1f\" stop-color=\"%s\"/>\n", k / 10.0, c);
    }
    sb_puts(s, "</linearGradient></defs>\n");
    sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"16\" height=\"%.1f\" fill=\"url(#cbar)\" stroke=\"#000000\"/>\n",
              x, y, h);
    for (int k = 0; k <= 4; k++) {
        double t = k / 4.0;
        double v = logscale ? lo * pow(hi / lo, t) : lo + t * (hi - lo);
        char lab[64];
        fmt_label(lab, sizeof lab, v);
        double yy = y + h - t * h;
        sb_printf(s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000000\"/>\n",
                  x + 16, yy, x + 20, yy);
        text_at(s, x + 23, yy + 4, "start", NULL, lab);
    }
    double lx = x + 82, ly = y + h / 2;
    sb_printf(s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f %.1f)\">",
              lx, ly, lx, ly);
    sb_text(s, label);
    sb_puts(s, "</text>\n");
}

static char *finish(sb *s, size_t *len, int *status, char *errbuf, size_t errlen)
{
    if (s->oom) {
        free(s->buf);
        seterr(errbuf, errlen, status, 500, "out of memory while drawing");
        return NULL;
    }
    if (len) *len = s->len;
    if (status) *status = 200;
    return s->buf;
}

/* ------------------------------------------------------------------------------------------ */
/* item sources (svg.h): the geometry of a result, one item at a time */

static const char *const PART_NAME[3] = {"grains", "cells", "spheres"};
static const char *const DESC_NAME[4] = {"elongation", "roundness", "circularity", "regularity"};

/* the current item; a number that is absent (or null, or not finite) is NaN */
typedef struct item {
    double *xy;               /* grains: the contour; cells: the polygons, one after the other */
    size_t npts, cap;         /* points in xy, room in xy (points) */
    size_t *rings;            /* cells: points of each polygon */
    size_t nrings, rcap;
    double area, orientation_deg, desc[4], seed[2];
    double q[4];              /* spheres: x, y, z, r */
} item;

struct gp_svg_items {
    gp_svg_part part;
    int (*rewind)(gp_svg_items *it);
    int (*next)(gp_svg_items *it); /* 1: an item in cur, 0: the end, -1: failed */
    item cur;
    const json_t *arr;  /* json */
    size_t idx;
    js_scan *js;        /* scan */
    uint64_t off;
    gp_export *e, *ep;  /* pack: its grain or sphere records, its contour points (a reader of
                         * its own, so that both are read in order, each through its cache) */
    uint64_t k;
};

static int pts_room(item *c, size_t n)
{
    if (n <= c->cap) return 0;
    size_t cap = c->cap ? c->cap : 256;
    while (cap < n) cap *= 2;
    double *xy = realloc(c->xy, 2 * cap * sizeof *xy);
    if (!xy) return -1;
    c->xy = xy;
    c->cap = cap;
    return 0;
}

static void item_clear(item *c)
{
    c->npts = c->nrings = 0;
    c->area = c->orientation_deg = NAN;
    for (int k = 0; k < 4; k++) c->desc[k] = c->q[k] = NAN;
    c->seed[0] = c->seed[1] = NAN;
}

/* appends the points of a JSON ring; -1 on out of memory */
static int item_ring(item *c, const json_t *ring)
{
    size_t n = json_array_size(ring);
    if (pts_room(c, c->npts + n)) return -1;
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(ring, i);
        c->xy[2 * (c->npts + i)] = jnum(json_array_get(p, 0), NAN);
        c->xy[2 * (c->npts + i) + 1] = jnum(json_array_get(p, 1), NAN);
    }
    c->npts += n;
    return 0;
}

/* one element of a result array (as api.md writes it) into the item; -1 on out of memory */
static int item_from_json(gp_svg_part part, item *c, const json_t *e)
{
    item_clear(c);
    if (part == GP_SVG_SPHERES) {
        for (int a = 0; a < 4; a++) c->q[a] = jnum(json_array_get(e, (size_t)a), NAN);
        return 0;
    }
    c->area = jnum(json_object_get(e, "area"), NAN);
    c->orientation_deg = jnum(json_object_get(e, "orientation_deg"), NAN);
    if (part == GP_SVG_GRAINS) {
        const json_t *d = json_object_get(e, "descriptors");
        for (int k = 0; k < 4; k++) c->desc[k] = jnum(json_object_get(d, DESC_NAME[k]), NAN);
        return item_ring(c, json_object_get(e, "contour"));
    }
    const json_t *sd = json_object_get(e, "seed");
    c->seed[0] = jnum(json_array_get(sd, 0), NAN);
    c->seed[1] = jnum(json_array_get(sd, 1), NAN);
    const json_t *polys = json_object_get(e, "polygons");
    size_t np = json_array_size(polys);
    if (np > c->rcap) {
        size_t *r = realloc(c->rings, np * sizeof *r);
        if (!r) return -1;
        c->rings = r;
        c->rcap = np;
    }
    for (size_t j = 0; j < np; j++) {
        size_t before = c->npts;
        if (item_ring(c, json_array_get(polys, j))) return -1;
        c->rings[c->nrings++] = c->npts - before;
    }
    return 0;
}

static gp_svg_items *items_new(gp_svg_part part)
{
    if ((unsigned)part > GP_SVG_SPHERES) return NULL;
    gp_svg_items *it = calloc(1, sizeof *it);
    if (it) it->part = part;
    return it;
}

void gp_svg_items_close(gp_svg_items *it)
{
    if (!it) return;
    js_close(it->js);
    gp_export_destroy(it->e);
    gp_export_destroy(it->ep);
    free(it->cur.xy);
    free(it->cur.rings);
    free(it);
}

/* -- in memory */
static int json_rewind(gp_svg_items *it)
{
    it->idx = 0;
    return 0;
}

static int json_next(gp_svg_items *it)
{
    if (it->idx >= json_array_size(it->arr)) return 0;
    return item_from_json(it->part, &it->cur, json_array_get(it->arr, it->idx++)) ? -1 : 1;
}

gp_svg_items *gp_svg_items_json(const json_t *array, gp_svg_part part)
{
    if (!json_is_array(array)) return NULL;
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    it->arr = array;
    it->rewind = json_rewind;
    it->next = json_next;
    return it;
}

/* -- an element's text read straight into the item (the scan source): the same values as
 * item_from_json() gives for the parsed element, without building a JSON tree (three times
 * faster on cells, which are read in three passes). A number is read with strtod (the C
 * locale: the daemon never sets another), null and any other value where a number belongs
 * give NaN, unknown members are skipped. -1 on text that is not JSON. */
typedef struct pp {
    const char *p, *e;
} pp;

static void pp_ws(pp *q)
{
    while (q->p < q->e && (*q->p == ' ' || *q->p == '\n' || *q->p == '\r' || *q->p == '\t')) q->p++;
}

/* passes over one value of any type */
static int pp_skip(pp *q)
{
    pp_ws(q);
    if (q->p >= q->e) return -1;
    char c = *q->p;
    if (c == '"' || c == '[' || c == '{') {
        int depth = 0, in_str = 0;
        for (; q->p < q->e; q->p++) {
            char ch = *q->p;
            if (in_str) {
                if (ch == '\\') q->p++;
                else if (ch == '"') {
                    in_str = 0;
                    if (depth == 0) {
                        q->p++;
                        return 0;
                    }
                }
            } else if (ch == '"') in_str = 1;
            else if (ch == '[' || ch == '{') depth++;
            else if ((ch == ']' || ch == '}') && --depth == 0) {
                q->p++;
                return 0;
            }
        }
        return -1;
    }
    const char *s = q->p;
    while (q->p < q->e && !strchr(" \n\r\t,]}:", *q->p)) q->p++;
    return q->p > s ? 0 : -1;
}

/* a number (or NaN for null or any other value) */
static int pp_num(pp *q, double *v)
{
    pp_ws(q);
    *v = NAN;
    if (q->p >= q->e) return -1;
    char c = *q->p;
    if (c == '-' || (c >= '0' && c <= '9')) {
        char *end;
        double x = strtod(q->p, &end);
        if (end == q->p || end > q->e) return -1;
        q->p = end;
        *v = x;
        return 0;
    }
    return pp_skip(q);
}

/* the next element of an array whose '[' was passed: 1 (q at the element), 0 after ']', -1 */
static int pp_next(pp *q, int *first)
{
    pp_ws(q);
    if (q->p >= q->e) return -1;
    if (*q->p == ']') {
        q->p++;
        return 0;
    }
    if (!*first) {
        if (*q->p != ',') return -1;
        q->p++;
        pp_ws(q);
    }
    *first = 0;
    return 1;
}

/* 1 and past '[' when an array starts here */
static int pp_open(pp *q, char bracket)
{
    pp_ws(q);
    if (q->p < q->e && *q->p == bracket) {
        q->p++;
        return 1;
    }
    return 0;
}

/* up to n numbers of an array (NaN for the missing ones and for a value that is no array) */
static int pp_nums(pp *q, double *v, int n)
{
    for (int i = 0; i < n; i++) v[i] = NAN;
    if (!pp_open(q, '[')) return pp_skip(q);
    int first = 1, r, i = 0;
    while ((r = pp_next(q, &first)) > 0) {
        double x;
        if (pp_num(q, &x)) return -1;
        if (i < n) v[i] = x;
        i++;
    }
    return r;
}

/* a ring [[x,y],...] appended to the item's points (no points when it is no array) */
static int pp_ring(pp *q, item *c)
{
    if (!pp_open(q, '[')) return pp_skip(q);
    int first = 1, r;
    while ((r = pp_next(q, &first)) > 0) {
        if (pts_room(c, c->npts + 1)) return -1;
        if (pp_nums(q, c->xy + 2 * c->npts, 2)) return -1;
        c->npts++;
    }
    return r;
}

/* the next member of an object whose '{' was passed: 1 with its key (escapes kept) and q at
 * its value, 0 after '}', -1 */
static int pp_member(pp *q, int *first, const char **key, size_t *klen)
{
    pp_ws(q);
    if (q->p >= q->e) return -1;
    if (*q->p == '}') {
        q->p++;
        return 0;
    }
    if (!*first) {
        if (*q->p != ',') return -1;
        q->p++;
        pp_ws(q);
    }
    *first = 0;
    if (q->p >= q->e || *q->p != '"') return -1;
    const char *k = ++q->p;
    while (q->p < q->e && *q->p != '"') q->p += *q->p == '\\' ? 2 : 1;
    if (q->p >= q->e) return -1;
    *key = k;
    *klen = (size_t)(q->p - k);
    q->p++;
    pp_ws(q);
    if (q->p >= q->e || *q->p != ':') return -1;
    q->p++;
    return 1;
}

static int key_is(const char *k, size_t n, const char *name)
{
    return strlen(name) == n && !memcmp(k, name, n);
}

static int item_parse(gp_svg_part part, item *c, const char *text, size_t len)
{
    item_clear(c);
    pp q = {text, text + len};
    if (part == GP_SVG_SPHERES) return pp_nums(&q, c->q, 4);
    if (!pp_open(&q, '{')) return pp_skip(&q);
    int first = 1, r;
    const char *k;
    size_t kl;
    while ((r = pp_member(&q, &first, &k, &kl)) > 0) {
        int rc;
        if (key_is(k, kl, "area")) rc = pp_num(&q, &c->area);
        else if (key_is(k, kl, "orientation_deg")) rc = pp_num(&q, &c->orientation_deg);
        else if (part == GP_SVG_GRAINS && key_is(k, kl, "contour")) {
            c->npts = 0;
            rc = pp_ring(&q, c);
        } else if (part == GP_SVG_GRAINS && key_is(k, kl, "descriptors")) {
            for (int j = 0; j < 4; j++) c->desc[j] = NAN;
            if (!pp_open(&q, '{')) {
                rc = pp_skip(&q);
            } else {
                int f2 = 1, r2;
                const char *k2;
                size_t kl2;
                while ((r2 = pp_member(&q, &f2, &k2, &kl2)) > 0) {
                    int j = 0;
                    while (j < 4 && !key_is(k2, kl2, DESC_NAME[j])) j++;
                    if (j < 4 ? pp_num(&q, &c->desc[j]) : pp_skip(&q)) return -1;
                }
                rc = r2;
            }
        } else if (part == GP_SVG_CELLS && key_is(k, kl, "seed")) {
            rc = pp_nums(&q, c->seed, 2);
        } else if (part == GP_SVG_CELLS && key_is(k, kl, "polygons")) {
            c->npts = c->nrings = 0;
            if (!pp_open(&q, '[')) {
                rc = pp_skip(&q);
            } else {
                int f2 = 1, r2;
                while ((r2 = pp_next(&q, &f2)) > 0) {
                    if (c->nrings == c->rcap) {
                        size_t nc = c->rcap ? 2 * c->rcap : 8;
                        size_t *nr = realloc(c->rings, nc * sizeof *nr);
                        if (!nr) return -1;
                        c->rings = nr;
                        c->rcap = nc;
                    }
                    size_t before = c->npts;
                    if (pp_ring(&q, c)) return -1;
                    c->rings[c->nrings++] = c->npts - before;
                }
                rc = r2;
            }
        } else {
            rc = pp_skip(&q);
        }
        if (rc) return -1;
    }
    return r;
}

/* -- an array of a JSON text, element by element */
static int scan_rewind(gp_svg_items *it)
{
    return js_array_begin(it->js, it->off);
}

static int scan_next(gp_svg_items *it)
{
    uint64_t a, b;
    int r = js_array_next(it->js, &a, &b);
    if (r <= 0) return r;
    const char *t = js_span(it->js, a, b);
    if (!t) return -1;
    return item_parse(it->part, &it->cur, t, (size_t)(b - a)) ? -1 : 1;
}

gp_svg_items *gp_svg_items_scan(const js_source *text, uint64_t off, gp_svg_part part)
{
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    it->js = js_open(text);
    if (!it->js) {
        gp_svg_items_close(it);
        return NULL;
    }
    it->off = off;
    it->rewind = scan_rewind;
    it->next = scan_next;
    return it;
}

/* -- an export pack */
static int pack_rewind(gp_svg_items *it)
{
    it->k = 0;
    return 0;
}

static int pack_next(gp_svg_items *it)
{
    gp_export *e = it->e;
    item *c = &it->cur;
    if (it->k >= e->nitems) return 0;
    uint64_t k = it->k++;
    item_clear(c);
    if (it->part == GP_SVG_SPHERES) {
        if (gp_xr_sphere(e, k, c->q)) return -1;
        return 1;
    }
    gp_xgrain g;
    if (gp_xr_grain(e, k, &g) || pts_room(c, (size_t)g.point_count)) return -1;
    for (uint64_t i = 0; i < g.point_count; i++)
        if (gp_xr_point(it->ep, g.point_first + i, c->xy + 2 * i)) return -1;
    c->npts = (size_t)g.point_count;
    c->area = g.area;
    c->orientation_deg = g.orientation_deg;
    c->desc[0] = g.elongation;
    c->desc[1] = g.roundness;
    c->desc[2] = g.circularity;
    c->desc[3] = g.regularity;
    /* the pack keeps raw doubles; the JSON result writes a non-finite one as null */
    if (!isfinite(c->area)) c->area = NAN;
    if (!isfinite(c->orientation_deg)) c->orientation_deg = NAN;
    for (int j = 0; j < 4; j++)
        if (!isfinite(c->desc[j])) c->desc[j] = NAN;
    for (size_t i = 0; i < 2 * c->npts; i++)
        if (!isfinite(c->xy[i])) c->xy[i] = NAN;
    return 1;
}

gp_svg_items *gp_svg_items_pack(const gp_export_source *pack, gp_svg_part part)
{
    if (part == GP_SVG_CELLS) return NULL;
    gp_svg_items *it = items_new(part);
    if (!it) return NULL;
    gp_error err;
    /* any format opens the pack and checks its header; only the record readers are used */
    if (gp_export_open(GP_EXPORT_CSV, pack, &it->e, &err) ||
        it->e->dim != (part == GP_SVG_SPHERES ? 3 : 2) ||
        (part == GP_SVG_GRAINS && gp_export_open(GP_EXPORT_CSV, pack, &it->ep, &err))) {
        gp_svg_items_close(it);
        return NULL;
    }
    it->rewind = pack_rewind;
    it->next = pack_next;
    return it;
}

/* ------------------------------------------------------------------------------------------ */
/* the rendering stream */

#define STEP_BYTES (16u * 1024u) /* a step stages about this much of the document */

struct gp_svg {
    sb out;                    /* staged text; out.buf[pos..len) not handed out yet */
    size_t pos;
    int (*step)(gp_svg *g);    /* stages the next part: 0 more, 1 that was the last, -1 failed;
                                * NULL once everything is staged */
    char err[200];
    /* the geometry views */
    gp_svg_items *items;
    int section;
    frame f;
    int by_orient, logscale;
    double amin, amax, min_px, z, dmin, dmax, scale, seed_r;
    sb mid, tail;              /* between the two loops (cells), after the last one */
};

static gp_svg_items *open_items(const gp_svg_input *in, gp_svg_part part, int *failed)
{
    *failed = 0;
    if (in->open) return in->open(in->user, part, failed);
    const json_t *a = json_object_get(in->summary, PART_NAME[part]);
    gp_svg_items *it = gp_svg_items_json(a, part);
    if (!it && json_is_array(a)) *failed = 1;
    return it;
}

/* a pass over the items begins; -1 (with the message) when the source cannot go back */
static int pass_begin(gp_svg *g)
{
    if (g->items->rewind(g->items) == 0) return 0;
    snprintf(g->err, sizeof g->err, "reading the %s failed", PART_NAME[g->items->part]);
    return -1;
}

static int pass_failed(gp_svg *g)
{
    snprintf(g->err, sizeof g->err, "reading the %s failed", PART_NAME[g->items->part]);
    return -1;
}

/* values of one field of a part's items (NaN ones left out); NULL when none. field: 0 area,
 * 1 orientation, 2..5 the descriptors. *failed when the items could not be read. */
static double *collect_items(const gp_svg_input *in, gp_svg_part part, int field, size_t *n,
                             int *failed)
{
    *n = 0;
    gp_svg_items *it = open_items(in, part, failed);
    if (!it) return NULL;
    size_t cap = 0;
    double *v = NULL;
    int r;
    if (it->rewind(it)) r = -1;
    else
        while ((r = it->next(it)) > 0) {
            const item *c = &it->cur;
            double x = field == 0 ? c->area : field == 1 ? c->orientation_deg : c->desc[field - 2];
            if (isnan(x)) continue;
            if (*n == cap) {
                size_t nc = cap ? 2 * cap : 1024;
                double *nv = realloc(v, nc * sizeof *nv);
                if (!nv) {
                    r = -1;
                    break;
                }
                v = nv;
                cap = nc;
            }
            v[(*n)++] = x;
        }
    gp_svg_items_close(it);
    if (r < 0) *failed = 1;
    if (r < 0 || !*n) {
        free(v);
        *n = 0;
        return NULL;
    }
    return v;
}

/* ------------------------------------------------------------------------------------------ */
/* 2D views */

/* the packing: grains coloured by area or orientation. Pass 1: bounds, area range, count;
 * then the head; step_packing draws the grains and stages the tail. */
static int step_packing(gp_svg *g)
{
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const item *c = &g->items->cur;
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
    if (r < 0) return pass_failed(g);
    if (r > 0) return 0;
    sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

static int view_packing(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                        int *status, char *eb, size_t el)
{
    const json_t *res = in->summary;
    const char *color = opt && opt->color && *opt->color ? opt->color : "size";
    int by_orient = !strcmp(color, "orientation");
    if (!by_orient && strcmp(color, "size") != 0) {
        seterr(eb, el, status, 400, "unknown color \"%s\"; valid: size, orientation", color);
        return -1;
    }
    int failed;
    g->items = open_items(in, GP_SVG_GRAINS, &failed);
    if (!g->items) {
        if (failed) seterr(eb, el, status, 500, "cannot read the grains of the result");
        else seterr(eb, el, status, 409, "view \"packing\" needs the grains: the spec did not ask for output \"grains\"");
        return -1;
    }
    bounds b;
    bounds_init(&b);
    container_bounds(&b, json_object_get(res, "container"));
    size_t ng = 0;
    double amin = INFINITY, amax = -INFINITY;
    int r = pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const item *c = &g->items->cur;
            ng++;
            bounds_xy(&b, c->xy, c->npts);
            if (c->area > 0) amin = fmin(amin, c->area), amax = fmax(amax, c->area);
        }
    if (r < 0) {
        seterr(eb, el, status, 500, "cannot read the grains of the result");
        return -1;
    }
    if (!bounds_ok(&b)) b.xmin = b.ymin = 0, b.xmax = b.ymax = 1;
    if (!(amax >= amin)) amin = amax = 1;
    int logscale = amax > 10 * amin;
    int height;
    frame f = map_frame(b, width, &height);
    sb *s = &g->out;
    char title[160];
    const json_t *stats = json_object_get(res, "stats");
    const json_t *sfj = json_object_get(stats, "solid_fraction");
    if (json_is_object(sfj)) sfj = json_object_get(sfj, "achieved"); /* {"target", "achieved"} */
    double sf = jnum(sfj, NAN);
    if (isfinite(sf))
        snprintf(title, sizeof title, "Packing: %zu grains, solid fraction %.3f", ng, sf);
    else
        snprintf(title, sizeof title, "Packing: %zu grains", ng);
    doc_begin(s, width, height, title);
    axes(s, &f, "x (m)", "y (m)", 0);
    sb_puts(s, "<g class=\"grains\" stroke=\"#222222\" stroke-width=\"0.4\">\n");
    sb_puts(&g->tail, "</g>\n");
    container_outline(&g->tail, &f, json_object_get(res, "container"));
    double cbx = f.x0 + f.w + 20, cbh = fmin(f.h - 30, 300);
    if (by_orient) colorbar(&g->tail, cbx, f.y0 + 24, cbh, -90, 90, 1, 0, "orientation (deg)");
    else colorbar(&g->tail, cbx, f.y0 + 24, cbh, amin, amax, 0, logscale, "area (m²)");
    doc_end(&g->tail);
    g->f = f;
    g->by_orient = by_orient;
    g->logscale = logscale;
    g->amin = amin;
    g->amax = amax;
    g->min_px = ng > 2000 ? 0.6 : 0.3;
    if (pass_begin(g)) {
        seterr(eb, el, status, 500, "cannot read the grains of the result");
        return -1;
    }
    g->step = step_packing;
    return 0;
}

/* the cells and their seeds: pass 1 bounds, area range and count; the head; step_cells draws
 * the polygons (section 0), then the seeds (section 1, a second pass), then the tail */
static int step_cells(gp_svg *g)
{
    size_t start = g->out.len;
    int r = 1;
    while (g->out.len - start < STEP_BYTES && (r = g->items->next(g->items)) > 0) {
        const item *c = &g->items->cur;
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
    if (r < 0) return pass_failed(g);
    if (r > 0) return 0;
    if (g->section == 0) {
        sb_puts(&g->out, g->mid.buf ? g->mid.buf : "");
        g->section = 1;
        return pass_begin(g);
    }
    sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

static int view_cells(gp_svg *g, const gp_svg_input *in, int width, int *status, char *eb,
                      size_t el)
{
    const json_t *res = in->summary;
    int failed;
    g->items = open_items(in, GP_SVG_CELLS, &failed);
    if (!g->items) {
        if (failed) seterr(eb, el, status, 500, "cannot read the cells of the result");
        else seterr(eb, el, status, 409, "view \"cells\" needs the cells: the spec did not ask for output \"cells\"");
        return -1;
    }
    bounds b;
    bounds_init(&b);
    container_bounds(&b, json_object_get(res, "container"));
    size_t nc = 0;
    double amin = INFINITY, amax = -INFINITY;
    int r = pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const item *c = &g->items->cur;
            nc++;
            bounds_xy(&b, c->xy, c->npts);
            if (c->area > 0) amin = fmin(amin, c->area), amax = fmax(amax, c->area);
        }
    if (r < 0) {
        seterr(eb, el, status, 500, "cannot read the cells of the result");
        return -1;
    }
    if (!bounds_ok(&b)) b.xmin = b.ymin = 0, b.xmax = b.ymax = 1;
    if (!(amax >= amin)) amin = amax = 1;
    int height;
    frame f = map_frame(b, width, &height);
    sb *s = &g->out;
    char title[160];
    snprintf(title, sizeof title, "Voronoi cells: %zu cells and their seeds", nc);
    doc_begin(s, width, height, title);
    axes(s, &f, "x (m)", "y (m)", 0);
    sb_puts(s, "<g class=\"cells\" stroke=\"#333333\" stroke-width=\"0.5\" fill-opacity=\"0.55\">\n");
    sb_puts(&g->mid, "</g>\n<g class=\"seeds\" fill=\"#d62728\">\n");
    sb_puts(&g->tail, "</g>\n");
    container_outline(&g->tail, &f, json_object_get(res, "container"));
    colorbar(&g->tail, f.x0 + f.w + 20, f.y0 + 24, fmin(f.h - 30, 300), amin, amax, 0, 0,
             "cell area (m²)");
    doc_end(&g->tail);
    g->f = f;
    g->amin = amin;
    g->amax = amax;
    g->min_px = nc > 2000 ? 0.6 : 0.3;
    g->seed_r = nc > 2000 ? 0.8 : nc > 200 ? 1.5 : 2.5;
    g->section = 0;
    if (pass_begin(g)) {
        seterr(eb, el, status, 500, "cannot read the cells of the result");
        return -1;
    }
    g->step = step_cells;
    return 0;
}

/* a histogram read from JSON or computed from values */
typedef struct hist {
    size_t k;
    double *edges, *target, *achieved, *achieved2;
    double mean;
    int has_mean;
} hist;

static void hist_free(hist *h)
{
    free(h->edges);
    free(h->target);
    free(h->achieved);
    free(h->achieved2);
    memset(h, 0, sizeof *h);
}

/* reads {"edges", "target", "achieved"|"counts", "mean"}; 0 ok */
static int hist_read(const json_t *o, hist *h)
{
    memset(h, 0, sizeof *h);
    if (!json_is_object(o)) return -1;
    size_t ne, nt, na;
    h->edges = jarray(json_object_get(o, "edges"), &ne);
    const json_t *a = json_object_get(o, "achieved");
    if (!a) a = json_object_get(o, "counts");
    h->achieved = jarray(a, &na);
    h->target = jarray(json_object_get(o, "target"), &nt);
    if (!h->edges || !h->achieved || ne != na + 1 || ne < 2) {
        hist_free(h);
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
static int hist_from_values(const double *v, size_t n, size_t k, double lo, double hi, hist *h)
{
    memset(h, 0, sizeof *h);
    if (!n) return -1;
    if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
    h->edges = malloc((k + 1) * sizeof *h->edges);
    h->achieved = calloc(k, sizeof *h->achieved);
    if (!h->edges || !h->achieved) {
        hist_free(h);
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

static void minmax(const double *v, size_t n, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (isfinite(v[i])) *lo = fmin(*lo, v[i]), *hi = fmax(*hi, v[i]);
}

/* bars of h->achieved (and h->achieved2 as outlines) and h->target as a line with markers */
static void draw_hist(sb *s, const frame *f, const hist *h, const char *bar_color)
{
    sb_printf(s, "<g class=\"bars\" fill=\"%s\" fill-opacity=\"0.7\" stroke=\"%s\">\n", bar_color, bar_color);
    for (size_t i = 0; i < h->k; i++) {
        double x0 = fx(f, h->edges[i]), x1 = fx(f, h->edges[i + 1]);
        double y = fy(f, fmax(f->ymin, fmin(f->ymax, h->achieved[i]))), y0 = fy(f, f->ymin);
        if (!isfinite(y)) continue;
        sb_printf(s, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/>\n", x0 + 0.5, y,
                  fmax(0, x1 - x0 - 1), fmax(0, y0 - y));
    }
    sb_puts(s, "</g>\n");
    if (h->achieved2) {
        sb_puts(s, "<path class=\"achieved2\" fill=\"none\" stroke=\"#ff7f0e\" stroke-width=\"2\" d=\"");
        for (size_t i = 0; i < h->k; i++) {
            double x0 = fx(f, h->edges[i]), x1 = fx(f, h->edges[i + 1]);
            double y = fy(f, fmax(f->ymin, fmin(f->ymax, h->achieved2[i])));
            sb_printf(s, "%s%.1f %.1fH%.1f", i ? "L" : "M", x0, y, x1);
        }
        sb_puts(s, "\"/>\n");
    }
    if (h->target) {
        sb_puts(s, "<path class=\"target\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" d=\"");
        for (size_t i = 0; i < h->k; i++) {
            double xc = fx(f, 0.5 * (h->edges[i] + h->edges[i + 1]));
            sb_printf(s, "%s%.1f %.1f", i ? "L" : "M", xc, fy(f, fmin(f->ymax, h->target[i])));
        }
        sb_puts(s, "\"/>\n");
        for (size_t i = 0; i < h->k; i++)
            marker(s, fx(f, 0.5 * (h->edges[i] + h->edges[i + 1])), fy(f, fmin(f->ymax, h->target[i])),
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

static frame hist_frame(double x0, double y0, double w, double h, const hist *hs)
{
    frame f = {x0, y0, w, h, hs->edges[0], hs->edges[hs->k], 0, hist_ymax(hs), 0};
    if (!(f.xmax > f.xmin)) f.xmax = f.xmin + 1;
    return f;
}

/* the size view as histograms (results without stats.fit) */
static char *view_size_hist(const gp_svg_input *in, int width, size_t *len, int *status,
                            char *eb, size_t el)
{
    const json_t *res = in->summary;
    const json_t *stats = json_object_get(res, "stats");
    hist h;
    const char *what = "cell area (m²)";
    int have = hist_read(json_object_get(stats, "size_histogram"), &h) == 0;
    if (have) {
        hist g;
        if (hist_read(json_object_get(stats, "grain_size_histogram"), &g) == 0) {
            if (g.k == h.k) {
                h.achieved2 = g.achieved;
                g.achieved = NULL;
            }
            hist_free(&g);
        }
    } else {
        size_t n;
        int failed;
        double *v = collect_items(in, GP_SVG_CELLS, 0, &n, &failed);
        if (!v && !failed) {
            v = collect_items(in, GP_SVG_GRAINS, 0, &n, &failed);
            what = "grain area (m²)";
        }
        if (!v) {
            if (failed) seterr(eb, el, status, 500, "cannot read the cells or grains of the result");
            else seterr(eb, el, status, 409, "view \"size\" needs stats.size_histogram, cells or grains in the result");
            return NULL;
        }
        double lo, hi;
        minmax(v, n, &lo, &hi);
        int ok = hist_from_values(v, n, n < 50 ? 8 : 20, lo, hi, &h) == 0;
        free(v);
        if (!ok) {
            seterr(eb, el, status, 500, "out of memory");
            return NULL;
        }
    }
    int height = (int)lround(width * 0.62);
    frame f = hist_frame(80, 40, width - 110, height - 110, &h);
    sb s = {0};
    doc_begin(&s, width, height, "Size distribution: target vs achieved");
    axes(&s, &f, what, "fraction of cells", 1);
    draw_hist(&s, &f, &h, "#1f77b4");
    legend_item it[3];
    int n = 0;
    it[n++] = (legend_item){have ? "achieved (cells)" : "achieved", "bar", "#1f77b4"};
    if (h.achieved2) it[n++] = (legend_item){"achieved (grains)", "line", "#ff7f0e"};
    if (h.target) it[n++] = (legend_item){"target (lognormal)", "marker", "#d62728"};
    legend(&s, f.x0 + f.w - 190, f.y0 + 8, it, n);
    doc_end(&s);
    hist_free(&h);
    return finish(&s, len, status, eb, el);
}

/* --- size view from stats.fit: the target law's CDF against the achieved one, per series --- */

typedef struct cdf_series {
    const char *name, *color;       /* "cells" / "grains" */
    const char *law;
    double *x, *target, *achieved;  /* n points, x increasing */
    size_t n;
    double ks, ks_critical, w1, cov, target_cov;
} cdf_series;

static void cdf_free(cdf_series *c)
{
    free(c->x);
    free(c->target);
    free(c->achieved);
    c->x = c->target = c->achieved = NULL;
    c->n = 0;
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

/* the x range of the curves (positive values only when for_log) */
static void cdf_range(const cdf_series *c, int n, int for_log, double *lo, double *hi)
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
static void cdf_path(sb *s, const frame *f, const cdf_series *c, int achieved)
{
    const double *y = achieved ? c->achieved : c->target;
    sb_printf(s, "<path class=\"cdf-%s %s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s d=\"",
              achieved ? "achieved" : "target", c->name, c->color,
              achieved ? "" : " stroke-dasharray=\"6 4\"");
    int first = 1;
    for (size_t i = 0; i < c->n; i++) {
        if (!isfinite(c->x[i]) || !isfinite(y[i]) || (f->xlog && !(c->x[i] > 0))) continue;
        double px = fx(f, c->x[i]), py = fy(f, fmax(0, fmin(1, y[i])));
        sb_printf(s, "%s%.1f %.1f", first ? "M" : "L", px, py);
        first = 0;
    }
    sb_puts(s, "\"/>\n");
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

static char *view_size_fit(const json_t *res, cdf_series *c, int nc, int width, size_t *len,
                           int *status, char *eb, size_t el)
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
    sb s = {0};
    doc_begin(&s, width, height, "Size distribution: target law vs achieved (CDF)");
    axes(&s, &f, xlog ? "area (m², log scale)" : "area (m²)", "cumulative fraction (by number)",
         1);
    legend_item it[4];
    char names[4][64];
    for (int k = 0; k < nc; k++) {
        cdf_path(&s, &f, &c[k], 0);
        cdf_path(&s, &f, &c[k], 1);
        snprintf(names[2 * k], sizeof names[0], "%s: target (%s)", c[k].name,
                 c[k].law ? c[k].law : "law");
        snprintf(names[2 * k + 1], sizeof names[0], "%s: achieved", c[k].name);
        it[2 * k] = (legend_item){names[2 * k], "dash", c[k].color};
        it[2 * k + 1] = (legend_item){names[2 * k + 1], "line", c[k].color};
    }
    legend(&s, f.x0 + 10, f.y0 + 8, it, 2 * nc);
    double y = plot_h + 6;
    for (int k = 0; k < nc; k++, y += 16) {
        char line[256];
        int over = fit_line(line, sizeof line, &c[k]);
        text_at(&s, 20, y, "start",
                over ? "class=\"fit ks-over\" fill=\"#d62728\"" : "class=\"fit\"", line);
    }
    warning_lines(&s, warnings, 20, y, maxch);
    doc_end(&s);
    return finish(&s, len, status, eb, el);
}

/* the size view: CDFs from stats.fit when the result has them, else histograms (results stored
 * before stats.fit, or without it) */
static char *view_size(const gp_svg_input *in, int width, size_t *len, int *status, char *eb,
                       size_t el)
{
    const json_t *res = in->summary;
    const json_t *fit = json_object_get(json_object_get(res, "stats"), "fit");
    cdf_series c[2];
    int nc = 0;
    if (cdf_read(fit, "cell_area", "cells", "#1f77b4", &c[nc]) == 0) nc++;
    if (cdf_read(fit, "grain_area", "grains", "#ff7f0e", &c[nc]) == 0) nc++;
    if (!nc) return view_size_hist(in, width, len, status, eb, el);
    char *svg = view_size_fit(res, c, nc, width, len, status, eb, el);
    for (int k = 0; k < nc; k++) cdf_free(&c[k]);
    return svg;
}

static char *view_orientation(const gp_svg_input *in, int width, size_t *len, int *status,
                              char *eb, size_t el)
{
    const json_t *res = in->summary;
    hist h;
    int have = hist_read(json_object_get(json_object_get(res, "stats"), "orientation_histogram"), &h) == 0;
    if (!have) {
        size_t n;
        int failed;
        double *v = collect_items(in, GP_SVG_GRAINS, 1, &n, &failed);
        if (!v && !failed) v = collect_items(in, GP_SVG_CELLS, 1, &n, &failed);
        if (!v) {
            if (failed) {
                seterr(eb, el, status, 500, "cannot read the grains or cells of the result");
                return NULL;
            }
            seterr(eb, el, status, 409, "view \"orientation\" needs stats.orientation_histogram, grains or cells in the result");
            return NULL;
        }
        int ok = hist_from_values(v, n, 18, -90, 90, &h) == 0;
        free(v);
        if (!ok) {
            seterr(eb, el, status, 500, "out of memory");
            return NULL;
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
    sb s = {0};
    doc_begin(&s, width, height, "Orientation rose: target vs achieved (axial, degrees)");
    /* grid: rings and spokes */
    sb_puts(&s, "<g class=\"grid\" fill=\"none\" stroke=\"#cccccc\">\n");
    char lab[64];
    for (double r = st; r <= rmax + st * 1e-9; r += st) {
        double pr = R * r / rmax;
        sb_printf(&s, "<path d=\"M%.1f %.1fa%.1f %.1f 0 1 0 %.1f 0a%.1f %.1f 0 1 0 %.1f 0z\"/>\n",
                  cx - pr, cy, pr, pr, 2 * pr, pr, pr, -2 * pr);
    }
    for (int a = 0; a < 360; a += 30) {
        double t = a * M_PI / 180;
        sb_printf(&s, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", cx, cy,
                  cx + R * cos(t), cy - R * sin(t));
    }
    sb_puts(&s, "</g>\n");
    for (double r = st; r <= rmax + st * 1e-9; r += st) {
        fmt_label(lab, sizeof lab, r);
        text_at(&s, cx + R * r / rmax * cos(M_PI / 12) + 2, cy - R * r / rmax * sin(M_PI / 12), "start",
                "fill=\"#666666\" font-size=\"10\"", lab);
    }
    for (int a = -90; a <= 90; a += 30) {
        double t = a * M_PI / 180;
        snprintf(lab, sizeof lab, "%d°", a);
        text_at(&s, cx + (R + 18) * cos(t), cy - (R + 18) * sin(t) + 4, "middle", NULL, lab);
    }
    /* achieved: wedges for each class and its mirror (axial data) */
    sb_puts(&s, "<g class=\"achieved\" fill=\"#1f77b4\" fill-opacity=\"0.6\" stroke=\"#1f77b4\">\n");
    for (size_t i = 0; i < h.k; i++) {
        double pr = R * fmin(h.achieved[i], rmax) / rmax;
        if (!(pr > 0)) continue;
        for (int mirror = 0; mirror < 2; mirror++) {
            double a0 = (h.edges[i] + 180 * mirror) * M_PI / 180, a1 = (h.edges[i + 1] + 180 * mirror) * M_PI / 180;
            sb_printf(&s, "<path d=\"M%.1f %.1fL%.1f %.1fA%.1f %.1f 0 0 0 %.1f %.1fz\"/>\n", cx, cy,
                      cx + pr * cos(a0), cy - pr * sin(a0), pr, pr, cx + pr * cos(a1), cy - pr * sin(a1));
        }
    }
    sb_puts(&s, "</g>\n");
    if (h.target) {
        sb_puts(&s, "<path class=\"target\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" d=\"");
        for (int mirror = 0, first = 1; mirror < 2; mirror++)
            for (size_t i = 0; i < h.k; i++) {
                double a = (0.5 * (h.edges[i] + h.edges[i + 1]) + 180 * mirror) * M_PI / 180;
                double pr = R * fmin(h.target[i], rmax) / rmax;
                sb_printf(&s, "%s%.1f %.1f", first ? "M" : "L", cx + pr * cos(a), cy - pr * sin(a));
                first = 0;
            }
        sb_puts(&s, "z\"/>\n");
        for (int mirror = 0; mirror < 2; mirror++)
            for (size_t i = 0; i < h.k; i++) {
                double a = (0.5 * (h.edges[i] + h.edges[i + 1]) + 180 * mirror) * M_PI / 180;
                double pr = R * fmin(h.target[i], rmax) / rmax;
                marker(&s, cx + pr * cos(a), cy - pr * sin(a), "#d62728");
            }
    }
    legend_item it[2] = {{"achieved (fraction per class)", "bar", "#1f77b4"},
                         {"target", "marker", "#d62728"}};
    legend(&s, 10, height - 56, it, h.target ? 2 : 1);
    doc_end(&s);
    hist_free(&h);
    return finish(&s, len, status, eb, el);
}

static char *view_descriptors(const gp_svg_input *in, int width, size_t *len, int *status,
                              char *eb, size_t el)
{
    const char *const *names = DESC_NAME;
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
        double *v = collect_items(in, GP_SVG_GRAINS, 2 + k, &n, &failed);
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
        if (!ok) seterr(eb, el, status, 500, "out of memory or the grains cannot be read");
        else seterr(eb, el, status, 409, "view \"descriptors\" needs the descriptors: the spec did not ask for output \"descriptors\"");
        return NULL;
    }
    int height = (int)lround(width * 0.75);
    sb s = {0};
    doc_begin(&s, width, height, "Shape descriptors of the grains");
    double pw = (width - 40) / 2.0, ph = (height - 50) / 2.0;
    for (int k = 0; k < 4; k++) {
        double ox = 20 + (k % 2) * pw, oy = 40 + (k / 2) * ph;
        if (!h[k].k) {
            text_at(&s, ox + pw / 2, oy + ph / 2, "middle", NULL, "(not in the result)");
            continue;
        }
        frame f = hist_frame(ox + 62, oy + 22, pw - 82, ph - 72, &h[k]);
        axes(&s, &f, names[k], "fraction of grains", 0);
        draw_hist(&s, &f, &h[k], "#2ca02c");
        /* mean marker: a vertical dashed line with its value */
        if (h[k].has_mean && h[k].mean >= f.xmin && h[k].mean <= f.xmax) {
            double x = fx(&f, h[k].mean);
            sb_printf(&s, "<line class=\"mean\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#000000\" stroke-width=\"1.5\" stroke-dasharray=\"5 3\"/>\n",
                      x, f.y0, x, f.y0 + f.h);
            char lab[64];
            snprintf(lab, sizeof lab, "mean %.3g", h[k].mean);
            text_at(&s, x + 4, f.y0 + 10, "start", "font-size=\"11\"", lab);
        }
        char t[64];
        snprintf(t, sizeof t, "%s", names[k]);
        text_at(&s, f.x0 + f.w / 2, oy + 14, "middle", "font-weight=\"bold\"", t);
    }
    doc_end(&s);
    for (int k = 0; k < 4; k++) hist_free(&h[k]);
    return finish(&s, len, status, eb, el);
}

/* ------------------------------------------------------------------------------------------ */
/* 3D views */

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
        ramp(t, c, sizeof c);
        sb_printf(&g->out, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.2f\" fill=\"%s\"/>\n",
                  fx(&g->f, isnan(q[0]) ? 0 : q[0]), fy(&g->f, isnan(q[1]) ? 0 : q[1]),
                  rc * g->scale, c);
    }
    if (r < 0) return pass_failed(g);
    if (r > 0) return 0;
    sb_puts(&g->out, g->tail.buf ? g->tail.buf : "");
    return 1;
}

static int view_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                        int *status, char *eb, size_t el)
{
    const json_t *res = in->summary;
    int failed;
    g->items = open_items(in, GP_SVG_SPHERES, &failed);
    if (!g->items) {
        if (failed) seterr(eb, el, status, 500, "cannot read the spheres of the result");
        else seterr(eb, el, status, 409, "view \"section\" needs the spheres: the spec did not ask for output \"spheres\"");
        return -1;
    }
    double box[3] = {NAN, NAN, NAN}, lo[3] = {0, 0, 0};
    const json_t *jb = json_object_get(res, "box");
    int have_box = json_is_array(jb) && json_array_size(jb) == 3;
    for (int a = 0; a < 3; a++) {
        if (have_box) box[a] = jnum(json_array_get(jb, (size_t)a), NAN);
        if (!(box[a] > 0)) have_box = 0;
    }
    /* z is known before the pass when the result has its box: check it, count the cut spheres
     * in the same pass */
    double z = have_box ? box[2] / 2 : NAN;
    if (have_box && opt && opt->has_z) {
        z = opt->z;
        if (!isfinite(z) || z < 0 || z > box[2]) {
            seterr(eb, el, status, 400, "z = %g is outside the box (z from %g to %g m)", z, 0.0,
                   box[2]);
            return -1;
        }
    }
    double dmin = INFINITY, dmax = -INFINITY;
    double bl[3] = {INFINITY, INFINITY, INFINITY}, bh[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t n = 0, ncut = 0;
    int r = pass_begin(g);
    if (r == 0)
        while ((r = g->items->next(g->items)) > 0) {
            const double *q = g->items->cur.q;
            n++;
            double rr = q[3];
            if (!(rr > 0)) continue;
            if (fabs(q[2] - z) < rr) ncut++;
            dmin = fmin(dmin, 2 * rr);
            dmax = fmax(dmax, 2 * rr);
            for (int a = 0; a < 3; a++) {
                bl[a] = fmin(bl[a], q[a] - rr);
                bh[a] = fmax(bh[a], q[a] + rr);
            }
        }
    if (r < 0) {
        seterr(eb, el, status, 500, "cannot read the spheres of the result");
        return -1;
    }
    if (!have_box) {
        for (int a = 0; a < 3; a++) {
            lo[a] = bh[a] >= bl[a] ? bl[a] : 0;
            box[a] = bh[a] >= bl[a] ? bh[a] - bl[a] : 1;
        }
        z = lo[2] + box[2] / 2;
        if (opt && opt->has_z) {
            z = opt->z;
            if (!isfinite(z) || z < lo[2] || z > lo[2] + box[2]) {
                seterr(eb, el, status, 400, "z = %g is outside the box (z from %g to %g m)", z,
                       lo[2], lo[2] + box[2]);
                return -1;
            }
        }
        /* a second pass counts the spheres cut */
        r = pass_begin(g);
        if (r == 0)
            while ((r = g->items->next(g->items)) > 0) {
                const double *q = g->items->cur.q;
                if (q[3] > 0 && fabs(q[2] - z) < q[3]) ncut++;
            }
        if (r < 0) {
            seterr(eb, el, status, 500, "cannot read the spheres of the result");
            return -1;
        }
    }
    if (!(dmax >= dmin)) dmin = dmax = 1;
    bounds b = {lo[0], lo[0] + box[0], lo[1], lo[1] + box[1]};
    int height;
    frame f = map_frame(b, width, &height);
    sb *s = &g->out;
    char title[200];
    snprintf(title, sizeof title, "Section at z = %.4g m: %zu of %zu spheres cut", z, ncut, n);
    doc_begin(s, width, height, title);
    axes(s, &f, "x (m)", "y (m)", 0);
    sb_printf(s, "<rect class=\"box\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f4f4f4\" "
                 "stroke=\"#000000\" stroke-width=\"1.5\"/>\n",
              fx(&f, b.xmin), fy(&f, b.ymax), fx(&f, b.xmax) - fx(&f, b.xmin), fy(&f, b.ymin) - fy(&f, b.ymax));
    sb_puts(s, "<g class=\"spheres\" stroke=\"#222222\" stroke-width=\"0.4\">\n");
    sb_puts(&g->tail, "</g>\n");
    double k = dmax < 1 ? 1000 : 1;
    int logscale = dmax > 4 * dmin;
    colorbar(&g->tail, f.x0 + f.w + 20, f.y0 + 24, fmin(f.h - 30, 300), dmin * k, dmax * k, 0,
             logscale, k > 1 ? "diameter (mm)" : "diameter (m)");
    doc_end(&g->tail);
    g->f = f;
    g->z = z;
    g->dmin = dmin;
    g->dmax = dmax;
    g->logscale = logscale;
    g->scale = f.w / (f.xmax - f.xmin);
    if (pass_begin(g)) {
        seterr(eb, el, status, 500, "cannot read the spheres of the result");
        return -1;
    }
    g->step = step_section;
    return 0;
}

static char *view_psd(const json_t *res, int width, size_t *len, int *status, char *eb, size_t el)
{
    const json_t *psd = json_object_get(json_object_get(res, "stats"), "psd");
    static const char *keys[4] = {"target_weight", "achieved_weight", "target_number", "achieved_number"};
    static const char *labels[4] = {"target, by weight", "achieved, by weight", "target, by number",
                                    "achieved, by number"};
    static const char *colors[4] = {"#1f77b4", "#1f77b4", "#d62728", "#d62728"};
    size_t nd = 0, nc[4] = {0};
    double *d = jarray(json_object_get(psd, "diameters"), &nd);
    double *c[4] = {NULL};
    for (int k = 0; k < 4; k++) {
        c[k] = jarray(json_object_get(psd, keys[k]), &nc[k]);
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
        seterr(eb, el, status, 409, "view \"psd\" needs stats.psd (diameters with target/achieved curves) in the result");
        return NULL;
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
    sb s = {0};
    doc_begin(&s, width, height, "Grain-size distribution: target vs achieved");
    axes(&s, &f, unit > 1 ? "sieve diameter (mm, log scale)" : "sieve diameter (m, log scale)",
         "percent passing (%)", 1);
    for (int k = 0; k < 4; k++) {
        if (!c[k]) continue;
        int dashed = k % 2 == 0;
        sb_printf(&s, "<path class=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s d=\"", keys[k],
                  colors[k], dashed ? " stroke-dasharray=\"6 4\"" : "");
        int first = 1;
        for (size_t i = 0; i < nd; i++) {
            if (!(d[i] > 0) || !isfinite(c[k][i])) continue;
            sb_printf(&s, "%s%.1f %.1f", first ? "M" : "L", fx(&f, d[i] * unit), fy(&f, fmax(0, fmin(100, c[k][i]))));
            first = 0;
        }
        sb_puts(&s, "\"/>\n");
        if (!dashed)
            for (size_t i = 0; i < nd; i++)
                if (d[i] > 0 && isfinite(c[k][i]))
                    marker(&s, fx(&f, d[i] * unit), fy(&f, fmax(0, fmin(100, c[k][i]))), colors[k]);
    }
    legend_item it[4];
    int n = 0;
    for (int k = 0; k < 4; k++)
        if (c[k]) it[n++] = (legend_item){labels[k], k % 2 == 0 ? "dash" : "marker", colors[k]};
    legend(&s, f.x0 + 10, f.y0 + 8, it, n);
    doc_end(&s);
    free(d);
    for (int k = 0; k < 4; k++) free(c[k]);
    return finish(&s, len, status, eb, el);
}

/* ------------------------------------------------------------------------------------------ */

const char *gp_svg_views(const char *kind)
{
    if (!kind) return NULL;
    if (!strcmp(kind, KIND_2D)) return VIEWS_2D;
    if (!strcmp(kind, KIND_3D)) return VIEWS_3D;
    return NULL;
}

void gp_svg_close(gp_svg *g)
{
    if (!g) return;
    gp_svg_items_close(g->items);
    free(g->out.buf);
    free(g->mid.buf);
    free(g->tail.buf);
    free(g);
}

/* a view drawn whole (the statistics views): the document becomes the stream's staged text */
static int whole(gp_svg *g, char *svg, size_t len)
{
    if (!svg) return -1;
    g->out.buf = svg;
    g->out.len = g->out.cap = len;
    return 0;
}

gp_svg *gp_svg_open(const gp_svg_input *in, const char *view, const gp_svg_options *opt,
                    int *status, char *errbuf, size_t errlen)
{
    if (errbuf && errlen) errbuf[0] = 0;
    const json_t *result = in ? in->summary : NULL;
    if (!json_is_object(result)) {
        seterr(errbuf, errlen, status, 500, "the result is not a JSON object");
        return NULL;
    }
    const char *kind = in->kind;
    if (!kind || !*kind) {
        const char *k = json_string_value(json_object_get(result, "kind"));
        if (k) kind = k;
        else if (json_object_get(result, "spheres") || json_object_get(result, "box") ||
                 json_object_get(json_object_get(result, "stats"), "psd"))
            kind = KIND_3D;
        else kind = KIND_2D;
    }
    const char *views = gp_svg_views(kind);
    if (!views) {
        seterr(errbuf, errlen, status, 400, "unknown kind \"%s\"", kind);
        return NULL;
    }
    int width = opt && opt->width > 0 ? opt->width : 800;
    if (width < 320) width = 320;
    if (width > 4000) width = 4000;
    if (!view || !*view) {
        seterr(errbuf, errlen, status, 400, "missing view; valid views for %s: %s", kind, views);
        return NULL;
    }
    gp_svg *g = calloc(1, sizeof *g);
    if (!g) {
        seterr(errbuf, errlen, status, 500, "out of memory");
        return NULL;
    }
    int rc = 1; /* 1: unknown view */
    size_t len = 0;
    char *doc = NULL; /* a view drawn whole */
    if (!strcmp(kind, KIND_2D)) {
        if (!strcmp(view, "packing")) rc = view_packing(g, in, opt, width, status, errbuf, errlen);
        else if (!strcmp(view, "cells")) rc = view_cells(g, in, width, status, errbuf, errlen);
        else if (!strcmp(view, "size")) rc = -1, doc = view_size(in, width, &len, status, errbuf, errlen);
        else if (!strcmp(view, "orientation"))
            rc = -1, doc = view_orientation(in, width, &len, status, errbuf, errlen);
        else if (!strcmp(view, "descriptors"))
            rc = -1, doc = view_descriptors(in, width, &len, status, errbuf, errlen);
    } else {
        if (!strcmp(view, "section")) rc = view_section(g, in, opt, width, status, errbuf, errlen);
        else if (!strcmp(view, "psd")) rc = -1, doc = view_psd(result, width, &len, status, errbuf, errlen);
    }
    if (doc) rc = whole(g, doc, len);
    if (rc == 0 && (g->out.oom || g->mid.oom || g->tail.oom)) {
        seterr(errbuf, errlen, status, 500, "out of memory while drawing");
        rc = -1;
    }
    if (rc) {
        if (rc > 0) {
            char v[64];
            snprintf(v, sizeof v, "%s", view);
            seterr(errbuf, errlen, status, 400, "unknown view \"%s\"; valid views for %s: %s", v,
                   kind, views);
        }
        gp_svg_close(g);
        return NULL;
    }
    if (status) *status = 200;
    return g;
}

/* runs one step; 0 more, 1 done, -1 failed */
static int run_step(gp_svg *g)
{
    int r = g->step(g);
    if (r >= 0 && g->out.oom) {
        snprintf(g->err, sizeof g->err, "out of memory while drawing");
        r = -1;
    }
    if (r < 0) {
        if (!g->err[0]) snprintf(g->err, sizeof g->err, "drawing failed");
        g->step = NULL;
        return -1;
    }
    if (r > 0) g->step = NULL;
    return r;
}

int gp_svg_read(gp_svg *g, char *buf, size_t cap, size_t *n)
{
    *n = 0;
    if (g->err[0]) return -1;
    size_t got = 0;
    while (got < cap) {
        if (g->pos < g->out.len) {
            size_t k = g->out.len - g->pos;
            if (k > cap - got) k = cap - got;
            memcpy(buf + got, g->out.buf + g->pos, k);
            g->pos += k;
            got += k;
            continue;
        }
        if (!g->step) break;
        g->out.len = g->pos = 0;
        if (run_step(g) < 0) return -1;
    }
    *n = got;
    return 0;
}

const char *gp_svg_error(const gp_svg *g)
{
    return g->err[0] ? g->err : "no error";
}

char *gp_svg_render(const json_t *result, const char *kind, const char *view,
                    const gp_svg_options *opt, size_t *len, int *status, char *errbuf,
                    size_t errlen)
{
    if (len) *len = 0;
    gp_svg_input in = {kind, result, NULL, NULL};
    gp_svg *g = gp_svg_open(&in, view, opt, status, errbuf, errlen);
    if (!g) return NULL;
    /* the whole document in memory: every step appends to the staged text */
    while (g->step)
        if (run_step(g) < 0) {
            seterr(errbuf, errlen, status, 500, "%s", g->err);
            gp_svg_close(g);
            return NULL;
        }
    char *svg = g->out.buf;
    if (!svg) { /* cannot happen: every view stages its head */
        gp_svg_close(g);
        seterr(errbuf, errlen, status, 500, "nothing drawn");
        return NULL;
    }
    if (len) *len = g->out.len;
    g->out.buf = NULL;
    gp_svg_close(g);
    if (status) *status = 200;
    return svg;
}
