/* svg_stats.h -- the statistics views' parts that both Fourier-Voronoi kinds draw (the 2D
 * kind's svg_stats2d.c, the 3D kind's svg_fv3d.c), from their summaries' stats:
 *   the size view   the CDFs of stats.fit (target law dashed, achieved solid, cells and grains)
 *                   with KS and its 5 % critical value in the legend; for a sieve law the
 *                   grains' passing by mass (stats.fit.passing); a line per population (N, W1,
 *                   COV, the KS when over) and the result's warnings;
 *   the descriptor panels  one histogram per shape descriptor, two by two, the mean dashed and
 *                   the target in red.
 * What differs between the kinds (area or volume, the words) is a parameter; the layout, the
 * colours and the classes of the elements are the same. */
#ifndef GPD_SVG_STATS_H
#define GPD_SVG_STATS_H

#include <jansson.h>

#include "svg/svg_plot.h"

/* what tells one kind's size view from the other's */
typedef struct svg_stats_size_kind {
    const char *cell_key, *grain_key; /* the stats.fit members: "cell_area", "grain_area" */
    const char *title;                /* the picture's */
    const char *measure;              /* the CDFs' x axis: "area", "volume" */
    /* the unit of that axis whose largest value is hi (SI): the factor from SI and its name */
    const char *(*unit)(double hi, double *factor);
    const char *diameter;             /* the passing panel's x axis */
    const char *no_ks;                /* after "<series>: achieved" when the KS is not known */
} svg_stats_size_kind;

/* The size view of the result res (its summary) into s, width px wide: 0, or 1 (nothing
 * drawn) when stats.fit has neither of k's members with their CDFs. */
int svg_stats_size(sb *s, const json_t *res, int width, const svg_stats_size_kind *k);

/* the four descriptors a kind draws in panels */
typedef struct svg_stats_desc {
    const char *const *name;   /* their names: the panels' titles and x axes */
    const hist *h;             /* their histograms; one without classes: "(not in the result)" */
    const double *sd, *target; /* NaN: not known, none */
    const char *target_label;  /* the legend's line of the target; NULL: no such line */
    int asked;                 /* the target also in each panel's title, "(asked 0.8)" */
} svg_stats_desc;

/* The legend row and the four panels of d, two by two below it, in a picture width px wide
 * (the panels fill lround(0.75 width) + 20 px from the top); returns the y under them. */
double svg_stats_desc_panels(sb *s, int width, const svg_stats_desc *d);

#endif /* GPD_SVG_STATS_H */
