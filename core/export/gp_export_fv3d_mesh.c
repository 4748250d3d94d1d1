/* gp_export_fv3d_mesh.c -- the grains of a fv3d pack as surfaces: vtk and stl. A grain's
 * surface is the shared icosphere placed as the grain (vertex k = centre + scale R (radius_k
 * direction_k), gp_fv3d_grain_vertices' doubles), its triangles counter-clockwise seen from
 * outside; reals in %.17g, so that the files give the meshes' volumes back to rounding.
 *
 * vtk: legacy VTK polydata (ASCII, version 3.0), as the other kinds' vtk files:
 *   FIELD box_lo, box_hi (the container's bounding box); POINTS every grain's vertices, grain by
 *   grain (grain g's vertex k is point g V + k); POLYGONS every grain's triangles (cell g T + t);
 *   CELL_DATA grain_id (int), cell_id (int, its Voronoi cell) and volume (double, m^3, the
 *   grain's), each triangle carrying its grain's. In ParaView: Threshold on grain_id, or colour
 *   by volume.
 * stl: ASCII STL, one "solid grain_<id>" a grain (vtkSTLReader's ScalarTags numbers them), its
 *   facets' normals the unit normals of their triangles (%.9g), vertices %.17g. ASCII rather than
 *   binary: binary STL has 32-bit floats, which lose the volumes' 1e-9; at mesh level 4 a grain
 *   is 5,120 facets, about 1.5 MB.
 * Each record is one line (a point, a triangle, a value) or one facet; the grain being written
 * has its vertices in e->x3.verts (3 V doubles), the icosphere is loaded once (gp_x3_mesh).
 */
#include "gp_export_internal.h"

#include <math.h>
#include <stdlib.h>

/* Loads grain e->index's record and, with verts, its vertices. */
static int load_grain(gp_export *e, int verts)
{
    gp_x3 *x = &e->x3;
    if (gp_xr_grain3(e, e->index, &x->grain)) return -1;
    if (!verts) return 0;
    if (!x->verts) {
        uint64_t n = e->info.npoints;
        if (!(x->verts = malloc((n ? 3 * (size_t)n : 1) * sizeof(double))))
            return gp_error_set(&e->err, GP_ERR_NOMEM, "out of memory for a grain's vertices"), -1;
    }
    return gp_x3_vertices(e, e->index, &x->grain, x->verts);
}

/* ------------------------------------------------------------------ vtk */

enum {
    V_HEAD = 0,
    V_POINTS,
    V_POLYS_HEAD,
    V_POLYS,
    V_CELL_HEAD,
    V_ARRAY_HEAD, /* then V_ARRAY for array e->aux */
    V_ARRAY,
    V_END
};

static const char *const vtk_arrays[] = {"grain_id", "cell_id", "volume"};

/* Steps (grain e->index, item e->sub) to the next of `per` items a grain; 1 past the last. */
static int next_item(gp_export *e, uint64_t per)
{
    if (++e->sub < per) return 0;
    e->sub = 0;
    return ++e->index >= e->info.nitems;
}

int gp_export_step_fv3d_vtk(gp_export *e)
{
    gp_x3 *x = &e->x3;
    const gp_export_info *in = &e->info;
    unsigned long long np = (unsigned long long)(in->nitems * in->npoints);
    unsigned long long nc = (unsigned long long)(in->nitems * in->ntriangles);
    int a = (int)e->aux;
    switch (e->section) {
    case V_HEAD:
        if (gp_x3_mesh(e)) return -1;
        if (gp_xw_printf(e,
                         "# vtk DataFile Version 3.0\n"
                         "grainpack fourier-voronoi-3d: %llu grains (triangulated surfaces), SI "
                         "units (m)\n"
                         "ASCII\n"
                         "DATASET POLYDATA\n"
                         "FIELD FieldData 2\n"
                         "box_lo 3 1 double\n%.17g %.17g %.17g\n"
                         "box_hi 3 1 double\n%.17g %.17g %.17g\n"
                         "POINTS %llu double\n",
                         (unsigned long long)in->nitems, in->lo[0], in->lo[1], in->lo[2],
                         in->hi[0], in->hi[1], in->hi[2], np))
            return -1;
        e->index = e->sub = 0;
        e->section = np ? V_POINTS : V_POLYS_HEAD;
        return 0;
    case V_POINTS: {
        if (e->sub == 0 && load_grain(e, 1)) return -1;
        const double *v = x->verts + 3 * e->sub;
        if (gp_xw_printf(e, "%.17g %.17g %.17g\n", v[0], v[1], v[2])) return -1;
        if (next_item(e, in->npoints)) e->section = V_POLYS_HEAD;
        return 0;
    }
    case V_POLYS_HEAD:
        if (gp_xw_printf(e, "POLYGONS %llu %llu\n", nc, 4 * nc)) return -1;
        e->index = e->sub = 0;
        e->section = nc ? V_POLYS : V_CELL_HEAD;
        return 0;
    case V_POLYS: {
        const uint32_t *t = x->tris + 3 * e->sub;
        unsigned long long o = (unsigned long long)(e->index * in->npoints);
        if (gp_xw_printf(e, "3 %llu %llu %llu\n", o + t[0], o + t[1], o + t[2])) return -1;
        if (next_item(e, in->ntriangles)) e->section = V_CELL_HEAD;
        return 0;
    }
    case V_CELL_HEAD:
        if (gp_xw_printf(e, "CELL_DATA %llu\n", nc)) return -1;
        e->aux = 0;
        e->section = nc ? V_ARRAY_HEAD : V_END;
        return nc == 0;
    case V_ARRAY_HEAD:
        if (gp_xw_printf(e, "SCALARS %s %s 1\nLOOKUP_TABLE default\n", vtk_arrays[a],
                         a < 2 ? "int" : "double"))
            return -1;
        e->index = e->sub = 0;
        e->section = V_ARRAY;
        return 0;
    case V_ARRAY: {
        if (e->sub == 0 && load_grain(e, 0)) return -1;
        int rc = a == 0   ? gp_xw_printf(e, "%llu\n", (unsigned long long)e->index)
                 : a == 1 ? gp_xw_printf(e, "%llu\n", (unsigned long long)x->grain.cell)
                          : gp_xw_printf(e, "%.17g\n", x->grain.volume);
        if (rc) return -1;
        if (!next_item(e, in->ntriangles)) return 0;
        e->aux = a + 1;
        e->section = V_ARRAY_HEAD;
        return a + 1 >= (int)(sizeof vtk_arrays / sizeof vtk_arrays[0]);
    }
    default:
        return 1;
    }
}

/* ------------------------------------------------------------------ stl */

enum { S_SOLID = 0, S_FACET, S_END };

static int stl_facet(gp_export *e)
{
    const gp_x3 *x = &e->x3;
    const uint32_t *t = x->tris + 3 * e->sub;
    const double *a = x->verts + 3 * (size_t)t[0], *b = x->verts + 3 * (size_t)t[1],
                 *c = x->verts + 3 * (size_t)t[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (l > 0)
        for (int k = 0; k < 3; k++) n[k] /= l;
    return gp_xw_printf(e,
                        "facet normal %.9g %.9g %.9g\n"
                        " outer loop\n"
                        "  vertex %.17g %.17g %.17g\n"
                        "  vertex %.17g %.17g %.17g\n"
                        "  vertex %.17g %.17g %.17g\n"
                        " endloop\n"
                        "endfacet\n",
                        n[0], n[1], n[2], a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]);
}

int gp_export_step_fv3d_stl(gp_export *e)
{
    unsigned long long g = (unsigned long long)e->index;
    switch (e->section) {
    case S_SOLID:
        if (e->info.nitems == 0)
            return gp_xw_printf(e, "solid grainpack\nendsolid grainpack\n") ? -1 : 1;
        if (e->index == 0 && gp_x3_mesh(e)) return -1;
        if (load_grain(e, 1) || gp_xw_printf(e, "solid grain_%llu\n", g)) return -1;
        e->sub = 0;
        e->section = e->info.ntriangles ? S_FACET : S_END;
        return 0;
    case S_FACET:
        if (stl_facet(e)) return -1;
        if (++e->sub >= e->info.ntriangles) e->section = S_END;
        return 0;
    default:
        if (gp_xw_printf(e, "endsolid grain_%llu\n", g)) return -1;
        e->section = S_SOLID;
        return ++e->index >= e->info.nitems;
    }
}
