/* gp_flip.c -- see gp_flip.h. */
#include "gp_flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static gp_status check_tiles(const int tiles[3], size_t n, size_t *ntile, gp_error *err)
{
    size_t t = 1;
    for (int a = 0; a < 3; a++) {
        if (tiles[a] < 1 || tiles[a] > 4096)
            return gp_error_set(err, GP_ERR_INVALID, "tiling[%d] = %d must be in [1, 4096]", a, tiles[a]);
        t *= (size_t)tiles[a];
    }
    if (n && t > ((size_t)-1) / 8 / n)
        return gp_error_set(err, GP_ERR_INVALID, "tiling: too many spheres");
    *ntile = t;
    return GP_OK;
}

static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

gp_status gp_flip_tile(const double *xyzr, size_t n, const double box[3], const int tiles[3],
                       size_t max_spheres, double **out, size_t *nout, gp_error *err)
{
    return gp_flip_tile_ex(xyzr, n, box, tiles, max_spheres, NULL, out, nout, err);
}

gp_status gp_flip_tile_ex(const double *xyzr, size_t n, const double box[3], const int tiles[3],
                          size_t max_spheres, const volatile int *cancel, double **out,
                          size_t *nout, gp_error *err)
{
    *out = NULL;
    *nout = 0;
    size_t nt = 0;
    gp_status st = check_tiles(tiles, n, &nt, err);
    if (st)
        return st;
    for (int a = 0; a < 3; a++)
        if (!(box[a] > 0) || !isfinite(box[a]))
            return gp_error_set(err, GP_ERR_INVALID, "flip: box[%d] must be > 0", a);
    if (nt * n > max_spheres)
        return gp_error_set(err, GP_ERR_INVALID,
                            "tiling: %zu tiles of %zu spheres exceed the limit of %zu spheres",
                            nt, n, max_spheres);
    size_t total = nt * n;
    double *o = malloc((total > 0 ? total : 1) * 4 * sizeof *o);
    if (!o)
        return gp_error_set(err, GP_ERR_NOMEM, "flip: out of memory (%zu spheres)", nt * n);
    for (int kz = 0; kz < tiles[2]; kz++)
        for (int ky = 0; ky < tiles[1]; ky++)
            for (int kx = 0; kx < tiles[0]; kx++) {
                if (cancel_raised(cancel)) { /* a tile: n spheres, at most 400,000 */
                    free(o);
                    return gp_error_set(err, GP_ERR_CANCELLED, "flip: cancelled");
                }
                int k[3] = {kx, ky, kz};
                size_t t = ((size_t)kz * (size_t)tiles[1] + (size_t)ky) * (size_t)tiles[0] + (size_t)kx;
                double *dst = o + 4 * t * n;
                for (size_t i = 0; i < n; i++) {
                    for (int a = 0; a < 3; a++) {
                        double c = xyzr[4 * i + a];
                        dst[4 * i + a] = k[a] * box[a] + ((k[a] & 1) ? box[a] - c : c);
                    }
                    dst[4 * i + 3] = xyzr[4 * i + 3];
                }
            }
    *out = o;
    *nout = nt * n;
    return GP_OK;
}

static int cmp_contact(const void *pa, const void *pb)
{
    const gp_dem3d_contact *a = pa, *b = pb;
    if (a->i != b->i) return a->i < b->i ? -1 : 1;
    return a->j < b->j ? -1 : a->j > b->j;
}

gp_status gp_flip_contacts(const gp_dem3d_contact *c, size_t nc, const double *xyzr, size_t n,
                           const int tiles[3], gp_dem3d_contact **out, size_t *nout,
                           gp_error *err)
{
    return gp_flip_contacts_ex(c, nc, xyzr, n, tiles, NULL, out, nout, err);
}

gp_status gp_flip_contacts_ex(const gp_dem3d_contact *c, size_t nc, const double *xyzr, size_t n,
                              const int tiles[3], const volatile int *cancel,
                              gp_dem3d_contact **out, size_t *nout, gp_error *err)
{
    *out = NULL;
    *nout = 0;
    size_t nt = 0;
    gp_status st = check_tiles(tiles, n, &nt, err);
    if (st)
        return st;
    (void)xyzr;
    size_t cap = nt * nc;
    gp_dem3d_contact *o = malloc((cap ? cap : 1) * sizeof *o);
    gp_dem3d_contact *w = malloc((cap ? cap : 1) * sizeof *w);
    if (!o || !w) {
        free(o); free(w);
        return gp_error_set(err, GP_ERR_NOMEM, "flip: out of memory (%zu contacts)", cap);
    }
    size_t m = 0, mw = 0;
    for (int kz = 0; kz < tiles[2]; kz++)
        for (int ky = 0; ky < tiles[1]; ky++)
            for (int kx = 0; kx < tiles[0]; kx++) {
                if (cancel_raised(cancel)) {
                    free(o);
                    free(w);
                    return gp_error_set(err, GP_ERR_CANCELLED, "flip: cancelled");
                }
                int k[3] = {kx, ky, kz};
                size_t t = ((size_t)kz * (size_t)tiles[1] + (size_t)ky) * (size_t)tiles[0] + (size_t)kx;
                size_t m0 = m; /* this tile's sphere contacts start here */
                size_t stride[3] = {1, (size_t)tiles[0], (size_t)tiles[0] * (size_t)tiles[1]};
                for (size_t q = 0; q < nc; q++) {
                    gp_dem3d_contact e = c[q];
                    for (int a = 0; a < 3; a++)
                        if (k[a] & 1) {
                            e.normal[a] = -e.normal[a];
                            e.force[a] = -e.force[a];
                        }
                    e.i = t * n + c[q].i;
                    if (c[q].j >= 0) {
                        e.j = (long)(t * n + (size_t)c[q].j);
                        o[m++] = e;
                        continue;
                    }
                    int wall = (int)(-1 - c[q].j), a = wall / 2;
                    int side = (wall & 1) ^ (k[a] & 1);
                    int kn = k[a] + (side ? 1 : -1);
                    if (kn < 0 || kn >= tiles[a]) {
                        e.j = -1 - (2 * a + side);
                        w[mw++] = e;
                    } else if (side) {
                        /* inner face: the sphere meets its own image in the next tile (Eq. 13) */
                        size_t t2 = t + stride[a];
                        e.j = (long)(t2 * n + c[q].i);
                        e.overlap = 2 * c[q].overlap;
                        o[m++] = e; /* normal +a (towards the image), force unchanged (-f e_a) */
                    }
                }
                /* Every contact made here has its i in this tile's range [t n, (t + 1) n), and
                 * tiles come in increasing t: sorting each tile's run sorts them all, the same
                 * order as one sort of the whole (a sort by (i, j), which no two contacts share),
                 * in runs short enough to look at the cancel flag between them. */
                qsort(o + m0, m - m0, sizeof *o, cmp_contact);
            }
    for (size_t q = 0; q < mw; q++)
        o[m + q] = w[q];
    free(w);
    *out = o;
    *nout = m + mw;
    return GP_OK;
}
