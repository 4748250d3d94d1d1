/* gp_export_fv3d.c -- the records of a fv3d pack (gp_export.h has its layout): the fv3d block,
 * grain records, clump spheres, the icosphere and the placed vertices of a grain, for the
 * formats of gp_export_fv3d_dem.c and gp_export_fv3d_mesh.c and for the record reader.
 *
 * Reads go through the export's 64 KiB read cache; grain records through a second window, so
 * that a format walking the spheres or radii of grain after grain reads each array front to
 * back once instead of reloading the cache at every grain. A grain's vertices are computed from
 * its radii (read in order) and the directions, loaded once into memory (24 bytes a direction),
 * with the arithmetic of gp_fv3d_grain_vertices: the same doubles, bit for bit.
 */
#include "gp_export_internal.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ the block */

int gp_x3_read_block(gp_export *e)
{
    const unsigned char *p = gp_xr_window(e, GP_PACK_HEADER, GP_PACK_FV3D);
    if (!p || memcmp(p, GP_PACK_FV3D_MAGIC, 8)) return -1;
    gp_x3 *x = &e->x3;
    uint32_t layout;
    memcpy(&e->info.ntriangles, p + 8, 8);
    memcpy(&x->data_bytes, p + 16, 8);
    memcpy(&x->rigid_bytes, p + 24, 8);
    memcpy(&layout, p + 32, 4);
    memcpy(&e->info.volume, p + 40, 8);
    memcpy(&x->rmin, p + 48, 8);
    memcpy(&x->rmax, p + 56, 8);
    if (layout != GP_EXPORT_FV3D_LAYOUT) x->data_bytes = x->rigid_bytes = 0;
    const gp_export_info *in = &e->info;
    e->off_items = GP_PACK_HEADER + GP_PACK_FV3D;
    /* the offsets are used only once the size check (gp_x3_pack_size) has passed */
    e->off_discs = e->off_items + (uint64_t)GP_PACK_GRAIN3 * in->nitems;
    x->off_radii = e->off_discs + 32 * in->ndiscs;
    x->off_dirs = x->off_radii + 8 * in->nitems * in->npoints;
    x->off_tris = x->off_dirs + 24 * in->npoints;
    return 0;
}

double gp_x3_pack_size(const gp_export_info *in)
{
    return GP_PACK_HEADER + (double)GP_PACK_FV3D + (double)GP_PACK_GRAIN3 * (double)in->nitems +
           32.0 * (double)in->ndiscs + 8.0 * (double)in->nitems * (double)in->npoints +
           24.0 * (double)in->npoints + 12.0 * (double)in->ntriangles;
}

/* ------------------------------------------------------------------ records */

int gp_xr_grain3(gp_export *e, uint64_t g, gp_export_grain3 *out)
{
    if (g >= e->info.nitems)
        return gp_error_set(&e->err, GP_ERR_INTERNAL, "grain %llu", (unsigned long long)g), -1;
    const unsigned char *p = gp_xr_window2(e, e->off_items + (uint64_t)GP_PACK_GRAIN3 * g, GP_PACK_GRAIN3);
    if (!p) return -1;
    memcpy(&out->cell, p, 8);
    memcpy(&out->sphere_first, p + 8, 8);
    memcpy(&out->sphere_count, p + 16, 8);
    p += 24;
    double v[19];
    memcpy(v, p, sizeof v);
    memcpy(out->centre, v, 3 * sizeof(double));
    memcpy(out->rotation, v + 3, 4 * sizeof(double));
    out->scale = v[7];
    out->volume = v[8];
    out->mass = v[9];
    memcpy(out->centroid, v + 10, 3 * sizeof(double));
    memcpy(out->inertia, v + 13, 6 * sizeof(double));
    /* a corrupt record must not send the readers past the sphere array */
    uint64_t n = e->info.ndiscs;
    if (out->sphere_first > n || out->sphere_count > n - out->sphere_first) {
        gp_error_set(&e->err, GP_ERR_INVALID, "pack grain %llu spheres outside their array",
                     (unsigned long long)g);
        return -1;
    }
    return 0;
}

static int read_doubles(gp_export *e, uint64_t off, double *out, size_t n)
{
    const unsigned char *p = gp_xr_window(e, off, 8 * n);
    if (!p) return -1;
    memcpy(out, p, 8 * n);
    return 0;
}

int gp_xr_clump(gp_export *e, uint64_t k, double q[4])
{
    if (k >= e->info.ndiscs)
        return gp_error_set(&e->err, GP_ERR_INTERNAL, "clump sphere %llu", (unsigned long long)k), -1;
    return read_doubles(e, e->off_discs + 32 * k, q, 4);
}

int gp_xr_direction(gp_export *e, uint64_t k, double d[3])
{
    if (k >= e->info.npoints)
        return gp_error_set(&e->err, GP_ERR_INTERNAL, "direction %llu", (unsigned long long)k), -1;
    return read_doubles(e, e->x3.off_dirs + 24 * k, d, 3);
}

int gp_xr_triangle(gp_export *e, uint64_t t, uint32_t tri[3])
{
    if (t >= e->info.ntriangles)
        return gp_error_set(&e->err, GP_ERR_INTERNAL, "triangle %llu", (unsigned long long)t), -1;
    const unsigned char *p = gp_xr_window(e, e->x3.off_tris + 12 * t, 12);
    if (!p) return -1;
    memcpy(tri, p, 12);
    for (int k = 0; k < 3; k++)
        if (tri[k] >= e->info.npoints) {
            gp_error_set(&e->err, GP_ERR_INVALID, "pack triangle %llu: vertex %u of %llu",
                         (unsigned long long)t, tri[k], (unsigned long long)e->info.npoints);
            return -1;
        }
    return 0;
}

/* ------------------------------------------------------------------ the icosphere, vertices */

/* 3 x n elements of size sz (n < 2^60 here: the pack's size bounds it) */
static void *alloc3(gp_export *e, uint64_t n, size_t sz)
{
    void *p = malloc((n ? 3 * (size_t)n : 1) * sz);
    if (!p) gp_error_set(&e->err, GP_ERR_NOMEM, "out of memory for the icosphere (%llu)",
                         (unsigned long long)n);
    return p;
}

static int load_dirs(gp_export *e)
{
    gp_x3 *x = &e->x3;
    if (x->dirs) return 0;
    if (!(x->dirs = alloc3(e, e->info.npoints, sizeof(double)))) return -1;
    for (uint64_t k = 0; k < e->info.npoints; k++)
        if (gp_xr_direction(e, k, x->dirs + 3 * k)) return -1;
    return 0;
}

int gp_x3_mesh(gp_export *e)
{
    gp_x3 *x = &e->x3;
    if (load_dirs(e)) return -1;
    if (x->tris) return 0;
    if (!(x->tris = alloc3(e, e->info.ntriangles, sizeof(uint32_t)))) return -1;
    for (uint64_t t = 0; t < e->info.ntriangles; t++)
        if (gp_xr_triangle(e, t, x->tris + 3 * t)) return -1;
    return 0;
}

/* the rotation of a unit quaternion w, x, y, z (gp_fv3d's formula, for the same bits) */
static void rot_of(const double q[4], double R[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                   2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(R, M, sizeof M);
}

int gp_x3_vertices(gp_export *e, uint64_t g, const gp_export_grain3 *gr, double *xyz)
{
    if (load_dirs(e)) return -1;
    uint64_t nd = e->info.npoints;
    double R[9];
    rot_of(gr->rotation, R);
    const double *dirs = e->x3.dirs;
    /* the radii in pieces of the read cache's size */
    const uint64_t piece = 4096;
    for (uint64_t k0 = 0; k0 < nd; k0 += piece) {
        uint64_t m = nd - k0 < piece ? nd - k0 : piece;
        const unsigned char *p = gp_xr_window(e, e->x3.off_radii + 8 * (g * nd + k0), 8 * (size_t)m);
        if (!p) return -1;
        for (uint64_t i = 0; i < m; i++) {
            double r;
            memcpy(&r, p + 8 * i, 8);
            const double *d = dirs + 3 * (k0 + i);
            double q[3] = {r * d[0], r * d[1], r * d[2]};
            double *v = xyz + 3 * (k0 + i);
            for (int a = 0; a < 3; a++)
                v[a] = gr->centre[a] + gr->scale * (R[3 * a] * q[0] + R[3 * a + 1] * q[1] + R[3 * a + 2] * q[2]);
        }
    }
    return 0;
}
