/* gp_export_csv.c -- comma-separated values with a header line, reals in %.17g (they parse
 * back to the result's doubles bit for bit).
 * 3D: "x,y,z,r", one sphere per line. 2D: "grain,x,y,r", one ODEC disc per line, grain = the
 * result's grain id.
 */
#include "gp_export_internal.h"

int gp_export_step_csv(gp_export *e)
{
    if (e->section == 0) {
        e->section = 1;
        e->index = e->sub = 0;
        if (gp_xw_printf(e, e->dim == 3 ? "x,y,z,r\n" : "grain,x,y,r\n")) return -1;
        if (e->nitems == 0) return 1;
        return e->dim == 2 ? gp_xr_grain(e, 0, &e->grain) : 0;
    }
    if (e->dim == 3) {
        double q[4];
        if (gp_xr_sphere(e, e->index, q)) return -1;
        if (gp_xw_printf(e, "%.17g,%.17g,%.17g,%.17g\n", q[0], q[1], q[2], q[3])) return -1;
        return ++e->index >= e->nitems;
    }
    double d[3];
    if (gp_xr_disc(e, e->grain.disc_first + e->sub, d)) return -1;
    if (gp_xw_printf(e, "%llu,%.17g,%.17g,%.17g\n", (unsigned long long)e->index, d[0], d[1], d[2]))
        return -1;
    if (++e->sub < e->grain.disc_count) return 0;
    e->sub = 0;
    if (++e->index >= e->nitems) return 1;
    return gp_xr_grain(e, e->index, &e->grain);
}
