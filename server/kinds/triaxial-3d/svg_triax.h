/* svg_triax.h -- the SVG views of a triaxial-3d result (result_triax.h), drawn from its summary
 * with the plot kit (svg/svg_plot.h):
 *   stress-strain  sigma1/sigma3 (top) and the volumetric strain (bottom) against the axial
 *                  strain, a curve per confinement, its peak marked (needs output curves);
 *   mohr           the Mohr circles of the peak states (stats.tests[].peak) with the
 *                  Mohr-Coulomb envelope (stats.mohr_coulomb), equal scales;
 *   section        the specimen at the end of the last test, cut at z (the 3D kind's section,
 *                  svg_views3d_section_with; needs output spheres). */
#ifndef GPD_SVG_TRIAX_H
#define GPD_SVG_TRIAX_H

#include "svg/svg.h"

int svg_triax_stress_strain(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                            int width, gpd_err *err);
int svg_triax_mohr(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                   gpd_err *err);
int svg_triax_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                      gpd_err *err);

#endif /* GPD_SVG_TRIAX_H */
