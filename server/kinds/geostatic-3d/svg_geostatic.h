/* svg_geostatic.h -- the SVG views of a geostatic-3d result (result_geostatic.h), drawn from its
 * summary with the plot kit (svg/svg_plot.h), depth drawn downward from the top of the box:
 *   profile     the core's sigma_v and the two sigma_h against depth, with the weight of the
 *               grains above over the area (sigma_v = gamma z) and K0 sigma_v for
 *               K0 = 1 - sin phi' (needs output profile);
 *   k0          K0(z) = sigma_h / sigma_v of each slab (those left out of the mean in grey)
 *               with 1 - sin phi' and the mean (needs output profile);
 *   stress-map  sigma_v over the vertical section in cells (left), and each cell's sigma_v
 *               over its row's mean (right: where the tiles' seams and corners carry more or
 *               less), the tiles' seams drawn over both. */
#ifndef GPD_SVG_GEOSTATIC_H
#define GPD_SVG_GEOSTATIC_H

#include "svg/svg.h"

int svg_geostatic_profile(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                          int width, gpd_err *err);
int svg_geostatic_k0(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err);
int svg_geostatic_stress_map(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                             int width, gpd_err *err);

#endif /* GPD_SVG_GEOSTATIC_H */
