/* svg_fv3d.h -- the SVG views of the 3D Fourier-Voronoi kind (kind_fv3d.c), drawn in
 * svg_fv3d.c: a section of the specimen at a height z, the grains projected on the xy plane,
 * the volume distributions and the shape descriptors. */
#ifndef GPD_SVG_FV3D_H
#define GPD_SVG_FV3D_H

#include "svg/svg.h"

int svg_fv3d_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err);
int svg_fv3d_projection(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                        int width, gpd_err *err);
int svg_fv3d_size(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                  gpd_err *err);
int svg_fv3d_descriptors(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err);

#endif /* GPD_SVG_FV3D_H */
