/* gp_voronoi.c -- bounded Voronoi tessellation with local updates. See gp_voronoi.h.
 *
 * Design (the reasons a reviewer needs):
 *
 * - Seeds live in a uniform grid of bins over the container's bounding box, about
 *   GP_VOR_SEEDS_PER_BIN seeds per bin (sized on the container's area, capped at 4N + 64 bins).
 *   Each bin keeps its seeds sorted by index.
 *
 * - Cell i is computed on its own, voro++-style: start from a box B slightly larger than the
 *   container's bounding box and clip it by the bisector half-planes of the seeds found in rings
 *   of bins around seed i (Chebyshev distance 0-1, 2, 3, ...; nearest seeds first). A bin is skipped when its nearest
 *   point is at least 2 Rmax from the seed (Rmax = farthest vertex of the current polygon: no
 *   seed there can cut it), and the search stops when the next ring is that far. When the outer
 *   ring is convex its edges are clipped in the same loop (their half-planes contain the
 *   container), so a convex container costs nothing extra: the polygon IS the cell.
 *   The order of the clips is canonical (rings in a fixed order, seeds by index), and so are
 *   the vertices (below): a cell is a pure function of the seed set. A full build uses this
 *   search; a move uses the neighbour lists (below) and gets the same cells bit for bit.
 *
 * - Holes and non-convex outer rings ("general" rings) are binned too. A cell whose convex
 *   polygon C reaches a bin holding general edges is intersected with the container by a
 *   hand-written convex-polygon-with-region clip (general_clip, in phases: the ring edges'
 *   entry and exit events on C, paired and sorted along C, walked into loops, holes keyholed,
 *   loops stored): ring chains inside C, joined along C's boundary, one loop per part. Vertex
 *   classification and crossings are computed from one snapped set of signed distances, so
 *   they are consistent by construction; touching contacts (a zero-length chain) are dropped;
 *   anything still inconsistent is reported as GP_ERR_INTERNAL, never guessed. No general
 *   polygon library (GEOS) is needed: C is convex, which makes this simple.
 *
 * - Moves ("Moves" below): moving seed i changes only i and the cells that are its neighbours
 *   before or after the move, nb_old(i) U nb_new(i) (about 9 cells, independent of N). The
 *   neighbours used are those of the convex polygon C (its edges with a seed tag): C is the
 *   Voronoi cell within the box B, clipped by the outer ring when that is convex, so they are
 *   the Delaunay neighbours within a convex domain D (B, or the convex container), and in
 *   non-convex containers too. A move takes each changed cell's candidates from these lists, not
 *   from the grid, whose ring search would cost most of an IMC step (docs/design/imc.md): see
 *   "Moves".
 *
 * - Each cell owns a heap buffer (grown, never shrunk). A move computes the new cells into spare
 *   buffers from a pool and swaps pointers; rollback swaps them back (bit-exact, O(1) per cell),
 *   commit copies the new cells into the cells' own buffers and returns the spares to the pool,
 *   so that a cell's data stays where the build put it (in index order: see gp_voronoi_commit).
 *   After warm-up a step does not allocate.
 *
 * Tags: every polygon edge carries a tag: >= 0 the seed whose bisector it lies on, -1 a keyhole
 * bridge, TAG_B + k side k of the box B, otherwise container edge -tag - 2.
 *
 * Canonical vertices: after clipping, every vertex of C is recomputed as the intersection of the
 * two lines named by its edges' tags, and the polygon starts at its largest tag. So C depends on
 * the seed set only, not on the clipping history (a far seed that cut an intermediate polygon
 * leaves no trace), which is what makes a stale-free local update equal a fresh build.
 *
 * Moves. Lemma (D convex, seeds in D): a seed q that is not the nearest to a point x of D has a
 * neighbour r strictly nearer to x -- the segment from q to x leaves q's cell at a point y of an
 * edge shared with some r, and |x - r| <= |x - y| + |y - r| = |x - y| + |y - q| = |x - q|, equal
 * only for degenerate positions. Hence, for a point x in q's cell, x's second-nearest seed is
 * a neighbour of q (on the segment from x to it only the two cells meet). Three cases:
 *  - the moved seed i at its new place p (compute_cell_moved): a best-first search of the
 *    neighbour graph before the move (i at its old place, passed through, never clipped by),
 *    from the seed nearest to p (a greedy walk from a seed of p's bin: by the lemma it ends at
 *    the nearest), popping seeds in increasing distance from p and clipping by each. By the
 *    lemma every seed is reached through a chain of nearer ones, so a seed not popped yet is
 *    at least as far as the heap's top; the search stops when the top is 2 Rmax away, where
 *    no seed can cut. A seed found 2 Rmax away is not pushed at all (Rmax only shrinks, so it
 *    would never be popped; the seeds beyond it that could still cut have nearer chains).
 *    The convex ring's edges: those in the bins under the polygon.
 *  - a former neighbour j of i (compute_cell_nb): removing i hands each point of i's old cell
 *    to its second-nearest seed, a neighbour of i; so new contacts arise only among nb_old(i),
 *    and inserting i at p removes contacts except with i: nb_new(j) is in nb_old(j) U nb_old(i)
 *    U {i}, which are the candidates. The new cell lies in old C_j U old C_i, so the convex
 *    ring's edges that bound it bound one of those: their edges are the edge candidates.
 *  - a new neighbour j only (compute_cell_cut): it lost to i and gained nothing (i's old cell
 *    went to i's old neighbours), so its new
 *    polygon is the old one (when that was one convex part) cut by the bisector of j and p.
 * Each result is then made canonical like any cell: which superset of the neighbours clipped it
 * leaves no trace (canonical vertices, above), so a moved cell equals the one a full build
 * (from the grid) gives, bit for bit, barring near-degenerate vertices (four seeds co-circular
 * within ~1e-13 of the container, nearly parallel edges), which no test of 10^4 moves has met.
 * compute_cell_nb starts from old C_j less i's edge where that polygon closes (half of the
 * cases), so that only nb_old(i) and i are left to clip.
 */
#include "gp_voronoi.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_grid.h"

#define GP_VOR_SEEDS_PER_BIN 2.0
#define GP_VOR_PI 3.14159265358979323846
#define TAG_B INT32_MIN
#define TAG_SMALL (INT32_MIN + 4) /* a side of the provisional small box: never in a result */

typedef struct vcell {
    int32_t nv, cap;      /* vertices of all parts / capacity of v, tag */
    int32_t nparts, seed_part, pcap;
    int32_t nnb, nbcap;   /* neighbours of the convex polygon (update set), sorted */
    int32_t nce;          /* convex outer-ring edges of the convex polygon, in nb[nnb ..) */
    int32_t convex;       /* 1: one convex part (the clipped Voronoi polygon itself) */
    double area, orient;
    gp_vec2 oe;           /* convex: the side orient is the direction of (NaN otherwise) */
    gp_vec2 *v;
    int32_t *tag;
    int32_t *poff;        /* nparts + 1 offsets into v */
    int32_t *nb;
} vcell;

typedef struct vbin {
    int32_t cnt, cap;
    int32_t *s; /* NULL: use inl */
    int32_t inl[4];
} vbin;

typedef struct vevent {
    double key;
    gp_vec2 p;
    int32_t edge, line, type, mate, pos, dropped;
} vevent;

struct gp_voronoi {
    uint32_t n;
    gp_vec2 origin;
    double L, W, H, tol;
    /* container, local coordinates: rings concatenated; vertex id == id of the edge it starts */
    uint32_t nrings, nedges;
    uint32_t *roff;
    gp_vec2 *rv;
    int32_t *enext;     /* next edge (= end vertex) of edge e */
    int32_t *ering;
    int outer_convex, has_general;
    double carea;
    gp_vec2 bmin, bmax; /* the box B */
    /* grid */
    int32_t nbx, nby;
    double hx, hy, ihx, ihy;
    vbin *bins;
    uint32_t *ce_off, *ce, *ge_off, *ge;
    unsigned char *bstate;
    /* seeds (local and as given) and cells */
    gp_vec2 *seed, *useed;
    vcell **cell;
    vcell **pool;
    uint32_t npool, poolcap;
    /* pending move */
    int pending;
    uint32_t mv_i;
    gp_vec2 mv_seed, mv_useed;
    uint32_t *chg;
    vcell **chg_old;
    uint32_t nchg, chgcap;
    /* scratch */
    uint32_t *estamp, stamp;
    uint32_t *eslot_st, gstamp;
    int32_t *eslot_in, *eslot_out;
    uint32_t *rst;
    int32_t *rev;
    uint32_t *cst, cstamp;
    uint32_t *kst, kstamp; /* candidates of one cell recomputed by a move */
    double *hq_d;          /* the moved cell's search: a min-heap of (distance, seed) */
    int32_t *hq_j;
    int32_t hqcap;
    gp_vec2 *sa, *sb;
    int32_t *ta, *tb;
    double *sd;
    int32_t scap;
    int32_t *gedges;
    int32_t gecap;
    vevent *ev;
    int32_t evcap;
    int32_t *evs;
    int32_t evscap;
    double *da, *db, *lex, *ley, *leps;
    int32_t lcap;
    gp_vec2 *lv; /* loop builder */
    int32_t *lt, *lpo;
    int32_t lvcap, lpcap;
    gp_vec2 *hv;
    int32_t hcap;
    int32_t *aff;
    int32_t affcap;
    double *cand_d;
    int32_t *cand_j;
    int32_t candcap;
};

/* ------------------------------------------------------------------------------------------ */
/* small helpers                                                                               */

static int grow(void **p, int32_t *cap, int32_t need, size_t elt)
{
    if (need <= *cap) return 0;
    int32_t c = *cap ? *cap : 16;
    while (c < need) c *= 2;
    void *q = realloc(*p, (size_t)c * elt);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

static inline double cross3(gp_vec2 o, gp_vec2 a, gp_vec2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

static double ring_area_about(const gp_vec2 *p, int32_t n, gp_vec2 r)
{
    double s = 0.0;
    for (int32_t k = 0; k < n; k++) {
        gp_vec2 a = p[k], b = p[k + 1 == n ? 0 : k + 1];
        s += (a.x - r.x) * (b.y - r.y) - (a.y - r.y) * (b.x - r.x);
    }
    return 0.5 * s;
}

static double seg_dist2(gp_vec2 q, gp_vec2 a, gp_vec2 b)
{
    double ex = b.x - a.x, ey = b.y - a.y, qx = q.x - a.x, qy = q.y - a.y;
    double l2 = ex * ex + ey * ey, t = l2 > 0 ? (qx * ex + qy * ey) / l2 : 0.0;
    if (t < 0) t = 0;
    if (t > 1) t = 1;
    double dx = qx - t * ex, dy = qy - t * ey;
    return dx * dx + dy * dy;
}

static inline int32_t *bin_items(vbin *b) { return b->s ? b->s : b->inl; }

static int bin_insert(vbin *b, int32_t i)
{
    if (b->cnt == (b->s ? b->cap : 4)) {
        int32_t nc = b->cnt * 2;
        int32_t *q = malloc((size_t)nc * sizeof *q);
        if (!q) return -1;
        memcpy(q, bin_items(b), (size_t)b->cnt * sizeof *q);
        free(b->s);
        b->s = q;
        b->cap = nc;
    }
    int32_t *it = bin_items(b);
    int32_t k = b->cnt;
    while (k > 0 && it[k - 1] > i) {
        it[k] = it[k - 1];
        k--;
    }
    it[k] = i;
    b->cnt++;
    return 0;
}

static void bin_remove(vbin *b, int32_t i)
{
    int32_t *it = bin_items(b);
    int32_t k = 0;
    while (k < b->cnt && it[k] != i) k++;
    for (; k + 1 < b->cnt; k++) it[k] = it[k + 1];
    if (b->cnt > 0) b->cnt--;
}

static inline int32_t bin_x(const gp_voronoi *v, double x)
{
    return (int32_t)gp_grid_cell(x * v->ihx, (size_t)v->nbx);
}
static inline int32_t bin_y(const gp_voronoi *v, double y)
{
    return (int32_t)gp_grid_cell(y * v->ihy, (size_t)v->nby);
}

/* the bin of local point p */
static inline int32_t bin_of(const gp_voronoi *v, gp_vec2 p) { return bin_y(v, p.y) * v->nbx + bin_x(v, p.x); }

/* The bins a polygon's bounding box reaches, padded by 1e-9 L (an edge on a bin's border is
 * in both): r = {ix0, ix1, iy0, iy1}, inclusive. */
static void poly_bins(const gp_voronoi *v, const gp_vec2 *p, size_t m, int32_t r[4])
{
    gp_vec2 lo, hi;
    gp_poly_bbox(p, m, &lo, &hi, NULL);
    double pad = 1e-9 * v->L;
    r[0] = bin_x(v, lo.x - pad), r[1] = bin_x(v, hi.x + pad);
    r[2] = bin_y(v, lo.y - pad), r[3] = bin_y(v, hi.y + pad);
}

static void stamp_next(uint32_t *stamp, uint32_t *arr, size_t n)
{
    if (++*stamp == 0) {
        memset(arr, 0, n * sizeof *arr);
        *stamp = 1;
    }
}

static vcell *pool_get(gp_voronoi *v)
{
    if (v->npool) return v->pool[--v->npool];
    return calloc(1, sizeof(vcell));
}

static int pool_put(gp_voronoi *v, vcell *c)
{
    if (v->npool == v->poolcap) {
        uint32_t nc = v->poolcap ? v->poolcap * 2 : 64;
        vcell **q = realloc(v->pool, nc * sizeof *q);
        if (!q) return -1;
        v->pool = q;
        v->poolcap = nc;
    }
    v->pool[v->npool++] = c;
    return 0;
}

static void cell_free(vcell *c)
{
    if (!c) return;
    free(c->v);
    free(c->tag);
    free(c->poff);
    free(c->nb);
    free(c);
}

/* c back to the pool, or freed when the pool cannot grow (out of memory) */
static void pool_give(gp_voronoi *v, vcell *c)
{
    if (pool_put(v, c)) cell_free(c);
}

static int cell_reserve(vcell *c, int32_t nv, int32_t np, int32_t nnb)
{
    if (nv > c->cap) {
        int32_t cap = c->cap;
        if (grow((void **)&c->v, &cap, nv, sizeof(gp_vec2))) return -1;
        int32_t cap2 = c->cap;
        if (grow((void **)&c->tag, &cap2, cap, sizeof(int32_t))) return -1;
        c->cap = cap;
    }
    if (np + 1 > c->pcap && grow((void **)&c->poff, &c->pcap, np + 1, sizeof(int32_t))) return -1;
    if (nnb > c->nbcap && grow((void **)&c->nb, &c->nbcap, nnb, sizeof(int32_t))) return -1;
    return 0;
}

static int scratch_reserve(gp_voronoi *v, int32_t need)
{
    if (need <= v->scap) return 0;
    int32_t c0 = v->scap;
    int32_t c = c0;
    if (grow((void **)&v->sa, &c, need, sizeof(gp_vec2))) return -1;
    c = c0;
    if (grow((void **)&v->sb, &c, need, sizeof(gp_vec2))) return -1;
    c = c0;
    if (grow((void **)&v->ta, &c, need, sizeof(int32_t))) return -1;
    c = c0;
    if (grow((void **)&v->tb, &c, need, sizeof(int32_t))) return -1;
    c = c0;
    if (grow((void **)&v->sd, &c, need, sizeof(double))) return -1;
    v->scap = c;
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* convex polygon primitives                                                                   */

/* Keeps the part of polygon (sv, st, m) where d(x) = (x - o) . nrm <= 0 (|d| <= eps counts as
 * 0), writes it to (dv, dt) with newtag on the new edge. Returns the new vertex count, -1 when
 * the half-plane does not cut (the caller keeps its polygon), 0 when nothing is left. */
static inline __attribute__((always_inline)) int32_t
clip_hp(const gp_vec2 *sv, const int32_t *st, int32_t m, gp_vec2 o, gp_vec2 nrm, double eps, int32_t newtag,
        gp_vec2 *dv, int32_t *dt, double *d, gp_vec2 s, double *rmax2)
{
    /* First pass: the raw signed distances and their largest. A snapped distance is > 0 exactly
     * when the raw one is > eps, so "no vertex beyond the line" (a candidate that does not
     * cut: about half of them) is decided here, without snapping or flag bookkeeping. */
    double tmax = -INFINITY;
    for (int32_t k = 0; k < m; k++) {
        double t = (sv[k].x - o.x) * nrm.x + (sv[k].y - o.y) * nrm.y;
        d[k] = t;
        tmax = t > tmax ? t : tmax;
    }
    if (!(tmax > eps)) return -1;
    /* Second pass: the kept part, each distance snapped as it is first read (d[0] up front, the
     * others as the next vertex). Nothing kept (w == 0) is the "all beyond the line" case. */
#define GP_SNAP(T) ((T) <= eps && (T) >= -eps ? 0.0 : (T))
    int32_t w = 0;
    double r2 = 0.0;
#define GP_EMIT(P, T)                                                                  \
    do {                                                                               \
        gp_vec2 p_ = (P);                                                              \
        double ex_ = p_.x - s.x, ey_ = p_.y - s.y, d2_ = ex_ * ex_ + ey_ * ey_;        \
        if (d2_ > r2) r2 = d2_;                                                        \
        dv[w] = p_;                                                                    \
        dt[w++] = (T);                                                                 \
    } while (0)
    const double d0 = GP_SNAP(d[0]);
    double dk = d0;
    for (int32_t k = 0; k < m; k++) {
        int32_t j = k + 1 == m ? 0 : k + 1;
        double dj = j == 0 ? d0 : GP_SNAP(d[j]);
        if (dk <= 0.0) {
            GP_EMIT(sv[k], (dk == 0.0 && dj > 0.0) ? newtag : st[k]);
            if (dk < 0.0 && dj > 0.0) {
                double t = dk / (dk - dj);
                GP_EMIT(((gp_vec2){sv[k].x + t * (sv[j].x - sv[k].x), sv[k].y + t * (sv[j].y - sv[k].y)}), newtag);
            }
        } else if (dj < 0.0) {
            double t = dk / (dk - dj);
            GP_EMIT(((gp_vec2){sv[k].x + t * (sv[j].x - sv[k].x), sv[k].y + t * (sv[j].y - sv[k].y)}), st[k]);
        }
        dk = dj;
    }
#undef GP_EMIT
#undef GP_SNAP
    *rmax2 = r2;
    return w;
}

/* Orientation of a convex counter-clockwise polygon: the axis angle (radians, (-pi/2, pi/2])
 * of the side across which the width is smallest, by gp_min_caliper's rotating calipers (same
 * start and tie rule) on squared widths; sides shorter than sqrt(eps2) are skipped, they are
 * collinear runs of the clipped polygon. */
static double convex_orientation(const gp_vec2 *p, int32_t m, double eps2, const vcell *prev, gp_vec2 *e)
{
    size_t k = gp_min_caliper_edge(p, (size_t)m, eps2, 1);
    size_t k1 = k + 1 >= (size_t)m ? 0 : k + 1;
    *e = k == (size_t)m ? (gp_vec2){1.0, 0.0} : (gp_vec2){p[k1].x - p[k].x, p[k1].y - p[k].y};
    /* the cell before a move, thinnest across the same side bit for bit (about half of a
     * move's cells: canonical vertices away from the changed edge keep their bits): the same
     * angle, without the atan2 */
    if (prev && memcmp(&prev->oe, e, sizeof *e) == 0) return prev->orient;
    return gp_axis_angle(e->x, e->y);
}

static int vlt(const void *a, const void *b)
{
    const gp_vec2 *p = a, *q = b;
    if (p->x < q->x) return -1;
    if (p->x > q->x) return 1;
    if (p->y < q->y) return -1;
    if (p->y > q->y) return 1;
    return 0;
}

/* convex hull (monotone chain) of p into h (capacity 2n), counter-clockwise; returns count */
static int32_t hull(gp_vec2 *p, int32_t n, gp_vec2 *h)
{
    qsort(p, (size_t)n, sizeof *p, vlt);
    int32_t k = 0;
    for (int32_t i = 0; i < n; i++) {
        while (k >= 2 && cross3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    for (int32_t i = n - 2, t = k + 1; i >= 0; i--) {
        while (k >= t && cross3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    return k > 1 ? k - 1 : k;
}

/* ------------------------------------------------------------------------------------------ */
/* the general clip: convex polygon C (CCW) intersected with the container near it            */

static int push_lv(gp_voronoi *v, int32_t *n, gp_vec2 p, int32_t tag)
{
    if (*n + 1 > v->lvcap) {
        int32_t c = v->lvcap;
        if (grow((void **)&v->lv, &c, *n + 1, sizeof(gp_vec2))) return -1;
        int32_t c2 = v->lvcap;
        if (grow((void **)&v->lt, &c2, c, sizeof(int32_t))) return -1;
        v->lvcap = c;
    }
    v->lv[*n] = p;
    v->lt[*n] = tag;
    (*n)++;
    return 0;
}

/* removes consecutive duplicates (within dup) of loop [b, e) in lv, keeping the later vertex's
 * tag; returns the new end */
static int32_t dedup_loop(gp_voronoi *v, int32_t b, int32_t e, double dup)
{
    int32_t w = b;
    for (int32_t k = b; k < e; k++) {
        int32_t k1 = k + 1 < e ? k + 1 : -1;
        if (k1 >= 0 && fabs(v->lv[k].x - v->lv[k1].x) <= dup && fabs(v->lv[k].y - v->lv[k1].y) <= dup)
            continue;
        v->lv[w] = v->lv[k];
        v->lt[w++] = v->lt[k];
    }
    while (w - b >= 2 && fabs(v->lv[w - 1].x - v->lv[b].x) <= dup &&
           fabs(v->lv[w - 1].y - v->lv[b].y) <= dup)
        w--; /* the last equals the first: drop the last (its edge is zero-length) */
    return w;
}

static inline double line_d(const gp_voronoi *v, const gp_vec2 *P, int32_t k, gp_vec2 x)
{
    double d = v->lex[k] * (x.y - P[k].y) - v->ley[k] * (x.x - P[k].x);
    return (d <= v->leps[k] && d >= -v->leps[k]) ? 0.0 : d;
}

/* Inserts hole ring r (all inside loop [b, e) of lv) with a keyhole bridge. Rebuilds lv. */
static int keyhole(gp_voronoi *v, int32_t *nlv, int32_t li, int32_t nloops, int32_t r)
{
    int32_t hb = (int32_t)v->roff[r], he = (int32_t)v->roff[r + 1], hn = he - hb;
    int32_t b = v->lpo[li], e = v->lpo[li + 1];
    int32_t hm = hb;
    for (int32_t k = hb; k < he; k++)
        if (v->rv[k].x > v->rv[hm].x) hm = k;
    gp_vec2 h = v->rv[hm];
    /* ray to +x from h: nearest loop edge crossing; bridge to that edge's rightmost end */
    double best = INFINITY;
    int32_t u = -1;
    for (int32_t k = b; k < e; k++) {
        gp_vec2 a = v->lv[k], c = v->lv[k + 1 < e ? k + 1 : b];
        if ((a.y > h.y) != (c.y > h.y)) {
            double x = a.x + (h.y - a.y) * (c.x - a.x) / (c.y - a.y);
            if (x >= h.x && x < best) {
                best = x;
                u = a.x >= c.x ? k : (k + 1 < e ? k + 1 : b);
            }
        }
    }
    if (u < 0) return -1;
    /* new loop: lv[b..u], h .. (hole order) .. h, lv[u..e) */
    int32_t add = hn + 2;
    if (grow((void **)&v->hv, &v->hcap, *nlv + add, sizeof(gp_vec2))) return -1;
    int32_t tmpcap = 0;
    int32_t *tt = NULL;
    if (grow((void **)&tt, &tmpcap, *nlv + add, sizeof(int32_t))) return -1;
    int32_t w = 0;
    for (int32_t k = 0; k <= u; k++) {
        v->hv[w] = v->lv[k];
        tt[w++] = k == u ? -1 : v->lt[k];
    }
    for (int32_t c = 0; c < hn; c++) {
        int32_t k = hm + c;
        if (k >= he) k -= hn;
        v->hv[w] = v->rv[k];
        tt[w++] = -(k + 2);
    }
    v->hv[w] = h;
    tt[w++] = -1;
    for (int32_t k = u; k < *nlv; k++) {
        v->hv[w] = v->lv[k];
        tt[w++] = v->lt[k];
    }
    if (w > v->lvcap) {
        int32_t c = v->lvcap;
        if (grow((void **)&v->lv, &c, w, sizeof(gp_vec2))) { free(tt); return -1; }
        int32_t c2 = v->lvcap;
        if (grow((void **)&v->lt, &c2, c, sizeof(int32_t))) { free(tt); return -1; }
        v->lvcap = c;
    }
    memcpy(v->lv, v->hv, (size_t)w * sizeof(gp_vec2));
    memcpy(v->lt, tt, (size_t)w * sizeof(int32_t));
    free(tt);
    *nlv = w;
    for (int32_t q = li + 1; q <= nloops; q++) v->lpo[q] += add;
    return 0;
}

/* The general clip of one cell: C = (P, T, m), convex and counter-clockwise, intersected with
 * the general rings near it (their edges gathered in v->gedges[0 .. ng), sorted). The phases
 * below run in order over this state; the loops being built live in v->lv / v->lt, their
 * offsets in v->lpo. */
typedef struct clip_run {
    gp_voronoi *v;
    gp_vec2 s;            /* the seed */
    const gp_vec2 *P;
    const int32_t *T;
    int32_t m, ng;
    uint32_t es;          /* this clip's stamp in v->eslot_st */
    double dup;           /* points closer than this (per coordinate) are one */
    int32_t ne;           /* events in v->ev */
    int32_t nk;           /* events kept, in boundary order in ord[0 .. nk) */
    int32_t *ord, *used;
    int32_t nlv, nloops;  /* vertices and loops built */
} clip_run;

/* The lines of C's edges: direction (lex, ley) and snapping tolerance leps. */
static gp_status clip_lines(gp_voronoi *v, const gp_vec2 *P, int32_t m)
{
    if (m > v->lcap) {
        int32_t c = v->lcap ? v->lcap : 16;
        while (c < m) c *= 2;
        double **arrs[5] = {&v->lex, &v->ley, &v->leps, &v->da, &v->db};
        for (int a = 0; a < 5; a++) {
            double *q = realloc(*arrs[a], (size_t)c * sizeof(double));
            if (!q) return GP_ERR_NOMEM;
            *arrs[a] = q;
        }
        v->lcap = c;
    }
    const double epsr = 1e-13 * v->L;
    for (int32_t k = 0; k < m; k++) {
        int32_t k1 = k + 1 == m ? 0 : k + 1;
        v->lex[k] = P[k1].x - P[k].x;
        v->ley[k] = P[k1].y - P[k].y;
        v->leps[k] = epsr * (fabs(v->lex[k]) + fabs(v->ley[k]));
    }
    return GP_OK;
}

/* The entry and exit of ring edge e through C, as events keyed by their position along C's
 * boundary (line k + parameter on it). Both come from one snapped set of signed distances
 * (line_d), so classification and crossings agree by construction. */
static gp_status edge_events(clip_run *R, int32_t e)
{
    gp_voronoi *v = R->v;
    const gp_vec2 *P = R->P;
    const int32_t m = R->m;
    double *da = v->da, *db = v->db;
    gp_vec2 a = v->rv[e], b = v->rv[v->enext[e]];
    int ain = 1, bin = 1;
    for (int32_t k = 0; k < m; k++) {
        da[k] = line_d(v, P, k, a);
        db[k] = line_d(v, P, k, b);
        if (da[k] < 0) ain = 0;
        if (db[k] < 0) bin = 0;
    }
    v->rst[v->ering[e]] = 1;
    v->eslot_st[e] = R->es;
    v->eslot_in[e] = -1;
    v->eslot_out[e] = -1;
    if (ain && bin) return GP_OK;
    double t0 = 0.0, t1 = 1.0;
    int32_t k0 = -1, k1 = -1;
    for (int32_t k = 0; k < m; k++) {
        if (da[k] < 0 && db[k] < 0) return GP_OK; /* wholly outside one line */
        if (da[k] < 0) {
            double t = da[k] / (da[k] - db[k]);
            if (t > t0 || k0 < 0) {
                t0 = t;
                k0 = k;
            }
        } else if (db[k] < 0) {
            double t = da[k] / (da[k] - db[k]);
            if (t < t1 || k1 < 0) {
                t1 = t;
                k1 = k;
            }
        }
    }
    int want_in = !ain, want_out = !bin;
    if (!ain && !bin && !(t0 < t1)) return GP_OK;
    if (R->ne + 2 > v->evcap && grow((void **)&v->ev, &v->evcap, R->ne + 2, sizeof(vevent)))
        return GP_ERR_NOMEM;
    for (int w = 0; w < 2; w++) {
        if (w == 0 && !want_in) continue;
        if (w == 1 && !want_out) continue;
        double t = w == 0 ? t0 : t1;
        int32_t k = w == 0 ? k0 : k1;
        if (k < 0) return GP_ERR_INTERNAL;
        vevent *E = &v->ev[R->ne];
        E->p.x = a.x + t * (b.x - a.x);
        E->p.y = a.y + t * (b.y - a.y);
        if (t == 0.0) E->p = a;
        if (t == 1.0) E->p = b;
        double l2 = v->lex[k] * v->lex[k] + v->ley[k] * v->ley[k];
        double sp = ((E->p.x - P[k].x) * v->lex[k] + (E->p.y - P[k].y) * v->ley[k]) / l2;
        if (!(sp >= 0)) sp = 0;
        if (sp > 1) sp = 1;
        E->key = k + sp;
        E->edge = e;
        E->line = k;
        E->type = w;
        E->mate = -1;
        E->dropped = 0;
        if (w == 0) v->eslot_in[e] = R->ne;
        else v->eslot_out[e] = R->ne;
        v->rev[v->ering[e]] = 1;
        R->ne++;
    }
    return GP_OK;
}

/* Events of every gathered edge; per ring, whether it was seen (rst) and crossed (rev). */
static gp_status clip_events(clip_run *R)
{
    gp_voronoi *v = R->v;
    stamp_next(&v->gstamp, v->eslot_st, v->nedges);
    R->es = v->gstamp;
    R->ne = 0;
    for (uint32_t r = 0; r < v->nrings; r++) {
        v->rst[r] = 0;
        v->rev[r] = 0;
    }
    for (int32_t g = 0; g < R->ng; g++) {
        gp_status st = edge_events(R, v->gedges[g]);
        if (st != GP_OK) return st;
    }
    return GP_OK;
}

/* Pairs each entry with the exit that ends its ring chain inside C; a touching contact (a
 * chain of at most one ring vertex within dup) is dropped. Every event must find its mate. */
static gp_status clip_pair(clip_run *R)
{
    gp_voronoi *v = R->v;
    const double dup = R->dup;
    for (int32_t q = 0; q < R->ne; q++) {
        vevent *E = &v->ev[q];
        if (E->type != 0) continue;
        int32_t e = E->edge, nint = 0, steps = 0, r = v->ering[e];
        int32_t ringlen = (int32_t)(v->roff[r + 1] - v->roff[r]);
        double x0 = E->p.x, x1 = E->p.x, y0 = E->p.y, y1 = E->p.y;
        while (v->eslot_out[e] < 0) {
            int32_t vx = v->enext[e];
            gp_vec2 p = v->rv[vx];
            if (p.x < x0) x0 = p.x;
            if (p.x > x1) x1 = p.x;
            if (p.y < y0) y0 = p.y;
            if (p.y > y1) y1 = p.y;
            nint++;
            e = vx;
            if (v->eslot_st[e] != R->es || ++steps > ringlen) return GP_ERR_INTERNAL;
        }
        int32_t xq = v->eslot_out[e];
        vevent *X = &v->ev[xq];
        if (X->p.x < x0) x0 = X->p.x;
        if (X->p.x > x1) x1 = X->p.x;
        if (X->p.y < y0) y0 = X->p.y;
        if (X->p.y > y1) y1 = X->p.y;
        E->mate = xq;
        X->mate = q;
        if (nint <= 1 && x1 - x0 <= dup && y1 - y0 <= dup) E->dropped = X->dropped = 1;
    }
    for (int32_t q = 0; q < R->ne; q++)
        if (v->ev[q].mate < 0) return GP_ERR_INTERNAL;
    return GP_OK;
}

/* The kept events in order along C's boundary (key, then exits before entries, then edge). */
static gp_status clip_sort(clip_run *R)
{
    gp_voronoi *v = R->v;
    const int32_t ne = R->ne;
    if (grow((void **)&v->evs, &v->evscap, 2 * ne + 2, sizeof(int32_t))) return GP_ERR_NOMEM;
    int32_t *ord = v->evs;
    int32_t nk = 0;
    for (int32_t q = 0; q < ne; q++) {
        if (v->ev[q].dropped) continue;
        int32_t k = nk++;
        while (k > 0) {
            const vevent *A = &v->ev[ord[k - 1]], *B = &v->ev[q];
            int gt = A->key > B->key ||
                     (A->key == B->key && (A->type < B->type || (A->type == B->type && A->edge > B->edge)));
            if (!gt) break;
            ord[k] = ord[k - 1];
            k--;
        }
        ord[k] = q;
    }
    for (int32_t k = 0; k < nk; k++) v->ev[ord[k]].pos = k;
    R->ord = ord;
    R->used = v->evs + ne + 1;
    R->nk = nk;
    return GP_OK;
}

/* One loop from exit k0: along C to the next entry, then along the ring to its exit, and so
 * on until back at k0. */
static gp_status clip_walk(clip_run *R, int32_t k0)
{
    gp_voronoi *v = R->v;
    const int32_t m = R->m, nk = R->nk, *ord = R->ord;
    int32_t k = k0, guard = 0;
    do {
        const vevent *X = &v->ev[ord[k]];
        R->used[k] = 1;
        const vevent *E = &v->ev[ord[(k + 1) % nk]];
        if (push_lv(v, &R->nlv, X->p, R->T[X->line])) return GP_ERR_NOMEM;
        if (!(E->line == X->line && E->key >= X->key)) {
            int32_t c = X->line;
            do {
                c = c + 1 == m ? 0 : c + 1;
                if (push_lv(v, &R->nlv, R->P[c], R->T[c])) return GP_ERR_NOMEM;
            } while (c != E->line);
        }
        if (push_lv(v, &R->nlv, E->p, -(E->edge + 2))) return GP_ERR_NOMEM;
        int32_t e = E->edge;
        while (v->eslot_out[e] < 0) {
            int32_t vx = v->enext[e];
            if (push_lv(v, &R->nlv, v->rv[vx], -(vx + 2))) return GP_ERR_NOMEM;
            e = vx;
        }
        k = v->ev[v->eslot_out[e]].pos;
        if (++guard > nk) return GP_ERR_INTERNAL;
    } while (k != k0);
    return GP_OK;
}

/* The loops when rings cross C: along C the kept events must alternate exit, entry, exit,
 * ...; each unused exit starts a loop; loops of fewer than 3 distinct points are dropped. */
static gp_status clip_loops_crossing(clip_run *R)
{
    gp_voronoi *v = R->v;
    const int32_t nk = R->nk;
    if (nk % 2) return GP_ERR_INTERNAL;
    int32_t f = v->ev[R->ord[0]].type;
    for (int32_t k = 0; k < nk; k++)
        if (v->ev[R->ord[k]].type != ((f + k) & 1)) return GP_ERR_INTERNAL;
    for (int32_t k = 0; k < nk; k++) R->used[k] = 0;
    for (int32_t k0 = 0; k0 < nk; k0++) {
        if (R->used[k0] || v->ev[R->ord[k0]].type != 1) continue;
        int32_t b = R->nlv;
        gp_status st = clip_walk(R, k0);
        if (st != GP_OK) return st;
        R->nlv = dedup_loop(v, b, R->nlv, R->dup);
        if (R->nlv - b < 3) {
            R->nlv = b;
            continue;
        }
        if (grow((void **)&v->lpo, &v->lpcap, R->nloops + 2, sizeof(int32_t))) return GP_ERR_NOMEM;
        v->lpo[++R->nloops] = R->nlv;
    }
    return GP_OK;
}

/* No crossing: C lies inside the region (the loop is C), or a general outer ring lies inside C
 * (the loop is that ring). */
static gp_status clip_loops_inside(clip_run *R)
{
    gp_voronoi *v = R->v;
    int outer_in = 0;
    if (!v->outer_convex && v->rst[0] && !v->rev[0]) {
        int in = 1;
        for (int32_t k = 0; k < R->m; k++)
            if (line_d(v, R->P, k, v->rv[0]) < 0) in = 0;
        outer_in = in;
    }
    if (outer_in) {
        for (uint32_t k = v->roff[0]; k < v->roff[1]; k++)
            if (push_lv(v, &R->nlv, v->rv[k], -((int32_t)k + 2))) return GP_ERR_NOMEM;
    } else {
        for (int32_t k = 0; k < R->m; k++)
            if (push_lv(v, &R->nlv, R->P[k], R->T[k])) return GP_ERR_NOMEM;
    }
    if (grow((void **)&v->lpo, &v->lpcap, 2, sizeof(int32_t))) return GP_ERR_NOMEM;
    v->lpo[++R->nloops] = R->nlv;
    return GP_OK;
}

/* Holes lying entirely inside C: each is keyholed into the loop that holds it. */
static gp_status clip_keyholes(clip_run *R)
{
    gp_voronoi *v = R->v;
    for (uint32_t r = 1; r < v->nrings; r++) {
        if (!v->rst[r] || v->rev[r]) continue;
        gp_vec2 h0 = v->rv[v->roff[r]];
        int in = 1;
        for (int32_t k = 0; k < R->m; k++)
            if (line_d(v, R->P, k, h0) < 0) in = 0;
        if (!in) continue;
        for (int32_t li = 0; li < R->nloops; li++) {
            if (gp_poly_contains(v->lv + v->lpo[li], (size_t)(v->lpo[li + 1] - v->lpo[li]), h0)) {
                if (keyhole(v, &R->nlv, li, R->nloops, (int32_t)r)) return GP_ERR_NOMEM;
                break;
            }
        }
    }
    return GP_OK;
}

/* The loops into out: zero-area artefacts dropped, every other loop counter-clockwise. */
static gp_status clip_store(clip_run *R, vcell *out)
{
    gp_voronoi *v = R->v;
    const double amin = 1e-24 * v->L * v->L;
    int32_t w = 0, wv = 0;
    double total = 0.0;
    for (int32_t li = 0; li < R->nloops; li++) {
        int32_t b = v->lpo[li], e = v->lpo[li + 1];
        double a = ring_area_about(v->lv + b, e - b, R->s);
        if (a < -amin) return GP_ERR_INTERNAL;
        if (a <= amin) continue;
        total += a;
        if (wv != b) {
            memmove(v->lv + wv, v->lv + b, (size_t)(e - b) * sizeof(gp_vec2));
            memmove(v->lt + wv, v->lt + b, (size_t)(e - b) * sizeof(int32_t));
        }
        v->lpo[w] = wv;
        wv += e - b;
        w++;
    }
    v->lpo[w] = wv;
    R->nloops = w;
    if (w == 0) return GP_ERR_INTERNAL;
    if (cell_reserve(out, wv, w, out->nnb)) return GP_ERR_NOMEM;
    memcpy(out->v, v->lv, (size_t)wv * sizeof(gp_vec2));
    memcpy(out->tag, v->lt, (size_t)wv * sizeof(int32_t));
    memcpy(out->poff, v->lpo, (size_t)(w + 1) * sizeof(int32_t));
    out->nv = wv;
    out->nparts = w;
    out->area = total;
    out->convex = 0;
    return GP_OK;
}

/* The part that holds the seed (for a seed on a part boundary, the part nearest to it), and
 * the cell's orientation: the minimum caliper of the hull of that part. */
static gp_status seed_part_orientation(gp_voronoi *v, vcell *out, gp_vec2 s)
{
    int32_t sp = -1;
    for (int32_t li = 0; li < out->nparts && sp < 0; li++)
        if (gp_poly_contains(out->v + out->poff[li], (size_t)(out->poff[li + 1] - out->poff[li]), s))
            sp = li;
    if (sp < 0) {
        double bd = INFINITY;
        for (int32_t li = 0; li < out->nparts; li++) {
            int32_t b = out->poff[li], e = out->poff[li + 1];
            for (int32_t k = b; k < e; k++) {
                double d = seg_dist2(s, out->v[k], out->v[k + 1 < e ? k + 1 : b]);
                if (d < bd) {
                    bd = d;
                    sp = li;
                }
            }
        }
    }
    out->seed_part = sp;
    int32_t b = out->poff[sp], e = out->poff[sp + 1], np = e - b;
    if (grow((void **)&v->hv, &v->hcap, 3 * np + 2, sizeof(gp_vec2))) return GP_ERR_NOMEM;
    memcpy(v->hv, out->v + b, (size_t)np * sizeof(gp_vec2));
    int32_t hn = hull(v->hv, np, v->hv + np);
    if (hn < 3) return GP_ERR_INTERNAL;
    gp_vec2 he; /* a part's hull, not the cell: out->oe stays NaN, never reused */
    out->orient = convex_orientation(v->hv + np, hn, (1e-13 * v->L) * (1e-13 * v->L), NULL, &he);
    return GP_OK;
}

/* C = (P, T, m), CCW convex, against the general edges gathered in v->gedges[0..ng): the parts
 * of C intersected with the container, into out. GP_OK or an error code. */
static gp_status general_clip(gp_voronoi *v, gp_vec2 s, const gp_vec2 *P, const int32_t *T,
                              int32_t m, int32_t ng, vcell *out)
{
    clip_run R = {.v = v, .s = s, .P = P, .T = T, .m = m, .ng = ng, .dup = 1e-12 * v->L};
    gp_status st = clip_lines(v, P, m);
    if (st == GP_OK) st = clip_events(&R);
    if (st == GP_OK) st = clip_pair(&R);
    if (st == GP_OK) st = clip_sort(&R);
    if (st == GP_OK && grow((void **)&v->lpo, &v->lpcap, 2, sizeof(int32_t))) st = GP_ERR_NOMEM;
    if (st == GP_OK) {
        v->lpo[0] = 0;
        st = R.nk > 0 ? clip_loops_crossing(&R) : clip_loops_inside(&R);
    }
    if (st == GP_OK) st = clip_keyholes(&R);
    if (st == GP_OK) st = clip_store(&R, out);
    if (st == GP_OK) st = seed_part_orientation(v, out, s);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* one cell                                                                                    */

/* One half-plane clip of the current polygon (in sa/ta when *ina, else sb/tb). */
static inline __attribute__((always_inline)) gp_status
clip_step(gp_voronoi *v, int32_t *m, int *ina, gp_vec2 o, gp_vec2 nrm, double eps, int32_t tag, gp_vec2 s,
          double *rmax2)
{
    if (*m + 2 > v->scap && scratch_reserve(v, *m + 2)) return GP_ERR_NOMEM;
    gp_vec2 *cv = *ina ? v->sa : v->sb, *nv = *ina ? v->sb : v->sa;
    int32_t *ct = *ina ? v->ta : v->tb, *nt = *ina ? v->tb : v->ta;
    int32_t w = clip_hp(cv, ct, *m, o, nrm, eps, tag, nv, nt, v->sd, s, rmax2);
    if (w == 0) return GP_ERR_INTERNAL;
    if (w < 0) return GP_OK;
    *ina = !*ina;
    *m = w;
    return GP_OK;
}

/* the line of a tag, relative to s: n . (x - s) = c */
static inline __attribute__((always_inline)) void tag_line(const gp_voronoi *v, gp_vec2 s, int32_t t, gp_vec2 *n,
                                                          double *c)
{
    if (t >= 0) {
        gp_vec2 q = v->seed[t];
        n->x = q.x - s.x;
        n->y = q.y - s.y;
        *c = 0.5 * (n->x * n->x + n->y * n->y);
    } else if (t <= TAG_B + 4) {
        switch (t - TAG_B) {
        case 0: *n = (gp_vec2){0, -1}; *c = s.y - v->bmin.y; break;
        case 1: *n = (gp_vec2){1, 0}; *c = v->bmax.x - s.x; break;
        case 2: *n = (gp_vec2){0, 1}; *c = v->bmax.y - s.y; break;
        default: *n = (gp_vec2){-1, 0}; *c = s.x - v->bmin.x; break;
        }
    } else {
        int32_t e = -t - 2;
        gp_vec2 a = v->rv[e], b = v->rv[v->enext[e]];
        n->x = b.y - a.y;
        n->y = a.x - b.x;
        *c = n->x * (a.x - s.x) + n->y * (a.y - s.y);
    }
}

/* Rewrites polygon (cv, ct, m) into (dv, dt): starts at the largest tag, every vertex the
 * intersection of its two edge lines (kept as clipped where that is ill-conditioned). */
static void canonicalise(const gp_voronoi *v, gp_vec2 s, const gp_vec2 *cv, const int32_t *ct, int32_t m,
                         gp_vec2 *dv, int32_t *dt)
{
    int32_t st = 0;
    for (int32_t k = 1; k < m; k++)
        if (ct[k] > ct[st]) st = k;
    const double far = 1e-9 * v->L;
    int32_t kp = st == 0 ? m - 1 : st - 1;
    gp_vec2 n1, n2;
    double c1, c2;
    tag_line(v, s, ct[kp], &n1, &c1);
    double a1 = fabs(n1.x) + fabs(n1.y); /* each line's L1 norm once: it serves two vertices */
    for (int32_t j = 0; j < m; j++) {
        int32_t k = st + j;
        if (k >= m) k -= m;
        tag_line(v, s, ct[k], &n2, &c2);
        double a2 = fabs(n2.x) + fabs(n2.y);
        double det = n1.x * n2.y - n1.y * n2.x;
        double sc = a1 * a2;
        gp_vec2 x = cv[k];
        if (fabs(det) > 1e-10 * sc) {
            gp_vec2 y = {s.x + (c1 * n2.y - c2 * n1.y) / det, s.y + (n1.x * c2 - n2.x * c1) / det};
            if (fabs(y.x - x.x) <= far && fabs(y.y - x.y) <= far) x = y;
        }
        dv[j] = x;
        dt[j] = ct[k];
        n1 = n2;
        c1 = c2;
        a1 = a2;
    }
}

static gp_status compute_cell_box(gp_voronoi *v, uint32_t i, vcell *out, int full);

/* Cell i: first from a box of half-size 2 bins around the seed (cheap: the polygon and Rmax are
 * small from the start); if the box still bounds the result, again from the whole box B. */
static gp_status compute_cell(gp_voronoi *v, uint32_t i, vcell *out)
{
    gp_status st = compute_cell_box(v, i, out, 0);
    if (st == GP_ERR_NOT_CONVERGED) st = compute_cell_box(v, i, out, 1);
    return st;
}

/* One cell being clipped: the polygon is in sa/ta (ina) or sb/tb, m vertices; rmax2 is the
 * squared distance from the seed to its farthest vertex (no seed 2 Rmax away can cut it). */
typedef struct cell_run {
    gp_voronoi *v;
    uint32_t i;
    gp_vec2 s;           /* the seed */
    int32_t m;
    int ina;
    double rmax2;
    uint32_t es;         /* this cell's stamp in v->estamp */
    const vcell *prev;   /* in a move, the cell before it (convex_orientation); else NULL */
    int32_t bx, by;      /* the seed's bin */
    double epsr;
} cell_run;

/* The run of cell i without a polygon yet: for the recomputations of a move that start from
 * an old cell (compute_cell_cut, compute_cell_nb), which then need no box. */
static gp_status cell_init(cell_run *R, gp_voronoi *v, uint32_t i)
{
    if (scratch_reserve(v, 64)) return GP_ERR_NOMEM;
    stamp_next(&v->stamp, v->estamp, v->nedges);
    *R = (cell_run){.v = v, .i = i, .s = v->seed[i], .m = 0, .ina = 1, .es = v->stamp,
                    .epsr = 1e-13 * v->L};
    return GP_OK;
}

/* The starting polygon of R into sa/ta: the box B, or (full == 0) its part within 2 bins of
 * the seed, whose sides are tagged TAG_SMALL. */
static void cell_box(cell_run *R, int full)
{
    gp_voronoi *v = R->v;
    const gp_vec2 s = R->s;
    gp_vec2 *cv = v->sa;
    int32_t *ct = v->ta;
    double r0 = 2.0 * fmax(v->hx, v->hy);
    double x0 = v->bmin.x, y0 = v->bmin.y, x1 = v->bmax.x, y1 = v->bmax.y;
    ct[0] = TAG_B;
    ct[1] = TAG_B + 1;
    ct[2] = TAG_B + 2;
    ct[3] = TAG_B + 3;
    if (!full) {
        if (s.y - r0 > y0) { y0 = s.y - r0; ct[0] = TAG_SMALL; }
        if (s.x + r0 < x1) { x1 = s.x + r0; ct[1] = TAG_SMALL; }
        if (s.y + r0 < y1) { y1 = s.y + r0; ct[2] = TAG_SMALL; }
        if (s.x - r0 > x0) { x0 = s.x - r0; ct[3] = TAG_SMALL; }
    }
    cv[0] = (gp_vec2){x0, y0};
    cv[1] = (gp_vec2){x1, y0};
    cv[2] = (gp_vec2){x1, y1};
    cv[3] = (gp_vec2){x0, y1};
    double rmax2 = 0.0;
    for (int32_t k = 0; k < 4; k++) {
        double dx = cv[k].x - s.x, dy = cv[k].y - s.y, d2 = dx * dx + dy * dy;
        if (d2 > rmax2) rmax2 = d2;
    }
    R->m = 4;
    R->ina = 1;
    R->rmax2 = rmax2;
}

/* A cell run from the box (cell_box), with the seed's bin for the grid search. */
static gp_status cell_start(cell_run *R, gp_voronoi *v, uint32_t i, int full)
{
    gp_status st = cell_init(R, v, i);
    if (st != GP_OK) return st;
    cell_box(R, full);
    R->bx = bin_x(v, R->s.x);
    R->by = bin_y(v, R->s.y);
    return GP_OK;
}

/* Clips the cell by the convex outer ring's edges in bin b that have not clipped it yet (their
 * half-planes contain the container, so a convex container costs nothing extra). */
static gp_status clip_convex_edges_in_bin(cell_run *R, int32_t b)
{
    gp_voronoi *v = R->v;
    for (uint32_t q = v->ce_off[b]; q < v->ce_off[b + 1]; q++) {
        uint32_t e = v->ce[q];
        if (v->estamp[e] == R->es) continue;
        v->estamp[e] = R->es;
        gp_vec2 a = v->rv[e], c = v->rv[v->enext[e]];
        gp_vec2 nrm = {c.y - a.y, a.x - c.x};
        gp_status st = clip_step(v, &R->m, &R->ina, a, nrm, R->epsr * (fabs(nrm.x) + fabs(nrm.y)),
                                 -(int32_t)e - 2, R->s, &R->rmax2);
        if (st != GP_OK) return st;
    }
    return GP_OK;
}

/* Bin b (nearest point md2 from the seed): clips by the convex outer ring's edges in it, and
 * appends its seeds closer than 2 Rmax to the candidates v->cand_d / cand_j [*nc ..). */
static gp_status cell_bin(cell_run *R, int32_t b, double md2, int32_t *nc)
{
    gp_voronoi *v = R->v;
    const gp_vec2 s = R->s;
    if (v->outer_convex && md2 <= R->rmax2) {
        gp_status st = clip_convex_edges_in_bin(R, b);
        if (st != GP_OK) return st;
    }
    vbin *bn = &v->bins[b];
    const int32_t *it = bin_items(bn);
    if (*nc + bn->cnt > v->candcap) {
        int32_t c0 = v->candcap;
        if (grow((void **)&v->cand_d, &c0, *nc + bn->cnt, sizeof(double))) return GP_ERR_NOMEM;
        c0 = v->candcap;
        if (grow((void **)&v->cand_j, &c0, *nc + bn->cnt, sizeof(int32_t))) return GP_ERR_NOMEM;
        v->candcap = c0;
    }
    for (int32_t q = 0; q < bn->cnt; q++) {
        int32_t j = it[q];
        if ((uint32_t)j == R->i) continue;
        double nx = v->seed[j].x - s.x, ny = v->seed[j].y - s.y, d2 = nx * nx + ny * ny;
        if (d2 >= 4.0 * R->rmax2) continue;
        v->cand_d[*nc] = d2;
        v->cand_j[(*nc)++] = j;
    }
    return GP_OK;
}

/* Batch r: the bins of rings (r == 1 ? 0 : r) .. r around the seed's bin, skipping those at
 * least 2 Rmax away; then their candidate seeds' bisectors, nearest first in the first batch
 * (the near ones shrink the polygon, the far ones then fail the cheap distance test). The
 * result does not depend on this order (canonical vertices). */
static gp_status cell_batch(cell_run *R, int32_t r)
{
    gp_voronoi *v = R->v;
    const gp_vec2 s = R->s;
    const int32_t bx = R->bx, by = R->by;
    int32_t nc = 0;
    for (int32_t rr = r == 1 ? 0 : r; rr <= r; rr++) {
        int32_t y0 = by - rr, y1 = by + rr;
        for (int32_t yy = y0 < 0 ? 0 : y0; yy <= y1 && yy < v->nby; yy++) {
            int edge_row = (yy == y0 || yy == y1);
            int32_t step = edge_row ? 1 : 2 * rr;
            for (int32_t xx = bx - rr; xx <= bx + rr; xx += (step ? step : 1)) {
                if (xx < 0 || xx >= v->nbx) continue;
                double lx = xx * v->hx, ux = lx + v->hx, ly = yy * v->hy, uy = ly + v->hy;
                double dx = s.x < lx ? lx - s.x : (s.x > ux ? s.x - ux : 0.0);
                double dy = s.y < ly ? ly - s.y : (s.y > uy ? s.y - uy : 0.0);
                double md2 = dx * dx + dy * dy;
                if (md2 >= 4.0 * R->rmax2) continue;
                gp_status st = cell_bin(R, yy * v->nbx + xx, md2, &nc);
                if (st != GP_OK) return st;
            }
        }
    }
    for (int32_t q = 0; q < nc; q++) {
        if (r == 1 && q < 8) { /* partial selection sort: the nearest few first */
            int32_t b = q;
            for (int32_t k = q + 1; k < nc; k++)
                if (v->cand_d[k] < v->cand_d[b]) b = k;
            double td = v->cand_d[q];
            int32_t tj = v->cand_j[q];
            v->cand_d[q] = v->cand_d[b];
            v->cand_j[q] = v->cand_j[b];
            v->cand_d[b] = td;
            v->cand_j[b] = tj;
        }
        if (v->cand_d[q] >= 4.0 * R->rmax2) continue;
        int32_t j = v->cand_j[q];
        double nx = v->seed[j].x - s.x, ny = v->seed[j].y - s.y;
        gp_vec2 mid = {s.x + 0.5 * nx, s.y + 0.5 * ny};
        gp_status st = clip_step(v, &R->m, &R->ina, mid, (gp_vec2){nx, ny},
                                 R->epsr * (fabs(nx) + fabs(ny)), j, s, &R->rmax2);
        if (st != GP_OK) return st;
    }
    return GP_OK;
}

/* 1 when every seed outside the block of rings 0..r is at least 2 Rmax away (or there is none). */
static int cell_done(const cell_run *R, int32_t r)
{
    const gp_voronoi *v = R->v;
    const gp_vec2 s = R->s;
    const int32_t bx = R->bx, by = R->by;
    double dmin = INFINITY;
    if (bx - r > 0) dmin = fmin(dmin, s.x - (bx - r) * v->hx);
    if (bx + r < v->nbx - 1) dmin = fmin(dmin, (bx + r + 1) * v->hx - s.x);
    if (by - r > 0) dmin = fmin(dmin, s.y - (by - r) * v->hy);
    if (by + r < v->nby - 1) dmin = fmin(dmin, (by + r + 1) * v->hy - s.y);
    if (dmin == INFINITY) return 1;
    return dmin > 0 && dmin * dmin >= 4.0 * R->rmax2;
}

/* The neighbours of C (sorted, unique: each line appears once in a convex polygon) into
 * nb[0 .. nnb), then C's convex outer-ring edges (in C's order) into nb[nnb .. nnb + nce): the
 * two lists a move reads to find the candidates of the cells it recomputes. */
static gp_status cell_neighbours(const gp_voronoi *v, vcell *out, const int32_t *ct, int32_t m)
{
    /* both lists together hold at most one entry per edge: reserve m instead of counting */
    if (cell_reserve(out, m, 1, m)) return GP_ERR_NOMEM;
    int32_t nn = 0, other = 0;
    int32_t *nb = out->nb;
    for (int32_t k = 0; k < m; k++) {
        int32_t t = ct[k], q = nn;
        if (t < 0) {
            other = 1;
            continue;
        }
        for (; q > 0; q--) { /* insertion: a handful of entries */
            int32_t u = nb[q - 1];
            if (u <= t) break;
            nb[q] = u;
        }
        nb[q] = t;
        nn++;
    }
    int32_t ne = 0;
    for (int32_t k = 0; k < m && other && v->outer_convex; k++)
        if (ct[k] < -1 && ct[k] > TAG_SMALL && v->ering[-ct[k] - 2] == 0) nb[nn + ne++] = -ct[k] - 2;
    out->nnb = nn;
    out->nce = ne;
    return GP_OK;
}

/* The general (hole, non-convex) edges in the bins C's bounding box reaches, into v->gedges
 * sorted by id (so that the clip does not depend on the bins' visiting order). */
static gp_status cell_general_edges(cell_run *R, const gp_vec2 *cv, int32_t m, int32_t *ngp)
{
    gp_voronoi *v = R->v;
    int32_t r[4];
    poly_bins(v, cv, (size_t)m, r);
    int32_t ng = 0;
    for (int32_t yy = r[2]; yy <= r[3]; yy++)
        for (int32_t xx = r[0]; xx <= r[1]; xx++) {
            int32_t b = yy * v->nbx + xx;
            for (uint32_t q = v->ge_off[b]; q < v->ge_off[b + 1]; q++) {
                uint32_t e = v->ge[q];
                if (v->estamp[e] == R->es) continue;
                v->estamp[e] = R->es;
                if (grow((void **)&v->gedges, &v->gecap, ng + 1, sizeof(int32_t)))
                    return GP_ERR_NOMEM;
                v->gedges[ng++] = (int32_t)e;
            }
        }
    for (int32_t a = 1; a < ng; a++) {
        int32_t t = v->gedges[a], q = a;
        while (q > 0 && v->gedges[q - 1] > t) {
            v->gedges[q] = v->gedges[q - 1];
            q--;
        }
        v->gedges[q] = t;
    }
    *ngp = ng;
    return GP_OK;
}

/* The clipped polygon of R made canonical (vertices from its lines), its neighbour lists, and
 * then either the cell itself (convex case) or its general clip with the container, into out. */
static gp_status cell_finish(cell_run *R, vcell *out)
{
    gp_voronoi *v = R->v;
    const int32_t m = R->m;
    gp_vec2 *cv = R->ina ? v->sb : v->sa; /* canonical copy into the other buffer */
    int32_t *ct = R->ina ? v->tb : v->ta;
    out->oe = (gp_vec2){NAN, NAN};
    canonicalise(v, R->s, R->ina ? v->sa : v->sb, R->ina ? v->ta : v->tb, m, cv, ct);
    gp_status st = cell_neighbours(v, out, ct, m);
    if (st != GP_OK) return st;
    if (v->has_general) { /* does C reach a general (hole / non-convex) edge? */
        int32_t ng = 0;
        st = cell_general_edges(R, cv, m, &ng);
        if (st != GP_OK) return st;
        /* C lives in the scratch buffers that general_clip does not touch */
        if (ng > 0) return general_clip(v, R->s, cv, ct, m, ng, out);
    }
    memcpy(out->v, cv, (size_t)m * sizeof(gp_vec2));
    memcpy(out->tag, ct, (size_t)m * sizeof(int32_t));
    out->nv = m;
    out->nparts = 1;
    out->seed_part = 0;
    out->poff[0] = 0;
    out->poff[1] = m;
    out->convex = 1;
    out->area = ring_area_about(cv, m, R->s);
    out->orient = convex_orientation(cv, m, R->epsr * R->epsr, R->prev, &out->oe);
    if (!(out->area > 0.0)) return GP_ERR_INTERNAL;
    return GP_OK;
}

static gp_status compute_cell_box(gp_voronoi *v, uint32_t i, vcell *out, int full)
{
    cell_run R;
    gp_status st = cell_start(&R, v, i, full);
    /* rings 0 and 1 form the first batch, then one ring per batch */
    for (int32_t r = 1; st == GP_OK; r++) {
        st = cell_batch(&R, r);
        if (st == GP_OK && cell_done(&R, r)) break;
    }
    if (st != GP_OK) return st;
    for (int32_t k = 0; k < R.m; k++)
        if ((R.ina ? v->ta : v->tb)[k] == TAG_SMALL) return GP_ERR_NOT_CONVERGED; /* box too small */
    return cell_finish(&R, out);
}

/* Old C_j (one convex part) without its edge on i's bisector, into sa/ta: that edge's two
 * neighbouring edges extended to their meeting point X. The new cell of j lies in this polygon
 * (it holds every half-plane of old C_j but i's, and beyond i's edge only the triangle that
 * the two extended edges close). Returns 2 when X lies strictly inside every other old edge's
 * half-plane: then the polygon IS the intersection of those half-planes and j's old neighbours
 * need not clip again; 1 when they must (another line bounds it beyond i's edge); 0, nothing
 * written, where the two lines do not close (unbounded) or X is ill-conditioned: then the cell
 * is clipped from the box. */
static int unclip_start(cell_run *R, const vcell *old_j, uint32_t i)
{
    gp_voronoi *v = R->v;
    const int32_t m = old_j->nv;
    if (!old_j->convex || m < 4) return 0;
    int32_t k = 0;
    while (k < m && old_j->tag[k] != (int32_t)i) k++;
    if (k == m) return 0;
    const gp_vec2 *P = old_j->v;
    int32_t km = k == 0 ? m - 1 : k - 1, k1 = k + 1 == m ? 0 : k + 1, k2 = k1 + 1 == m ? 0 : k1 + 1;
    gp_vec2 a = P[k], b = P[k1];
    gp_vec2 da = {P[k].x - P[km].x, P[k].y - P[km].y}, db = {P[k2].x - P[k1].x, P[k2].y - P[k1].y};
    double det = da.x * db.y - da.y * db.x;
    double sc = (fabs(da.x) + fabs(da.y)) * (fabs(db.x) + fabs(db.y));
    if (!(det > 1e-10 * sc)) return 0; /* the two lines must close the polygon (turn left) */
    /* a + t da = b + u db: t = cross(b - a, db) / cross(da, db) */
    double t = ((b.x - a.x) * db.y - (b.y - a.y) * db.x) / det;
    if (!(t >= 0.0)) return 0;
    gp_vec2 x = {a.x + t * da.x, a.y + t * da.y};
    int exact = 2;
    for (int32_t c = 0; c < m && exact == 2; c++) {
        if (c == km || c == k || c == k1) continue;
        gp_vec2 n;
        double cc;
        tag_line(v, R->s, old_j->tag[c], &n, &cc);
        double hx = n.x * (x.x - R->s.x) + n.y * (x.y - R->s.y);
        if (!(hx < cc - R->epsr * (fabs(n.x) + fabs(n.y)))) exact = 1;
    }
    int32_t w = 0;
    double r2 = 0.0;
    for (int32_t c = 0; c < m; c++) {
        if (c == k1) continue; /* b goes, a becomes X (which starts edge k1's line) */
        gp_vec2 p = c == k ? x : P[c];
        v->sa[w] = p;
        v->ta[w++] = c == k ? old_j->tag[k1] : old_j->tag[c];
        double ex = p.x - R->s.x, ey = p.y - R->s.y;
        if (ex * ex + ey * ey > r2) r2 = ex * ex + ey * ey;
    }
    R->m = w;
    R->ina = 1;
    R->rmax2 = r2;
    return exact;
}

/* The candidates of compute_cell_nb into cand_d / cand_j, sorted by (distance, index), each
 * seed once: nb(j) (unless skip_j: they clip the start polygon already), nb_old(i), and i. */
static gp_status nb_candidates(gp_voronoi *v, const cell_run *R, const vcell *old_j,
                               const vcell *old_i, uint32_t i, int skip_j, int32_t *ncp)
{
    int32_t need = old_j->nnb + old_i->nnb + 1;
    if (need > v->candcap) {
        int32_t c0 = v->candcap;
        if (grow((void **)&v->cand_d, &c0, need, sizeof(double))) return GP_ERR_NOMEM;
        c0 = v->candcap;
        if (grow((void **)&v->cand_j, &c0, need, sizeof(int32_t))) return GP_ERR_NOMEM;
        v->candcap = c0;
    }
    stamp_next(&v->kstamp, v->kst, v->n);
    v->kst[R->i] = v->kstamp;
    for (int32_t q = 0; skip_j && q < old_j->nnb; q++)
        if ((uint32_t)old_j->nb[q] != i) v->kst[old_j->nb[q]] = v->kstamp; /* i has moved */
    const gp_vec2 s = R->s;
    int32_t nc = 0;
    for (int32_t part = skip_j; part < 3; part++) {
        const int32_t *lst = part == 0 ? old_j->nb : part == 1 ? old_i->nb : (const int32_t *)&i;
        int32_t cnt = part == 0 ? old_j->nnb : part == 1 ? old_i->nnb : 1;
        for (int32_t q = 0; q < cnt; q++) {
            int32_t k = lst[q];
            if (v->kst[k] == v->kstamp) continue;
            v->kst[k] = v->kstamp;
            double nx = v->seed[k].x - s.x, ny = v->seed[k].y - s.y, d2 = nx * nx + ny * ny;
            int32_t w = nc++;
            while (w > 0 && (v->cand_d[w - 1] > d2 || (v->cand_d[w - 1] == d2 && v->cand_j[w - 1] > k))) {
                v->cand_d[w] = v->cand_d[w - 1];
                v->cand_j[w] = v->cand_j[w - 1];
                w--;
            }
            v->cand_d[w] = d2;
            v->cand_j[w] = k;
        }
    }
    *ncp = nc;
    return GP_OK;
}

/* The container's lines for compute_cell_nb: with a non-convex container C is bounded by B,
 * whose sides old_i may have had and old_j not (old_i's stored parts do not show them), so all
 * four (mostly no cut); with a convex outer ring, the ring edges of old_j (unless skip_j) and
 * old_i. */
static gp_status nb_container_lines(cell_run *R, const vcell *old_j, const vcell *old_i, int skip_j,
                                    int b_sides)
{
    gp_voronoi *v = R->v;
    const gp_vec2 s = R->s;
    gp_status st = GP_OK;
    for (int32_t side = 0; b_sides && !v->outer_convex && side < 4 && st == GP_OK; side++) {
        gp_vec2 n;
        double c;
        tag_line(v, s, TAG_B + side, &n, &c);
        gp_vec2 o = {s.x + c * n.x, s.y + c * n.y}; /* |n| = 1: the point of the line nearest s */
        st = clip_step(v, &R->m, &R->ina, o, n, R->epsr * (fabs(n.x) + fabs(n.y)), TAG_B + side, s, &R->rmax2);
    }
    for (int32_t part = skip_j; part < 2 && v->outer_convex && st == GP_OK; part++) {
        const vcell *c = part ? old_i : old_j;
        for (int32_t q = 0; q < c->nce && st == GP_OK; q++) {
            int32_t e = c->nb[c->nnb + q];
            if (v->estamp[e] == R->es) continue;
            v->estamp[e] = R->es;
            gp_vec2 a = v->rv[e], b = v->rv[v->enext[e]];
            gp_vec2 nrm = {b.y - a.y, a.x - b.x};
            st = clip_step(v, &R->m, &R->ina, a, nrm, R->epsr * (fabs(nrm.x) + fabs(nrm.y)), -e - 2, s,
                           &R->rmax2);
        }
    }
    return st;
}

/* Cell j (a neighbour of i before the move) from the neighbour lists instead of the grid: the
 * bisectors of the seeds in nb(j) U nb_old(i) U {i} (old_j, old_i: the cells before the move),
 * nearest first, and the container's lines of old_j and old_i, clipped from old C_j less i's
 * edge where that closes (unclip_start), else from the box B. Why that is enough is in the
 * header of this file ("Moves"); the result is the cell a full build computes (canonical
 * vertices). */
static gp_status compute_cell_nb(gp_voronoi *v, uint32_t j, const vcell *old_j, const vcell *old_i,
                                 uint32_t i, vcell *out)
{
    cell_run R;
    gp_status st = cell_init(&R, v, j);
    if (st == GP_OK && old_j->nv + 2 > v->scap && scratch_reserve(v, old_j->nv + 2)) st = GP_ERR_NOMEM;
    if (st != GP_OK) return st;
    R.prev = old_j;
    /* from old C_j less i's edge (exactly: 2), j's old lines are in already; else they clip */
    const int start = unclip_start(&R, old_j, i), skip_j = start == 2;
    if (start == 0) cell_box(&R, 1);
    int32_t nc = 0;
    st = nb_candidates(v, &R, old_j, old_i, i, skip_j, &nc);
    const gp_vec2 s = R.s;
    for (int32_t q = 0; q < nc && st == GP_OK; q++) {
        if (v->cand_d[q] >= 4.0 * R.rmax2) break; /* sorted: no farther seed can cut */
        int32_t k = v->cand_j[q];
        double nx = v->seed[k].x - s.x, ny = v->seed[k].y - s.y;
        gp_vec2 mid = {s.x + 0.5 * nx, s.y + 0.5 * ny};
        st = clip_step(v, &R.m, &R.ina, mid, (gp_vec2){nx, ny}, R.epsr * (fabs(nx) + fabs(ny)), k, s,
                       &R.rmax2);
    }
    if (st == GP_OK) st = nb_container_lines(&R, old_j, old_i, skip_j, start != 0);
    return st == GP_OK ? cell_finish(&R, out) : st;
}

/* The moved seed's search runs on the neighbour graph of the tessellation before the move, in
 * which seed i still stands at its old place. */
static inline gp_vec2 node_pos(const gp_voronoi *v, int32_t k)
{
    return (uint32_t)k == v->mv_i ? v->mv_seed : v->seed[k];
}

static inline double node_d2(const gp_voronoi *v, int32_t k, gp_vec2 p)
{
    gp_vec2 q = node_pos(v, k);
    return (q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y);
}

/* The seed of the old graph nearest to p: from a seed of p's bin (or the old i), step to the
 * neighbour nearest to p while that is closer. A seed that is not the nearest always has a
 * closer neighbour (header, "Moves"), so the walk ends at the nearest; a few steps, as it
 * starts next to p. */
static int32_t nearest_node(const gp_voronoi *v, gp_vec2 p, double *dcur)
{
    int32_t cur = (int32_t)v->mv_i;
    int32_t bx = bin_x(v, p.x), by = bin_y(v, p.y);
    for (int32_t r = 0; r <= 1 && cur == (int32_t)v->mv_i; r++)
        for (int32_t yy = by - r; yy <= by + r && cur == (int32_t)v->mv_i; yy++)
            for (int32_t xx = bx - r; xx <= bx + r; xx++) {
                if (xx < 0 || yy < 0 || xx >= v->nbx || yy >= v->nby) continue;
                const vbin *b = &v->bins[yy * v->nbx + xx];
                const int32_t *it = b->s ? b->s : b->inl;
                int32_t q = 0;
                while (q < b->cnt && (uint32_t)it[q] == v->mv_i) q++;
                if (q < b->cnt) {
                    cur = it[q];
                    break;
                }
            }
    double dc = node_d2(v, cur, p);
    for (;;) {
        const vcell *c = v->cell[cur];
        int32_t best = -1;
        for (int32_t q = 0; q < c->nnb; q++) {
            double d = node_d2(v, c->nb[q], p);
            if (d < dc) {
                dc = d;
                best = c->nb[q];
            }
        }
        if (best < 0) break;
        cur = best;
    }
    *dcur = dc;
    return cur;
}

static int heap_push(gp_voronoi *v, int32_t *nh, double d, int32_t j)
{
    if (*nh + 1 > v->hqcap) {
        int32_t c0 = v->hqcap;
        if (grow((void **)&v->hq_d, &c0, *nh + 1, sizeof(double))) return -1;
        c0 = v->hqcap;
        if (grow((void **)&v->hq_j, &c0, *nh + 1, sizeof(int32_t))) return -1;
        v->hqcap = c0;
    }
    int32_t k = (*nh)++;
    while (k > 0) {
        int32_t up = (k - 1) / 2;
        if (v->hq_d[up] < d || (v->hq_d[up] == d && v->hq_j[up] < j)) break;
        v->hq_d[k] = v->hq_d[up];
        v->hq_j[k] = v->hq_j[up];
        k = up;
    }
    v->hq_d[k] = d;
    v->hq_j[k] = j;
    return 0;
}

static void heap_pop(gp_voronoi *v, int32_t *nh)
{
    int32_t n = --(*nh), k = 0;
    double d = v->hq_d[n];
    int32_t j = v->hq_j[n];
    for (;;) {
        int32_t c = 2 * k + 1;
        if (c >= n) break;
        if (c + 1 < n && (v->hq_d[c + 1] < v->hq_d[c] || (v->hq_d[c + 1] == v->hq_d[c] && v->hq_j[c + 1] < v->hq_j[c])))
            c++;
        if (d < v->hq_d[c] || (d == v->hq_d[c] && j < v->hq_j[c])) break;
        v->hq_d[k] = v->hq_d[c];
        v->hq_j[k] = v->hq_j[c];
        k = c;
    }
    v->hq_d[k] = d;
    v->hq_j[k] = j;
}

/* The convex outer ring's edges in the bins that C's bounding box reaches, clipped (the
 * moved cell: its edges are not known from an old polygon). */
static gp_status clip_convex_edges_near(cell_run *R)
{
    gp_voronoi *v = R->v;
    int32_t r[4];
    poly_bins(v, R->ina ? v->sa : v->sb, (size_t)R->m, r);
    for (int32_t yy = r[2]; yy <= r[3]; yy++)
        for (int32_t xx = r[0]; xx <= r[1]; xx++) {
            gp_status st = clip_convex_edges_in_bin(R, yy * v->nbx + xx);
            if (st != GP_OK) return st;
        }
    return GP_OK;
}

/* The moved seed i's new cell, before any other cell of the move is replaced: the seeds of the
 * old graph in increasing distance from the new place p (best-first from the nearest), each
 * clipping the polygon, until the next is 2 Rmax away -- every seed not reached yet is at least
 * that far (header, "Moves"). Then the convex outer ring's edges near the polygon. */
static gp_status compute_cell_moved(gp_voronoi *v, uint32_t i, vcell *out)
{
    cell_run R;
    gp_status st = cell_start(&R, v, i, 1);
    if (st != GP_OK) return st;
    R.prev = v->cell[i]; /* still the cell before the move (recompute swaps it after) */
    const gp_vec2 s = R.s;
    double d0;
    int32_t k0 = nearest_node(v, s, &d0), nh = 0;
    stamp_next(&v->kstamp, v->kst, v->n);
    v->kst[k0] = v->kstamp;
    if (heap_push(v, &nh, d0, k0)) return GP_ERR_NOMEM;
    while (nh > 0 && v->hq_d[0] < 4.0 * R.rmax2) {
        int32_t k = v->hq_j[0];
        heap_pop(v, &nh);
        if ((uint32_t)k != i) {
            double nx = v->seed[k].x - s.x, ny = v->seed[k].y - s.y;
            gp_vec2 mid = {s.x + 0.5 * nx, s.y + 0.5 * ny};
            st = clip_step(v, &R.m, &R.ina, mid, (gp_vec2){nx, ny}, R.epsr * (fabs(nx) + fabs(ny)), k, s,
                           &R.rmax2);
            if (st != GP_OK) return st;
        }
        const vcell *c = v->cell[k];
        for (int32_t q = 0; q < c->nnb; q++) {
            int32_t t = c->nb[q];
            if (v->kst[t] == v->kstamp) continue;
            /* A seed 2 Rmax away now would never be popped (Rmax only shrinks): it is not
             * pushed, nor marked, so that another path may test it again. The seeds it would
             * lead to that can still cut are reached through nearer ones (header, "Moves"). */
            double d = node_d2(v, t, s);
            if (d >= 4.0 * R.rmax2) continue;
            v->kst[t] = v->kstamp;
            if (heap_push(v, &nh, d, t)) return GP_ERR_NOMEM;
        }
    }
    if (v->outer_convex) {
        st = clip_convex_edges_near(&R);
        if (st != GP_OK) return st;
    }
    return cell_finish(&R, out);
}

/* Cell j that was not i's neighbour before the move and is after it: nothing was added to it,
 * i took a part, so the new cell is the old (convex, unclipped by the container) polygon cut by
 * the bisector of j and i's new place. */
static gp_status compute_cell_cut(gp_voronoi *v, uint32_t j, const vcell *old_j, uint32_t i, vcell *out)
{
    cell_run R;
    gp_status st = cell_init(&R, v, j);
    if (st == GP_OK && old_j->nv + 2 > v->scap && scratch_reserve(v, old_j->nv + 2)) st = GP_ERR_NOMEM;
    if (st != GP_OK) return st;
    memcpy(v->sa, old_j->v, (size_t)old_j->nv * sizeof(gp_vec2));
    memcpy(v->ta, old_j->tag, (size_t)old_j->nv * sizeof(int32_t));
    R.prev = old_j;
    R.m = old_j->nv;
    R.ina = 1;
    const gp_vec2 s = R.s;
    double nx = v->seed[i].x - s.x, ny = v->seed[i].y - s.y;
    gp_vec2 mid = {s.x + 0.5 * nx, s.y + 0.5 * ny};
    st = clip_step(v, &R.m, &R.ina, mid, (gp_vec2){nx, ny}, R.epsr * (fabs(nx) + fabs(ny)), (int32_t)i, s,
                   &R.rmax2);
    if (st != GP_OK) return st;
    return cell_finish(&R, out);
}

/* ------------------------------------------------------------------------------------------ */
/* containment                                                                                 */

static int contains_local(const gp_voronoi *vc, gp_vec2 p)
{
    gp_voronoi *v = (gp_voronoi *)vc;
    const double tol = v->tol;
    if (!(p.x >= -tol && p.x <= v->W + tol && p.y >= -tol && p.y <= v->H + tol)) return 0;
    int32_t bx = bin_x(v, p.x), by = bin_y(v, p.y), b = by * v->nbx + bx;
    int has = v->ce_off[b + 1] > v->ce_off[b] || v->ge_off[b + 1] > v->ge_off[b];
    if (!has) return v->bstate[b];
    for (int pass = 0; pass < 2; pass++) {
        const uint32_t *off = pass ? v->ge_off : v->ce_off, *lst = pass ? v->ge : v->ce;
        for (uint32_t q = off[b]; q < off[b + 1]; q++) {
            uint32_t e = lst[q];
            if (seg_dist2(p, v->rv[e], v->rv[v->enext[e]]) <= tol * tol) return 1;
        }
    }
    /* ray along the axis direction that reaches an edge-free bin (or leaves the grid) first */
    static const int DX[4] = {1, -1, 0, 0}, DY[4] = {0, 0, 1, -1};
    int bestd = 0;
    int32_t bestlen = INT32_MAX;
    for (int d = 0; d < 4; d++) {
        int32_t x = bx, y = by, len = 0;
        for (;;) {
            x += DX[d];
            y += DY[d];
            len++;
            if (x < 0 || y < 0 || x >= v->nbx || y >= v->nby) break;
            int32_t c = y * v->nbx + x;
            if (v->ce_off[c + 1] == v->ce_off[c] && v->ge_off[c + 1] == v->ge_off[c]) break;
            if (len >= bestlen) break;
        }
        if (len < bestlen) {
            bestlen = len;
            bestd = d;
        }
    }
    const int horiz = DY[bestd] == 0;
    const int32_t ex = bx + DX[bestd] * bestlen, ey = by + DY[bestd] * bestlen;
    int state;
    double lim;
    if (ex < 0 || ey < 0 || ex >= v->nbx || ey >= v->nby) {
        state = 0;
        lim = (DX[bestd] + DY[bestd]) > 0 ? INFINITY : -INFINITY;
    } else {
        state = v->bstate[ey * v->nbx + ex];
        lim = horiz ? (ex + 0.5) * v->hx : (ey + 0.5) * v->hy;
    }
    const double dir = (DX[bestd] + DY[bestd]) > 0 ? 1.0 : -1.0;
    const double p0 = horiz ? p.x : p.y;
    stamp_next(&v->stamp, v->estamp, v->nedges);
    const uint32_t es = v->stamp;
    int cnt = 0;
    for (int32_t t = 0; t < bestlen; t++) {
        int32_t c = (by + DY[bestd] * t) * v->nbx + (bx + DX[bestd] * t);
        for (int pass = 0; pass < 2; pass++) {
            const uint32_t *off = pass ? v->ge_off : v->ce_off, *lst = pass ? v->ge : v->ce;
            for (uint32_t q = off[c]; q < off[c + 1]; q++) {
                uint32_t e = lst[q];
                if (v->estamp[e] == es) continue;
                v->estamp[e] = es;
                gp_vec2 a = v->rv[e], z = v->rv[v->enext[e]];
                double xi;
                if (horiz) {
                    if ((a.y > p.y) == (z.y > p.y)) continue;
                    xi = a.x + (p.y - a.y) * (z.x - a.x) / (z.y - a.y);
                } else {
                    if ((a.x > p.x) == (z.x > p.x)) continue;
                    xi = a.y + (p.x - a.x) * (z.y - a.y) / (z.x - a.x);
                }
                if (dir * (xi - p0) > 0 && dir * (lim - xi) > 0) cnt++;
            }
        }
    }
    return state ^ (cnt & 1);
}

int gp_voronoi_contains(const gp_voronoi *v, gp_vec2 p)
{
    if (!v) return 0;
    gp_vec2 q = {p.x - v->origin.x, p.y - v->origin.y};
    return contains_local(v, q);
}

/* ------------------------------------------------------------------------------------------ */
/* build                                                                                       */

static int ring_copy(gp_vec2 *dst, const gp_vec2 *src, size_t n, gp_vec2 o, double tol, int ccw,
                     int32_t *outn)
{
    int32_t w = 0;
    for (size_t k = 0; k < n; k++) {
        gp_vec2 p = {src[k].x - o.x, src[k].y - o.y};
        if (w > 0 && fabs(p.x - dst[w - 1].x) <= tol && fabs(p.y - dst[w - 1].y) <= tol) continue;
        dst[w++] = p;
    }
    while (w > 1 && fabs(dst[w - 1].x - dst[0].x) <= tol && fabs(dst[w - 1].y - dst[0].y) <= tol) w--;
    if (w < 3) return -1;
    double a = ring_area_about(dst, w, dst[0]);
    if (!(fabs(a) > 0)) return -1;
    if ((a > 0) != (ccw != 0)) {
        for (int32_t i = 0, j = w - 1; i < j; i++, j--) {
            gp_vec2 t = dst[i];
            dst[i] = dst[j];
            dst[j] = t;
        }
    }
    *outn = w;
    return 0;
}

static int dcmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static int cancel_raised(const volatile int *cancel);

/* The bins: about GP_VOR_SEEDS_PER_BIN seeds each, so their side h follows from the container's
 * area (not its bounding box: a thin or holed container keeps that occupancy), rounded up to a
 * whole number of bins per axis (a bin at most h wide) and widened by 1.25 while there are more
 * than 4N + 64 bins. Not gp_grid_size (gp_grid.h), which sizes a grid by a search's reach: a
 * cell's search walks rings of bins outwards until they are 2 Rmax away, so a bin needs no
 * least width, only its occupancy. */
static gp_status build_grid(gp_voronoi *v, const volatile int *cancel)
{
    double area = v->carea;
    double h = sqrt(area * GP_VOR_SEEDS_PER_BIN / (double)v->n);
    double nbxf, nbyf;
    for (;;) {
        nbxf = ceil(v->W / h);
        nbyf = ceil(v->H / h);
        if (nbxf < 1) nbxf = 1;
        if (nbyf < 1) nbyf = 1;
        if (nbxf * nbyf <= 4.0 * v->n + 64.0) break;
        h *= 1.25;
    }
    v->nbx = (int32_t)nbxf;
    v->nby = (int32_t)nbyf;
    v->hx = v->W / v->nbx;
    v->hy = v->H / v->nby;
    v->ihx = 1.0 / v->hx;
    v->ihy = 1.0 / v->hy;
    size_t nb = (size_t)v->nbx * v->nby;
    v->bins = calloc(nb, sizeof *v->bins);
    v->ce_off = calloc(nb + 1, sizeof(uint32_t));
    v->ge_off = calloc(nb + 1, sizeof(uint32_t));
    v->bstate = calloc(nb, 1);
    if (!v->bins || !v->ce_off || !v->ge_off || !v->bstate) return GP_ERR_NOMEM;
    /* edges into bins: two passes (count, fill) */
    const double pad = 1e-9 * v->L;
    for (int pass = 0; pass < 2; pass++) {
        uint32_t *cfill = NULL, *gfill = NULL;
        if (pass == 1) {
            for (size_t b = 0; b < nb; b++) {
                v->ce_off[b + 1] += v->ce_off[b];
                v->ge_off[b + 1] += v->ge_off[b];
            }
            v->ce = malloc((v->ce_off[nb] + 1) * sizeof(uint32_t));
            v->ge = malloc((v->ge_off[nb] + 1) * sizeof(uint32_t));
            cfill = malloc(nb * sizeof(uint32_t));
            gfill = malloc(nb * sizeof(uint32_t));
            if (!v->ce || !v->ge || !cfill || !gfill) {
                free(cfill);
                free(gfill);
                return GP_ERR_NOMEM;
            }
            memcpy(cfill, v->ce_off, nb * sizeof(uint32_t));
            memcpy(gfill, v->ge_off, nb * sizeof(uint32_t));
        }
        for (uint32_t e = 0; e < v->nedges; e++) {
            if ((e + 1) % 1024 == 0 && cancel_raised(cancel)) {
                free(cfill);
                free(gfill);
                return GP_ERR_CANCELLED;
            }
            gp_vec2 a = v->rv[e], c = v->rv[v->enext[e]];
            int general = !(v->outer_convex && v->ering[e] == 0);
            int32_t ix0 = bin_x(v, fmin(a.x, c.x) - pad), ix1 = bin_x(v, fmax(a.x, c.x) + pad);
            int32_t iy0 = bin_y(v, fmin(a.y, c.y) - pad), iy1 = bin_y(v, fmax(a.y, c.y) + pad);
            double ex = c.x - a.x, ey = c.y - a.y, tc = pad * (fabs(ex) + fabs(ey));
            for (int32_t yy = iy0; yy <= iy1; yy++)
                for (int32_t xx = ix0; xx <= ix1; xx++) {
                    double lx = xx * v->hx - pad, ux = (xx + 1) * v->hx + pad;
                    double ly = yy * v->hy - pad, uy = (yy + 1) * v->hy + pad;
                    double c1 = ex * (ly - a.y) - ey * (lx - a.x), c2 = ex * (ly - a.y) - ey * (ux - a.x);
                    double c3 = ex * (uy - a.y) - ey * (lx - a.x), c4 = ex * (uy - a.y) - ey * (ux - a.x);
                    if ((c1 > tc && c2 > tc && c3 > tc && c4 > tc) ||
                        (c1 < -tc && c2 < -tc && c3 < -tc && c4 < -tc))
                        continue;
                    size_t b = (size_t)yy * v->nbx + xx;
                    if (pass == 0) {
                        if (general) v->ge_off[b + 1]++;
                        else v->ce_off[b + 1]++;
                    } else {
                        if (general) v->ge[gfill[b]++] = e;
                        else v->ce[cfill[b]++] = e;
                    }
                }
        }
        free(cfill);
        free(gfill);
    }
    /* inside/outside of edge-free bins: scanline through each row's centre */
    double *xs = malloc((v->nedges + 1) * sizeof(double));
    if (!xs) return GP_ERR_NOMEM;
    for (int32_t yy = 0; yy < v->nby; yy++) {
        if ((yy + 1) % 16 == 0 && cancel_raised(cancel)) { /* a row costs O(edges) */
            free(xs);
            return GP_ERR_CANCELLED;
        }
        double yc = (yy + 0.5) * v->hy;
        size_t nx = 0;
        for (uint32_t e = 0; e < v->nedges; e++) {
            gp_vec2 a = v->rv[e], c = v->rv[v->enext[e]];
            if ((a.y > yc) != (c.y > yc)) xs[nx++] = a.x + (yc - a.y) * (c.x - a.x) / (c.y - a.y);
        }
        qsort(xs, nx, sizeof(double), dcmp);
        size_t q = 0;
        for (int32_t xx = 0; xx < v->nbx; xx++) {
            double xc = (xx + 0.5) * v->hx;
            while (q < nx && xs[q] < xc) q++;
            v->bstate[(size_t)yy * v->nbx + xx] = (unsigned char)(q & 1);
        }
    }
    free(xs);
    return GP_OK;
}

static int dup_check(const gp_voronoi *v, gp_vec2 p, uint32_t self, uint32_t *other)
{
    const double t = 1e-12 * v->L;
    /* only the bins the box p +- t reaches (bin_x is monotone): one bin but at a bin's edge,
     * where the 3 x 3 around p read ~18 seeds scattered in memory */
    int32_t x0 = bin_x(v, p.x - t), x1 = bin_x(v, p.x + t), y0 = bin_y(v, p.y - t), y1 = bin_y(v, p.y + t);
    for (int32_t yy = y0; yy <= y1; yy++)
        for (int32_t xx = x0; xx <= x1; xx++) {
            vbin *b = &v->bins[yy * v->nbx + xx];
            const int32_t *it = bin_items(b);
            for (int32_t q = 0; q < b->cnt; q++) {
                uint32_t j = (uint32_t)it[q];
                if (j == self) continue;
                if (fabs(v->seed[j].x - p.x) <= t && fabs(v->seed[j].y - p.y) <= t) {
                    *other = j;
                    return 1;
                }
            }
        }
    return 0;
}

static const char *status_msg(gp_status st)
{
    return st == GP_ERR_NOMEM ? "out of memory" : "inconsistent clip (degenerate geometry)";
}

gp_voronoi *gp_voronoi_create(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                              const size_t *nhole, size_t nholes, const gp_vec2 *seeds, size_t n,
                              gp_error *err)
{
    return gp_voronoi_create_ex(outer, nouter, holes, nhole, nholes, seeds, n, NULL, err);
}

/* The caller's cancel flag, raised by another thread with an atomic store: read it atomically,
 * and only after every CANCEL_EVERY items of a loop (a cell costs about 6 us at 10^6 seeds), so
 * that a small tessellation (milliseconds) is never cut short. */
#define CANCEL_EVERY 1024
static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

/* The arguments of gp_voronoi_create_ex, and the outer ring's bounding box. */
static gp_status create_check(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                              const size_t *nhole, size_t nholes, const gp_vec2 *seeds, size_t n,
                              gp_vec2 *lo, gp_vec2 *hi, size_t *total, gp_error *err)
{
    if (!outer || nouter < 3)
        return gp_error_set(err, GP_ERR_INVALID, "voronoi: outer ring needs >= 3 points");
    if (!seeds || n < 1 || n > (size_t)INT32_MAX / 4)
        return gp_error_set(err, GP_ERR_INVALID, "voronoi: need 1 <= n seeds (got %zu)", n);
    if (nholes && (!holes || !nhole))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi: holes/nhole missing");
    *total = nouter;
    for (size_t h = 0; h < nholes; h++) {
        if (!holes[h] || nhole[h] < 3)
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: hole %zu needs >= 3 points", h);
        *total += nhole[h];
    }
    for (size_t k = 0; k < nouter; k++)
        if (!isfinite(outer[k].x) || !isfinite(outer[k].y))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: outer vertex %zu is not finite", k);
    for (size_t h = 0; h < nholes; h++)
        for (size_t k = 0; k < nhole[h]; k++)
            if (!isfinite(holes[h][k].x) || !isfinite(holes[h][k].y))
                return gp_error_set(err, GP_ERR_INVALID, "voronoi: hole %zu vertex %zu is not finite",
                                    h, k);
    return gp_poly_bbox(outer, nouter, lo, hi, err);
}

/* The rings in local coordinates (outer counter-clockwise, holes clockwise), their offsets and
 * the container's area. */
static gp_status load_rings(gp_voronoi *v, const gp_vec2 *outer, size_t nouter,
                            const gp_vec2 *const *holes, const size_t *nhole, size_t nholes,
                            size_t total, gp_error *err)
{
    v->nrings = (uint32_t)(1 + nholes);
    v->roff = calloc(v->nrings + 1, sizeof(uint32_t));
    v->rv = malloc(total * sizeof(gp_vec2));
    v->rst = calloc(v->nrings, sizeof(uint32_t));
    v->rev = calloc(v->nrings, sizeof(int32_t));
    if (!v->roff || !v->rv || !v->rst || !v->rev)
        return gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
    int32_t w;
    if (ring_copy(v->rv, outer, nouter, v->origin, v->tol, 1, &w))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi: outer ring is degenerate (no area)");
    v->roff[1] = (uint32_t)w;
    v->carea = ring_area_about(v->rv, w, v->rv[0]);
    for (size_t h = 0; h < nholes; h++) {
        uint32_t b = v->roff[h + 1];
        if (ring_copy(v->rv + b, holes[h], nhole[h], v->origin, v->tol, 0, &w))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: hole %zu is degenerate (no area)", h);
        v->roff[h + 2] = b + (uint32_t)w;
        v->carea += ring_area_about(v->rv + b, w, v->rv[b]); /* negative (clockwise) */
        if (!gp_poly_contains(v->rv, v->roff[1], v->rv[b]))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: hole %zu is not inside the outer ring", h);
    }
    if (!(v->carea > 0))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi: container area is not positive");
    return GP_OK;
}

/* 1 if the outer ring is convex: no reflex turn (collinear runs allowed), and one turn in total
 * (a self-overlapping star has no reflex turn either). */
static int outer_is_convex(const gp_voronoi *v)
{
    uint32_t no = v->roff[1];
    int convex = 1;
    for (uint32_t k = 0; k < no && convex; k++) {
        gp_vec2 a = v->rv[k ? k - 1 : no - 1], b = v->rv[k], c = v->rv[v->enext[k]];
        double cr = cross3(a, b, c);
        double sc = (fabs(b.x - a.x) + fabs(b.y - a.y)) * (fabs(c.x - b.x) + fabs(c.y - b.y));
        if (cr < -1e-12 * sc) convex = 0;
    }
    double turn = 0;
    for (uint32_t k = 0; k < no && convex; k++) {
        gp_vec2 a = v->rv[k ? k - 1 : no - 1], b = v->rv[k], c = v->rv[v->enext[k]];
        turn += atan2(cross3(a, b, c), (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y));
    }
    if (convex && fabs(turn - 2 * GP_VOR_PI) > 1e-6) convex = 0;
    return convex;
}

/* Per-edge tables (next edge, ring, scratch stamps), the convexity of the outer ring, and the
 * box B. */
static gp_status edge_tables(gp_voronoi *v, size_t nholes, gp_error *err)
{
    v->nedges = v->roff[v->nrings];
    v->enext = malloc(v->nedges * sizeof(int32_t));
    v->ering = malloc(v->nedges * sizeof(int32_t));
    v->estamp = calloc(v->nedges, sizeof(uint32_t));
    v->eslot_st = calloc(v->nedges, sizeof(uint32_t));
    v->eslot_in = malloc(v->nedges * sizeof(int32_t));
    v->eslot_out = malloc(v->nedges * sizeof(int32_t));
    if (!v->enext || !v->ering || !v->estamp || !v->eslot_st || !v->eslot_in || !v->eslot_out)
        return gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
    for (uint32_t r = 0; r < v->nrings; r++)
        for (uint32_t k = v->roff[r]; k < v->roff[r + 1]; k++) {
            v->enext[k] = (int32_t)(k + 1 < v->roff[r + 1] ? k + 1 : v->roff[r]);
            v->ering[k] = (int32_t)r;
        }
    v->outer_convex = outer_is_convex(v);
    v->has_general = !v->outer_convex || nholes > 0;
    double mg = 1e-3 * fmin(v->W, v->H) + 1e-6 * v->L;
    v->bmin = (gp_vec2){-mg, -mg};
    v->bmax = (gp_vec2){v->W + mg, v->H + mg};
    return GP_OK;
}

/* The seeds, in local coordinates and as given, into the bins; each inside the container and
 * no duplicate. */
static gp_status insert_seeds(gp_voronoi *v, const gp_vec2 *seeds, size_t n,
                              const volatile int *cancel, gp_error *err)
{
    v->seed = malloc(n * sizeof(gp_vec2));
    v->useed = malloc(n * sizeof(gp_vec2));
    v->cell = calloc(n, sizeof(vcell *));
    v->cst = calloc(n, sizeof(uint32_t));
    v->kst = calloc(n, sizeof(uint32_t));
    if (!v->seed || !v->useed || !v->cell || !v->cst || !v->kst)
        return gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
    for (size_t i = 0; i < n; i++) {
        if ((i + 1) % (16 * CANCEL_EVERY) == 0 && cancel_raised(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "voronoi: cancelled");
        gp_vec2 p = {seeds[i].x - v->origin.x, seeds[i].y - v->origin.y};
        if (!isfinite(p.x) || !isfinite(p.y) || !contains_local(v, p))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: seed %zu (%g, %g) is outside the container",
                                i, seeds[i].x, seeds[i].y);
        v->seed[i] = p;
        v->useed[i] = seeds[i];
        uint32_t other;
        if (dup_check(v, p, (uint32_t)i, &other))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi: seeds %u and %zu coincide (duplicate seeds)",
                                other, i);
        if (bin_insert(&v->bins[bin_of(v, p)], (int32_t)i))
            return gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
    }
    return GP_OK;
}

/* Every cell, from scratch. */
static gp_status compute_cells(gp_voronoi *v, size_t n, const volatile int *cancel, gp_error *err)
{
    for (size_t i = 0; i < n; i++) {
        if ((i + 1) % CANCEL_EVERY == 0 && cancel_raised(cancel))
            return gp_error_set(err, GP_ERR_CANCELLED, "voronoi: cancelled");
        v->cell[i] = calloc(1, sizeof(vcell));
        if (!v->cell[i]) return gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
        gp_status st = compute_cell(v, (uint32_t)i, v->cell[i]);
        if (st != GP_OK) return gp_error_set(err, st, "voronoi: cell %zu: %s", i, status_msg(st));
    }
    return GP_OK;
}

gp_voronoi *gp_voronoi_create_ex(const gp_vec2 *outer, size_t nouter, const gp_vec2 *const *holes,
                                 const size_t *nhole, size_t nholes, const gp_vec2 *seeds,
                                 size_t n, const volatile int *cancel, gp_error *err)
{
    gp_vec2 lo, hi;
    size_t total = 0;
    if (create_check(outer, nouter, holes, nhole, nholes, seeds, n, &lo, &hi, &total, err) != GP_OK)
        return NULL;
    gp_voronoi *v = calloc(1, sizeof *v);
    if (!v) {
        gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
        return NULL;
    }
    v->n = (uint32_t)n;
    v->origin = lo;
    v->W = hi.x - lo.x;
    v->H = hi.y - lo.y;
    v->L = fmax(v->W, v->H);
    v->tol = 1e-12 * v->L;
    gp_status st = GP_OK;
    if (!(v->W > 0 && v->H > 0 && isfinite(v->L)))
        st = gp_error_set(err, GP_ERR_INVALID, "voronoi: container has no area");
    if (st == GP_OK) st = load_rings(v, outer, nouter, holes, nhole, nholes, total, err);
    if (st == GP_OK) st = edge_tables(v, nholes, err);
    if (st == GP_OK) {
        st = build_grid(v, cancel);
        if (st == GP_ERR_CANCELLED) gp_error_set(err, st, "voronoi: cancelled");
        else if (st != GP_OK) st = gp_error_set(err, GP_ERR_NOMEM, "voronoi: out of memory");
    }
    if (st == GP_OK) st = insert_seeds(v, seeds, n, cancel, err);
    if (st == GP_OK) st = compute_cells(v, n, cancel, err);
    if (st != GP_OK) {
        gp_voronoi_destroy(v);
        return NULL;
    }
    return v;
}

void gp_voronoi_destroy(gp_voronoi *v)
{
    if (!v) return;
    if (v->pending) gp_voronoi_commit(v);
    if (v->cell)
        for (uint32_t i = 0; i < v->n; i++) cell_free(v->cell[i]);
    for (uint32_t k = 0; k < v->npool; k++) cell_free(v->pool[k]);
    if (v->bins) {
        size_t nb = (size_t)v->nbx * v->nby;
        for (size_t b = 0; b < nb; b++) free(v->bins[b].s);
    }
    free(v->bins);
    free(v->pool);
    free(v->cell);
    free(v->seed);
    free(v->useed);
    free(v->roff);
    free(v->rv);
    free(v->enext);
    free(v->ering);
    free(v->ce_off);
    free(v->ce);
    free(v->ge_off);
    free(v->ge);
    free(v->bstate);
    free(v->chg);
    free(v->chg_old);
    free(v->estamp);
    free(v->eslot_st);
    free(v->eslot_in);
    free(v->eslot_out);
    free(v->rst);
    free(v->rev);
    free(v->cst);
    free(v->kst);
    free(v->hq_d);
    free(v->hq_j);
    free(v->sa);
    free(v->sb);
    free(v->ta);
    free(v->tb);
    free(v->sd);
    free(v->gedges);
    free(v->ev);
    free(v->evs);
    free(v->da);
    free(v->db);
    free(v->lex);
    free(v->ley);
    free(v->leps);
    free(v->lv);
    free(v->lt);
    free(v->lpo);
    free(v->hv);
    free(v->aff);
    free(v->cand_d);
    free(v->cand_j);
    free(v);
}

/* ------------------------------------------------------------------------------------------ */
/* moves                                                                                       */

static int chg_push(gp_voronoi *v, uint32_t j, vcell *old)
{
    if (v->nchg == v->chgcap) {
        uint32_t nc = v->chgcap ? v->chgcap * 2 : 64;
        uint32_t *a = realloc(v->chg, nc * sizeof *a);
        if (!a) return -1;
        v->chg = a;
        vcell **b = realloc(v->chg_old, nc * sizeof *b);
        if (!b) return -1;
        v->chg_old = b;
        v->chgcap = nc;
    }
    v->chg[v->nchg] = j;
    v->chg_old[v->nchg] = old;
    v->nchg++;
    return 0;
}

static void undo(gp_voronoi *v)
{
    for (uint32_t k = v->nchg; k-- > 0;) {
        uint32_t j = v->chg[k];
        pool_give(v, v->cell[j]);
        v->cell[j] = v->chg_old[k];
    }
    v->nchg = 0;
    uint32_t i = v->mv_i;
    gp_vec2 p = v->seed[i];
    bin_remove(&v->bins[bin_of(v, p)], (int32_t)i);
    v->seed[i] = v->mv_seed;
    v->useed[i] = v->mv_useed;
    bin_insert(&v->bins[bin_of(v, v->mv_seed)], (int32_t)i);
}

/* How a move recomputes a cell: the moved seed's (best-first search), a former neighbour of it
 * (the neighbour lists), a new neighbour only (one cut of its old polygon). */
enum { RC_MOVED, RC_NB, RC_CUT };

static gp_status recompute(gp_voronoi *v, uint32_t j, int how, const vcell *old_i)
{
    vcell *c = pool_get(v);
    if (!c) return GP_ERR_NOMEM;
    const uint32_t i = v->mv_i;
    gp_status st = how == RC_MOVED ? compute_cell_moved(v, j, c)
                   : how == RC_NB  ? compute_cell_nb(v, j, v->cell[j], old_i, i, c)
                                   : compute_cell_cut(v, j, v->cell[j], i, c);
    if (st == GP_OK && chg_push(v, j, v->cell[j])) st = GP_ERR_NOMEM;
    if (st != GP_OK) {
        pool_give(v, c);
        return st;
    }
    v->cell[j] = c;
    return GP_OK;
}

gp_status gp_voronoi_try_move(gp_voronoi *v, size_t i, gp_vec2 pu, gp_error *err)
{
    if (!v || i >= v->n) return gp_error_set(err, GP_ERR_INVALID, "voronoi move: bad index");
    if (v->pending)
        return gp_error_set(err, GP_ERR_INVALID, "voronoi move: a move is pending (commit or roll back)");
    gp_vec2 p = {pu.x - v->origin.x, pu.y - v->origin.y};
    if (!isfinite(p.x) || !isfinite(p.y) || !contains_local(v, p))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi move: (%g, %g) is outside the container",
                            pu.x, pu.y);
    uint32_t other;
    if (dup_check(v, p, (uint32_t)i, &other))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi move: seed %zu would coincide with seed %u",
                            i, other);
    /* pool capacity for the worst-case number of buffers a rollback returns */
    v->mv_i = (uint32_t)i;
    v->mv_seed = v->seed[i];
    v->mv_useed = v->useed[i];
    v->nchg = 0;
    const vcell *oc = v->cell[i];
    if (grow((void **)&v->aff, &v->affcap, oc->nnb + 1, sizeof(int32_t)))
        return gp_error_set(err, GP_ERR_NOMEM, "voronoi move: out of memory");
    int32_t na = oc->nnb;
    memcpy(v->aff, oc->nb, (size_t)na * sizeof(int32_t));
    bin_remove(&v->bins[bin_of(v, v->mv_seed)], (int32_t)i);
    v->seed[i] = p;
    v->useed[i] = pu;
    gp_status st = GP_OK;
    if (bin_insert(&v->bins[bin_of(v, p)], (int32_t)i)) {
        st = GP_ERR_NOMEM;
        v->seed[i] = v->mv_seed;
        v->useed[i] = v->mv_useed;
        bin_insert(&v->bins[bin_of(v, v->mv_seed)], (int32_t)i);
        return gp_error_set(err, st, "voronoi move: out of memory");
    }
    st = recompute(v, (uint32_t)i, RC_MOVED, NULL);
    if (st == GP_OK) {
        const vcell *nc = v->cell[i];
        if (grow((void **)&v->aff, &v->affcap, na + nc->nnb, sizeof(int32_t))) st = GP_ERR_NOMEM;
        else {
            memcpy(v->aff + na, nc->nb, (size_t)nc->nnb * sizeof(int32_t));
            na += nc->nnb;
        }
    }
    if (st == GP_OK) {
        stamp_next(&v->cstamp, v->cst, v->n);
        v->cst[i] = v->cstamp;
        for (int32_t k = 0; k < na && st == GP_OK; k++) {
            uint32_t j = (uint32_t)v->aff[k];
            if (v->cst[j] == v->cstamp) continue;
            v->cst[j] = v->cstamp;
            int how = k < oc->nnb ? RC_NB : v->cell[j]->convex ? RC_CUT : RC_NB;
            st = recompute(v, j, how, oc);
        }
    }
    if (st != GP_OK) {
        undo(v);
        return gp_error_set(err, st, "voronoi move of seed %zu: %s", i, status_msg(st));
    }
    v->pending = 1;
    return GP_OK;
}

/* dst = src (contents, not capacities); -1 with dst unchanged when out of memory */
static int cell_copy(vcell *dst, const vcell *src)
{
    if (cell_reserve(dst, src->nv, src->nparts, src->nnb + src->nce)) return -1;
    memcpy(dst->v, src->v, (size_t)src->nv * sizeof(gp_vec2));
    memcpy(dst->tag, src->tag, (size_t)src->nv * sizeof(int32_t));
    memcpy(dst->poff, src->poff, (size_t)(src->nparts + 1) * sizeof(int32_t));
    if (src->nnb + src->nce > 0) /* a lone cell has none, and maybe no list (NULL) */
        memcpy(dst->nb, src->nb, (size_t)(src->nnb + src->nce) * sizeof(int32_t));
    dst->nv = src->nv;
    dst->nparts = src->nparts;
    dst->seed_part = src->seed_part;
    dst->nnb = src->nnb;
    dst->nce = src->nce;
    dst->convex = src->convex;
    dst->area = src->area;
    dst->orient = src->orient;
    dst->oe = src->oe;
    return 0;
}

/* The new cells are copied back into the cells' own buffers and the spares go back to the
 * pool. Why not keep the spares (a pointer swap): the pool is LIFO, so after a few accepted
 * moves per cell every cell would live in buffers last used by some random cell far away, and
 * the memory order the caller set up by numbering the seeds along a space-filling curve
 * (gp_imc.c) would be lost; a copy of ~9 cells of ~300 bytes costs far less than the cache
 * misses. When a copy cannot grow a buffer, that cell keeps its spare (a pointer swap). */
void gp_voronoi_commit(gp_voronoi *v)
{
    if (!v || !v->pending) return;
    for (uint32_t k = 0; k < v->nchg; k++) {
        uint32_t j = v->chg[k];
        vcell *own = v->chg_old[k], *fresh = v->cell[j], *spare = own;
        if (cell_copy(own, fresh) == 0) {
            v->cell[j] = own;
            spare = fresh;
        }
        pool_give(v, spare);
    }
    v->nchg = 0;
    v->pending = 0;
}

void gp_voronoi_rollback(gp_voronoi *v)
{
    if (!v || !v->pending) return;
    undo(v);
    v->pending = 0;
}

size_t gp_voronoi_changed(const gp_voronoi *v, const uint32_t **cells)
{
    if (!v || !v->pending) {
        if (cells) *cells = NULL;
        return 0;
    }
    if (cells) *cells = v->chg;
    return v->nchg;
}

/* 1 when dst's pending move (if any) and src's share a changed cell (the moved seeds are
 * changed cells of their own moves) */
static int moves_overlap(const gp_voronoi *dst, const gp_voronoi *src)
{
    for (uint32_t a = 0; dst->pending && a < dst->nchg; a++)
        for (uint32_t b = 0; b < src->nchg; b++)
            if (dst->chg[a] == src->chg[b]) return 1;
    return 0;
}

/* dst's cell j becomes src's (content), seed i and its bin follow src's pending move */
gp_status gp_voronoi_apply(gp_voronoi *dst, const gp_voronoi *src, gp_error *err)
{
    if (!dst || !src || !src->pending || dst->n != src->n || moves_overlap(dst, src))
        return gp_error_set(err, GP_ERR_INVALID,
                            "voronoi apply: need a pending move in src, none in dst that changes the same cells");
    const uint32_t i = src->mv_i;
    gp_vec2 o = dst->seed[i], p = src->seed[i];
    int32_t bo = bin_of(dst, o), bn = bin_of(dst, p);
    if (bo != bn) {
        if (bin_insert(&dst->bins[bn], (int32_t)i)) return gp_error_set(err, GP_ERR_NOMEM, "voronoi apply: out of memory");
        bin_remove(&dst->bins[bo], (int32_t)i);
    }
    dst->seed[i] = p;
    dst->useed[i] = src->useed[i];
    for (uint32_t k = 0; k < src->nchg; k++) {
        uint32_t j = src->chg[k];
        if (cell_copy(dst->cell[j], src->cell[j]))
            return gp_error_set(err, GP_ERR_NOMEM, "voronoi apply: out of memory (dst is now unusable)");
    }
    return GP_OK;
}

/* a cell's arrays a move reads: its vertices and their tags, its neighbours */
static void warm_cell(const vcell *c)
{
    __builtin_prefetch(c->v);
    __builtin_prefetch((const char *)c->v + 64);
    __builtin_prefetch(c->tag);
    __builtin_prefetch(c->nb);
}

/* Level by level over the k points, so that each level's loads overlap: the bins, a seed of
 * each, its record, its arrays, its neighbours' records and arrays. */
size_t gp_voronoi_warm(const gp_voronoi *v, const gp_vec2 *q, size_t k, uint32_t *ids, size_t cap)
{
    int32_t b[GP_VORONOI_WARM_MAX], k0[GP_VORONOI_WARM_MAX];
    if (!v || v->n == 0) return 0;
    if (k > GP_VORONOI_WARM_MAX) k = GP_VORONOI_WARM_MAX;
    for (size_t i = 0; i < k; i++) {
        gp_vec2 p = {q[i].x - v->origin.x, q[i].y - v->origin.y};
        b[i] = p.x >= 0 && p.x <= v->W && p.y >= 0 && p.y <= v->H ? bin_of(v, p) : -1;
        if (b[i] >= 0) __builtin_prefetch(&v->bins[b[i]]);
    }
    for (size_t i = 0; i < k; i++) {
        const vbin *B = b[i] >= 0 ? &v->bins[b[i]] : NULL;
        k0[i] = B && B->cnt > 0 ? (B->s ? B->s : B->inl)[0] : -1;
        if (k0[i] >= 0) __builtin_prefetch(&v->cell[k0[i]]);
    }
    for (size_t i = 0; i < k; i++)
        if (k0[i] >= 0) __builtin_prefetch(v->cell[k0[i]]);
    size_t m = 0;
    for (size_t i = 0; i < k; i++) {
        if (k0[i] < 0) continue;
        const vcell *c = v->cell[k0[i]];
        warm_cell(c);
        if (m < cap) ids[m++] = (uint32_t)k0[i];
        for (int32_t j = 0; j < c->nnb && m < cap; j++) {
            int32_t t = c->nb[j];
            __builtin_prefetch(&v->cell[t]);
            __builtin_prefetch(&v->seed[t]);
            __builtin_prefetch(&v->kst[t]);
            __builtin_prefetch(&v->cst[t]);
            ids[m++] = (uint32_t)t;
        }
    }
    for (size_t j = 0; j < m; j++) __builtin_prefetch(v->cell[ids[j]]);
    for (size_t j = 0; j < m; j++) warm_cell(v->cell[ids[j]]);
    return m;
}

size_t gp_voronoi_footprint(const gp_voronoi *v, uint32_t *out, size_t cap)
{
    if (!v || !v->pending) return 0;
    size_t cnt = 0;
    for (uint32_t k = 0; k < v->nchg; k++) {
        const vcell *now = v->cell[v->chg[k]], *was = v->chg_old[k];
        if (cnt < cap) out[cnt] = v->chg[k];
        cnt++;
        for (int pass = 0; pass < 2; pass++) {
            const vcell *c = pass ? was : now;
            for (int32_t q = 0; q < c->nnb; q++, cnt++)
                if (cnt < cap) out[cnt] = (uint32_t)c->nb[q];
        }
    }
    return cnt;
}

gp_status gp_voronoi_move(gp_voronoi *v, size_t i, gp_vec2 p, gp_error *err)
{
    gp_status st = gp_voronoi_try_move(v, i, p, err);
    if (st == GP_OK) gp_voronoi_commit(v);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* queries                                                                                     */

size_t gp_voronoi_count(const gp_voronoi *v) { return v ? v->n : 0; }
double gp_voronoi_container_area(const gp_voronoi *v) { return v ? v->carea : 0.0; }

gp_vec2 gp_voronoi_seed(const gp_voronoi *v, size_t i)
{
    if (!v || i >= v->n) return (gp_vec2){NAN, NAN};
    return v->useed[i];
}

double gp_voronoi_cell_area(const gp_voronoi *v, size_t i)
{
    return (v && i < v->n) ? v->cell[i]->area : NAN;
}

double gp_voronoi_cell_orientation(const gp_voronoi *v, size_t i)
{
    return (v && i < v->n) ? v->cell[i]->orient : NAN;
}

size_t gp_voronoi_cell_parts(const gp_voronoi *v, size_t i)
{
    return (v && i < v->n) ? (size_t)v->cell[i]->nparts : 0;
}

size_t gp_voronoi_cell_seed_part(const gp_voronoi *v, size_t i)
{
    return (v && i < v->n) ? (size_t)v->cell[i]->seed_part : 0;
}

size_t gp_voronoi_cell_polygon(const gp_voronoi *v, size_t i, size_t part, gp_vec2 *out, size_t cap)
{
    if (!v || i >= v->n) return 0;
    const vcell *c = v->cell[i];
    if (part >= (size_t)c->nparts) return 0;
    int32_t b = c->poff[part], e = c->poff[part + 1];
    for (int32_t k = b; k < e && (size_t)(k - b) < cap && out; k++) {
        out[k - b].x = c->v[k].x + v->origin.x;
        out[k - b].y = c->v[k].y + v->origin.y;
    }
    return (size_t)(e - b);
}

size_t gp_voronoi_neighbours(const gp_voronoi *v, size_t i, size_t *out, size_t cap)
{
    if (!v || i >= v->n) return 0;
    const vcell *c = v->cell[i];
    size_t cnt = 0;
    /* the tags are few: a quadratic unique-count keeps this allocation-free */
    for (int32_t k = 0; k < c->nv; k++) {
        int32_t t = c->tag[k];
        if (t < 0) continue;
        int seen = 0;
        for (int32_t q = 0; q < k && !seen; q++) seen = c->tag[q] == t;
        if (seen) continue;
        /* insert t in sorted order among the first min(cnt, cap) outputs */
        size_t lim = cnt < cap ? cnt : cap, pos = lim;
        if (out) {
            while (pos > 0 && out[pos - 1] > (size_t)t) pos--;
            if (pos < cap) {
                size_t top = lim < cap ? lim : cap - 1;
                for (size_t q = top; q > pos; q--) out[q] = out[q - 1];
                out[pos] = (size_t)t;
            }
        }
        cnt++;
    }
    return cnt;
}

int gp_voronoi_sample_cell(const gp_voronoi *v, size_t i, double (*u01)(void *), void *state,
                           gp_vec2 *p)
{
    if (!v || i >= v->n || !u01 || !p) return -1;
    const vcell *c = v->cell[i];
    if (c->convex) {
        const gp_vec2 *q = c->v;
        double tot = 0.0;
        for (int32_t k = 1; k + 1 < c->nv; k++) tot += cross3(q[0], q[k], q[k + 1]);
        double u = u01(state) * tot, acc = 0.0;
        int32_t k = 1;
        for (; k + 2 < c->nv; k++) {
            acc += cross3(q[0], q[k], q[k + 1]);
            if (u < acc) break;
        }
        double r1 = u01(state), r2 = u01(state);
        if (r1 + r2 > 1.0) {
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        p->x = q[0].x + r1 * (q[k].x - q[0].x) + r2 * (q[k + 1].x - q[0].x) + v->origin.x;
        p->y = q[0].y + r1 * (q[k].y - q[0].y) + r2 * (q[k + 1].y - q[0].y) + v->origin.y;
        return 0;
    }
    /* a part by area, then rejection in its bounding box */
    double u = u01(state) * c->area, acc = 0.0;
    int32_t part = c->nparts - 1;
    for (int32_t k = 0; k < c->nparts; k++) {
        acc += ring_area_about(c->v + c->poff[k], c->poff[k + 1] - c->poff[k], c->v[c->poff[k]]);
        if (u < acc) {
            part = k;
            break;
        }
    }
    const gp_vec2 *q = c->v + c->poff[part];
    int32_t nq = c->poff[part + 1] - c->poff[part];
    gp_vec2 lo, hi;
    gp_poly_bbox(q, (size_t)nq, &lo, &hi, NULL);
    for (int t = 0; t < 1000; t++) {
        gp_vec2 r = {lo.x + u01(state) * (hi.x - lo.x), lo.y + u01(state) * (hi.y - lo.y)};
        if (gp_poly_contains(q, (size_t)nq, r)) {
            p->x = r.x + v->origin.x;
            p->y = r.y + v->origin.y;
            return 0;
        }
    }
    *p = v->useed[i];
    return -1;
}

/* ------------------------------------------------------------------------------------------ */

gp_status gp_voronoi_circle_polygon(gp_vec2 c, double r, double tol, gp_vec2 **out, size_t *n,
                                    gp_error *err)
{
    if (!out || !n) return gp_error_set(err, GP_ERR_INVALID, "circle_polygon: out and n are required");
    *out = NULL;
    *n = 0;
    if (!(r > 0) || !(tol > 0) || !isfinite(r) || !isfinite(c.x) || !isfinite(c.y))
        return gp_error_set(err, GP_ERR_INVALID, "circle_polygon: need r > 0 and tol > 0");
    double m;
    if (tol >= r) m = 8;
    else {
        /* sagitta r (1 - cos(pi/m)) <= tol */
        m = ceil(GP_VOR_PI / acos(1.0 - tol / r));
        if (m < 8) m = 8;
    }
    if (!(m <= 1048576.0))
        return gp_error_set(err, GP_ERR_INVALID, "circle_polygon: tol %g too small for r %g", tol, r);
    size_t k = (size_t)m;
    /* guard against rounding in acos: grow until the sagitta really is within tol */
    while (k < 1048576 && r * (1.0 - cos(GP_VOR_PI / (double)k)) > tol) k++;
    gp_vec2 *p = malloc(k * sizeof *p);
    if (!p) return gp_error_set(err, GP_ERR_NOMEM, "circle_polygon: out of memory");
    for (size_t j = 0; j < k; j++) {
        double a = 2.0 * GP_VOR_PI * (double)j / (double)k;
        p[j].x = c.x + r * cos(a);
        p[j].y = c.y + r * sin(a);
    }
    *out = p;
    *n = k;
    return GP_OK;
}
