/* gp_export_yade.c -- the text YADE's ymport reads.
 * 3D: ymport.text(file): "x y z r" per line.
 * 2D: ymport.textClumps(file): "x y z r clumpId" per line, z = 0, clumpId = grain id; the
 *     discs of a grain are consecutive, which is how textClumps groups them. Lines starting
 *     with '#' are skipped by both; there are no blank lines (textClumps fails on them).
 */
#include "gp_export_internal.h"

int gp_export_step_yade(gp_export *e)
{
    if (e->section == 0) {
        e->section = 1;
        e->index = e->sub = 0;
        int rc = e->dim == 3
                     ? gp_xw_printf(e, "# grainpack spheres-3d, %llu spheres, SI (m); "
                                       "yade: ymport.text(FILE)\n# x y z r\n",
                                    (unsigned long long)e->nitems)
                     : gp_xw_printf(e, "# grainpack fourier-voronoi-2d, %llu grains, %llu discs, "
                                       "SI (m); yade: ymport.textClumps(FILE)\n"
                                       "# x y z r clumpId\n",
                                    (unsigned long long)e->nitems, (unsigned long long)e->ndiscs);
        if (rc) return -1;
        if (e->nitems == 0) return 1;
        return e->dim == 2 ? gp_xr_grain(e, 0, &e->grain) : 0;
    }
    if (e->dim == 3) {
        double q[4];
        if (gp_xr_sphere(e, e->index, q)) return -1;
        if (gp_xw_printf(e, "%.17g %.17g %.17g %.17g\n", q[0], q[1], q[2], q[3])) return -1;
        return ++e->index >= e->nitems;
    }
    double d[3];
    if (gp_xr_disc(e, e->grain.disc_first + e->sub, d)) return -1;
    if (gp_xw_printf(e, "%.17g %.17g 0 %.17g %llu\n", d[0], d[1], d[2],
                     (unsigned long long)e->index))
        return -1;
    if (++e->sub < e->grain.disc_count) return 0;
    e->sub = 0;
    if (++e->index >= e->nitems) return 1;
    return gp_xr_grain(e, e->index, &e->grain);
}
