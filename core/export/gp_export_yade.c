/* gp_export_yade.c -- the text YADE's ymport reads.
 * 3D: ymport.text(file): "x y z r" per line.
 * 2D: ymport.textClumps(file): "x y z r clumpId" per line, z = 0, clumpId = grain id; the
 *     discs of a grain are consecutive, which is how textClumps groups them. Lines starting
 *     with '#' are skipped by both; there are no blank lines (textClumps fails on them).
 */
#include "gp_export_internal.h"

static int yade_header(gp_export *e)
{
    if (e->info.dim == 3)
        return gp_xw_printf(e, "# grainpack spheres-3d, %llu spheres, SI (m); "
                               "yade: ymport.text(FILE)\n# x y z r\n",
                            (unsigned long long)e->info.nitems);
    return gp_xw_printf(e, "# grainpack fourier-voronoi-2d, %llu grains, %llu discs, "
                           "SI (m); yade: ymport.textClumps(FILE)\n"
                           "# x y z r clumpId\n",
                        (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs);
}

static int yade_sphere(gp_export *e, const double q[4])
{
    return gp_xw_printf(e, "%.17g %.17g %.17g %.17g\n", q[0], q[1], q[2], q[3]);
}

static int yade_disc(gp_export *e, const double d[3])
{
    return gp_xw_printf(e, "%.17g %.17g 0 %.17g %llu\n", d[0], d[1], d[2],
                        (unsigned long long)e->index);
}

static const gp_xlines yade_lines = {yade_header, yade_sphere, yade_disc, NULL};

int gp_export_step_yade(gp_export *e)
{
    return gp_xw_lines(e, &yade_lines);
}
