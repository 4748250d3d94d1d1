/* gp_trace.h -- grain outlines from a binary image: the "image treatment, contour
 * discretization" step of Mollon & Zhao 2012, Sec. 2.2, that feeds gp_outline.
 *
 * Input: a w x h image of bytes, row-major, row 0 at the TOP (as PGM and most formats store
 * it); nonzero = grain. gp_trace_pgm_parse + gp_trace_threshold make one from a PGM file's
 * bytes (the caller reads the file: core does no I/O); gp_trace_pgm_header reads only the
 * header, for a caller that bounds the image's size before its values are read.
 *
 * Algorithm:
 *  1. Grains are the 4-connected components of the nonzero pixels (one breadth-first pass,
 *     O(w h)). Why 4 and not 8: two grains of a photograph that touch at a single pixel corner
 *     are two grains, and an 8-connected grain would pinch to a point there, giving an outline
 *     that touches itself (not simple, not star-shaped). The background is then 8-connected
 *     (the dual rule), which is what makes each grain's outline one simple closed curve.
 *  2. Components touching the image border are skipped (counted in nborder: their outline is
 *     the frame's cut, not the grain's), unless keep_border is set; components of fewer than
 *     min_pixels pixels are skipped (counted in nsmall).
 *  3. Holes (8-connected background regions not reaching the border) are not part of the
 *     outline -- a Fourier outline is the outer boundary -- but are reported: the count and
 *     pixels of the holes each grain encloses.
 *  4. The outline is the 0.5 iso-line of the grain's indicator (1 on its pixels, 0 elsewhere,
 *     other grains included) by marching squares, written here as boundary-crack following:
 *     on a binary image the 0.5 crossing between a grain pixel and a background pixel is
 *     always the midpoint of their shared edge, so the vertices are the midpoints of the
 *     boundary cracks, joined in order (axis steps along straight runs, 45-degree chamfers at
 *     corners). The saddle case (two grain pixels meeting diagonally) is resolved as
 *     "separate", consistent with 4-connectivity. Vertices inside straight runs are dropped
 *     (exactly: the midpoints are on a half-integer grid), which leaves the polygon unchanged.
 *
 * Output coordinates: pixel units, x to the right and y UP, origin at the image's bottom-left
 * corner: pixel (column c, row r) is the square [c, c+1] x [h-1-r, h-r], its centre at
 * (c + 0.5, h - r - 0.5). So an outline is counter-clockwise (positive signed area) both in
 * these coordinates and as the image is seen on screen, and angles (phases, orientation)
 * read as on the screen. Area of an outline = pixel count - (convex corners) / 8
 * + (concave corners) / 8; its perimeter overestimates a smooth boundary's by up to ~5 %
 * (the chamfered staircase; 1/cos(22.5 deg) at worst), which is why gp_outline measures the
 * descriptors on the Fourier grain, not on this polygon.
 *
 * Outlines come in raster order of their grains' first pixel (top row first, then left).
 * Ownership: a result owns its outlines (gp_trace_result_free); a gp_trace_gray owns its
 * values (gp_trace_gray_free). Work: O(w h) time and 8 bytes per pixel of scratch, plus the
 * outlines. No state: thread safe.
 */
#ifndef GP_TRACE_H
#define GP_TRACE_H

#include <stddef.h>

#include "gp_error.h"
#include "gp_geom.h"

#define GP_TRACE_MIN_PIXELS_DEFAULT 100
#define GP_TRACE_MAX_PIXELS ((size_t)1 << 30)

typedef struct gp_trace_params {
    size_t min_pixels; /* smaller components are skipped (default 100: below ~11 px across the
                        * +-0.5 px staircase is > 5 % of the radius and swamps D_3 and up) */
    int keep_border;   /* 1: trace components touching the border too (default 0) */
} gp_trace_params;

void gp_trace_params_defaults(gp_trace_params *p);

typedef struct gp_trace_outline {
    gp_vec2 *pts;       /* n vertices, counter-clockwise, not closed (last != first) */
    size_t n;
    size_t pixels;      /* pixels of the grain */
    size_t holes;       /* holes it encloses (not in the outline) */
    size_t hole_pixels;
    size_t col, row;    /* its first pixel in raster order (image row, top = 0) */
    int touches_border; /* only with keep_border */
} gp_trace_outline;

typedef struct gp_trace_result {
    gp_trace_outline *outlines; /* n */
    size_t n;
    size_t ncomponents; /* all 4-connected components */
    size_t nborder;     /* skipped: touching the border */
    size_t nsmall;      /* skipped: fewer than min_pixels */
} gp_trace_result;

/* Traces img (w x h bytes, row 0 at the top, nonzero = grain) as above; p may be NULL
 * (defaults). GP_ERR_INVALID for a NULL image, w or h == 0, or w h > GP_TRACE_MAX_PIXELS;
 * GP_ERR_NOMEM. On error *out is zeroed. */
gp_status gp_trace_image(const unsigned char *img, size_t w, size_t h, const gp_trace_params *p,
                         gp_trace_result *out, gp_error *err);

void gp_trace_result_free(gp_trace_result *r); /* zeroes it; NULL is fine */

/* A grey image: v[row * w + col], row 0 at the top, values 0 .. maxval. */
typedef struct gp_trace_gray {
    size_t w, h;
    unsigned maxval; /* 1 .. 65535 */
    unsigned short *v;
} gp_trace_gray;

/* A PGM file's header, as gp_trace_pgm_header reads it. */
typedef struct gp_trace_pgm_info {
    size_t w, h;     /* >= 1 each, w h <= GP_TRACE_MAX_PIXELS */
    unsigned maxval; /* 1 .. 65535 */
    int binary;      /* 1: P5, 0: P2 */
    size_t data;     /* offset of the values: past the one whitespace byte that ends a P5
                      * header; for P2 where the header's last number ends */
    size_t data_min; /* bytes the values take at least from data: P5 exactly w h, or 2 w h
                      * for maxval > 255; P2 2 w h - 1 (a digit each, a blank between two) */
} gp_trace_pgm_info;

/* Reads the header of a PGM file held in buf (len bytes) without touching its values: the
 * magic "P5" or "P2", width, height and maxval, separated by whitespace (space, tab, CR, LF,
 * VT, FF) and '#' comments (to the end of their line). A number is plain decimal digits
 * without a leading zero (zero-padded numbers are refused, so that every reader of a header
 * sees the same sizes), each side at most GP_TRACE_MAX_PIXELS and their product too, maxval
 * 1 .. 65535; a P5 header ends with exactly one whitespace byte. The one header reader: a
 * caller that bounds the sizes before parsing (the daemon's side limit) calls it, and
 * gp_trace_pgm_parse calls it too. GP_ERR_INVALID with the reason; on error *out is
 * zeroed. No allocation. */
gp_status gp_trace_pgm_header(const void *buf, size_t len, gp_trace_pgm_info *out,
                              gp_error *err);

/* Parses a PGM file held in buf (len bytes): the header as gp_trace_pgm_header, then the
 * values: "P5" (binary: one byte per value for maxval < 256, else two, most significant
 * first) or "P2" (ASCII decimal values, with '#' comments anywhere between them). The data
 * length is checked against the header (data_min) before the image is allocated, so the
 * memory taken is at most twice the input's size. Bytes after the last value are ignored (a
 * second image is not read). GP_ERR_INVALID with the reason for a bad header, truncated
 * data, a missing value or one above maxval; GP_ERR_NOMEM. On error *out is zeroed. */
gp_status gp_trace_pgm_parse(const void *buf, size_t len, gp_trace_gray *out, gp_error *err);

void gp_trace_gray_free(gp_trace_gray *g); /* zeroes it; NULL is fine */

/* mask[i] = 1 where the grain is: v > level (bright grains), or v < level with dark_grains
 * (dark grains on a bright background), else 0. mask has w h bytes. */
gp_status gp_trace_threshold(const gp_trace_gray *g, unsigned level, int dark_grains,
                             unsigned char *mask, gp_error *err);

#endif /* GP_TRACE_H */
