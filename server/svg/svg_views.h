/* svg_views.h -- the SVG views of each kind, as the kind files list them (kind.h: gpd_view):
 * each is a gp_svg_view_fn (svg.h). */
#ifndef GPD_SVG_VIEWS_H
#define GPD_SVG_VIEWS_H

#include "svg/svg.h"

/* the 2D kind (maps: svg_views2d.c; statistics: svg_stats2d.c) */
int svg_views2d_packing(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err);
int svg_views2d_cells(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                   gpd_err *err);
int svg_stats2d_size(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                  gpd_err *err);
int svg_stats2d_orientation(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err);
int svg_stats2d_descriptors(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err);

/* the 3D kind (svg_views3d.c) */
int svg_views3d_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err);
int svg_views3d_psd(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                 gpd_err *err);
/* The section of any result of spheres (its "spheres", "box" [bx, by, bz] from 0 or else their
 * bounds, "tiling"), with two subtitle lines of sub's (l1, l2 of n bytes each, from the result,
 * the cut's z and that cut's porosity, NaN when unknown); sub NULL: the spheres-3d kind's
 * (porosity and grading from its stats) */
typedef void (*svg_views3d_subtitle_fn)(const json_t *res, double z, double cut_porosity,
                                        char *l1, char *l2, size_t n);
int svg_views3d_section_with(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                             int width, svg_views3d_subtitle_fn sub, gpd_err *err);

#endif /* GPD_SVG_VIEWS_H */
