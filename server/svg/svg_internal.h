/* svg_internal.h -- what the parts of the SVG renderer share: the item sources (svg_items.c),
 * the rendering stream (svg.c) and the views of each kind (svg_views2d.c, svg_views3d.c).
 * Other modules use svg.h; tests/server/test_svg.c reads the element parser through this. */
#ifndef GPD_SVG_INTERNAL_H
#define GPD_SVG_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "svg/svg.h"
#include "svg/svg_plot.h"

/* a part's name in a result ("grains", "cells", "spheres": the member and the output) */
extern const char *const svg_items_part_name[3];
/* the four shape descriptors, in the order of svg_item.desc */
extern const char *const svg_items_desc_name[4];

/* ---- item sources ---- */

/* the current item; a number that is absent (or null, or not finite) is NaN */
typedef struct svg_item {
    double *xy;       /* grains: the contour; cells: the polygons, one after the other */
    size_t npts, cap; /* points in xy, room in xy (points) */
    size_t *rings;    /* cells: points of each polygon */
    size_t nrings, rcap;
    double area, orientation_deg, desc[4], seed[2];
    double q[4]; /* spheres: x, y, z, r */
} svg_item;

struct gp_svg_items {
    gp_svg_part part;
    int light; /* next() fills the numbers only: no contour, polygons (the statistics passes,
                * which would otherwise read every point of every grain) */
    int (*rewind)(gp_svg_items *it);
    int (*next)(gp_svg_items *it); /* 1: an item in cur, 0: the end, -1: failed */
    svg_item cur;
    const json_t *arr; /* json */
    size_t idx;
    js_scan *js; /* scan */
    uint64_t off;
    gp_export_reader *e, *ep; /* pack: its grain or sphere records, its contour points (a reader of
                        * its own, so that both are read in order, each through its cache; none
                        * for a fv3d pack, whose radii e reads beside the records in a window
                        * of their own) */
    uint64_t k;
};

/* One element of a result array (as api.md writes it) into the item: from its JSON tree, or
 * straight from its text (the same values, without building a tree). -1 on out of memory or,
 * for the text, text that is not JSON. */
int svg_items_from_json(gp_svg_part part, svg_item *c, const json_t *e);
int svg_items_parse(gp_svg_part part, svg_item *c, const char *text, size_t len);
/* the same without the points (contour, polygons skipped): a light source's parse */
int svg_items_parse_light(gp_svg_part part, svg_item *c, const char *text, size_t len);
/* Appends the points of a JSON ring [[x,y],...] to the item's; -1 on out of memory. */
int svg_items_ring(svg_item *c, const json_t *ring);
/* Frees what the item holds (not the item). */
void svg_items_free(svg_item *c);

/* ---- the rendering stream ---- */

#define STEP_BYTES (16u * 1024u) /* a step stages about this much of the document */

/* ---- the detail inset of a large map (svg_views2d.c) ---- */

#define INSET_MIN 2000   /* maps of more items than this get an inset */
#define INSET_TARGET 150 /* items the window is sized for (about; those it cuts add some) */
#define INSET_GRID 32    /* the density grid the window is chosen on */
#define INSET_KEEP 65536 /* points of the window's items kept from the drawing pass (1 MB) */

/* a ring (or, n = 0, a seed: one point) of an item in the window, kept for the inset */
typedef struct svg_kept {
    size_t first, n; /* its points in svg_inset.kxy */
    char col[8];     /* "#rrggbb" */
} svg_kept;

typedef struct svg_inset {
    int on;
    double x0, x1, y0, y1; /* the window (m) */
    frame f;               /* where it is drawn, enlarged */
    size_t n;              /* items drawn in it */
    bounds gb;             /* the grid's bounds (the container's), when grid_on */
    int grid_on;
    unsigned grid[INSET_GRID][INSET_GRID]; /* items by the centre of their bounding box */
    /* The window's items, copied as the map's drawing pass meets them (about INSET_TARGET of
     * them: a few hundred KB), so that the inset needs no pass of its own; past INSET_KEEP
     * points (full) it reads the items again instead. */
    double *kxy;
    size_t kpts, kcap;
    svg_kept *kept;
    size_t nkept, kept_cap, next;
    int full;
} svg_inset;

/* A picture being drawn. A view drawn whole (the statistics views) writes all of it into out
 * when it opens; a geometry view writes the head, keeps the rest in mid and tail and sets step,
 * which the reads call to draw the items a few KB at a time. */
struct gp_svg {
    sb out;                 /* staged text; out.buf[pos..len) not handed out yet */
    size_t pos;
    int (*step)(gp_svg *g); /* stages the next part: 0 more, 1 that was the last, -1 failed;
                             * NULL once everything is staged */
    char err[200];
    /* the geometry views */
    gp_svg_items *items;
    int section;
    frame f;
    int by_orient, logscale;
    double amin, amax, min_px, z, dmin, dmax, scale, seed_r;
    sb mid, tail; /* between the two loops (cells), after the last one */
    svg_inset inset;
};

/* The items of part: from in->open, else the summary's arrays. NULL when the result has none,
 * with *failed = 1 when they could not be read. */
gp_svg_items *svg_items_open(const gp_svg_input *in, gp_svg_part part, int *failed);
/* g->items = the items of part that view draws; -1 with err when there are none: 409 naming
 * the output to ask for, or 500 when they cannot be read. */
int svg_open_part(gp_svg *g, const gp_svg_input *in, gp_svg_part part, const char *view,
                  gpd_err *err);
/* 500 "cannot read the <part> of the result"; returns -1 */
int svg_part_error(gpd_err *err, gp_svg_part part);
/* a pass over g->items begins: 0, or -1 with g->err when the source cannot go back */
int svg_pass_begin(gp_svg *g);
/* the source of g->items failed mid-pass: g->err; returns -1 */
int svg_pass_failed(gp_svg *g);
/* the drawing pass over g->items begins: the reads call step (500 when it cannot begin) */
int svg_start_steps(gp_svg *g, int (*step)(gp_svg *g), gpd_err *err);
/* svg_items_open, the source made light (numbers only: the statistics views) */
gp_svg_items *svg_items_open_light(const gp_svg_input *in, gp_svg_part part, int *failed);
/* One pass over it, fn(user, item) on each item: 0, or -1 when the source failed. Memory O(1):
 * what the statistics views need of the items they accumulate in passes. */
int svg_items_fold(gp_svg_items *it, void (*fn)(void *user, const svg_item *c), void *user);
/* Values of one field of a part's items (NaN ones left out); NULL when none. field: 0 area,
 * 1 orientation, 2..5 the descriptors. *failed when the items could not be read. */
double *svg_items_collect(const gp_svg_input *in, gp_svg_part part, int field, size_t *n,
                          int *failed);

#endif /* GPD_SVG_INTERNAL_H */
