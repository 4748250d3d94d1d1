/* svg_view.h -- what a view of the SVG renderer is given: the view function's type (a kind's
 * table of views holds them, kinds/kind.h), the result it reads (gp_svg_input), its options and
 * the parts of a result its items come from. The stream that runs a view is svg.h; the views
 * themselves live with their kinds (kinds/<kind>/svg_*.c).
 */
#ifndef GP_SVG_VIEW_H
#define GP_SVG_VIEW_H

#include <jansson.h>

#include "util/util.h"

typedef struct gp_svg_options {
    const char *color;  /* packing: "size" (default) or "orientation"; NULL = default */
    int has_z;          /* section: cut at z (m) instead of the middle of the box */
    double z;
    int width;          /* picture width in px; 0 = default (800) */
} gp_svg_options;

/* "grains", "cells" or "spheres" */
typedef enum gp_svg_part { GP_SVG_GRAINS = 0, GP_SVG_CELLS, GP_SVG_SPHERES } gp_svg_part;

typedef struct gp_svg_items gp_svg_items;

/* What a view reads. summary: the result's small members (or the whole result: its arrays
 * are then the items when open is NULL); it must outlive the rendering.
 * open(user, part, &failed): the items of a part when a view needs them (the rendering closes
 * them); NULL when the result has no such part, with failed = 1 when they could not be read
 * (a 500). NULL open: the arrays of summary. */
typedef struct gp_svg_input {
    const char *kind;
    const json_t *summary;
    gp_svg_items *(*open)(void *user, gp_svg_part part, int *failed);
    void *user;
} gp_svg_input;

typedef struct gp_svg gp_svg;

/* A view of a kind (kind.h: gpd_view.open): prepares g to draw view of in, reading what it
 * needs (its statistics, its items' bounds and ranges), at width px (320..4000). 0, or -1 with
 * err (the statuses of gp_svg_render). */
typedef int (*gp_svg_view_fn)(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                              int width, gpd_err *err);

#endif /* GP_SVG_VIEW_H */
