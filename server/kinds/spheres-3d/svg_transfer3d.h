/* svg_transfer3d.h -- the "transfer" view of a spheres-3d result (kind_spheres3d.c): the
 * radial distribution g(r) of the sample and of the final (tiled) packing overlaid, from the
 * summary's stats.transfer.rdf (r in units of the sample's d50, the largest difference marked),
 * drawn with the plot kit (svg/svg_plot.h). A result without stats.transfer (an untiled
 * specimen) answers 409. */
#ifndef GPD_SVG_TRANSFER3D_H
#define GPD_SVG_TRANSFER3D_H

#include "svg/svg.h"

int svg_transfer3d_rdf(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                       gpd_err *err);

#endif /* GPD_SVG_TRANSFER3D_H */
