/* gp_export_vtk.c -- legacy VTK polydata (ASCII, version 3.0), which ParaView and VTK's
 * vtkPolyDataReader open.
 *
 * 3D: the spheres as points (one vertex cell each) with a point array "radius"; the box as
 *     field data "box_lo" and "box_hi" (3 components each), so that point counts stay those of
 *     the specimen. In ParaView: Point Gaussian representation, scale by "radius".
 * 2D: points = every grain contour point, then every ODEC disc centre (z = 0);
 *     cells = one vertex per disc, then one polygon per grain (VTK orders cells so);
 *     cell arrays grain_id, area, orientation_deg and, when computed, elongation, roundness,
 *     circularity, regularity -- a disc cell carries its grain's values; point array "radius"
 *     (0 on contour points, the disc radius on disc centres).
 * The legacy reader takes any whitespace between values, so a record may be a grain's worth of
 * values on several lines.
 */
#include "gp_export_internal.h"

#include <math.h>

enum { V3_HEAD, V3_POINTS, V3_VERTS_HEAD, V3_VERTS, V3_DATA_HEAD, V3_RADIUS };

int gp_export_step_vtk3d(gp_export *e)
{
    double q[4];
    unsigned long long n = (unsigned long long)e->info.nitems;
    switch (e->section) {
    case V3_HEAD:
        if (gp_xw_printf(e,
                         "# vtk DataFile Version 3.0\n"
                         "grainpack spheres-3d: %llu spheres, SI units (m)\n"
                         "ASCII\n"
                         "DATASET POLYDATA\n"
                         "FIELD FieldData 2\n"
                         "box_lo 3 1 double\n%.17g %.17g %.17g\n"
                         "box_hi 3 1 double\n%.17g %.17g %.17g\n"
                         "POINTS %llu double\n",
                         n, e->info.lo[0], e->info.lo[1], e->info.lo[2], e->info.hi[0], e->info.hi[1],
                         e->info.hi[2], n))
            return -1;
        e->section = n ? V3_POINTS : V3_VERTS_HEAD;
        e->index = 0;
        return 0;
    case V3_POINTS:
        if (gp_xr_sphere(e, e->index, q) || gp_xw_printf(e, "%.17g %.17g %.17g\n", q[0], q[1], q[2]))
            return -1;
        if (++e->index >= e->info.nitems) e->section = V3_VERTS_HEAD;
        return 0;
    case V3_VERTS_HEAD:
        if (gp_xw_printf(e, "VERTICES %llu %llu\n", n, 2 * n)) return -1;
        e->section = n ? V3_VERTS : V3_DATA_HEAD;
        e->index = 0;
        return 0;
    case V3_VERTS:
        if (gp_xw_printf(e, "1 %llu\n", (unsigned long long)e->index)) return -1;
        if (++e->index >= e->info.nitems) e->section = V3_DATA_HEAD;
        return 0;
    case V3_DATA_HEAD:
        if (gp_xw_printf(e, "POINT_DATA %llu\nSCALARS radius double 1\nLOOKUP_TABLE default\n", n))
            return -1;
        e->section = V3_RADIUS;
        e->index = 0;
        return n == 0;
    default:
        if (gp_xr_sphere(e, e->index, q) || gp_xw_printf(e, "%.17g\n", q[3])) return -1;
        return ++e->index >= e->info.nitems;
    }
}

/* ---- 2D ---- */

enum {
    V2_HEAD,
    V2_CONTOUR,
    V2_DISCS,
    V2_VERTS_HEAD,
    V2_VERTS,
    V2_POLYS_HEAD,
    V2_POLYS,
    V2_CELL_HEAD,
    V2_ARRAY_HEAD, /* then V2_ARRAY_DISCS, V2_ARRAY_POLYS for array e->aux */
    V2_ARRAY_DISCS,
    V2_ARRAY_POLYS,
    V2_POINT_HEAD,
    V2_RADIUS_CONTOUR,
    V2_RADIUS_DISCS
};

static const char *const cell_arrays[] = {"grain_id",   "area",      "orientation_deg",
                                          "elongation", "roundness", "circularity",
                                          "regularity"};

static int n_cell_arrays(const gp_export *e)
{
    return (e->info.flags & GP_EXPORT_HAS_DESCRIPTORS) ? 7 : 3;
}

static double grain_value(const gp_export_grain *g, int a)
{
    switch (a) {
    case 1: return g->area;
    case 2: return g->orientation_deg;
    case 3: return g->elongation;
    case 4: return g->roundness;
    case 5: return g->circularity;
    default: return g->regularity;
    }
}

/* One value of array a for grain g, repeated `times` times (one line each). */
static int write_values(gp_export *e, int a, uint64_t g, const gp_export_grain *gr, uint64_t times)
{
    for (uint64_t k = 0; k < times; k++) {
        int rc = a == 0 ? gp_xw_printf(e, "%llu\n", (unsigned long long)g)
                        : gp_xw_printf(e, "%.17g\n", grain_value(gr, a));
        if (rc) return -1;
    }
    return 0;
}

int gp_export_step_vtk2d(gp_export *e)
{
    unsigned long long np = (unsigned long long)(e->info.npoints + e->info.ndiscs);
    unsigned long long nd = (unsigned long long)e->info.ndiscs;
    unsigned long long ng = (unsigned long long)e->info.nitems;
    double p[3];
    int a = (int)e->aux;
    switch (e->section) {
    case V2_HEAD:
        if (gp_xw_printf(e,
                         "# vtk DataFile Version 3.0\n"
                         "grainpack fourier-voronoi-2d: %llu grains (polygons), %llu ODEC discs "
                         "(vertices), SI units (m)\n"
                         "ASCII\n"
                         "DATASET POLYDATA\n"
                         "POINTS %llu double\n",
                         ng, nd, np))
            return -1;
        e->index = 0;
        e->section = e->info.npoints ? V2_CONTOUR : e->info.ndiscs ? V2_DISCS : V2_VERTS_HEAD;
        return 0;
    case V2_CONTOUR:
        if (gp_xr_point(e, e->index, p) || gp_xw_printf(e, "%.17g %.17g 0\n", p[0], p[1]))
            return -1;
        if (++e->index >= e->info.npoints) {
            e->index = 0;
            e->section = e->info.ndiscs ? V2_DISCS : V2_VERTS_HEAD;
        }
        return 0;
    case V2_DISCS:
        if (gp_xr_disc(e, e->index, p) || gp_xw_printf(e, "%.17g %.17g 0\n", p[0], p[1]))
            return -1;
        if (++e->index >= e->info.ndiscs) e->section = V2_VERTS_HEAD;
        return 0;
    case V2_VERTS_HEAD:
        if (gp_xw_printf(e, "VERTICES %llu %llu\n", nd, 2 * nd)) return -1;
        e->index = 0;
        e->section = nd ? V2_VERTS : V2_POLYS_HEAD;
        return 0;
    case V2_VERTS:
        if (gp_xw_printf(e, "1 %llu\n", (unsigned long long)(e->info.npoints + e->index)))
            return -1;
        if (++e->index >= e->info.ndiscs) e->section = V2_POLYS_HEAD;
        return 0;
    case V2_POLYS_HEAD:
        if (gp_xw_printf(e, "POLYGONS %llu %llu\n", ng,
                         ng + (unsigned long long)e->info.npoints))
            return -1;
        e->index = 0;
        e->section = ng ? V2_POLYS : V2_CELL_HEAD;
        return 0;
    case V2_POLYS: {
        gp_export_grain g;
        if (gp_xr_grain(e, e->index, &g)) return -1;
        if (gp_xw_printf(e, "%llu", (unsigned long long)g.point_count)) return -1;
        for (uint64_t k = 0; k < g.point_count; k++)
            if (gp_xw_printf(e, " %llu", (unsigned long long)(g.point_first + k))) return -1;
        if (gp_xw_printf(e, "\n")) return -1;
        if (++e->index >= e->info.nitems) e->section = V2_CELL_HEAD;
        return 0;
    }
    case V2_CELL_HEAD:
        if (gp_xw_printf(e, "CELL_DATA %llu\n", nd + ng)) return -1;
        e->aux = 0;
        e->section = V2_ARRAY_HEAD;
        return 0;
    case V2_ARRAY_HEAD:
        if (a >= n_cell_arrays(e)) {
            e->section = V2_POINT_HEAD;
            return 0;
        }
        if (gp_xw_printf(e, "SCALARS %s %s 1\nLOOKUP_TABLE default\n", cell_arrays[a],
                         a == 0 ? "int" : "double"))
            return -1;
        e->index = 0;
        e->section = ng ? V2_ARRAY_DISCS : V2_ARRAY_HEAD;
        if (!ng) e->aux = a + 1;
        return 0;
    case V2_ARRAY_DISCS:
    case V2_ARRAY_POLYS: {
        gp_export_grain g;
        if (gp_xr_grain(e, e->index, &g)) return -1;
        int discs = e->section == V2_ARRAY_DISCS;
        if (write_values(e, a, e->index, &g, discs ? g.disc_count : 1)) return -1;
        if (++e->index >= e->info.nitems) {
            e->index = 0;
            if (discs) {
                e->section = V2_ARRAY_POLYS;
            } else {
                e->aux = a + 1;
                e->section = V2_ARRAY_HEAD;
            }
        }
        return 0;
    }
    case V2_POINT_HEAD:
        if (gp_xw_printf(e, "POINT_DATA %llu\nSCALARS radius double 1\nLOOKUP_TABLE default\n", np))
            return -1;
        e->index = 0;
        if (e->info.npoints) e->section = V2_RADIUS_CONTOUR;
        else if (e->info.ndiscs) e->section = V2_RADIUS_DISCS;
        else return 1;
        return 0;
    case V2_RADIUS_CONTOUR:
        if (gp_xw_printf(e, "0\n")) return -1;
        if (++e->index >= e->info.npoints) {
            e->index = 0;
            if (!e->info.ndiscs) return 1;
            e->section = V2_RADIUS_DISCS;
        }
        return 0;
    default:
        if (gp_xr_disc(e, e->index, p) || gp_xw_printf(e, "%.17g\n", p[2])) return -1;
        return ++e->index >= e->info.ndiscs;
    }
}
