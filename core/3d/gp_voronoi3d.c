/* gp_voronoi3d.c -- bounded 3D Voronoi tessellation with local updates. See gp_voronoi3d.h.
 *
 * Layout: convex polyhedra as vertex graphs and their cutting ("poly"), the object and its
 * grid of seeds, one cell (the search), canonical cells (the finished polyhedron rewritten
 * from its planes, so that its bits do not depend on the cuts' order), the container (and
 * its queries), the build, the moves, the queries. docs/design/voronoi3d.md has the reasons
 * and the measurements.
 *
 * Tags: every face of a polyhedron carries a tag: >= 0 the seed whose bisector it lies on,
 * -1 - k the container's half-space k, TAG_BBOX + k (k < 6) a side of the starting box of a
 * non-box container (never in a finished cell: the container's half-spaces cut the box).
 */
#include "gp_voronoi3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gp_grid.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#define V3_EPS 1e-12           /* cutting tolerance, relative to the polyhedron's radius */
#define V3_DUP 1e-10           /* duplicates: closer than this times the container's size */
#define V3_INSIDE 1e-12        /* the inside test's tolerance, times the container's size */
#define V3_SEEDS_PER_BIN 3.0
#define V3_SLACK (1.0 + 1e-9)  /* the security radius' comparisons, against rounding */
#define V3_PI 3.14159265358979323846
#define V3_COND 1e-3           /* a vertex's triple of planes is well-conditioned from this */
#define V3_SNAP 1e-6           /* a canonical vertex this far (times R) from the cut's is refused */
#define V3_MAXDEG 16           /* the planes a degenerate vertex's triple is chosen from */
#define TAG_BBOX (INT32_MIN + 16)
#define CANCEL_EVERY 1024

/* ------------------------------------------------------------------------------------------ */
/* convex polyhedra                                                                            */

/* A convex polyhedron as its vertex graph (voro++'s representation), in the cell's frame:
 * vertices 0 .. nv-1, each with its edges in counter-clockwise order seen from outside. Edge
 * entry k of vertex v holds the neighbour e_k, the index of v among e_k's entries (back) and
 * the face of the half-edge v -> e_k: the face between e_k and e_k+1, whose loop (counter-
 * clockwise from outside) runs ... e_k+1 -> v -> e_k ..., so that the half-edge after v -> w
 * in its face is w -> (w's entry before v's). A face is an id: its tag and the plane it was
 * cut with; a face no edge names any more is gone. A vertex slot owns a stretch of the edge
 * pool (3 entries, more for a degenerate vertex), which stays with the slot when vertices
 * move to keep 0 .. nv-1 dense. */
typedef struct poly {
    int32_t nv, vcap;      /* live vertices, slot capacity */
    int32_t nslot;         /* slots given edge storage since the polyhedron was started */
    int32_t ep, ecap;      /* edge pool: entries handed out, capacity */
    int32_t nf, fcap;      /* face ids */
    double *x, *y, *z;     /* per vertex: coordinates (apart, for the plane test's loop) */
    double *x2;            /* per vertex: |x|^2 */
    int32_t *deg, *off, *room; /* per slot: degree, edge storage offset and size */
    int32_t *nb, *bk, *ef; /* per edge entry: neighbour, back index, face id */
    int32_t *ftag;         /* per face id: tag */
    double *fpl;           /* per face id: its plane n . x <= c as cut (n, c), 4 each */
    double r2;             /* largest squared distance of a vertex from the frame's origin */
} poly;

typedef struct cand {
    double r[3], d2; /* from the cell's seed to seed j (read from the bin, which is in cache) */
    int32_t j;
} cand;

/* A vertex's place in the canonical order: its three lowest tags, as unsigned keys (hi: the
 * first two), and its slot. */
typedef struct vkey {
    uint64_t hi, lo;
    int32_t slot;
} vkey;

/* vertex classes of a cut (DEAD: an on vertex left without a face by a degenerate cut) */
enum { C_OUT = 1, C_IN = 2, C_ON = 4, C_DEAD = 8 };

/* Scratch of the cutting and of one cell's search (one per object: builds and moves are
 * single-threaded). */
typedef struct scratch {
    poly p;
    int32_t scap;       /* capacity of the per-slot scratch */
    double *d;          /* per slot: n . x - c of the current cut */
    unsigned char *cls; /* per slot: class */
    int32_t *outl;      /* the outside vertices, ascending; then the dead ones */
    /* per new vertex: the entry where the walk to its cap neighbour starts (degenerate cut);
     * what the plain cut reads before it writes */
    int32_t wcap, *ws;
    struct xnew {
        double x, y, z;
        int32_t e, u, w, j, f1, f2, prev, next;
    } * xt;
    int32_t *cnext, *cprev; /* degenerate cut: the cap's loop through each of its vertices */
    int32_t *wl;        /* degenerate cut: the rebuilt vertices */
    int32_t xcap;       /* capacity of the per-entry scratch */
    int32_t *xn;        /* per entry of an outside vertex to an inside one: the new vertex */
    int32_t *rs, *re;   /* degenerate cut, per entry of an on vertex: the cap's ends there */
    int32_t *enx;       /* canonical cell, per entry: the next entry of its face */
    int32_t tcap, *tnb, *tef; /* degenerate cut: one rebuilt vertex's entries */
    int32_t fmcap;
    unsigned char *fmask; /* degenerate cut, per face id: its vertices' classes */
    cand *cd;           /* candidates */
    int32_t *ord, *bkt; /* the bucket sort's order and buckets */
    int32_t ordcap;
    int32_t *cnt;       /* the bucket sort's counts */
    int32_t ncd, cdcap, cntcap;
    double cdmax;       /* the largest d2 of the candidates */
    int32_t *bl;        /* the bins of a batch in reach */
    double si[3];       /* the cell's seed (local frame) */
    int32_t dup;        /* a seed found to coincide with the cell's */
    double near_d2;     /* the nearest candidate of the last batch (when ncd > 0) */
    int32_t near_j;
    int32_t *cut;       /* seeds whose planes cut the cell */
    int32_t ncut, cutcap;
    /* canonical cells: per vertex the offset of its faces in vfac, its key, its number; per
     * face id its first edge entry; the present faces, by tag; one loop */
    int32_t canv, canl, canf;
    int32_t *voff, *vfac, *vord, *remap, *fent, *fpres, *ford, *lbuf;
    vkey *vkey;
    double *pp;         /* per vertex: x_p x_q (the moments) */
} scratch;

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

/* Arrays of one capacity grown together. */
typedef struct slab {
    void **p;
    size_t elt;
} slab;

static int grow_set(const slab *a, int n, int32_t *cap, int32_t need)
{
    if (need <= *cap) return 0;
    int32_t c = *cap ? *cap : 32;
    while (c < need) c *= 2;
    for (int k = 0; k < n; k++) {
        void *q = realloc(*a[k].p, (size_t)c * a[k].elt);
        if (!q) return -1;
        *a[k].p = q;
    }
    *cap = c;
    return 0;
}

/* Room for nv vertex slots (and their scratch). */
static int vslots(scratch *S, int32_t nv)
{
    poly *P = &S->p;
    if (nv + 1 <= P->vcap && nv + 1 <= S->scap) return 0;
    slab a[] = {{(void **)&P->x, sizeof(double)},   {(void **)&P->y, sizeof(double)},
                {(void **)&P->z, sizeof(double)},   {(void **)&P->x2, sizeof(double)},
                {(void **)&P->deg, sizeof(int32_t)}, {(void **)&P->off, sizeof(int32_t)},
                {(void **)&P->room, sizeof(int32_t)}};
    slab b[] = {{(void **)&S->d, sizeof(double)},     {(void **)&S->cls, 1},
                {(void **)&S->outl, sizeof(int32_t)}, {(void **)&S->cnext, sizeof(int32_t)},
                {(void **)&S->cprev, sizeof(int32_t)}, {(void **)&S->wl, sizeof(int32_t)}};
    return grow_set(a, 7, &P->vcap, nv + 1) || grow_set(b, 6, &S->scap, nv + 1) ? -1 : 0;
}

/* Room for ne edge entries (and their scratch). */
static int eslots(scratch *S, int32_t ne)
{
    poly *P = &S->p;
    if (ne <= P->ecap && ne <= S->xcap) return 0;
    slab a[] = {{(void **)&P->nb, sizeof(int32_t)}, {(void **)&P->bk, sizeof(int32_t)},
                {(void **)&P->ef, sizeof(int32_t)}};
    slab b[] = {{(void **)&S->xn, sizeof(int32_t)}, {(void **)&S->rs, sizeof(int32_t)},
                {(void **)&S->re, sizeof(int32_t)}, {(void **)&S->enx, sizeof(int32_t)}};
    return grow_set(a, 3, &P->ecap, ne) || grow_set(b, 4, &S->xcap, ne) ? -1 : 0;
}

/* Room for nf face ids. */
static int fslots(scratch *S, int32_t nf)
{
    poly *P = &S->p;
    if (nf <= P->fcap) return 0;
    slab a[] = {{(void **)&P->ftag, sizeof(int32_t)}, {(void **)&P->fpl, 4 * sizeof(double)}};
    return grow_set(a, 2, &P->fcap, nf);
}

static void poly_free(poly *P)
{
    void *a[] = {P->x, P->y, P->z, P->x2, P->deg, P->off, P->room, P->nb, P->bk, P->ef, P->ftag, P->fpl};
    for (size_t k = 0; k < sizeof a / sizeof a[0]; k++) free(a[k]);
    memset(P, 0, sizeof *P);
}

/* The box [lo, hi] (frame coordinates), face k (x-, x+, y-, y+, z-, z+) tagged tag[k]. Vertex
 * k = bx + 2 by + 4 bz; its neighbours are k ^ 1, k ^ 4, k ^ 2 counter-clockwise from outside
 * at a corner with an even number of hi coordinates, k ^ 1, k ^ 2, k ^ 4 at an odd one; the
 * face between the edges along two axes is the one across the third axis, on k's side. */
static int poly_box(scratch *S, const double lo[3], const double hi[3], const int32_t tag[6])
{
    static const int32_t nb[24] = {1, 4, 2, 0, 3, 5, 3, 0, 6, 2, 7, 1,
                                   5, 6, 0, 4, 1, 7, 7, 2, 4, 6, 5, 3};
    static const int32_t bk[24] = {0, 2, 1, 0, 2, 1, 0, 2, 1, 0, 2, 1,
                                   0, 2, 1, 0, 2, 1, 0, 2, 1, 0, 2, 1};
    static const int32_t ef[24] = {2, 0, 4, 4, 1, 2, 4, 0, 3, 3, 1, 4,
                                   5, 0, 2, 2, 1, 5, 3, 0, 5, 5, 1, 3};
    if (vslots(S, 8) || eslots(S, 24) || fslots(S, 6)) return -1;
    poly *P = &S->p;
    P->r2 = 0;
    for (int32_t k = 0; k < 8; k++) {
        P->x[k] = (k & 1) ? hi[0] : lo[0];
        P->y[k] = (k & 2) ? hi[1] : lo[1];
        P->z[k] = (k & 4) ? hi[2] : lo[2];
        double r2 = P->x[k] * P->x[k] + P->y[k] * P->y[k] + P->z[k] * P->z[k];
        P->x2[k] = r2;
        P->r2 = r2 > P->r2 ? r2 : P->r2;
        P->deg[k] = 3;
        P->off[k] = 3 * k;
        P->room[k] = 3;
    }
    memcpy(P->nb, nb, sizeof nb);
    memcpy(P->bk, bk, sizeof bk);
    memcpy(P->ef, ef, sizeof ef);
    for (int f = 0; f < 6; f++) {
        P->ftag[f] = tag[f];
        double *q = P->fpl + 4 * f; /* x <= hi, -x <= -lo */
        q[0] = q[1] = q[2] = 0;
        q[f / 2] = (f & 1) ? 1 : -1;
        q[3] = (f & 1) ? hi[f / 2] : -lo[f / 2];
    }
    P->nv = P->nslot = 8;
    P->ep = 24;
    P->nf = 6;
    return 0;
}

/* The largest of n . x - c over P's vertices, each kept in d. SSE2 two vertices at a time
 * where the compiler has it (the same operations in the same order: the same bits). */
static inline double plane_dist(const poly *P, const double n[3], double c, double *d)
{
    const double *x = P->x, *y = P->y, *z = P->z, n0 = n[0], n1 = n[1], n2 = n[2];
    int32_t k = 0, nv = P->nv;
    double m = -INFINITY;
#ifdef __SSE2__
    __m128d N0 = _mm_set1_pd(n0), N1 = _mm_set1_pd(n1), N2 = _mm_set1_pd(n2), C = _mm_set1_pd(c);
    __m128d M = _mm_set1_pd(-INFINITY);
    for (; k + 2 <= nv; k += 2) {
        __m128d e = _mm_add_pd(_mm_mul_pd(N0, _mm_loadu_pd(x + k)), _mm_mul_pd(N1, _mm_loadu_pd(y + k)));
        e = _mm_sub_pd(_mm_add_pd(e, _mm_mul_pd(N2, _mm_loadu_pd(z + k))), C);
        _mm_storeu_pd(d + k, e);
        M = _mm_max_pd(e, M);
    }
    double h[2];
    _mm_storeu_pd(h, M);
    m = h[0] > h[1] ? h[0] : h[1];
#endif
    for (; k < nv; k++) {
        double e = n0 * x[k] + n1 * y[k] + n2 * z[k] - c;
        d[k] = e;
        m = e > m ? e : m;
    }
    return m;
}

/* The largest of a[0 .. n) (0 when n is 0; the values are >= 0). */
static double vmax(const double *a, int32_t n)
{
    int32_t k = 0;
    double m = 0;
#ifdef __SSE2__
    __m128d M = _mm_setzero_pd();
    for (; k + 2 <= n; k += 2) M = _mm_max_pd(_mm_loadu_pd(a + k), M);
    double h[2];
    _mm_storeu_pd(h, M);
    m = h[0] > h[1] ? h[0] : h[1];
#endif
    for (; k < n; k++) m = a[k] > m ? a[k] : m;
    return m;
}

/* A new vertex at slot nv, with edge storage (3 entries made if the slot has none; the caller
 * reserved the room). */
static int32_t vertex_new(poly *P)
{
    int32_t v = P->nv++;
    if (v >= P->nslot) {
        P->off[v] = P->ep;
        P->room[v] = 3;
        P->ep += 3;
        P->nslot = v + 1;
    }
    return v;
}

/* Vertex s moved to slot h (the slots swap their edge storage); its neighbours follow. */
static void vertex_move(poly *P, int32_t s, int32_t h)
{
    P->x[h] = P->x[s];
    P->y[h] = P->y[s];
    P->z[h] = P->z[s];
    P->x2[h] = P->x2[s];
    P->deg[h] = P->deg[s];
    int32_t o = P->off[s], r = P->room[s];
    P->off[s] = P->off[h], P->room[s] = P->room[h];
    P->off[h] = o, P->room[h] = r;
    for (int32_t k = 0; k < P->deg[h]; k++) P->nb[P->off[P->nb[o + k]] + P->bk[o + k]] = h;
}

/* The new vertex on the edge from outside vertex u (its entry e) to inside vertex w, on the
 * plane: its entries w (the face of u -> w), the cap's next vertex (the cap) and the cap's
 * previous vertex (the face of w -> u), those two filled later; w's entry now names it, and
 * xn[e] too. */
static int32_t cross_vertex(scratch *S, int32_t u, int32_t e, int32_t cap)
{
    poly *P = &S->p;
    int32_t *restrict nb = P->nb, *restrict bk = P->bk, *restrict ef = P->ef;
    double *restrict X = P->x, *restrict Y = P->y, *restrict Z = P->z;
    int32_t w = nb[e], j = bk[e], ew = P->off[w] + j;
    int32_t x = vertex_new(P), ox = P->off[x];
    double t = S->d[w] / (S->d[w] - S->d[u]);
    double px = X[w] + t * (X[u] - X[w]), py = Y[w] + t * (Y[u] - Y[w]), pz = Z[w] + t * (Z[u] - Z[w]);
    X[x] = px, Y[x] = py, Z[x] = pz;
    P->x2[x] = px * px + py * py + pz * pz;
    P->deg[x] = 3;
    S->d[x] = 0;
    nb[ox] = w, bk[ox] = j, ef[ox] = ef[e];
    nb[ox + 1] = -1, ef[ox + 1] = cap;
    nb[ox + 2] = -1, ef[ox + 2] = ef[ew];
    nb[ew] = x, bk[ew] = 0;
    S->xn[e] = x;
    return x;
}

/* The cut's new vertices, one per edge from an outside vertex to an inside one (class by
 * d < -tol); for each, in ws, the entry after its edge in the face of inside -> outside (where
 * the walk of run_end starts). Returns their count. */
static int32_t cross_all(scratch *S, int32_t nout, int32_t cap, double tol)
{
    poly *P = &S->p;
    const int32_t *outl = S->outl;
    const double *d = S->d;
    int32_t nnew = 0;
    for (int32_t q = 0; q < nout; q++) {
        int32_t u = outl[q], o = P->off[u], du = P->deg[u];
        for (int32_t k = 0; k < du; k++)
            if (d[P->nb[o + k]] < -tol) {
                cross_vertex(S, u, o + k, cap);
                S->ws[nnew++] = o + (k ? k : du) - 1;
            }
    }
    return nnew;
}

/* From entry e of an outside vertex, along that half-edge's face through outside vertices
 * (d > tol) to the first vertex that is not outside: the entry (of the last outside vertex)
 * that reaches it, or -1 after `limit` steps (an inconsistent graph). */
static int32_t run_end(const scratch *S, int32_t e, double tol, int32_t limit)
{
    const poly *P = &S->p;
    const int32_t *nb = P->nb, *bk = P->bk, *off = P->off, *deg = P->deg;
    const double *d = S->d;
    for (int32_t step = 0; step < limit; step++) {
        int32_t b = nb[e];
        if (!(d[b] > tol)) return e;
        int32_t j = bk[e];
        e = off[b] + (j ? j : deg[b]) - 1;
    }
    return -1;
}

/* The cut without on vertices (the generic case). A new vertex on each edge from an outside
 * vertex to an inside one (a crossing); from each crossing, its face (the one of inside ->
 * outside) is followed through the outside vertices to the next crossing, whose new vertex
 * comes before it on the cap. Everything is read first, then written: the new vertices take
 * the outside vertices' slots (the first nout of them; the rest are appended). Returns the
 * count of slots still to free (outl[nnew .. nout) when there are fewer new vertices), -2
 * when the cap is not one loop through all the new vertices. */
static int32_t cut_plain(scratch *S, int32_t nout, int32_t cap, double tol)
{
    poly *P = &S->p;
    int32_t *nb = P->nb, *bk = P->bk, *ef = P->ef, *off = P->off, *deg = P->deg, *xn = S->xn;
    const int32_t *outl = S->outl;
    double *d = S->d; /* (run_end reads these too) */
    int32_t nnew = 0, nv0 = P->nv;
    struct xnew *restrict T = S->xt;
    /* the crossings: xn of the outside vertex's entry names it (written without a branch,
     * which would be as good as random; xn of the other entries is stale) */
    for (int32_t q = 0; q < nout; q++) {
        int32_t u = outl[q], o = off[u], du = deg[u];
        for (int32_t e = o; e < o + du; e++) {
            T[nnew].e = e;
            T[nnew].u = u;
            xn[e] = nnew;
            nnew += d[nb[e]] < -tol;
        }
    }
    if (nnew < 3) return -2;
    /* read: each new vertex's position, neighbour and faces, and its place on the cap (from
     * the entry after its edge in the face of inside -> outside) */
    double *restrict X = P->x, *restrict Y = P->y, *restrict Z = P->z;
    for (int32_t q = 0; q < nnew; q++) { /* no branch here: the divisions overlap */
        int32_t e = T[q].e, u = T[q].u, w = nb[e], j = bk[e];
        double t = d[w] / (d[w] - d[u]);
        T[q].x = X[w] + t * (X[u] - X[w]);
        T[q].y = Y[w] + t * (Y[u] - Y[w]);
        T[q].z = Z[w] + t * (Z[u] - Z[w]);
        T[q].w = w, T[q].j = j, T[q].f1 = ef[e], T[q].f2 = ef[off[w] + j];
        T[q].next = -1;
    }
    for (int32_t q = 0; q < nnew; q++) {
        int32_t e = T[q].e, u = T[q].u, k = e - off[u];
        int32_t r = run_end(S, e + (k ? 0 : deg[u]) - 1, tol, P->ep), p = r < 0 ? -1 : xn[r];
        if (p < 0 || p >= nnew || T[p].e != r) return -2; /* (xn holds stale values elsewhere) */
        T[q].prev = p;
    }
    for (int32_t q = 0; q < nnew; q++) T[T[q].prev].next = q; /* a permutation if one loop */
    int32_t cnt = 0, q = 0;
    do {
        q = T[q].next;
        cnt++;
    } while (q > 0 && cnt < nnew);
    if (q != 0 || cnt != nnew) return -2;
    /* write: the new vertices into the outside vertices' slots, then after the live ones */
    int32_t nslot = P->nslot, ep = P->ep;
    double *restrict X2 = P->x2;
#define NEW_ID(q) ((q) < nout ? outl[q] : nv0 + ((q) - nout))
    for (int32_t q = 0; q < nnew; q++) {
        int32_t x = NEW_ID(q), w = T[q].w, j = T[q].j;
        if (x >= nslot) {
            off[x] = ep;
            P->room[x] = 3;
            ep += 3;
            nslot = x + 1;
        }
        int32_t ox = off[x], nx = T[q].next, pv = T[q].prev;
        double px = T[q].x, py = T[q].y, pz = T[q].z;
        X[x] = px, Y[x] = py, Z[x] = pz;
        X2[x] = px * px + py * py + pz * pz;
        deg[x] = 3;
        d[x] = 0;
        nb[ox] = w, bk[ox] = j, ef[ox] = T[q].f1;
        nb[ox + 1] = NEW_ID(nx), bk[ox + 1] = 2, ef[ox + 1] = cap;
        nb[ox + 2] = NEW_ID(pv), bk[ox + 2] = 1, ef[ox + 2] = T[q].f2;
        nb[off[w] + j] = x, bk[off[w] + j] = 0;
    }
#undef NEW_ID
    P->nslot = nslot;
    P->ep = ep;
    if (nnew >= nout) {
        P->nv = nv0 + nnew - nout;
        return 0;
    }
    return nout - nnew;
}

/* The cap's edge a -> b; -1 when a already leaves or b is already reached (not one loop). */
static int cap_edge(scratch *S, int32_t a, int32_t b)
{
    if (a < 0 || S->cnext[a] >= 0 || S->cprev[b] >= 0) return -1;
    S->cnext[a] = b;
    S->cprev[b] = a;
    return 0;
}

/* The end of the run reached by entry e (see run_end), from start: the new vertex on that
 * edge, or the on vertex itself (which keeps the start for the face's entry there). */
static int32_t run_target(scratch *S, int32_t e, int32_t start)
{
    const poly *P = &S->p;
    int32_t q = P->nb[e];
    if (S->cls[q] == C_IN) return S->xn[e];
    int32_t j = P->bk[e];
    S->rs[P->off[q] + (j ? j : P->deg[q]) - 1] = start;
    return q;
}

/* The cut with on vertices (degenerate input), by the rules of one classification: a face
 * with an outside vertex and no inside one goes (dropped), one with both is clipped (each
 * run of outside vertices replaced by its ends: a new vertex on a crossing edge, or the on
 * vertex before or after it), one without an outside vertex stays. The cap is the loop of
 * the clipped runs' ends and of the edges between on vertices that have a dropped face on
 * one side and a face that stays on the other; the on vertices' edges are rebuilt around
 * their faces that stay (a vertex left with none goes: d = +inf). Returns the count of dead
 * vertices, listed ascending in outl; -1 out of memory, -2 when the cap is not one loop or a
 * vertex's faces do not close. */
static int32_t cut_degenerate(scratch *S, int32_t nout, int32_t cap, double tol)
{
    poly *P = &S->p;
    int32_t nv0 = P->nv, extra = 0, maxd = 0;
    for (int32_t v = 0; v < nv0; v++) {
        double e = S->d[v];
        S->cls[v] = (unsigned char)(e > tol ? C_OUT : (e < -tol ? C_IN : C_ON));
        if (S->cls[v] == C_OUT) extra += 3 * P->deg[v];
        if (S->cls[v] == C_ON) {
            extra += P->deg[v] + 1;
            maxd = P->deg[v] > maxd ? P->deg[v] : maxd;
        }
    }
    slab t[] = {{(void **)&S->tnb, sizeof(int32_t)}, {(void **)&S->tef, sizeof(int32_t)}};
    if (eslots(S, P->ep + extra) || grow((void **)&S->fmask, &S->fmcap, P->nf, 1) ||
        grow_set(t, 2, &S->tcap, maxd + 1))
        return -1;
    unsigned char *fm = S->fmask;
    memset(fm, 0, (size_t)P->nf);
    for (int32_t v = 0; v < nv0; v++)
        for (int32_t k = 0, o = P->off[v]; k < P->deg[v]; k++) fm[P->ef[o + k]] |= S->cls[v];
#define DROPPED(f) ((fm[f] & (C_OUT | C_IN)) == C_OUT)
    int32_t nnew = cross_all(S, nout, cap, tol), nall = nv0 + nnew;
    for (int32_t x = nv0; x < nall; x++) S->cls[x] = C_ON;
    for (int32_t v = 0; v < nall; v++) S->cnext[v] = S->cprev[v] = -1;
    for (int32_t v = 0; v < nv0; v++)
        if (S->cls[v] == C_ON)
            for (int32_t k = 0, o = P->off[v]; k < P->deg[v]; k++) S->rs[o + k] = S->re[o + k] = -1;
    /* the clipped runs: from a new vertex (its face inside -> outside is clipped) */
    for (int32_t q = 0; q < nnew; q++) {
        int32_t e = run_end(S, S->ws[q], tol, P->ep);
        if (e < 0 || cap_edge(S, run_target(S, e, nv0 + q), nv0 + q)) return -2;
    }
    /* ... and from an on vertex into a clipped face */
    for (int32_t p = 0; p < nv0; p++) {
        if (S->cls[p] != C_ON) continue;
        for (int32_t k = 0, o = P->off[p]; k < P->deg[p]; k++) {
            int32_t u = P->nb[o + k], j = P->bk[o + k];
            if (S->cls[u] != C_OUT || DROPPED(P->ef[o + k])) continue;
            int32_t e = run_end(S, P->off[u] + (j ? j : P->deg[u]) - 1, tol, P->ep);
            if (e < 0) return -2;
            S->re[o + k] = run_target(S, e, p);
            if (cap_edge(S, S->re[o + k], p)) return -2;
        }
    }
    /* edges between on vertices with a dropped face on one side only */
    for (int32_t a = 0; a < nv0; a++) {
        if (S->cls[a] != C_ON) continue;
        for (int32_t k = 0, o = P->off[a]; k < P->deg[a]; k++) {
            int32_t b = P->nb[o + k];
            if (S->cls[b] == C_ON && DROPPED(P->ef[o + k]) &&
                !DROPPED(P->ef[P->off[b] + P->bk[o + k]]) && cap_edge(S, a, b))
                return -2;
        }
    }
    /* the cap: one loop through all its vertices */
    int32_t ncap = nnew, start = nnew ? nv0 : -1;
    for (int32_t v = 0; v < nv0; v++)
        if (S->cnext[v] >= 0) {
            ncap++;
            start = start < 0 ? v : start;
        }
    if (ncap < 3) return -2;
    int32_t cnt = 0, v = start;
    do {
        v = S->cnext[v];
        cnt++;
    } while (v >= 0 && v != start && cnt < ncap);
    if (v != start || cnt != ncap) return -2;
    /* the on vertices' edges around their faces that stay, the cap between two of them */
    int32_t nre = 0;
    for (int32_t v = 0; v < nv0; v++) {
        if (S->cls[v] != C_ON) continue;
        int32_t D = P->deg[v], o = P->off[v], change = S->cnext[v] >= 0, first = -1;
        for (int32_t k = 0; k < D; k++) {
            int drop = DROPPED(P->ef[o + k]);
            change |= drop | (S->cls[P->nb[o + k]] == C_OUT);
            first = first < 0 && !drop ? k : first;
        }
        if (!change) continue;
        if (first < 0) { /* no face stays: the vertex goes */
            if (S->cnext[v] >= 0 || S->cprev[v] >= 0) return -2;
            S->cls[v] = C_DEAD;
            continue;
        }
        int32_t m = 0, gaps = 0, gt = -1, gs = -1, s0 = -1, tprev = -1;
        for (int32_t i = 0; i < D; i++) {
            int32_t k = (first + i) % D, k1 = k + 1 < D ? k + 1 : 0;
            if (DROPPED(P->ef[o + k])) continue;
            int32_t ek = P->nb[o + k], ek1 = P->nb[o + k1];
            int32_t s = S->cls[ek] == C_OUT ? S->re[o + k] : ek;
            int32_t t = S->cls[ek1] == C_OUT ? S->rs[o + k] : ek1;
            if (s < 0 || t < 0) return -2;
            if (i == 0) s0 = s;
            else if (tprev != s) {
                S->tnb[m] = tprev, S->tef[m++] = cap;
                gaps++, gt = tprev, gs = s;
            }
            S->tnb[m] = s, S->tef[m++] = P->ef[o + k];
            tprev = t;
        }
        if (tprev != s0) {
            S->tnb[m] = tprev, S->tef[m++] = cap;
            gaps++, gt = tprev, gs = s0;
        }
        if (gaps > 1 || (gaps == 1 && (S->cnext[v] != gt || S->cprev[v] != gs)) ||
            (gaps == 0 && S->cnext[v] >= 0))
            return -2;
        if (m > P->room[v]) {
            P->off[v] = P->ep;
            P->room[v] = m;
            P->ep += m;
        }
        memcpy(P->nb + P->off[v], S->tnb, (size_t)m * sizeof(int32_t));
        memcpy(P->ef + P->off[v], S->tef, (size_t)m * sizeof(int32_t));
        P->deg[v] = m;
        S->wl[nre++] = v;
    }
#undef DROPPED
    /* the new vertices' cap edges, then the back indices around the rebuilt vertices */
    for (int32_t x = nv0; x < nall; x++) {
        int32_t ox = P->off[x];
        P->nb[ox + 1] = S->cnext[x], P->bk[ox + 1] = 2;
        P->nb[ox + 2] = S->cprev[x], P->bk[ox + 2] = 1;
    }
    for (int32_t q = 0; q < nre; q++) {
        int32_t v = S->wl[q], o = P->off[v];
        for (int32_t k = 0; k < P->deg[v]; k++) {
            int32_t w = P->nb[o + k], ow = P->off[w], i = 0;
            while (i < P->deg[w] && P->nb[ow + i] != v) i++;
            if (i == P->deg[w]) return -2;
            P->bk[o + k] = i;
            P->bk[ow + i] = k;
        }
    }
    /* the dead: outside vertices and on vertices left without a face, ascending */
    int32_t nd = 0;
    for (int32_t v = 0; v < nv0; v++)
        if (S->cls[v] & (C_OUT | C_DEAD)) {
            S->d[v] = INFINITY;
            S->outl[nd++] = v;
        }
    return nd;
}

/* Removes the dead vertices (dead[0 .. nd), ascending; the dead have d > tol, the others,
 * new ones included, not) by moving the last live ones into their slots; r2 anew. */
static void poly_compact(scratch *S, const int32_t *dead, int32_t nd, double tol)
{
    poly *P = &S->p;
    const double *d = S->d;
    int32_t live = P->nv - nd, last = P->nv - 1;
    for (int32_t q = 0; q < nd && dead[q] < live; q++) {
        while (d[last] > tol) last--;
        vertex_move(P, last--, dead[q]);
    }
    P->nv = live;
    P->r2 = vmax(P->x2, live);
}

/* Cuts p by n . x <= c (tol in the units of n . x; the new face tagged tag). Every vertex is
 * classified once by its signed distance: outside (> tol), inside (< -tol) or on. Returns 0
 * when no vertex is outside (p unchanged), 1 when cut, -1 out of memory, -2 inconsistent
 * (nothing inside, or a cap that does not close). The plane test comes first (poly_cut;
 * poly_cut_found once plane_dist has found a vertex outside): most planes tested cut
 * nothing. */
static int poly_cut_found(scratch *S, const double n[3], double c, double tol, int32_t tag)
{
    poly *P = &S->p;
    double *d = S->d;
    int32_t nv = P->nv;
    int32_t *outl = S->outl, nout = 0, nin = 0, grow_by = 0, k = 0;
#ifdef __SSE2__
    __m128d T = _mm_set1_pd(tol), NT = _mm_set1_pd(-tol);
    for (; k + 2 <= nv; k += 2) {
        __m128d e = _mm_loadu_pd(d + k);
        int o = _mm_movemask_pd(_mm_cmpgt_pd(e, T)), in = _mm_movemask_pd(_mm_cmplt_pd(e, NT));
        nin += (in & 1) + (in >> 1);
        outl[nout] = k;
        nout += o & 1;
        outl[nout] = k + 1;
        nout += o >> 1;
    }
#endif
    for (; k < nv; k++) {
        double e = d[k];
        outl[nout] = k;
        nout += e > tol;
        nin += e < -tol;
    }
    if (nin == 0) return -2;
    for (int32_t q = 0; q < nout; q++) grow_by += P->deg[outl[q]];
    if (nv + grow_by + 1 > P->vcap || nv + grow_by + 1 > S->scap || P->ep + 3 * grow_by > P->ecap ||
        P->ep + 3 * grow_by > S->xcap || P->nf + 1 > P->fcap || grow_by + 1 > S->wcap) {
        slab w[] = {{(void **)&S->ws, sizeof(int32_t)}, {(void **)&S->xt, sizeof(struct xnew)}};
        if (vslots(S, nv + grow_by) || eslots(S, P->ep + 3 * grow_by) || fslots(S, P->nf + 1) ||
            grow_set(w, 2, &S->wcap, grow_by + 1))
            return -1;
    }
    int32_t cap = P->nf++;
    P->ftag[cap] = tag;
    double *q = P->fpl + 4 * cap;
    q[0] = n[0], q[1] = n[1], q[2] = n[2], q[3] = c;
    if (nout + nin == nv) {
        int32_t rest = cut_plain(S, nout, cap, tol);
        if (rest < 0) return rest;
        poly_compact(S, S->outl + nout - rest, rest, tol);
    } else {
        nout = cut_degenerate(S, nout, cap, tol);
        if (nout < 0) return nout;
        poly_compact(S, S->outl, nout, tol);
    }
    return 1;
}

static int poly_cut(scratch *S, const double n[3], double c, double tol, int32_t tag)
{
    return plane_dist(&S->p, n, c, S->d) <= tol ? 0 : poly_cut_found(S, n, c, tol, tag);
}

/* Adds the tetrahedra (origin, fan triangles from L[0] of the loop L of m vertices of x) to
 * s: 6 V, then 24 V g, then 120 times the integral of x x^T (xx xy xz yy yz zz); pp holds
 * each vertex's products x_p x_q in that order. */
static void loop_moments(const double *x, const double *pp, const int32_t *L, int32_t m,
                         double s[10])
{
    const double *a = x + 3 * L[0], *pa = pp + 6 * L[0];
#ifdef __SSE2__
    /* the same operations as below, two sums at a time (det * 1 is det) */
    __m128d U[5], A01 = _mm_loadu_pd(a), PA[3], one = _mm_set_sd(1.0);
    one = _mm_unpacklo_pd(one, one);
    for (int q = 0; q < 5; q++) U[q] = _mm_loadu_pd(s + 2 * q);
    for (int q = 0; q < 3; q++) PA[q] = _mm_loadu_pd(pa + 2 * q);
    for (int32_t k = 1; k + 1 < m; k++) {
        const double *b = x + 3 * L[k], *c = x + 3 * L[k + 1];
        const double *pb = pp + 6 * L[k], *pc = pp + 6 * L[k + 1];
        double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        __m128d T01 = _mm_add_pd(_mm_add_pd(A01, _mm_loadu_pd(b)), _mm_loadu_pd(c));
        double t2 = a[2] + b[2] + c[2];
        __m128d T2 = _mm_set1_pd(t2), D = _mm_set1_pd(det);
        __m128d T0 = _mm_unpacklo_pd(T01, T01), T1 = _mm_unpackhi_pd(T01, T01);
        __m128d TT[3] = {_mm_mul_pd(T0, T01), _mm_mul_pd(T01, _mm_unpacklo_pd(T2, T1)),
                         _mm_mul_pd(_mm_unpacklo_pd(T1, T2), T2)};
        U[0] = _mm_add_pd(U[0], _mm_mul_pd(D, _mm_unpacklo_pd(one, T01)));
        U[1] = _mm_add_pd(U[1], _mm_mul_pd(D, _mm_unpacklo_pd(T1, T2)));
        for (int q = 0; q < 3; q++) {
            __m128d e = _mm_add_pd(_mm_add_pd(PA[q], _mm_loadu_pd(pb + 2 * q)), _mm_loadu_pd(pc + 2 * q));
            U[2 + q] = _mm_add_pd(U[2 + q], _mm_mul_pd(D, _mm_add_pd(e, TT[q])));
        }
    }
    for (int q = 0; q < 5; q++) _mm_storeu_pd(s + 2 * q, U[q]);
#else
    double u[10]; /* the face's sums in registers (s may alias x for all the compiler knows) */
    memcpy(u, s, sizeof u);
    for (int32_t k = 1; k + 1 < m; k++) {
        const double *b = x + 3 * L[k], *c = x + 3 * L[k + 1];
        const double *pb = pp + 6 * L[k], *pc = pp + 6 * L[k + 1];
        double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        double t[3] = {a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]};
        double tt[6] = {t[0] * t[0], t[0] * t[1], t[0] * t[2], t[1] * t[1], t[1] * t[2], t[2] * t[2]};
        u[0] += det;
        for (int q = 0; q < 3; q++) u[1 + q] += det * t[q];
        for (int q = 0; q < 6; q++) u[4 + q] += det * (pa[q] + pb[q] + pc[q] + tt[q]);
    }
    memcpy(s, u, sizeof u);
#endif
}

/* Volume, centroid and second moments about the frame's origin from loop_moments' sums. */
static void moments_finish(const double s[10], double *vol, double g[3], double m[6])
{
    *vol = s[0] / 6;
    for (int q = 0; q < 3; q++) g[q] = s[0] != 0 ? s[1 + q] / (4 * s[0]) : 0;
    for (int q = 0; q < 6; q++) m[q] = s[4 + q] / 120;
}

/* ------------------------------------------------------------------------------------------ */
/* the object                                                                                  */

typedef struct vcell {
    int32_t nv, nf, nl, nnb, ncut;
    double vol, cen[3], inr[6]; /* centroid relative to the seed; inertia xx xy xz yy yz zz */
    double *x;                  /* relative to the seed */
    int32_t *foff, *fv, *ftag, *nb, *cut;
} vcell;

/* A bin's seeds with their coordinates (local frame), sorted by index: the search reads them
 * in one sweep instead of chasing seeds spread over memory. */
typedef struct bent {
    double p[3];
    int32_t j, pad;
} bent;

typedef struct vbin {
    int32_t cnt, cap, own; /* own: e is the bin's own allocation, else a part of binblock */
    bent *e;
} vbin;

struct gp_voronoi3d {
    uint32_t n;
    gp_voronoi3d_kind kind;
    double origin[3], L[3], size, cvol, lost;
    int32_t nplanes;
    double *pl;        /* unit normal and offset (local frame), 4 per half-space */
    double blo[3], bhi[3]; /* the starting box of a non-box container (local frame) */
    /* grid */
    size_t gn[3];
    double ginv[3], gh[3], ghmin;
    /* the bin offsets within Chebyshev distance reach of a seed's bin, by increasing lower
     * bound of their distance from any point of that bin (lb), in batches of equal lb */
    int32_t reach, nbatch;
    int32_t *off;       /* dx dy dz per offset */
    int32_t *offl;      /* per offset: its bin index offset (dz gn[1] + dy) gn[0] + dx */
    int32_t *batch;     /* nbatch + 1 starts into off */
    double *blb;        /* per batch: the lower bound, squared */
    vbin *bins;
    bent *binblock; /* the bins' entries as built, in bin order (neighbours close in memory) */
    double *seed, *useed; /* local and caller's coordinates, 3 per seed */
    vcell **cell;
    scratch s;
    /* pending move */
    int pending;
    uint32_t mv_i;
    double mv_seed[3], mv_useed[3];
    uint32_t *chg;
    vcell **chg_old;
    uint32_t nchg, chgcap;
    uint32_t *stamp, stampv;
};

static int32_t bin_of(const gp_voronoi3d *v, const double p[3], int32_t b[3])
{
    for (int a = 0; a < 3; a++) b[a] = (int32_t)gp_grid_cell(p[a] * v->ginv[a], v->gn[a]);
    return (int32_t)(((size_t)b[2] * v->gn[1] + (size_t)b[1]) * v->gn[0] + (size_t)b[0]);
}

static int bin_insert(vbin *b, int32_t j, const double p[3])
{
    if (b->cnt == b->cap) {
        int32_t nc = b->cap ? 2 * b->cap : 4;
        bent *ne = malloc((size_t)nc * sizeof(bent));
        if (!ne) return -1;
        if (b->cnt) memcpy(ne, b->e, (size_t)b->cnt * sizeof(bent));
        if (b->own) free(b->e);
        b->e = ne;
        b->cap = nc;
        b->own = 1;
    }
    int32_t k = b->cnt;
    while (k > 0 && b->e[k - 1].j > j) {
        b->e[k] = b->e[k - 1];
        k--;
    }
    b->e[k] = (bent){{p[0], p[1], p[2]}, j, 0};
    b->cnt++;
    return 0;
}

static void bin_remove(vbin *b, int32_t j)
{
    int32_t k = 0;
    while (k < b->cnt && b->e[k].j != j) k++;
    for (; k + 1 < b->cnt; k++) b->e[k] = b->e[k + 1];
    if (b->cnt > 0) b->cnt--;
}

static void bin_set(vbin *b, int32_t j, const double p[3])
{
    for (int32_t k = 0; k < b->cnt; k++)
        if (b->e[k].j == j) memcpy(b->e[k].p, p, 3 * sizeof(double));
}

/* ------------------------------------------------------------------------------------------ */
/* one cell                                                                                    */

static int cand_less(const cand *a, const cand *b)
{
    return a->d2 < b->d2 || (a->d2 == b->d2 && a->j < b->j);
}

/* Squared distance from p to bin b (indices per axis). */
static double bin_dist2(const gp_voronoi3d *v, const double p[3], const int32_t b[3])
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        double lo = b[a] * v->gh[a], hi = lo + v->gh[a];
        double g = p[a] < lo ? lo - p[a] : (p[a] > hi ? p[a] - hi : 0);
        s += g * g;
    }
    return s;
}

/* The seeds of bin b (but seed i at si) nearer than sqrt(lim) into the candidates. */
static inline int gather_seeds(scratch *S, const vbin *b, uint32_t i, const double si[3], double lim)
{
    if (S->ncd + b->cnt > S->cdcap && grow((void **)&S->cd, &S->cdcap, S->ncd + b->cnt, sizeof(cand)))
        return -1;
    cand *cd = S->cd;
    int32_t n = S->ncd;
    double mx = S->cdmax;
    for (int32_t k = 0; k < b->cnt; k++) { /* without a branch: kept or not is random */
        int32_t j = b->e[k].j;
        const double *sj = b->e[k].p;
        double r[3] = {sj[0] - si[0], sj[1] - si[1], sj[2] - si[2]};
        double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        int keep = (d2 < lim) & ((uint32_t)j != i);
        cd[n] = (cand){{r[0], r[1], r[2]}, d2, j};
        n += keep;
        mx = keep && d2 > mx ? d2 : mx;
    }
    S->ncd = n;
    S->cdmax = mx;
    return 0;
}

/* Adds the seeds of bin bb that may cut cell i (nearer than 2 R) to the candidates. */
static int gather_bin(gp_voronoi3d *v, uint32_t i, const int32_t bb[3])
{
    scratch *S = &v->s;
    const double *si = S->si;
    double lim = 4 * S->p.r2 * V3_SLACK;
    if (bin_dist2(v, si, bb) > lim) return 0;
    const vbin *b = &v->bins[((size_t)bb[2] * v->gn[1] + (size_t)bb[1]) * v->gn[0] + (size_t)bb[0]];
    return gather_seeds(S, b, i, si, lim);
}

/* The bins at Chebyshev distance k0..k from bin c into the candidates. */
static int gather_shell(gp_voronoi3d *v, uint32_t i, const int32_t c[3], int32_t k0, int32_t k)
{
    int32_t bb[3];
    for (int32_t dz = -k; dz <= k; dz++) {
        bb[2] = c[2] + dz;
        if (bb[2] < 0 || bb[2] >= (int32_t)v->gn[2]) continue;
        for (int32_t dy = -k; dy <= k; dy++) {
            bb[1] = c[1] + dy;
            if (bb[1] < 0 || bb[1] >= (int32_t)v->gn[1]) continue;
            int inner = k0 == k && abs(dz) < k && abs(dy) < k;
            for (int32_t dx = -k; dx <= k; dx += inner ? 2 * k : 1) {
                bb[0] = c[0] + dx;
                if (bb[0] < 0 || bb[0] >= (int32_t)v->gn[0]) continue;
                if (gather_bin(v, i, bb)) return -1;
            }
        }
    }
    return 0;
}

static int note_cutter(scratch *S, int32_t j)
{
    if (grow((void **)&S->cut, &S->cutcap, S->ncut + 1, sizeof(int32_t))) return -1;
    S->cut[S->ncut++] = j;
    return 0;
}

/* Cuts by the candidates c[o[0]], c[o[1]] ... c[o[n - 1]] (o NULL: c[0 .. n)) in that order: 1
 * at a candidate farther than 2 R (so is the rest), else 0; or poly_cut's error. */
static int cut_run(scratch *S, const cand *c, const int32_t *o, int32_t n)
{
    for (int32_t k = 0; k < n; k++) {
        const cand *q = c + (o ? o[k] : k);
        double d2 = q->d2;
        if (d2 > 4 * S->p.r2 * V3_SLACK) return 1;
        double m = plane_dist(&S->p, q->r, 0.5 * d2, S->d), tol;
        if (m <= 0 || m <= (tol = V3_EPS * sqrt(S->p.r2 * d2))) continue; /* tol >= 0 */
        int rc = poly_cut_found(S, q->r, 0.5 * d2, tol, q->j);
        if (rc < 0) return rc;
        if (rc == 1 && note_cutter(S, q->j)) return -1;
    }
    return 0;
}

/* Cuts cell i by the candidates in increasing (distance, index) while they are nearer than
 * 2 R. Beyond 24 of them, a counting sort of their indices on the distance into about one
 * bucket per candidate, each bucket put in exact order (insertion) only when the cutting
 * reaches it: the buckets beyond the security radius are never sorted. */
static int cut_candidates(scratch *S)
{
    int32_t n = S->ncd;
    cand *c = S->cd;
    if (n <= 24) {
        for (int32_t k = 1; k < n; k++) {
            cand t = c[k];
            int32_t m = k;
            for (; m > 0 && cand_less(&t, &c[m - 1]); m--) c[m] = c[m - 1];
            c[m] = t;
        }
        if (n > 0) S->near_d2 = c[0].d2, S->near_j = c[0].j;
        int rc = cut_run(S, c, NULL, n);
        return rc < 0 ? rc : 0;
    }
    slab a[] = {{(void **)&S->ord, sizeof(int32_t)}, {(void **)&S->bkt, sizeof(int32_t)}};
    if (grow_set(a, 2, &S->ordcap, n) || grow((void **)&S->cnt, &S->cntcap, n + 1, sizeof(int32_t)))
        return -1;
    double mx = S->cdmax, sc = (n - 1) / (mx > 0 ? mx : 1);
    int32_t *cnt = S->cnt, *ord = S->ord, *bkt = S->bkt;
    memset(cnt, 0, (size_t)(n + 1) * sizeof(int32_t));
    for (int32_t k = 0; k < n; k++) cnt[(bkt[k] = (int32_t)(c[k].d2 * sc)) + 1]++;
    for (int32_t k = 0; k < n; k++) cnt[k + 1] += cnt[k];
    for (int32_t k = 0; k < n; k++) ord[cnt[bkt[k]]++] = k;
    /* bucket b is now ord[cnt[b - 1] .. cnt[b]) */
    for (int32_t b = 0, lo = 0; b < n; lo = cnt[b++]) {
        int32_t m = cnt[b] - lo, *o = ord + lo;
        if (m == 0) continue;
        for (int32_t k = 1; k < m; k++) {
            int32_t t = o[k], q = k;
            for (; q > 0 && cand_less(&c[t], &c[o[q - 1]]); q--) o[q] = o[q - 1];
            o[q] = t;
        }
        if (lo == 0) S->near_d2 = c[o[0]].d2, S->near_j = c[o[0]].j;
        int rc = cut_run(S, c, o, m);
        if (rc) return rc < 0 ? rc : 0;
    }
    return 0;
}

/* The container's half-spaces that reach the cell (non-box containers). */
static int cut_walls(gp_voronoi3d *v, uint32_t i)
{
    scratch *S = &v->s;
    const double *si = S->si;
    for (int32_t k = 0; k < v->nplanes; k++) {
        const double *pl = v->pl + 4 * k;
        double h = pl[3] - (pl[0] * si[0] + pl[1] * si[1] + pl[2] * si[2]);
        if (h * h > S->p.r2 && h > 0) continue;
        int rc = poly_cut(S, pl, h, V3_EPS * sqrt(S->p.r2), -1 - k);
        if (rc < 0) return rc;
    }
    return 0;
}

/* The starting polyhedron of cell i in its seed's frame. */
static int cell_start(gp_voronoi3d *v, uint32_t i)
{
    const double *si = v->s.si;
    double lo[3], hi[3];
    int32_t tag[6];
    int box = v->kind == GP_VORONOI3D_BOX;
    for (int a = 0; a < 3; a++) {
        lo[a] = (box ? 0 : v->blo[a]) - si[a];
        hi[a] = (box ? v->L[a] : v->bhi[a]) - si[a];
    }
    for (int f = 0; f < 6; f++) tag[f] = box ? -1 - f : TAG_BBOX + f;
    return poly_box(&v->s, lo, hi, tag);
}

/* Squared lower bound of the distance from a point of a bin to the bin at offset d. */
static double offset_lb(const gp_voronoi3d *v, const int32_t d[3])
{
    double s = 0;
    for (int a = 0; a < 3; a++) {
        double g = (abs(d[a]) > 1 ? abs(d[a]) - 1 : 0) * v->gh[a];
        s += g * g;
    }
    return s;
}

/* Per axis a, the squared gap from p to the bins c[a] + d, d = -reach .. reach, into
 * g2[a * (2 reach + 1) + d + reach] (as bin_dist2's terms; INFINITY outside the grid). */
static void gap_table(const gp_voronoi3d *v, const double p[3], const int32_t c[3], double *g2)
{
    int32_t R = v->reach;
    for (int a = 0; a < 3; a++)
        for (int32_t d = -R; d <= R; d++) {
            int32_t b = c[a] + d;
            double g = INFINITY;
            if (b >= 0 && b < (int32_t)v->gn[a]) {
                double lo = b * v->gh[a], hi = lo + v->gh[a];
                g = p[a] < lo ? lo - p[a] : (p[a] > hi ? p[a] - hi : 0);
                g *= g;
            }
            g2[a * (2 * R + 1) + d + R] = g;
        }
}

/* Candidates of batch bt of the offsets around bin c (linear index cl), then the cuts: a bin
 * within 2 R of the seed (its squared gaps from the table g2) gives its seeds within 2 R. */
static int search_batch(gp_voronoi3d *v, uint32_t i, int32_t cl, const double *g2, int32_t bt)
{
    scratch *S = &v->s;
    const double *si = S->si, *gx = g2 + v->reach, *gy = gx + 2 * v->reach + 1,
                 *gz = gy + 2 * v->reach + 1;
    double lim = 4 * S->p.r2 * V3_SLACK;
    int32_t nb = 0, *bl = S->bl; /* the bins in reach, listed without a branch */
    for (int32_t k = v->batch[bt]; k < v->batch[bt + 1]; k++) {
        const int32_t *d = v->off + 3 * k;
        bl[nb] = cl + v->offl[k];
        nb += gx[d[0]] + gy[d[1]] + gz[d[2]] <= lim;
    }
    S->ncd = 0;
    S->cdmax = 0;
    for (int32_t q = 0; q < nb; q++)
        if (gather_seeds(S, &v->bins[bl[q]], i, si, lim)) return -1;
    return cut_candidates(&v->s);
}

/* The search: the offset batches nearest first, then (for a cell that reaches farther, in a
 * sparse corner) whole shells of bins, until the security radius stops it. The first batch
 * holds the 27 bins around the seed's: its nearest seed, sorted first, is checked for a
 * duplicate (-3, the other in S->dup). */
static int cell_search(gp_voronoi3d *v, uint32_t i)
{
    scratch *S = &v->s;
    int32_t c[3], cl = bin_of(v, S->si, c);
    double dup = V3_DUP * v->size, g2[3 * 7];
    gap_table(v, S->si, c, g2);
    for (int32_t bt = 0; bt < v->nbatch; bt++) {
        if (v->blb[bt] > 4 * S->p.r2 * V3_SLACK) break;
        int rc = search_batch(v, i, cl, g2, bt);
        if (rc) return rc;
        if (bt == 0 && S->ncd > 0 && S->near_d2 < dup * dup) {
            S->dup = S->near_j;
            return -3;
        }
        if (bt == 0 && v->kind != GP_VORONOI3D_BOX && (rc = cut_walls(v, i))) return rc;
    }
    int32_t kmax = 0;
    for (int a = 0; a < 3; a++) {
        int32_t e = c[a] > (int32_t)v->gn[a] - 1 - c[a] ? c[a] : (int32_t)v->gn[a] - 1 - c[a];
        if (e > kmax) kmax = e;
    }
    for (int32_t k = v->reach + 1; k <= kmax; k++) {
        double g = (k - 1) * v->ghmin;
        if (g * g > 4 * S->p.r2 * V3_SLACK) break;
        S->ncd = 0;
        S->cdmax = 0;
        if (gather_shell(v, i, c, k, k)) return -1;
        int rc = cut_candidates(&v->s);
        if (rc) return rc;
    }
    return 0;
}

static int offset_cmp(const void *pa, const void *pb)
{
    const double *a = pa, *b = pb;
    for (int q = 0; q < 4; q++)
        if (a[q] != b[q]) return a[q] < b[q] ? -1 : 1;
    return 0;
}

/* The offsets within Chebyshev distance reach (3, or less in a small grid), sorted by lower
 * bound (ties by dz, dy, dx), and their batches. */
static gp_status build_reach(gp_voronoi3d *v)
{
    int32_t R = 3, big = 0;
    for (int a = 0; a < 3; a++) big = (int32_t)v->gn[a] - 1 > big ? (int32_t)v->gn[a] - 1 : big;
    R = big < R ? (big > 1 ? big : 1) : R;
    int32_t w = 2 * R + 1, n = w * w * w;
    double *t = malloc(4 * (size_t)n * sizeof(double));
    v->off = malloc(3 * (size_t)n * sizeof(int32_t));
    v->batch = malloc((size_t)(n + 1) * sizeof(int32_t));
    v->blb = malloc((size_t)n * sizeof(double));
    v->offl = malloc((size_t)n * sizeof(int32_t));
    if (!t || !v->off || !v->batch || !v->blb || !v->offl) {
        free(t);
        return GP_ERR_NOMEM;
    }
    for (int32_t k = 0; k < n; k++) {
        int32_t d[3] = {k % w - R, k / w % w - R, k / w / w - R};
        t[4 * k] = offset_lb(v, d);
        t[4 * k + 1] = d[2], t[4 * k + 2] = d[1], t[4 * k + 3] = d[0];
    }
    qsort(t, (size_t)n, 4 * sizeof(double), offset_cmp);
    v->nbatch = 0;
    for (int32_t k = 0; k < n; k++) {
        for (int q = 0; q < 3; q++) v->off[3 * k + q] = (int32_t)t[4 * k + 3 - q];
        v->offl[k] = (int32_t)((v->off[3 * k + 2] * (int64_t)v->gn[1] + v->off[3 * k + 1]) *
                                   (int64_t)v->gn[0] + v->off[3 * k]);
        if (k == 0 || t[4 * k] != t[4 * (k - 1)]) {
            v->blb[v->nbatch] = t[4 * k];
            v->batch[v->nbatch++] = k;
        }
    }
    v->batch[v->nbatch] = n;
    v->reach = R;
    v->s.bl = malloc((size_t)n * sizeof(int32_t)); /* room for any batch */
    if (!v->s.bl) {
        free(t);
        return GP_ERR_NOMEM;
    }
    free(t);
    return GP_OK;
}

static void sort_unique(int32_t *a, int32_t *n)
{
    for (int32_t k = 1; k < *n; k++) {
        int32_t t = a[k], m = k;
        while (m > 0 && a[m - 1] > t) {
            a[m] = a[m - 1];
            m--;
        }
        a[m] = t;
    }
    int32_t m = 0;
    for (int32_t k = 0; k < *n; k++)
        if (m == 0 || a[m - 1] != a[k]) a[m++] = a[k];
    *n = m;
}

/* ------------------------------------------------------------------------------------------ */
/* canonical cells: the reported numbers as a function of the final planes                    */

static void cross3(const double a[3], const double b[3], double r[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The point on planes a, b, c (n0 n1 n2 c each) by Cramer's rule, one fixed formula; returns
 * the determinant. */
static double solve3(const double *a, const double *b, const double *c, double x[3])
{
    double u[3], w[3], z[3];
    cross3(b, c, u);
    cross3(c, a, w);
    cross3(a, b, z);
    double det = dot3(a, u);
    for (int q = 0; q < 3; q++) x[q] = (a[3] * u[q] + b[3] * w[q] + c[3] * z[q]) / det;
    return det;
}

/* The conditioning of planes a, b, c given their determinant: |det| / (|n_a| |n_b| |n_c|). */
static double conditioning(const double *a, const double *b, const double *c, double det)
{
    double nn = sqrt(dot3(a, a) * dot3(b, b) * dot3(c, c));
    return nn > 0 ? fabs(det) / nn : 0;
}

/* A vertex's canonical position from the planes of its faces (F[0..d), sorted by tag): of
 * three planes, their point; of more (degenerate input), the first triple in lexicographic
 * order whose conditioning reaches V3_COND, else the best-conditioned one (the first of
 * equals), trying only the lowest V3_MAXDEG planes. Keeps the cut's position xcut when the
 * solution is not finite or lies farther than V3_SNAP R from it (a triple too close to
 * singular). */
static void vertex_canon(const poly *P, const int32_t *F, int32_t d, const double *xcut,
                         double R, double x[3])
{
    if (d == 3) {
        solve3(P->fpl + 4 * F[0], P->fpl + 4 * F[1], P->fpl + 4 * F[2], x);
    } else {
        double best = -1, y[3];
        d = d < V3_MAXDEG ? d : V3_MAXDEG;
        memcpy(x, xcut, 3 * sizeof(double));
        for (int32_t a = 0; a < d && best < V3_COND; a++)
            for (int32_t b = a + 1; b < d && best < V3_COND; b++)
                for (int32_t c = b + 1; c < d && best < V3_COND; c++) {
                    const double *pa = P->fpl + 4 * F[a], *pb = P->fpl + 4 * F[b], *pc = P->fpl + 4 * F[c];
                    double cond = conditioning(pa, pb, pc, solve3(pa, pb, pc, y));
                    if (cond > best) {
                        best = cond;
                        memcpy(x, y, sizeof y);
                    }
                }
    }
    double e[3] = {x[0] - xcut[0], x[1] - xcut[1], x[2] - xcut[2]};
    if (!(dot3(e, e) <= V3_SNAP * V3_SNAP * R * R)) memcpy(x, xcut, 3 * sizeof(double));
}

static int canon_reserve(scratch *S)
{
    const poly *P = &S->p;
    int32_t nl = 0;
    for (int32_t v = 0; v < P->nv; v++) nl += P->deg[v];
    slab a[] = {{(void **)&S->voff, sizeof(int32_t)}, {(void **)&S->vord, sizeof(int32_t)},
                {(void **)&S->remap, sizeof(int32_t)}, {(void **)&S->vkey, sizeof(vkey)},
                {(void **)&S->pp, 6 * sizeof(double)}};
    slab b[] = {{(void **)&S->vfac, sizeof(int32_t)}, {(void **)&S->lbuf, sizeof(int32_t)}};
    slab c[] = {{(void **)&S->fent, sizeof(int32_t)}, {(void **)&S->fpres, sizeof(int32_t)},
                {(void **)&S->ford, sizeof(int32_t)}};
    return grow_set(a, 5, &S->canv, P->nv + 1) || grow_set(b, 2, &S->canl, nl + 1) ||
                   grow_set(c, 3, &S->canf, P->nf + 1)
               ? -1
               : 0;
}

/* A tag as an unsigned key of the same order. */
static uint64_t tag_key(int32_t t)
{
    return (uint64_t)((uint32_t)t ^ 0x80000000u);
}

/* Faces F[0..3) sorted by tag, without branches (the order is as good as random). */
static void sort3(const int32_t *tag, int32_t F[3])
{
    int32_t a = F[0], b = F[1], c = F[2], t;
    int s = tag[a] > tag[b];
    t = s ? a : b, a = s ? b : a, b = t;
    s = tag[b] > tag[c];
    t = s ? b : c, b = s ? c : b, c = t;
    s = tag[a] > tag[b];
    t = s ? a : b, a = s ? b : a, b = t;
    F[0] = a, F[1] = b, F[2] = c;
}

/* Each vertex's faces, sorted by tag, into vfac[voff[v] .. voff[v + 1]) and its key (its
 * three lowest tags) into vkey[v]; an edge entry of each present face into fent, the
 * present faces into fpres; returns their count, -2 when a vertex has fewer than three
 * faces (not a closed polyhedron). */
static int32_t vertex_faces(scratch *S)
{
    const poly *P = &S->p;
    const int32_t *ef = P->ef, *nb = P->nb, *bk = P->bk, *off = P->off, *deg = P->deg;
    int32_t *restrict fent = S->fent, *restrict enx = S->enx, *restrict voff = S->voff;
    for (int32_t f = 0; f < P->nf; f++) fent[f] = -1;
    voff[0] = 0;
    for (int32_t v = 0; v < P->nv; v++) {
        int32_t d = deg[v], o = off[v], *F = S->vfac + voff[v];
        if (d < 3) return -2;
        voff[v + 1] = voff[v] + d;
        for (int32_t e = o; e < o + d; e++) {
            int32_t f = ef[e], w = nb[e], j = bk[e];
            *F++ = f;
            fent[f] = e; /* any of its entries */
            enx[e] = off[w] + (j ? j : deg[w]) - 1;
        }
        F -= d;
        if (d == 3) {
            sort3(P->ftag, F);
        } else {
            for (int32_t a = 1; a < d; a++) {
                int32_t t = F[a], m = a;
                for (; m > 0 && P->ftag[F[m - 1]] > P->ftag[t]; m--) F[m] = F[m - 1];
                F[m] = t;
            }
        }
        S->vkey[v] = (vkey){tag_key(P->ftag[F[0]]) << 32 | tag_key(P->ftag[F[1]]),
                            tag_key(P->ftag[F[2]]), v};
    }
    int32_t n = 0;
    for (int32_t f = 0; f < P->nf; f++)
        if (fent[f] >= 0) S->fpres[n++] = f;
    return n;
}

/* Vertex a before vertex b: their tags in lexicographic order (a prefix first); equal lists
 * (two vertices on the same planes: degenerate input only) by slot. */
static int vertex_before(const scratch *S, const vkey *a, const vkey *b)
{
    if (a->hi != b->hi) return a->hi < b->hi;
    if (a->lo != b->lo) return a->lo < b->lo;
    const int32_t *A = S->vfac + S->voff[a->slot], *B = S->vfac + S->voff[b->slot];
    int32_t na = S->voff[a->slot + 1] - S->voff[a->slot], nb = S->voff[b->slot + 1] - S->voff[b->slot];
    for (int32_t k = 3; k < na && k < nb; k++)
        if (S->p.ftag[A[k]] != S->p.ftag[B[k]]) return S->p.ftag[A[k]] < S->p.ftag[B[k]];
    return na != nb ? na < nb : a->slot < b->slot;
}

/* The present faces by tag into ford: each face's rank is the count of smaller tags (one
 * face per plane, so the tags differ; counting has no unpredictable branch, unlike a sort). */
static void face_order(scratch *S, int32_t nf)
{
    const int32_t *F = S->fpres;
    int32_t *tg = S->lbuf; /* the tags side by side: the inner loop vectorises */
    for (int32_t q = 0; q < nf; q++) tg[q] = S->p.ftag[F[q]];
    for (int32_t q = 0; q < nf; q++) {
        int32_t r = 0, t = tg[q];
        for (int32_t g = 0; g < nf; g++) r += tg[g] < t;
        S->ford[r] = F[q];
    }
}

/* The loop of face f (its vertices, counter-clockwise from outside) into lbuf; its length,
 * or -1 when the walk does not come back within nl steps or leaves the face. */
static int32_t face_loop(scratch *S, int32_t f, int32_t nl)
{
    const poly *P = &S->p;
    int32_t e0 = S->fent[f], e = e0, m = 0;
    do {
        if (P->ef[e] != f || m == nl) return -1;
        S->lbuf[m++] = P->nb[e];
        e = S->enx[e];
    } while (e != e0);
    return m;
}

/* The canonical loops and tags of P into c: faces by tag, each loop from its vertex of lowest
 * key, the vertices numbered in order of first appearance along the loops so written (their
 * slots in vord, their numbers in remap). -2 when the loops do not cover the edges once. */
static int cell_loops(scratch *S, vcell *c)
{
    const poly *P = &S->p;
    int32_t n = 0;
    for (int32_t k = 0; k < P->nv; k++) S->remap[k] = -1;
    c->foff[0] = 0;
    for (int32_t q = 0; q < c->nf; q++) {
        int32_t f = S->ford[q], lo = 0, m = face_loop(S, f, c->nl - c->foff[q]);
        const int32_t *L = S->lbuf;
        if (m < 3) return -2;
        for (int32_t k = 1; k < m; k++) {
            const vkey *a = &S->vkey[L[k]], *b = &S->vkey[L[lo]];
            /* the keys differ but at degenerate vertices: decide those in full */
            int less = (a->hi < b->hi) | ((a->hi == b->hi) & (a->lo < b->lo));
            if (a->hi == b->hi && a->lo == b->lo) less = vertex_before(S, a, b);
            lo = less ? k : lo;
        }
        int32_t *out = c->fv + c->foff[q];
        for (int32_t k = 0, j = lo; k < m; k++, j = j + 1 < m ? j + 1 : 0) {
            int32_t u = L[j], fresh = S->remap[u] < 0; /* first seen: the next number */
            S->vord[n] = u;
            S->remap[u] = fresh ? n : S->remap[u];
            n += fresh;
            out[k] = S->remap[u];
        }
        c->foff[q + 1] = c->foff[q] + m;
        c->ftag[q] = P->ftag[f];
    }
    return c->foff[c->nf] == c->nl && n == c->nv ? 0 : -2;
}

/* The canonical positions of P's vertices into c, in vord's order. */
static void cell_vertices(const scratch *S, vcell *c)
{
    const poly *P = &S->p;
    double R = sqrt(P->r2);
    for (int32_t m = 0; m < c->nv; m++) {
        int32_t k = S->vord[m];
        double xc[3] = {P->x[k], P->y[k], P->z[k]};
        vertex_canon(P, S->vfac + S->voff[k], S->voff[k + 1] - S->voff[k], xc, R, c->x + 3 * m);
    }
}

/* Volume, centroid and inertia about the centroid of c from its own vertices and loops. */
static void cell_moments(vcell *c, double *pp)
{
    double s[10] = {0}, m[6];
    for (int32_t v = 0; v < c->nv; v++) {
        const double *x = c->x + 3 * v;
        double *q = pp + 6 * v;
        q[0] = x[0] * x[0], q[1] = x[0] * x[1], q[2] = x[0] * x[2];
        q[3] = x[1] * x[1], q[4] = x[1] * x[2], q[5] = x[2] * x[2];
    }
    for (int32_t f = 0; f < c->nf; f++)
        loop_moments(c->x, pp, c->fv + c->foff[f], c->foff[f + 1] - c->foff[f], s);
    moments_finish(s, &c->vol, c->cen, m);
    /* about the centroid: integral of r r^T less V g g^T; inertia = tr Id - that */
    const double *g = c->cen;
    double C[6] = {m[0] - c->vol * g[0] * g[0], m[1] - c->vol * g[0] * g[1],
                   m[2] - c->vol * g[0] * g[2], m[3] - c->vol * g[1] * g[1],
                   m[4] - c->vol * g[1] * g[2], m[5] - c->vol * g[2] * g[2]};
    double tr = C[0] + C[3] + C[5];
    c->inr[0] = tr - C[0];
    c->inr[1] = -C[1];
    c->inr[2] = -C[2];
    c->inr[3] = tr - C[3];
    c->inr[4] = -C[4];
    c->inr[5] = tr - C[5];
}

/* The finished polyhedron, made canonical, and its cutters packed into one block: GP_OK and
 * *out, or an error status (GP_ERR_INTERNAL also when a side of a starting box is left). */
static gp_status cell_pack(scratch *S, vcell **out)
{
    const poly *P = &S->p;
    if (canon_reserve(S)) return GP_ERR_NOMEM;
    int32_t nf = vertex_faces(S), nnb = 0, nv = P->nv, nl = nv ? S->voff[nv] : 0;
    if (nf < 4) return GP_ERR_INTERNAL;
    for (int32_t q = 0; q < nf; q++) {
        int32_t t = P->ftag[S->fpres[q]];
        if (t <= TAG_BBOX + 5) return GP_ERR_INTERNAL;
        nnb += t >= 0;
    }
    sort_unique(S->cut, &S->ncut);
    size_t ni = (size_t)(nf + 1) + (size_t)nl + (size_t)nf + (size_t)nnb + (size_t)S->ncut;
    vcell *c = malloc(sizeof(vcell) + 3 * (size_t)nv * sizeof(double) + ni * sizeof(int32_t));
    if (!c) return GP_ERR_NOMEM;
    c->nv = nv;
    c->nf = nf;
    c->nl = nl;
    c->ncut = S->ncut;
    c->x = (double *)(c + 1);
    c->foff = (int32_t *)(c->x + 3 * nv);
    c->fv = c->foff + nf + 1;
    c->ftag = c->fv + nl;
    c->nb = c->ftag + nf;
    face_order(S, nf);
    if (cell_loops(S, c)) {
        free(c);
        return GP_ERR_INTERNAL;
    }
    cell_vertices(S, c);
    c->nnb = 0;
    for (int32_t f = 0; f < nf; f++)
        if (c->ftag[f] >= 0) c->nb[c->nnb++] = c->ftag[f]; /* ascending: the faces are by tag */
    c->cut = c->nb + c->nnb;
    if (S->ncut > 0) memcpy(c->cut, S->cut, (size_t)S->ncut * sizeof(int32_t)); /* NULL when 0 */
    cell_moments(c, S->pp);
    *out = c;
    return GP_OK;
}

/* Cell i (its seed at si, local frame) computed from the current seeds: GP_OK and *out, or
 * an error status. */
static gp_status cell_compute(gp_voronoi3d *v, uint32_t i, const double si[3], vcell **out)
{
    scratch *S = &v->s;
    memcpy(S->si, si, sizeof S->si);
    S->ncut = 0;
    if (cell_start(v, i)) return GP_ERR_NOMEM;
    int rc = cell_search(v, i);
    if (rc == -1) return GP_ERR_NOMEM;
    if (rc == -3) return GP_ERR_INVALID;
    if (rc) return GP_ERR_INTERNAL;
    return cell_pack(S, out);
}

/* ------------------------------------------------------------------------------------------ */
/* the container                                                                               */

gp_voronoi3d_container gp_voronoi3d_box(const double lo[3], const double hi[3])
{
    gp_voronoi3d_container c = {.kind = GP_VORONOI3D_BOX};
    memcpy(c.lo, lo, sizeof c.lo);
    memcpy(c.hi, hi, sizeof c.hi);
    return c;
}

gp_voronoi3d_container gp_voronoi3d_convex(const double *planes, size_t nplanes)
{
    return (gp_voronoi3d_container){.kind = GP_VORONOI3D_CONVEX, .planes = planes,
                                    .nplanes = nplanes};
}

gp_voronoi3d_container gp_voronoi3d_cylinder(double x, double y, double radius, double z0,
                                             double z1, size_t facets)
{
    return (gp_voronoi3d_container){.kind = GP_VORONOI3D_CYLINDER, .axis = {x, y},
                                    .radius = radius, .z0 = z0, .z1 = z1, .facets = facets};
}

double gp_voronoi3d_cylinder_lost_volume(double r, double h, size_t facets)
{
    double m = (double)(facets ? facets : 64);
    return (V3_PI - 0.5 * m * sin(2 * V3_PI / m)) * r * r * h;
}

/* The number of half-spaces of a convex or cylinder container (side facets, bottom, top), or
 * an error for a bad one. */
static gp_status container_count(const gp_voronoi3d_container *c, size_t *m, gp_error *err)
{
    *m = c->kind == GP_VORONOI3D_CONVEX ? c->nplanes : (c->facets ? c->facets : 64) + 2;
    if (c->kind == GP_VORONOI3D_CONVEX && (*m < 4 || !c->planes))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: a convex container needs >= 4 planes");
    if (c->kind == GP_VORONOI3D_CYLINDER &&
        (!(c->radius > 0) || !(c->z1 > c->z0) || *m < 5 || !isfinite(c->radius + c->z0 + c->z1 +
                                                                       c->axis[0] + c->axis[1])))
        return gp_error_set(err, GP_ERR_INVALID,
                            "voronoi3d: a cylinder needs radius > 0, z1 > z0, facets >= 3");
    if (*m > 100000) return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: too many planes");
    return GP_OK;
}

/* Half-space k of the m of a convex or cylinder container, unit normal, caller frame, into
 * p; -1 when it is not a half-space. */
static int container_plane(const gp_voronoi3d_container *c, size_t m, size_t k, double p[4])
{
    if (c->kind == GP_VORONOI3D_CONVEX) {
        memcpy(p, c->planes + 4 * k, 4 * sizeof(double));
    } else if (k + 2 < m) {
        double t = 2 * V3_PI * ((double)k + 0.5) / (double)(m - 2);
        p[0] = cos(t);
        p[1] = sin(t);
        p[2] = 0;
        p[3] = p[0] * c->axis[0] + p[1] * c->axis[1] + c->radius * cos(V3_PI / (double)(m - 2));
    } else {
        int top = k + 1 == m;
        p[0] = p[1] = 0;
        p[2] = top ? 1 : -1;
        p[3] = top ? c->z1 : -c->z0;
    }
    double nn = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (!(nn > 0) || !isfinite(nn) || !isfinite(p[3])) return -1;
    for (int q = 0; q < 4; q++) p[q] /= nn;
    return 0;
}

/* The half-spaces of a convex or cylinder container, unit normals, into v->pl (caller frame). */
static gp_status container_planes(gp_voronoi3d *v, const gp_voronoi3d_container *c, gp_error *err)
{
    size_t m;
    gp_status st = container_count(c, &m, err);
    if (st) return st;
    v->pl = malloc(4 * m * sizeof(double));
    if (!v->pl) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    v->nplanes = (int32_t)m;
    for (size_t k = 0; k < m; k++)
        if (container_plane(c, m, k, v->pl + 4 * k))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: plane %zu is not a half-space", k);
    return GP_OK;
}

/* The container's polyhedron cut from the cube of half-size B around ctr (caller frame);
 * 1 when a side of the cube is left (the cube was too small, or the set is unbounded). */
static int container_cut(gp_voronoi3d *v, const double ctr[3], double B)
{
    scratch *S = &v->s;
    double lo[3] = {-B, -B, -B}, hi[3] = {B, B, B};
    int32_t tag[6];
    for (int f = 0; f < 6; f++) tag[f] = TAG_BBOX + f;
    if (poly_box(S, lo, hi, tag)) return -1;
    for (int32_t k = 0; k < v->nplanes; k++) {
        const double *p = v->pl + 4 * k;
        double h = p[3] - (p[0] * ctr[0] + p[1] * ctr[1] + p[2] * ctr[2]);
        int rc = poly_cut(S, p, h, V3_EPS * sqrt(S->p.r2), -1 - k);
        if (rc < 0) return rc;
    }
    const poly *P = &S->p;
    for (int32_t k = 0; k < P->nv; k++)
        for (int32_t q = 0; q < P->deg[k]; q++)
            if (P->ftag[P->ef[P->off[k] + q]] <= TAG_BBOX + 5) return 1;
    return 0;
}

/* The bounding box of a convex or cylinder container: cut from a cube that contains it
 * (grown until no side is left), then from a cube just around the result, twice, so that
 * the rounding of a huge first cube does not stay. */
static gp_status container_bbox(gp_voronoi3d *v, double lo[3], double hi[3], gp_error *err)
{
    double ctr[3] = {0, 0, 0}, B = 1;
    for (int32_t k = 0; k < v->nplanes; k++)
        if (fabs(v->pl[4 * k + 3]) > B) B = fabs(v->pl[4 * k + 3]);
    B *= 4;
    int rc = 1;
    for (int t = 0; t < 40 && rc == 1; t++, B *= 1e3) {
        if (B > 1e300) break;
        rc = container_cut(v, ctr, B);
    }
    for (int pass = 0; pass < 2 && rc == 0; pass++) {
        const poly *P = &v->s.p;
        for (int a = 0; a < 3; a++) lo[a] = INFINITY, hi[a] = -INFINITY;
        for (int32_t k = 0; k < P->nv; k++)
            for (int a = 0; a < 3; a++) {
                double x = (a == 0 ? P->x : (a == 1 ? P->y : P->z))[k] + ctr[a];
                lo[a] = x < lo[a] ? x : lo[a];
                hi[a] = x > hi[a] ? x : hi[a];
            }
        B = 0;
        for (int a = 0; a < 3; a++) {
            ctr[a] = 0.5 * (lo[a] + hi[a]);
            B = fmax(B, 0.6 * (hi[a] - lo[a]));
        }
        if (!(B > 0)) rc = -2;
        else if (pass == 0) rc = container_cut(v, ctr, B);
    }
    if (rc == -1) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    if (rc) return gp_error_set(err, GP_ERR_INVALID,
                                "voronoi3d: the container's half-spaces do not bound a solid");
    return GP_OK;
}

/* The container's bounding box (caller frame; for a convex or cylinder one, its planes into
 * v->pl, caller frame too). */
static gp_status container_bounds(gp_voronoi3d *v, const gp_voronoi3d_container *c, double lo[3],
                                  double hi[3], gp_error *err)
{
    v->kind = c->kind;
    if (c->kind == GP_VORONOI3D_BOX) {
        for (int a = 0; a < 3; a++)
            if (!(c->hi[a] > c->lo[a]) || !isfinite(c->hi[a] - c->lo[a]))
                return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: box needs lo < hi (axis %d)", a);
        memcpy(lo, c->lo, 3 * sizeof(double));
        memcpy(hi, c->hi, 3 * sizeof(double));
    } else if (c->kind == GP_VORONOI3D_CONVEX || c->kind == GP_VORONOI3D_CYLINDER) {
        gp_status st = container_planes(v, c, err);
        if (!st) st = container_bbox(v, lo, hi, err);
        if (st) return st;
    } else {
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: unknown container kind");
    }
    return GP_OK;
}

/* v's frame, planes, volume and starting box from the caller's container. */
static gp_status container_setup(gp_voronoi3d *v, const gp_voronoi3d_container *c, gp_error *err)
{
    double lo[3], hi[3];
    gp_status st = container_bounds(v, c, lo, hi, err);
    if (st) return st;
    double s2 = 0;
    for (int a = 0; a < 3; a++) {
        v->origin[a] = lo[a];
        v->L[a] = hi[a] - lo[a];
        s2 += v->L[a] * v->L[a];
        v->blo[a] = -0.1 * v->L[a];
        v->bhi[a] = 1.1 * v->L[a];
    }
    v->size = sqrt(s2);
    if (c->kind == GP_VORONOI3D_BOX) {
        v->cvol = v->L[0] * v->L[1] * v->L[2];
        return GP_OK;
    }
    for (int32_t k = 0; k < v->nplanes; k++) {
        double *p = v->pl + 4 * k;
        p[3] -= p[0] * lo[0] + p[1] * lo[1] + p[2] * lo[2];
    }
    double ctr[3] = {0.5 * v->L[0], 0.5 * v->L[1], 0.5 * v->L[2]};
    int rc = container_cut(v, ctr, 0.6 * fmax(v->L[0], fmax(v->L[1], v->L[2])));
    vcell *cc = NULL;
    v->s.ncut = 0;
    st = rc == -1 ? GP_ERR_NOMEM : (rc ? GP_ERR_INTERNAL : cell_pack(&v->s, &cc));
    if (st) return gp_error_set(err, st, "voronoi3d: the container could not be rebuilt");
    v->cvol = cc->vol; /* canonical, as a cell's */
    free(cc);
    if (c->kind == GP_VORONOI3D_CYLINDER)
        v->lost = V3_PI * c->radius * c->radius * (c->z1 - c->z0) - v->cvol;
    return GP_OK;
}

static int contains_local(const gp_voronoi3d *v, const double p[3])
{
    double tol = V3_INSIDE * v->size;
    if (v->kind == GP_VORONOI3D_BOX) {
        for (int a = 0; a < 3; a++)
            if (!(p[a] >= -tol && p[a] <= v->L[a] + tol)) return 0;
        return 1;
    }
    for (int32_t k = 0; k < v->nplanes; k++) {
        const double *q = v->pl + 4 * k;
        if (!(q[0] * p[0] + q[1] * p[1] + q[2] * p[2] <= q[3] + tol)) return 0;
    }
    return 1;
}

gp_status gp_voronoi3d_container_bounds(const gp_voronoi3d_container *c, double lo[3], double hi[3],
                                        gp_error *err)
{
    if (!c || !lo || !hi) return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: need a container");
    gp_voronoi3d *v = calloc(1, sizeof *v);
    if (!v) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double l[3], h[3];
    gp_status st = container_bounds(v, c, l, h, err);
    gp_voronoi3d_destroy(v);
    if (st) return st;
    memcpy(lo, l, sizeof l);
    memcpy(hi, h, sizeof h);
    return GP_OK;
}

/* The test of contains_local() on the frame gp_voronoi3d_create() would set up: origin lo, size
 * |hi - lo|, the planes made by the same function and moved to that frame the same way. */
int gp_voronoi3d_container_inside(const gp_voronoi3d_container *c, const double lo[3],
                                  const double hi[3], const double p[3])
{
    if (!c || !lo || !hi || !p || !isfinite(p[0] + p[1] + p[2])) return 0;
    double L[3], q[3], s2 = 0;
    for (int a = 0; a < 3; a++) {
        L[a] = hi[a] - lo[a];
        s2 += L[a] * L[a];
        q[a] = p[a] - lo[a];
    }
    double tol = V3_INSIDE * sqrt(s2);
    if (c->kind == GP_VORONOI3D_BOX) {
        for (int a = 0; a < 3; a++)
            if (!(q[a] >= -tol && q[a] <= L[a] + tol)) return 0;
        return 1;
    }
    size_t m, sides;
    if ((c->kind != GP_VORONOI3D_CONVEX && c->kind != GP_VORONOI3D_CYLINDER) ||
        container_count(c, &m, NULL))
        return 0;
    if (c->kind == GP_VORONOI3D_CYLINDER) {
        /* the bottom and the top first; then a point well inside the facets' inscribed circle
         * passes them all, one well outside their circumscribed circle fails the facet nearest
         * its direction: the margins (1e-12 of the magnitudes in play, and 4 tol outside) are
         * far above the rounding of their tests (a few 1e-16 of those), so they need not be
         * computed (the cos and the sin of each) */
        for (size_t k = m - 2; k < m; k++) {
            double pl[4];
            container_plane(c, m, k, pl);
            pl[3] -= pl[0] * lo[0] + pl[1] * lo[1] + pl[2] * lo[2];
            if (!(pl[0] * q[0] + pl[1] * q[1] + pl[2] * q[2] <= pl[3] + tol)) return 0;
        }
        double dx = p[0] - c->axis[0], dy = p[1] - c->axis[1];
        double M = fabs(lo[0]) + fabs(lo[1]) + fabs(p[0]) + fabs(p[1]) + fabs(c->axis[0]) +
                   fabs(c->axis[1]) + c->radius;
        double a = c->radius * cos(V3_PI / (double)(m - 2)) - 1e-12 * M, r2 = dx * dx + dy * dy;
        double b = c->radius + 4 * tol + 1e-12 * M;
        if (a > 0 && r2 <= a * a) return 1;
        if (r2 > b * b) return 0;
    }
    sides = c->kind == GP_VORONOI3D_CYLINDER ? m - 2 : m;
    for (size_t k = 0; k < sides; k++) {
        double pl[4];
        if (container_plane(c, m, k, pl)) return 0;
        pl[3] -= pl[0] * lo[0] + pl[1] * lo[1] + pl[2] * lo[2];
        if (!(pl[0] * q[0] + pl[1] * q[1] + pl[2] * q[2] <= pl[3] + tol)) return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------------------------------ */
/* the build                                                                                   */

static gp_status build_grid(gp_voronoi3d *v)
{
    double lo[3] = {0, 0, 0}, box = v->L[0] * v->L[1] * v->L[2];
    double h = cbrt(box * V3_SEEDS_PER_BIN / (double)v->n);
    size_t nb = gp_grid_size(lo, v->L, h, 1024, (size_t)v->n + 64, v->gn, v->ginv);
    v->ghmin = INFINITY;
    for (int a = 0; a < 3; a++) {
        v->gh[a] = v->L[a] / (double)v->gn[a];
        if (v->gh[a] < v->ghmin) v->ghmin = v->gh[a];
    }
    v->bins = calloc(nb, sizeof(vbin));
    if (!v->bins || build_reach(v)) return GP_ERR_NOMEM;
    int32_t b[3];
    for (uint32_t i = 0; i < v->n; i++) v->bins[bin_of(v, v->seed + 3 * i, b)].cap++;
    size_t total = 0;
    for (size_t k = 0; k < nb; k++) total += (size_t)(v->bins[k].cap += 2); /* room for moves */
    v->binblock = malloc(total * sizeof(bent));
    if (!v->binblock) return GP_ERR_NOMEM;
    total = 0;
    for (size_t k = 0; k < nb; k++) {
        v->bins[k].e = v->binblock + total;
        total += (size_t)v->bins[k].cap;
    }
    for (uint32_t i = 0; i < v->n; i++) {
        const double *p = v->seed + 3 * i;
        if (bin_insert(&v->bins[bin_of(v, p, b)], (int32_t)i, p)) return GP_ERR_NOMEM;
    }
    return GP_OK;
}

/* Another seed than `self` within the duplicate distance of p (local frame): its index, or -1.
 * The bins are far wider than that distance, so the 27 around p hold every candidate. */
static int64_t find_duplicate(const gp_voronoi3d *v, const double p[3], uint32_t self)
{
    double lim = V3_DUP * v->size, lim2 = lim * lim;
    int32_t c[3], bb[3];
    bin_of(v, p, c);
    for (int32_t dz = -1; dz <= 1; dz++)
        for (int32_t dy = -1; dy <= 1; dy++)
            for (int32_t dx = -1; dx <= 1; dx++) {
                bb[0] = c[0] + dx, bb[1] = c[1] + dy, bb[2] = c[2] + dz;
                int ok = 1;
                for (int a = 0; a < 3; a++) ok &= bb[a] >= 0 && bb[a] < (int32_t)v->gn[a];
                if (!ok) continue;
                const vbin *b = &v->bins[((size_t)bb[2] * v->gn[1] + (size_t)bb[1]) * v->gn[0] + (size_t)bb[0]];
                for (int32_t k = 0; k < b->cnt; k++) {
                    const double *q = b->e[k].p;
                    double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
                    if ((uint32_t)b->e[k].j != self && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < lim2)
                        return b->e[k].j;
                }
            }
    return -1;
}

static int cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

static gp_status load_seeds(gp_voronoi3d *v, const double *seeds, gp_error *err)
{
    for (uint32_t i = 0; i < v->n; i++) {
        const double *p = seeds + 3 * (size_t)i;
        double *q = v->seed + 3 * (size_t)i;
        for (int a = 0; a < 3; a++) q[a] = p[a] - v->origin[a];
        memcpy(v->useed + 3 * (size_t)i, p, 3 * sizeof(double));
        if (!isfinite(p[0] + p[1] + p[2]) || !contains_local(v, q))
            return gp_error_set(err, GP_ERR_INVALID,
                                "voronoi3d: seed %u (%g, %g, %g) is outside the container", i,
                                p[0], p[1], p[2]);
    }
    return GP_OK;
}

/* The cells, bin by bin: neighbouring cells read the same bins, which then stay in cache (in
 * the seeds' order, every cell would start from cold bins). The order changes nothing else. */
static gp_status build_cells(gp_voronoi3d *v, const volatile int *cancel, gp_error *err)
{
    size_t nb = v->gn[0] * v->gn[1] * v->gn[2], done = 0;
    for (size_t b = 0; b < nb; b++)
        for (int32_t k = 0; k < v->bins[b].cnt; k++) {
            uint32_t i = (uint32_t)v->bins[b].e[k].j;
            if (++done % CANCEL_EVERY == 0 && cancel_raised(cancel))
                return gp_error_set(err, GP_ERR_CANCELLED, "voronoi3d: cancelled");
            gp_status st = cell_compute(v, i, v->bins[b].e[k].p, &v->cell[i]); /* in cache */
            uint32_t j = (uint32_t)v->s.dup;
            if (st == GP_ERR_INVALID)
                return gp_error_set(err, st, "voronoi3d: seeds %u and %u coincide", i < j ? i : j,
                                    i < j ? j : i);
            if (st)
                return gp_error_set(err, st, "voronoi3d: cell %u: %s", i,
                                    st == GP_ERR_NOMEM ? "out of memory" : "inconsistent cutting");
        }
    return GP_OK;
}

gp_voronoi3d *gp_voronoi3d_create(const gp_voronoi3d_container *c, const double *seeds, size_t n,
                                  gp_error *err)
{
    return gp_voronoi3d_create_ex(c, seeds, n, NULL, err);
}

gp_voronoi3d *gp_voronoi3d_create_ex(const gp_voronoi3d_container *c, const double *seeds,
                                     size_t n, const volatile int *cancel, gp_error *err)
{
    if (!c || !seeds || n < 1 || n > INT32_MAX) {
        gp_error_set(err, GP_ERR_INVALID, "voronoi3d: need a container and 1 <= n < 2^31 seeds");
        return NULL;
    }
    gp_voronoi3d *v = calloc(1, sizeof *v);
    if (!v) {
        gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        return NULL;
    }
    v->n = (uint32_t)n;
    gp_status st = container_setup(v, c, err);
    if (!st) {
        v->seed = malloc(3 * n * sizeof(double));
        v->useed = malloc(3 * n * sizeof(double));
        v->cell = calloc(n, sizeof(vcell *));
        v->stamp = calloc(n, sizeof(uint32_t));
        if (!v->seed || !v->useed || !v->cell || !v->stamp)
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    if (!st) st = load_seeds(v, seeds, err);
    if (!st && build_grid(v)) st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    if (!st) st = build_cells(v, cancel, err);
    if (st) {
        gp_voronoi3d_destroy(v);
        return NULL;
    }
    return v;
}

static void scratch_free(scratch *S)
{
    poly_free(&S->p);
    void *a[] = {S->d,    S->cls,  S->outl, S->ws, S->xt,    S->cnext, S->cprev, S->wl,
                 S->xn,   S->rs,   S->re, S->enx,   S->tnb,  S->tef,   S->fmask, S->cd,    S->ord, S->bkt,
                 S->cnt,  S->cut,  S->voff, S->vfac, S->vord,  S->remap, S->fent,  S->fpres,
                 S->ford, S->lbuf, S->vkey, S->pp, S->bl};
    for (size_t k = 0; k < sizeof a / sizeof a[0]; k++) free(a[k]);
}

void gp_voronoi3d_destroy(gp_voronoi3d *v)
{
    if (!v) return;
    if (v->pending) gp_voronoi3d_rollback(v);
    if (v->cell)
        for (uint32_t i = 0; i < v->n; i++) free(v->cell[i]);
    if (v->bins) {
        size_t nb = v->gn[0] * v->gn[1] * v->gn[2];
        for (size_t b = 0; b < nb; b++)
            if (v->bins[b].own) free(v->bins[b].e);
    }
    free(v->bins);
    free(v->binblock);
    free(v->cell);
    free(v->seed);
    free(v->useed);
    free(v->stamp);
    free(v->chg);
    free(v->chg_old);
    free(v->pl);
    free(v->off);
    free(v->batch);
    free(v->blb);
    free(v->offl);
    scratch_free(&v->s);
    free(v);
}

/* ------------------------------------------------------------------------------------------ */
/* moves                                                                                       */

/* Seed i (local p, caller's pu) into its bin; -1 out of memory (then nothing changed). */
static int seed_place(gp_voronoi3d *v, uint32_t i, const double p[3], const double pu[3])
{
    int32_t b[3];
    int32_t bo = bin_of(v, v->seed + 3 * i, b), bn = bin_of(v, p, b);
    if (bo != bn) {
        if (bin_insert(&v->bins[bn], (int32_t)i, p)) return -1;
        bin_remove(&v->bins[bo], (int32_t)i);
    } else {
        bin_set(&v->bins[bn], (int32_t)i, p);
    }
    memcpy(v->seed + 3 * i, p, 3 * sizeof(double));
    memcpy(v->useed + 3 * i, pu, 3 * sizeof(double));
    return 0;
}

/* The cells of the pending move go back (the new ones freed), and the seed. */
static void undo(gp_voronoi3d *v)
{
    for (uint32_t k = 0; k < v->nchg; k++) {
        uint32_t j = v->chg[k];
        if (v->chg_old[k]) {
            free(v->cell[j]);
            v->cell[j] = v->chg_old[k];
        }
    }
    v->nchg = 0;
    /* moving back into the old bin only needs room the bin had before */
    seed_place(v, v->mv_i, v->mv_seed, v->mv_useed);
}

static int chg_push(gp_voronoi3d *v, uint32_t j)
{
    if (v->stamp[j] == v->stampv) return 0;
    v->stamp[j] = v->stampv;
    if (v->nchg == v->chgcap) {
        uint32_t c = v->chgcap ? 2 * v->chgcap : 64;
        uint32_t *a = realloc(v->chg, c * sizeof *a);
        if (a) v->chg = a;
        vcell **b = realloc(v->chg_old, c * sizeof *b);
        if (b) v->chg_old = b;
        if (!a || !b) return -1;
        v->chgcap = c;
    }
    v->chg_old[v->nchg] = NULL;
    v->chg[v->nchg++] = j;
    return 0;
}

/* Recomputes cell chg[k] (its old block kept in chg_old[k]). */
static gp_status recompute(gp_voronoi3d *v, uint32_t k)
{
    uint32_t j = v->chg[k];
    vcell *c;
    gp_status st = cell_compute(v, j, v->seed + 3 * (size_t)j, &c);
    if (st) return st;
    v->chg_old[k] = v->cell[j];
    v->cell[j] = c;
    return GP_OK;
}

/* The changed cells after the moved one: the cutters of its old and new cells. */
static gp_status recompute_around(gp_voronoi3d *v, const vcell *old)
{
    const vcell *now = v->cell[v->mv_i];
    for (int pass = 0; pass < 2; pass++) {
        const vcell *c = pass ? now : old;
        for (int32_t q = 0; q < c->ncut; q++)
            if (chg_push(v, (uint32_t)c->cut[q])) return GP_ERR_NOMEM;
    }
    for (uint32_t k = 1; k < v->nchg; k++) {
        gp_status st = recompute(v, k);
        if (st) return st;
    }
    return GP_OK;
}

static void stamp_next(gp_voronoi3d *v)
{
    if (++v->stampv == 0) {
        memset(v->stamp, 0, v->n * sizeof(uint32_t));
        v->stampv = 1;
    }
}

gp_status gp_voronoi3d_try_move(gp_voronoi3d *v, size_t i, const double pu[3], gp_error *err)
{
    if (!v || i >= v->n || !pu) return gp_error_set(err, GP_ERR_INVALID, "voronoi3d move: bad index");
    if (v->pending)
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d move: a move is pending (commit or roll back)");
    double p[3] = {pu[0] - v->origin[0], pu[1] - v->origin[1], pu[2] - v->origin[2]};
    if (!isfinite(p[0] + p[1] + p[2]) || !contains_local(v, p))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d move: (%g, %g, %g) is outside the container",
                            pu[0], pu[1], pu[2]);
    int64_t other = find_duplicate(v, p, (uint32_t)i);
    if (other >= 0)
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d move: seed %zu would coincide with seed %lld",
                            i, (long long)other);
    v->mv_i = (uint32_t)i;
    memcpy(v->mv_seed, v->seed + 3 * i, sizeof v->mv_seed);
    memcpy(v->mv_useed, v->useed + 3 * i, sizeof v->mv_useed);
    if (seed_place(v, (uint32_t)i, p, pu)) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    v->nchg = 0;
    stamp_next(v);
    gp_status st = chg_push(v, (uint32_t)i) ? GP_ERR_NOMEM : recompute(v, 0);
    if (!st) st = recompute_around(v, v->chg_old[0]);
    if (st) {
        undo(v);
        return gp_error_set(err, st, "voronoi3d move of seed %zu: %s", i,
                            st == GP_ERR_NOMEM ? "out of memory" : "inconsistent cutting");
    }
    v->pending = 1;
    return GP_OK;
}

void gp_voronoi3d_commit(gp_voronoi3d *v)
{
    if (!v || !v->pending) return;
    for (uint32_t k = 0; k < v->nchg; k++) free(v->chg_old[k]);
    v->nchg = 0;
    v->pending = 0;
}

void gp_voronoi3d_rollback(gp_voronoi3d *v)
{
    if (!v || !v->pending) return;
    undo(v);
    v->pending = 0;
}

size_t gp_voronoi3d_changed(const gp_voronoi3d *v, const uint32_t **cells)
{
    if (!v || !v->pending) {
        if (cells) *cells = NULL;
        return 0;
    }
    if (cells) *cells = v->chg;
    return v->nchg;
}

gp_status gp_voronoi3d_move(gp_voronoi3d *v, size_t i, const double p[3], gp_error *err)
{
    gp_status st = gp_voronoi3d_try_move(v, i, p, err);
    if (st == GP_OK) gp_voronoi3d_commit(v);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* queries                                                                                     */

size_t gp_voronoi3d_count(const gp_voronoi3d *v)
{
    return v ? v->n : 0;
}

double gp_voronoi3d_container_volume(const gp_voronoi3d *v)
{
    return v ? v->cvol : 0;
}

double gp_voronoi3d_lost_volume(const gp_voronoi3d *v)
{
    return v ? v->lost : 0;
}

void gp_voronoi3d_seed(const gp_voronoi3d *v, size_t i, double p[3])
{
    for (int a = 0; a < 3; a++) p[a] = v && i < v->n ? v->useed[3 * i + a] : 0;
}

double gp_voronoi3d_cell_volume(const gp_voronoi3d *v, size_t i)
{
    return v && i < v->n ? v->cell[i]->vol : 0;
}

void gp_voronoi3d_cell_centroid(const gp_voronoi3d *v, size_t i, double c[3])
{
    for (int a = 0; a < 3; a++)
        c[a] = v && i < v->n ? v->cell[i]->cen[a] + v->seed[3 * i + a] + v->origin[a] : 0;
}

void gp_voronoi3d_cell_inertia(const gp_voronoi3d *v, size_t i, double I[9])
{
    static const int idx[9] = {0, 1, 2, 1, 3, 4, 2, 4, 5};
    for (int q = 0; q < 9; q++) I[q] = v && i < v->n ? v->cell[i]->inr[idx[q]] : 0;
}

size_t gp_voronoi3d_cell_vertices(const gp_voronoi3d *v, size_t i, double *xyz, size_t cap)
{
    if (!v || i >= v->n) return 0;
    const vcell *c = v->cell[i];
    for (int32_t k = 0; k < c->nv && (size_t)k < cap; k++)
        for (int a = 0; a < 3; a++)
            xyz[3 * k + a] = c->x[3 * k + a] + v->seed[3 * i + a] + v->origin[a];
    return (size_t)c->nv;
}

size_t gp_voronoi3d_cell_face_count(const gp_voronoi3d *v, size_t i)
{
    return v && i < v->n ? (size_t)v->cell[i]->nf : 0;
}

size_t gp_voronoi3d_cell_face(const gp_voronoi3d *v, size_t i, size_t f, uint32_t *loop,
                              size_t cap, int32_t *neighbour)
{
    if (!v || i >= v->n || f >= (size_t)v->cell[i]->nf) return 0;
    const vcell *c = v->cell[i];
    int32_t b = c->foff[f], e = c->foff[f + 1];
    for (int32_t k = b; k < e && (size_t)(k - b) < cap; k++) loop[k - b] = (uint32_t)c->fv[k];
    if (neighbour) *neighbour = c->ftag[f];
    return (size_t)(e - b);
}

size_t gp_voronoi3d_cell_planes(const gp_voronoi3d *v, size_t i, double *planes, size_t cap)
{
    if (!v || i >= v->n) return 0;
    const vcell *c = v->cell[i];
    for (int32_t f = 0; f < c->nf && (size_t)f < cap; f++) {
        int32_t b = c->foff[f], e = c->foff[f + 1];
        double n[3] = {0, 0, 0}, m[3] = {0, 0, 0};
        for (int32_t k = b; k < e; k++) {
            const double *P = c->x + 3 * c->fv[k], *Q = c->x + 3 * c->fv[k + 1 < e ? k + 1 : b];
            n[0] += (P[1] - Q[1]) * (P[2] + Q[2]);
            n[1] += (P[2] - Q[2]) * (P[0] + Q[0]);
            n[2] += (P[0] - Q[0]) * (P[1] + Q[1]);
            for (int a = 0; a < 3; a++) m[a] += P[a] / (e - b);
        }
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), *q = planes + 4 * f;
        q[3] = 0;
        for (int a = 0; a < 3; a++) {
            q[a] = n[a] / len;
            q[3] += q[a] * (m[a] + v->seed[3 * i + a] + v->origin[a]);
        }
    }
    return (size_t)c->nf;
}

gp_status gp_voronoi3d_container_measure(const gp_voronoi3d_container *c, double *volume, double lo[3],
                                         double hi[3], gp_error *err)
{
    if (!c || !volume) return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: need a container");
    gp_voronoi3d *v = calloc(1, sizeof *v);
    if (!v) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    gp_status st = container_setup(v, c, err);
    if (!st) {
        *volume = v->cvol;
        for (int a = 0; a < 3; a++) {
            if (lo) lo[a] = v->origin[a];
            if (hi) hi[a] = v->origin[a] + v->L[a];
        }
    }
    gp_voronoi3d_destroy(v);
    return st;
}

size_t gp_voronoi3d_neighbours(const gp_voronoi3d *v, size_t i, size_t *out, size_t cap)
{
    if (!v || i >= v->n) return 0;
    const vcell *c = v->cell[i];
    for (int32_t k = 0; k < c->nnb && (size_t)k < cap; k++) out[k] = (size_t)c->nb[k];
    return (size_t)c->nnb;
}

int gp_voronoi3d_contains(const gp_voronoi3d *v, const double p[3])
{
    if (!v || !p) return 0;
    double q[3] = {p[0] - v->origin[0], p[1] - v->origin[1], p[2] - v->origin[2]};
    return contains_local(v, q);
}
