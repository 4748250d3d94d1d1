/* gp_flip.c -- see gp_flip.h. */
#include "gp_flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_progress.h"

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

gp_status gp_flip_tile(const double *xyzr, size_t n, const double box[3], const int tiles[3],
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
                if (gp_progress_cancelled(cancel)) { /* a tile: n spheres, at most 400,000 */
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

/* A sample contact's place in every tile's sorted run (see gp_flip.h): (i, j) of the
 * contact it makes there, less the tile's offset t n; q is its index in the sample. */
typedef struct flip_key {
    size_t i, j, q;
} flip_key;

static int cmp_key(const void *pa, const void *pb)
{
    const flip_key *a = pa, *b = pb;
    if (a->i != b->i) return a->i < b->i ? -1 : 1;
    if (a->j != b->j) return a->j < b->j ? -1 : 1;
    /* equal keys: the two walls of one axis, never both made in the same tile */
    return a->q < b->q ? -1 : a->q > b->q;
}

static void tile_strides(const int tiles[3], size_t stride[3])
{
    stride[0] = 1;
    stride[1] = (size_t)tiles[0];
    stride[2] = (size_t)tiles[0] * (size_t)tiles[1];
}

/* the sample's contacts in the order of every tile's run; *ord is malloc'ed (nc entries) */
static gp_status sort_keys(const gp_contact3d *c, size_t nc, size_t n, const int tiles[3],
                           flip_key **ord, gp_error *err)
{
    size_t stride[3];
    tile_strides(tiles, stride);
    flip_key *o = malloc((nc ? nc : 1) * sizeof *o);
    if (!o)
        return gp_error_set(err, GP_ERR_NOMEM, "flip: out of memory (%zu contacts)", nc);
    for (size_t q = 0; q < nc; q++) {
        o[q].i = c[q].i;
        o[q].q = q;
        if (c[q].j >= 0)
            o[q].j = (size_t)c[q].j;
        else /* the image pair this wall contact makes, where it makes one */
            o[q].j = stride[(-1 - c[q].j) / 2] * n + c[q].i;
    }
    qsort(o, nc, sizeof *o, cmp_key);
    *ord = o;
    return GP_OK;
}

enum { MADE_NONE = 0, MADE_PAIR = 1, MADE_WALL = 2 };

/* Maps sample contact s into tile t (indices k) as *e. Returns MADE_PAIR for a sphere pair or
 * an image pair (across an inner face, made by the lower of the two tiles so that it is listed
 * once), MADE_WALL for a contact with an outer wall, MADE_NONE where the image pair is the
 * lower neighbour's. */
static int map_contact(const gp_contact3d *s, const int k[3], size_t t, size_t n,
                       const int tiles[3], const size_t stride[3], gp_contact3d *e)
{
    int side = 0, a = 0, kn = 0;
    if (s->j < 0) {
        int wall = (int)(-1 - s->j);
        a = wall / 2;
        side = (wall & 1) ^ (k[a] & 1); /* 1: the wall is on this tile's high face */
        kn = k[a] + (side ? 1 : -1);    /* the neighbour across it */
        if (kn >= 0 && kn < tiles[a] && !side)
            return MADE_NONE;
    }
    *e = *s;
    for (int b = 0; b < 3; b++)
        if (k[b] & 1) {
            e->normal[b] = -e->normal[b];
            e->force[b] = -e->force[b];
        }
    e->i = t * n + s->i;
    if (s->j >= 0) {
        e->j = (long)(t * n + (size_t)s->j);
        return MADE_PAIR;
    }
    if (kn < 0 || kn >= tiles[a]) {
        e->j = -1 - (2 * a + side);
        return MADE_WALL;
    }
    /* inner face: the sphere meets its own image in the next tile (Eq. 13): normal +a
     * (towards the image), force unchanged (-f e_a), full overlap 2 delta */
    e->j = (long)((t + stride[a]) * n + s->i);
    e->overlap = 2 * s->overlap;
    return MADE_PAIR;
}

typedef struct emitter {
    gp_contact3d *buf;
    size_t cap, k;
    gp_flip_visit_fn visit;
    void *user;
    gp_error *err;
} emitter;

static gp_status flush(emitter *m)
{
    size_t k = m->k;
    m->k = 0;
    return k ? m->visit(m->user, m->buf, k, m->err) : GP_OK;
}

/* One pass over the tiles in index order: MADE_PAIR walks the sorted keys, MADE_WALL the
 * sample's wall contacts in their order. */
static gp_status walk(const gp_contact3d *c, const flip_key *ord, size_t nc, size_t n,
                      const int tiles[3], int made, const volatile int *cancel, emitter *m)
{
    size_t stride[3];
    tile_strides(tiles, stride);
    for (int kz = 0; kz < tiles[2]; kz++)
        for (int ky = 0; ky < tiles[1]; ky++)
            for (int kx = 0; kx < tiles[0]; kx++) {
                if (gp_progress_cancelled(cancel)) /* a tile: the sample's contacts, a few million */
                    return gp_error_set(m->err, GP_ERR_CANCELLED, "flip: cancelled");
                int k[3] = {kx, ky, kz};
                size_t t = ((size_t)kz * (size_t)tiles[1] + (size_t)ky) * (size_t)tiles[0] + (size_t)kx;
                for (size_t r = 0; r < nc; r++) {
                    const gp_contact3d *s = made == MADE_PAIR ? c + ord[r].q : c + r;
                    if (made == MADE_WALL && s->j >= 0)
                        continue;
                    if (map_contact(s, k, t, n, tiles, stride, m->buf + m->k) != made)
                        continue;
                    gp_status st;
                    if (++m->k == m->cap && (st = flush(m)))
                        return st;
                }
            }
    return GP_OK;
}

gp_status gp_flip_contacts_each(const gp_contact3d *c, size_t nc, size_t n, const int tiles[3],
                                const volatile int *cancel, gp_contact3d *buf, size_t cap,
                                gp_flip_visit_fn visit, void *user, gp_error *err)
{
    size_t nt = 0;
    gp_status st = check_tiles(tiles, n, &nt, err);
    if (st)
        return st;
    if (!buf || cap == 0 || !visit || (nc && !c))
        return gp_error_set(err, GP_ERR_INVALID, "flip: need a buffer (cap >= 1) and a visitor");
    flip_key *ord = NULL;
    if ((st = sort_keys(c, nc, n, tiles, &ord, err)))
        return st;
    emitter m = {buf, cap, 0, visit, user, err};
    st = walk(c, ord, nc, n, tiles, MADE_PAIR, cancel, &m);
    if (!st)
        st = walk(c, ord, nc, n, tiles, MADE_WALL, cancel, &m);
    if (!st)
        st = flush(&m);
    free(ord);
    return st;
}

typedef struct collector {
    gp_contact3d *o;
    size_t m;
} collector;

static gp_status collect(void *user, const gp_contact3d *chunk, size_t k, gp_error *err)
{
    (void)err;
    collector *cl = user;
    memcpy(cl->o + cl->m, chunk, k * sizeof *chunk);
    cl->m += k;
    return GP_OK;
}

#define COLLECT_CHUNK 4096

gp_status gp_flip_contacts(const gp_contact3d *c, size_t nc, size_t n, const int tiles[3],
                           const volatile int *cancel, gp_contact3d **out, size_t *nout,
                           gp_error *err)
{
    *out = NULL;
    *nout = 0;
    size_t nt = 0;
    gp_status st = check_tiles(tiles, n, &nt, err);
    if (st)
        return st;
    if (nc && nt > ((size_t)-1) / sizeof(gp_contact3d) / nc)
        return gp_error_set(err, GP_ERR_INVALID, "tiling: too many contacts");
    /* every sample contact makes at most one contact per tile: nt nc bounds the count (pages
     * past the end are never touched, and the block is shrunk to fit) */
    size_t cap = nt * nc;
    collector cl = {malloc((cap ? cap : 1) * sizeof *cl.o), 0};
    gp_contact3d *buf = malloc(COLLECT_CHUNK * sizeof *buf);
    if (!cl.o || !buf) {
        free(cl.o); free(buf);
        return gp_error_set(err, GP_ERR_NOMEM, "flip: out of memory (%zu contacts)", cap);
    }
    st = gp_flip_contacts_each(c, nc, n, tiles, cancel, buf, COLLECT_CHUNK, collect, &cl, err);
    free(buf);
    if (st) {
        free(cl.o);
        return st;
    }
    gp_contact3d *fit = realloc(cl.o, (cl.m ? cl.m : 1) * sizeof *fit);
    *out = fit ? fit : cl.o;
    *nout = cl.m;
    return GP_OK;
}
