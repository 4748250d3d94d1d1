/* gp_export_csv.c -- comma-separated values with a header line, reals in %.17g (they parse
 * back to the result's doubles bit for bit).
 * 3D: "x,y,z,r", one sphere per line. 2D: "grain,x,y,r", one ODEC disc per line, grain = the
 * result's grain id.
 */
#include "gp_export_internal.h"

static int csv_header(gp_export *e)
{
    return gp_xw_printf(e, e->info.dim == 3 ? "x,y,z,r\n" : "grain,x,y,r\n");
}

static int csv_sphere(gp_export *e, const double q[4])
{
    return gp_xw_printf(e, "%.17g,%.17g,%.17g,%.17g\n", q[0], q[1], q[2], q[3]);
}

static int csv_disc(gp_export *e, const double d[3])
{
    return gp_xw_printf(e, "%llu,%.17g,%.17g,%.17g\n", (unsigned long long)e->index, d[0], d[1],
                        d[2]);
}

static const gp_xlines csv_lines = {csv_header, csv_sphere, csv_disc, NULL};

int gp_export_step_csv(gp_export *e)
{
    return gp_xw_lines(e, &csv_lines);
}
