/* svg_plot.h -- the plot kit of the SVG views: an XML writer, colour ramps, frames with axes
 * and ticks, legends, colour bars, map frames with equal scales, histograms and CDF curves.
 *
 * Conventions: pixel coordinates printed with one or two decimals (bounded output), y axis of
 * data flipped so that up is up, legends and colour bars drawn with <rect>/<line>/<path> only
 * so that the <polygon> / <circle> elements of a picture are exactly its grains, cells, seeds
 * or sphere sections (a detail inset redraws some of them as <path>s). Everything writes into an sb (util.h's gpd_buf): a failed allocation is
 * seen once, at the end, in its oom flag. */
#ifndef GPD_SVG_PLOT_H
#define GPD_SVG_PLOT_H

#include <stddef.h>

#include <jansson.h>

#include "util/util.h"

typedef gpd_buf sb;

/* ---- the XML writer ---- */

void svg_plot_sb_printf(sb *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void svg_plot_sb_puts(sb *s, const char *str);
/* text content, XML-escaped */
void svg_plot_sb_text(sb *s, const char *str);
/* <text x y text-anchor [extra]>str</text> */
void svg_plot_text_at(sb *s, double x, double y, const char *anchor, const char *extra, const char *str);
/* the same, turned by -90 degrees about (x, y) (a vertical axis label) */
void svg_plot_text_up(sb *s, double x, double y, const char *str);
/* the document's head (XML declaration, <svg> with its size, title, white background, the
 * title drawn at the top) and its end */
void svg_plot_doc_begin(sb *s, int w, int h, const char *title);
void svg_plot_doc_end(sb *s);

/* printf's "%.1f" of v, quickly (the points of a large picture are most of its time); buf has
 * F1_MAX bytes; returns the length */
#define F1_MAX 320 /* "%.1f" of -DBL_MAX is 312 bytes */
int svg_plot_fmt_f1(char *buf, double v);
/* "%.4g", with a tiny value printed as 0 */
void svg_plot_fmt_label(char *buf, size_t n, double v);
/* a tick value as a reader wants it: fixed decimals enough for step (the spacing of the ticks;
 * 0 = v's own), "2×10⁻⁵" outside 1e-4..1e6 */
void svg_plot_fmt_tick(char *buf, size_t n, double v, double step);
/* the width in px of a text at 12 px (7 px a character: Helvetica's digits are 6.7) */
double svg_plot_text_w(const char *str);

/* ---- ticks: round values whose labels do not collide ---- */

#define TICKS_MAX 64
typedef struct ticks {
    int n;
    double v[TICKS_MAX];
    double step; /* linear ticks: their spacing; log ticks: 0 */
} ticks;

/* Round ticks over [lo, hi] drawn along px pixels: multiples of a 1-2-5 x 10^k step, at most
 * nmax + 1 of them, the smallest step whose labels keep apart (horiz: their widths plus 6 px;
 * vertical: 16 px, the 12 px font and a gap). */
void svg_plot_lin_ticks(double lo, double hi, double px, int horiz, int nmax, ticks *t);
/* Ticks of a log axis over [lo, hi] (lo > 0): m x 10^k for the densest of the mantissa sets
 * {1..9}, {1, 2, 3, 5}, {1, 2, 5}, {1} (then every 2nd, 3rd, 5th, 10th decade) whose labels keep apart as
 * svg_plot_lin_ticks'; a range too short for two of them gets svg_plot_lin_ticks. */
void svg_plot_log_ticks(double lo, double hi, double px, int horiz, ticks *t);

/* The unit of an area axis whose largest value is hi m²: the factor from m² and its name, so
 * that the labels read 1 to 10,000 rather than 0.0001 (m², cm², mm², µm²). */
const char *svg_plot_area_unit(double hi, double *factor);

/* ---- colours ---- */

/* viridis-like colour ramp, t in [0, 1] */
void svg_plot_ramp(double t, char *buf, size_t n);
/* cyclic colour for an axial orientation in degrees (period 180) */
void svg_plot_cyclic(double deg, char *buf, size_t n);

/* ---- JSON numbers ---- */

double svg_plot_jnum(const json_t *v, double dflt);
/* a numeric array (NULL-safe): a malloc'ed copy (NaN where an element is no number) and its
 * length, NULL when absent or empty */
double *svg_plot_jarray(const json_t *a, size_t *n);

/* ---- frames ---- */

typedef struct frame {
    double x0, y0, w, h;           /* pixels: left, top, width, height */
    double xmin, xmax, ymin, ymax; /* data; ymin > ymax turns the y axis down (depth) */
    int xlog;
} frame;

double svg_plot_fx(const frame *f, double x);
double svg_plot_fy(const frame *f, double y);
/* "nice" tick step for about n ticks over [lo, hi] */
double svg_plot_nice_step(double lo, double hi, int n);
/* axes with ticks and labels; grid lines when grid */
void svg_plot_axes(sb *s, const frame *f, const char *xlabel, const char *ylabel, int grid);

typedef struct legend_item {
    const char *label;
    const char *style; /* "bar", "line", "dash", "marker" */
    const char *color;
} legend_item;

void svg_plot_legend(sb *s, double x, double y, const legend_item *it, int n);
/* the same in one row from x (no box), centred on baseline y; returns its width */
double svg_plot_legend_row(sb *s, double x, double y, const legend_item *it, int n);
/* the width of svg_plot_legend()'s box for these items */
double svg_plot_legend_w(const legend_item *it, int n);
/* a marker as a small square path (not a <circle>, see the conventions above) */
void svg_plot_marker(sb *s, double x, double y, const char *color);
/* vertical colour bar with a gradient at (x, y), h px tall, of the values lo..hi (cyc: the
 * orientation colours, -90..90 degrees, ticks every 45); round ticks (svg_plot_lin_ticks, svg_plot_log_ticks)
 * labelled to their right ("cbar-tick", "cbar-label"), the label turned beside them */
void svg_plot_colorbar(sb *s, double x, double y, double h, double lo, double hi, int cyc, int logscale,
              const char *label);

/* ---- maps (2D geometry, and sections) ---- */

typedef struct bounds {
    double xmin, xmax, ymin, ymax;
} bounds;

void svg_plot_bounds_init(bounds *b);
/* a point that is not finite is left out */
void svg_plot_bounds_add(bounds *b, double x, double y);
void svg_plot_bounds_xy(bounds *b, const double *xy, size_t n);
int svg_plot_bounds_ok(const bounds *b);
/* a map frame with equal scales on both axes, fitting width px (room for a colour bar on the
 * right); the picture's height in *height */
frame svg_plot_map_frame(bounds b, int width, int *height);
/* a frame at (x0, y0) of b with equal scales, as large as fits in w by hmax px */
frame svg_plot_map_frame_in(bounds b, double x0, double y0, double w, double hmax);
/* "x,y x,y ..." of a ring of n points (xy: x0 y0 x1 y1 ...), decimated to min_px (a point
 * within min_px of the last one written, in both directions, is dropped, but a ring keeps at
 * least 3 points); returns points written */
size_t svg_plot_ring_points_xy(sb *s, const frame *f, const double *xy, size_t n, double min_px);

/* ---- histograms ---- */

/* read from JSON or computed from values */
typedef struct hist {
    size_t k;
    double *edges, *target, *achieved, *achieved2;
    double mean;
    int has_mean;
} hist;

void svg_plot_hist_free(hist *h);
/* reads {"edges", "target", "achieved"|"counts", "mean"}; 0 ok */
int svg_plot_hist_read(const json_t *o, hist *h);
/* k equal classes over [lo, hi] of values; fractions. 0 ok */
int svg_plot_hist_from_values(const double *v, size_t n, size_t k, double lo, double hi, hist *h);
/* the range of the finite values */
void svg_plot_minmax(const double *v, size_t n, double *lo, double *hi);
/* a frame for h at (x0, y0), w by h px: x over its edges, y from 0 to its tallest bar */
frame svg_plot_hist_frame(double x0, double y0, double w, double h, const hist *hs);
/* bars of h->achieved (and h->achieved2 as outlines) and h->target as a line with markers */
void svg_plot_draw_hist(sb *s, const frame *f, const hist *h, const char *bar_color);

/* ---- cumulative distributions ---- */

typedef struct cdf_series {
    const char *name, *color; /* "cells" / "grains" */
    const char *law;
    double *x, *target, *achieved; /* n points, x increasing */
    size_t n;
    double ks, ks_critical, w1, cov, target_cov, count;
} cdf_series;

void svg_plot_cdf_free(cdf_series *c);
/* the x range of n series' curves (positive values only when for_log) */
void svg_plot_cdf_range(const cdf_series *c, int n, int for_log, double *lo, double *hi);
/* one curve: the target dashed, the achieved solid */
void svg_plot_cdf_path(sb *s, const frame *f, const cdf_series *c, int achieved);

#endif /* GPD_SVG_PLOT_H */
