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

#endif /* GPD_SVG_VIEWS_H */
