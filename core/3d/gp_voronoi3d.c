/* gp_voronoi3d.c -- bounded 3D Voronoi tessellation with local updates. See gp_voronoi3d.h.
 *
 * Layout: convex polyhedra and their cutting ("poly"), the object and its grid of seeds, one
 * cell (the search), canonical cells (the finished polyhedron rewritten from its planes, so
 * that its bits do not depend on the cuts' order), the container, the build, the moves, the
 * queries.
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

/* A convex polyhedron cut in place: vertex slots (alive, or free with ref -1 and coordinates
 * 0), faces as loops in a pool (each face its own stretch, with room to grow). A cut touches
 * only the faces it crosses; the others stay as they are. */
typedef struct poly {
    int32_t nv, nf, nl, pool; /* vertex slots, faces, loop entries in use, pool entries used */
    int32_t vcap, fcap, lcap, nfree;
    double *x;                /* 3 per slot */
    double *x2;               /* per slot: |x|^2 (0 when free), for r2 without recomputing it */
    int32_t *ref;             /* per slot: the loop entries naming it, -1 when free */
    int32_t *freel;           /* free slots */
    int32_t *foff, *flen, *fcp, *ftag; /* per face: offset, length, room, tag */
    double *fpl;              /* per face: its plane n . x <= c as cut (n, c), 4 each */
    int32_t *fv;              /* the loops, counter-clockwise seen from outside */
    double r2;                /* largest squared distance of a vertex from the frame's origin */
} poly;

typedef struct xedge {
    int32_t a, b, v; /* edge a < b got the new vertex v */
} xedge;

/* Per inside vertex of a cut (valid when stamp is the cut's number): the new vertices on its
 * first three edges to outside vertices o, so that the second face to meet an edge finds its
 * vertex without a search; more edges go to the xedge list. */
typedef struct xslot {
    uint32_t stamp;
    int32_t n, o[3], v[3];
} xslot;

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

/* vertex classes of a cut, as bits so that a face's classes are one OR */
enum { C_OUT = 1, C_IN = 2, C_ON = 4 };

/* Scratch of the cutting and of one cell's search (one per object: builds and moves are
 * single-threaded). */
typedef struct scratch {
    poly p;
    double *d;
    unsigned char *cls;
    int32_t *remap;
    int32_t dcap;
    int32_t *buf;      /* one clipped loop; the pool while it is compacted */
    int32_t bufcap;
    xedge *xe;
    int32_t nxe, xecap;
    xslot *xs;         /* per slot, with the capacity dcap */
    uint32_t cutno;    /* the current cut's number for xs (never 0: fresh slots are 0) */
    int32_t *cf, *ct;  /* the new face's directed edges */
    unsigned char *cdead;
    int32_t nce, cecap;
    cand *cd, *cd2;    /* candidates; the bucket sort's second array */
    int32_t *cnt;      /* the bucket sort's counts */
    int32_t ncd, cdcap, cd2cap, cntcap;
    int32_t dup;       /* a seed found to coincide with the cell's */
    int32_t *cut;      /* seeds whose planes cut the cell */
    int32_t ncut, cutcap;
    /* canonical cells: per slot the offset of its faces in vfac (one per loop entry) and its
     * key; per vertex its slot; per face the order */
    int32_t *voff, *vfac, *vord, *ford;
    vkey *vkey;
    int32_t canv, canl, canf;
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

/* Room for nv vertex slots (with the scratch per slot), nf faces and a pool of nl entries. */
static int poly_reserve(scratch *S, int32_t nv, int32_t nf, int32_t nl)
{
    poly *P = &S->p;
    int32_t c[8];
    for (int k = 0; k < 8; k++) c[k] = k < 3 || k == 7 ? P->vcap : (k < 6 ? S->dcap : P->fcap);
    if (grow((void **)&P->x, &c[0], nv, 3 * sizeof(double)) ||
        grow((void **)&P->ref, &c[1], nv, sizeof(int32_t)) ||
        grow((void **)&P->freel, &c[2], nv, sizeof(int32_t)) ||
        grow((void **)&P->x2, &c[7], nv, sizeof(double)))
        return -1;
    P->vcap = c[0];
    int32_t c6 = S->dcap;
    if (grow((void **)&S->d, &c[3], nv, sizeof(double)) ||
        grow((void **)&S->cls, &c[4], nv, 1) || grow((void **)&S->remap, &c[5], nv, sizeof(int32_t)) ||
        grow((void **)&S->xs, &c6, nv, sizeof(xslot)))
        return -1;
    if (c6 > S->dcap) memset(S->xs + S->dcap, 0, (size_t)(c6 - S->dcap) * sizeof(xslot));
    S->dcap = c[3];
    int32_t f[5] = {P->fcap, P->fcap, P->fcap, P->fcap, P->fcap};
    if (grow((void **)&P->foff, &f[0], nf, sizeof(int32_t)) ||
        grow((void **)&P->flen, &f[1], nf, sizeof(int32_t)) ||
        grow((void **)&P->fcp, &f[2], nf, sizeof(int32_t)) ||
        grow((void **)&P->ftag, &f[3], nf, sizeof(int32_t)) ||
        grow((void **)&P->fpl, &f[4], nf, 4 * sizeof(double)))
        return -1;
    P->fcap = f[0];
    return grow((void **)&P->fv, &P->lcap, nl, sizeof(int32_t));
}

static void poly_free(poly *P)
{
    free(P->x);
    free(P->x2);
    free(P->ref);
    free(P->freel);
    free(P->foff);
    free(P->flen);
    free(P->fcp);
    free(P->ftag);
    free(P->fpl);
    free(P->fv);
    memset(P, 0, sizeof *P);
}

/* The box [lo, hi] (frame coordinates), face k (x-, x+, y-, y+, z-, z+) tagged tag[k]. Vertex
 * index bx + 2 by + 4 bz; the loops are counter-clockwise seen from outside. */
static int poly_box(scratch *S, const double lo[3], const double hi[3], const int32_t tag[6])
{
    static const int32_t loops[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                        {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    if (poly_reserve(S, 8, 6, 48)) return -1;
    poly *P = &S->p;
    P->r2 = 0;
    for (int k = 0; k < 8; k++) {
        double *x = P->x + 3 * k;
        x[0] = (k & 1) ? hi[0] : lo[0];
        x[1] = (k & 2) ? hi[1] : lo[1];
        x[2] = (k & 4) ? hi[2] : lo[2];
        P->ref[k] = 3;
        double r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
        P->x2[k] = r2;
        P->r2 = r2 > P->r2 ? r2 : P->r2;
    }
    for (int f = 0; f < 6; f++) {
        P->foff[f] = 8 * f;
        P->flen[f] = 4;
        P->fcp[f] = 8;
        P->ftag[f] = tag[f];
        double *q = P->fpl + 4 * f; /* x <= hi, -x <= -lo */
        q[0] = q[1] = q[2] = 0;
        q[f / 2] = (f & 1) ? 1 : -1;
        q[3] = (f & 1) ? hi[f / 2] : -lo[f / 2];
        memcpy(P->fv + 8 * f, loops[f], sizeof loops[f]);
    }
    P->nv = 8;
    P->nf = 6;
    P->nl = 24;
    P->pool = 48;
    P->nfree = 0;
    return 0;
}

/* The largest n . x over P's vertex slots, each n . x kept in S->d for classify() (S->d holds
 * P->nv: cut_reserve() leaves room for what a cut adds). Free slots sit at the origin, which
 * every plane of a seed leaves inside; for a wall they can only cost a classification. The test
 * before a cut, cheap because most tests find nothing to cut. */
static double poly_max(scratch *S, const double n[3])
{
    const double *x = S->p.x, n0 = n[0], n1 = n[1], n2 = n[2];
    double m = -INFINITY, *dist = S->d;
    for (int32_t k = 0, nv = S->p.nv; k < nv; k++) {
        double d = n0 * x[3 * k] + n1 * x[3 * k + 1] + n2 * x[3 * k + 2];
        dist[k] = d;
        m = d > m ? d : m;
    }
    return m;
}

/* Signed distances (in units of |n|: poly_max()'s n . x less c) and classes of P's vertices;
 * returns the number outside, *nin the number inside. Free slots get no class. */
static int classify(scratch *S, double c, double tol, int *nin)
{
    /* locals, so that the stores (a char may alias anything) force no reloads */
    const int32_t *ref = S->p.ref;
    double *dist = S->d;
    unsigned char *cls = S->cls;
    int nout = 0, nins = 0;
    for (int32_t k = 0, nv = S->p.nv; k < nv; k++) {
        double d = dist[k] - c;
        /* without branches: the classes are as good as random, a mispredicted branch costs
         * more than the arithmetic */
        int live = ref[k] >= 0, o = (d > tol) & live, in = (d < -tol) & live;
        dist[k] = d;
        cls[k] = (unsigned char)((o * C_OUT) | (in * C_IN) | ((live & !o & !in) * C_ON));
        nout += o;
        nins += in;
    }
    *nin = nins;
    return nout;
}

/* The new vertex on edge a-b (one inside, one outside), made once per edge (class ON). */
static int32_t cross_vertex(scratch *S, int32_t a, int32_t b)
{
    int32_t in = S->cls[a] == C_IN ? a : b, out = in == a ? b : a;
    xslot *X = &S->xs[in];
    if (X->stamp != S->cutno) X->stamp = S->cutno, X->n = 0;
    for (int32_t q = 0; q < X->n; q++)
        if (X->o[q] == out) return X->v[q];
    int32_t lo = a < b ? a : b, hi = a < b ? b : a;
    for (int32_t k = 0; k < S->nxe && X->n == 3; k++)
        if (S->xe[k].a == lo && S->xe[k].b == hi) return S->xe[k].v;
    poly *P = &S->p;
    double t = S->d[in] / (S->d[in] - S->d[out]);
    int32_t k = P->nfree ? P->freel[--P->nfree] : P->nv++;
    const double *xi = P->x + 3 * in, *xo = P->x + 3 * out;
    double *x = P->x + 3 * k;
    for (int q = 0; q < 3; q++) x[q] = xi[q] + t * (xo[q] - xi[q]);
    P->x2[k] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    P->ref[k] = 0;
    S->cls[k] = C_ON;
    if (X->n < 3) {
        X->o[X->n] = out;
        X->v[X->n++] = k;
    } else {
        S->xe[S->nxe++] = (xedge){lo, hi, k};
    }
    return k;
}

/* The loop's edges lying in the plane, reversed: edges of the new face. */
static void note_plane_edges(scratch *S, const int32_t *L, int32_t m)
{
    for (int32_t k = 0; k < m; k++) {
        int32_t u = L[k], w = L[k + 1 < m ? k + 1 : 0];
        if ((S->cls[u] & C_ON) && (S->cls[w] & C_ON)) {
            S->cf[S->nce] = w;
            S->ct[S->nce] = u;
            S->cdead[S->nce++] = 0;
        }
    }
}

static void face_drop(poly *P, int32_t f)
{
    const int32_t *L = P->fv + P->foff[f];
    for (int32_t k = 0; k < P->flen[f]; k++) P->ref[L[k]]--;
    P->nl -= P->flen[f];
    int32_t g = --P->nf;
    P->foff[f] = P->foff[g];
    P->flen[f] = P->flen[g];
    P->fcp[f] = P->fcp[g];
    P->ftag[f] = P->ftag[g];
    memcpy(P->fpl + 4 * f, P->fpl + 4 * g, 4 * sizeof(double));
}

/* Face f clipped to the inside, in place (moved to the pool's end if it outgrows its room). */
static void face_clip(scratch *S, int32_t f)
{
    poly *P = &S->p;
    int32_t m = P->flen[f], len = 0;
    const int32_t *L = P->fv + P->foff[f];
    for (int32_t k = 0; k < m; k++) {
        int32_t a = L[k], b = L[k + 1 < m ? k + 1 : 0];
        int out = S->cls[a] == C_OUT;
        P->ref[a] -= out;
        S->buf[len] = a;
        len += !out;
        if ((S->cls[a] | S->cls[b]) == (C_IN | C_OUT)) {
            int32_t x = cross_vertex(S, a, b);
            P->ref[x]++;
            S->buf[len++] = x;
        }
    }
    if (len > P->fcp[f]) {
        P->foff[f] = P->pool;
        P->fcp[f] = len + 4;
        P->pool += len + 4;
    }
    memcpy(P->fv + P->foff[f], S->buf, (size_t)len * sizeof(int32_t));
    P->nl += len - m;
    P->flen[f] = len;
    note_plane_edges(S, S->buf, len);
}

/* Face f against the classified plane: kept, dropped or clipped. */
static void face_cut(scratch *S, int32_t f)
{
    poly *P = &S->p;
    const int32_t *L = P->fv + P->foff[f];
    int32_t m = P->flen[f];
    unsigned mask = 0;
    for (int32_t k = 0; k < m; k++) mask |= S->cls[L[k]];
    if (!(mask & C_OUT)) {
        if (mask & C_ON) note_plane_edges(S, L, m);
    } else if (!(mask & C_IN)) {
        face_drop(P, f);
    } else {
        face_clip(S, f);
    }
}

/* The new face from the recorded edges: pairs met in both directions cancel (two kept faces
 * meeting on the plane), the rest must chain into one loop. -2 when they do not. */
static int cap_face(scratch *S, const double n[3], double c, int32_t tag)
{
    for (int32_t e = 0; e < S->nce; e++)
        for (int32_t g = e + 1; g < S->nce && !S->cdead[e]; g++)
            if (!S->cdead[g] && S->cf[g] == S->ct[e] && S->ct[g] == S->cf[e])
                S->cdead[e] = S->cdead[g] = 1;
    int32_t m = 0, e0 = -1;
    for (int32_t e = 0; e < S->nce; e++)
        if (!S->cdead[e]) {
            m++;
            if (e0 < 0) e0 = e;
        }
    if (m < 3) return -2;
    poly *P = &S->p;
    int32_t *L = P->fv + P->pool, cnt = 0, cur = e0;
    do {
        L[cnt++] = S->cf[cur];
        P->ref[S->cf[cur]]++;
        S->cdead[cur] = 1;
        int32_t to = S->ct[cur], nx = -1;
        for (int32_t g = 0; g < S->nce && nx < 0; g++)
            if (!S->cdead[g] && S->cf[g] == to) nx = g;
        if (nx < 0) {
            if (to != S->cf[e0]) return -2;
            break;
        }
        cur = nx;
    } while (cnt <= m);
    if (cnt != m) return -2;
    int32_t f = P->nf++;
    P->foff[f] = P->pool;
    P->flen[f] = m;
    P->fcp[f] = m + 4;
    P->ftag[f] = tag;
    double *q = P->fpl + 4 * f;
    q[0] = n[0], q[1] = n[1], q[2] = n[2], q[3] = c;
    P->pool += m + 4;
    P->nl += m;
    return 0;
}

/* The pool rewritten with each face's loop and a little room, in face order. */
static void pool_compact(scratch *S)
{
    poly *P = &S->p;
    int32_t at = 0;
    for (int32_t f = 0; f < P->nf; f++) {
        memcpy(S->buf + at, P->fv + P->foff[f], (size_t)P->flen[f] * sizeof(int32_t));
        P->foff[f] = at;
        P->fcp[f] = P->flen[f] + 4;
        at += P->fcp[f];
    }
    memcpy(P->fv, S->buf, (size_t)at * sizeof(int32_t));
    P->pool = at;
}

/* Room for a cut of p: every face may move to the pool's end, a new face, new vertices (at
 * most one per edge). */
static int cut_reserve(scratch *S)
{
    poly *P = &S->p;
    int32_t room = P->nl + 5 * P->nf + 8, nv = P->nv + P->nl / 2 + 4;
    if (grow((void **)&S->buf, &S->bufcap, room + P->nl + 2 * P->nv, sizeof(int32_t))) return -1;
    if (P->pool > 2 * P->nl + 64) pool_compact(S); /* into buf: needs nl + 4 nf */
    /* the common case: everything already fits (the checks below, at once) */
    if (nv <= P->vcap && nv <= S->dcap && P->nf + 2 <= P->fcap &&
        P->pool + room + P->nl + nv <= P->lcap && P->nl / 2 + 4 <= S->xecap && room <= S->cecap)
        return 0;
    if (poly_reserve(S, nv, P->nf + 2, P->pool + room + P->nl + nv)) return -1;
    if (grow((void **)&S->xe, &S->xecap, P->nl / 2 + 4, sizeof(xedge))) return -1;
    int32_t c1 = S->cecap, c2 = S->cecap, c3 = S->cecap; /* cf, ct, cdead: one capacity */
    if (grow((void **)&S->cf, &c1, room, sizeof(int32_t))) return -1;
    if (grow((void **)&S->ct, &c2, room, sizeof(int32_t))) return -1;
    if (grow((void **)&S->cdead, &c3, room, 1)) return -1;
    S->cecap = c1;
    return 0;
}

/* Slots no loop names any more become free; r2 from the rest. */
static void free_dead(poly *P)
{
    P->r2 = 0;
    for (int32_t k = 0; k < P->nv; k++) {
        if (P->ref[k] == 0) {
            double *x = P->x + 3 * k;
            P->ref[k] = -1;
            x[0] = x[1] = x[2] = 0;
            P->x2[k] = 0;
            P->freel[P->nfree++] = k;
        }
        P->r2 = P->x2[k] > P->r2 ? P->x2[k] : P->r2;
    }
}

/* Cuts p by n . x <= c (tol in the units of n . x; the new face tagged tag). Returns 0 when no
 * vertex is outside (p unchanged), 1 when cut, -1 out of memory, -2 inconsistent (nothing
 * inside, or a new face that does not close). */
static int poly_cut(scratch *S, const double n[3], double c, double tol, int32_t tag)
{
    poly *P = &S->p;
    if (poly_max(S, n) - c <= tol) return 0;
    if (cut_reserve(S)) return -1;
    int nin, nout = classify(S, c, tol, &nin);
    if (nout == 0) return 0;
    if (nin == 0) return -2;
    S->nxe = S->nce = 0;
    if (++S->cutno == 0) { /* wrapped: no stamp may look current */
        memset(S->xs, 0, (size_t)S->dcap * sizeof(xslot));
        S->cutno = 1;
    }
    for (int32_t f = P->nf - 1; f >= 0; f--) face_cut(S, f); /* backwards: drops swap in done faces */
    int rc = cap_face(S, n, c, tag);
    if (rc) return rc;
    free_dead(P);
    return 1;
}

/* Adds the tetrahedra (origin, fan triangles from L[0] of the loop L of m vertices of x) to
 * s: 6 V, then 24 V g, then 120 times the integral of x x^T (xx xy xz yy yz zz). */
static void loop_moments(const double *x, const int32_t *L, int32_t m, double s[10])
{
    const double *a = x + 3 * L[0];
    double u[10]; /* the face's sums in registers (s may alias x for all the compiler knows) */
    memcpy(u, s, sizeof u);
    for (int32_t k = 1; k + 1 < m; k++) {
        const double *b = x + 3 * L[k], *c = x + 3 * L[k + 1];
        double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        double t[3] = {a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]};
        u[0] += det;
        for (int q = 0; q < 3; q++) u[1 + q] += det * t[q];
        int idx = 4;
        for (int p = 0; p < 3; p++)
            for (int q = p; q < 3; q++)
                u[idx++] += det * (a[p] * a[q] + b[p] * b[q] + c[p] * c[q] + t[p] * t[q]);
    }
    memcpy(s, u, sizeof u);
}

/* Volume, centroid and second moments about the frame's origin from loop_moments' sums. */
static void moments_finish(const double s[10], double *vol, double g[3], double m[6])
{
    *vol = s[0] / 6;
    for (int q = 0; q < 3; q++) g[q] = s[0] != 0 ? s[1 + q] / (4 * s[0]) : 0;
    for (int q = 0; q < 6; q++) m[q] = s[4 + q] / 120;
}

/* Volume, centroid and second moments (about the frame's origin) of P. */
static void poly_moments(const poly *P, double *vol, double g[3], double m[6])
{
    double s[10] = {0};
    for (int32_t f = 0; f < P->nf; f++) loop_moments(P->x, P->fv + P->foff[f], P->flen[f], s);
    moments_finish(s, vol, g, m);
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

/* Candidates by (distance, index): a counting sort on the distance into about one bucket per
 * candidate, then an insertion pass (cheap on the nearly sorted result) that makes the order
 * exact. -1 out of memory. */
static int cand_sort(scratch *S)
{
    int32_t n = S->ncd;
    cand *c = S->cd;
    if (n > 24) {
        if (grow((void **)&S->cd2, &S->cd2cap, n, sizeof(cand)) ||
            grow((void **)&S->cnt, &S->cntcap, n + 1, sizeof(int32_t)))
            return -1;
        double mx = 0;
        for (int32_t k = 0; k < n; k++) mx = c[k].d2 > mx ? c[k].d2 : mx;
        double sc = (n - 1) / (mx > 0 ? mx : 1);
        memset(S->cnt, 0, (size_t)(n + 1) * sizeof(int32_t));
        for (int32_t k = 0; k < n; k++) S->cnt[(int32_t)(c[k].d2 * sc) + 1]++;
        for (int32_t k = 0; k < n; k++) S->cnt[k + 1] += S->cnt[k];
        for (int32_t k = 0; k < n; k++) S->cd2[S->cnt[(int32_t)(c[k].d2 * sc)]++] = c[k];
        memcpy(c, S->cd2, (size_t)n * sizeof(cand));
    }
    for (int32_t k = 1; k < n; k++) {
        cand t = c[k];
        int32_t m = k;
        while (m > 0 && cand_less(&t, &c[m - 1])) {
            c[m] = c[m - 1];
            m--;
        }
        c[m] = t;
    }
    return 0;
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

/* Adds the seeds of bin bb that may cut cell i (nearer than 2 R) to the candidates. */
static int gather_bin(gp_voronoi3d *v, uint32_t i, const int32_t bb[3])
{
    scratch *S = &v->s;
    const double *si = v->seed + 3 * i;
    double lim = 4 * S->p.r2 * V3_SLACK;
    if (bin_dist2(v, si, bb) > lim) return 0;
    vbin *b = &v->bins[((size_t)bb[2] * v->gn[1] + (size_t)bb[1]) * v->gn[0] + (size_t)bb[0]];
    if (grow((void **)&S->cd, &S->cdcap, S->ncd + b->cnt, sizeof(cand))) return -1;
    for (int32_t k = 0; k < b->cnt; k++) {
        int32_t j = b->e[k].j;
        if ((uint32_t)j == i) continue;
        const double *sj = b->e[k].p;
        double r[3] = {sj[0] - si[0], sj[1] - si[1], sj[2] - si[2]};
        double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        if (d2 < lim) S->cd[S->ncd++] = (cand){{r[0], r[1], r[2]}, d2, j};
    }
    return 0;
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

/* Cuts cell i by the candidates, nearest first, while they are nearer than 2 R. */
static int cut_candidates(scratch *S)
{
    if (cand_sort(S)) return -1;
    for (int32_t k = 0; k < S->ncd; k++) {
        double d2 = S->cd[k].d2;
        if (d2 > 4 * S->p.r2 * V3_SLACK) break;
        double tol = V3_EPS * sqrt(S->p.r2 * d2);
        int rc = poly_cut(S, S->cd[k].r, 0.5 * d2, tol, S->cd[k].j);
        if (rc < 0) return rc;
        if (rc == 1 && note_cutter(S, S->cd[k].j)) return -1;
    }
    return 0;
}

/* The container's half-spaces that reach the cell (non-box containers). */
static int cut_walls(gp_voronoi3d *v, uint32_t i)
{
    scratch *S = &v->s;
    const double *si = v->seed + 3 * i;
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
    const double *si = v->seed + 3 * i;
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

/* Candidates of one batch of offsets around bin c, then the cuts. */
static int search_batch(gp_voronoi3d *v, uint32_t i, const int32_t c[3], int32_t bt)
{
    scratch *S = &v->s;
    S->ncd = 0;
    for (int32_t k = v->batch[bt]; k < v->batch[bt + 1]; k++) {
        const int32_t *d = v->off + 3 * k;
        int32_t bb[3] = {c[0] + d[0], c[1] + d[1], c[2] + d[2]};
        int ok = 1;
        for (int a = 0; a < 3; a++) ok &= bb[a] >= 0 && bb[a] < (int32_t)v->gn[a];
        if (ok && gather_bin(v, i, bb)) return -1;
    }
    return cut_candidates(&v->s);
}

/* The search: the offset batches nearest first, then (for a cell that reaches farther, in a
 * sparse corner) whole shells of bins, until the security radius stops it. The first batch
 * holds the 27 bins around the seed's: its nearest seed, sorted first, is checked for a
 * duplicate (-3, the other in S->dup). */
static int cell_search(gp_voronoi3d *v, uint32_t i)
{
    scratch *S = &v->s;
    int32_t c[3];
    bin_of(v, v->seed + 3 * i, c);
    double dup = V3_DUP * v->size;
    for (int32_t bt = 0; bt < v->nbatch; bt++) {
        if (v->blb[bt] > 4 * S->p.r2 * V3_SLACK) break;
        int rc = search_batch(v, i, c, bt);
        if (rc) return rc;
        if (bt == 0 && S->ncd > 0 && S->cd[0].d2 < dup * dup) {
            S->dup = S->cd[0].j;
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
    if (!t || !v->off || !v->batch || !v->blb) {
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
        if (k == 0 || t[4 * k] != t[4 * (k - 1)]) {
            v->blb[v->nbatch] = t[4 * k];
            v->batch[v->nbatch++] = k;
        }
    }
    v->batch[v->nbatch] = n;
    v->reach = R;
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
    int32_t c[3] = {S->canv, S->canv, S->canv}, l = S->canl, f = S->canf;
    if (grow((void **)&S->voff, &c[0], P->nv + 1, sizeof(int32_t)) ||
        grow((void **)&S->vkey, &c[1], P->nv + 1, sizeof(vkey)) ||
        grow((void **)&S->vord, &c[2], P->nv + 1, sizeof(int32_t)) ||
        grow((void **)&S->vfac, &l, P->nl, sizeof(int32_t)) ||
        grow((void **)&S->ford, &f, P->nf, sizeof(int32_t)))
        return -1;
    S->canv = c[0];
    S->canl = l;
    S->canf = f;
    return 0;
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

/* Each live slot's faces, sorted by tag, into vfac[voff[k] .. voff[k + 1]), and its key (its
 * three lowest tags) into vkey[k]. -2 when a vertex has fewer than three faces (not a closed
 * polyhedron). */
static int vertex_faces(scratch *S)
{
    const poly *P = &S->p;
    int32_t *fill = S->remap;
    S->voff[0] = 0;
    for (int32_t k = 0; k < P->nv; k++) {
        S->voff[k + 1] = S->voff[k] + (P->ref[k] > 0 ? P->ref[k] : 0);
        fill[k] = S->voff[k];
    }
    for (int32_t f = 0; f < P->nf; f++) {
        const int32_t *L = P->fv + P->foff[f];
        for (int32_t k = 0; k < P->flen[f]; k++) S->vfac[fill[L[k]]++] = f;
    }
    for (int32_t k = 0; k < P->nv; k++) {
        if (P->ref[k] < 0) continue;
        int32_t *F = S->vfac + S->voff[k], d = S->voff[k + 1] - S->voff[k];
        if (d < 3) return -2;
        if (d == 3) {
            sort3(P->ftag, F);
        } else {
            for (int32_t a = 1; a < d; a++) {
                int32_t t = F[a], m = a;
                for (; m > 0 && P->ftag[F[m - 1]] > P->ftag[t]; m--) F[m] = F[m - 1];
                F[m] = t;
            }
        }
        S->vkey[k] = (vkey){tag_key(P->ftag[F[0]]) << 32 | tag_key(P->ftag[F[1]]),
                            tag_key(P->ftag[F[2]]), k};
    }
    return 0;
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

/* The faces by tag into ford: each face's rank is the count of smaller tags (one face per
 * plane, so the tags differ; counting has no unpredictable branch, unlike a sort). */
static void face_order(scratch *S)
{
    const poly *P = &S->p;
    for (int32_t f = 0; f < P->nf; f++) {
        int32_t r = 0, t = P->ftag[f];
        for (int32_t g = 0; g < P->nf; g++) r += P->ftag[g] < t;
        S->ford[r] = f;
    }
}

/* The canonical loops and tags of P into c: faces by tag, each loop from its vertex of lowest
 * key, the vertices numbered in order of first appearance along the loops so written (their
 * slots in vord, their numbers in remap). */
static void cell_loops(scratch *S, vcell *c)
{
    const poly *P = &S->p;
    int32_t n = 0;
    for (int32_t k = 0; k < P->nv; k++) S->remap[k] = -1;
    c->foff[0] = 0;
    for (int32_t q = 0; q < P->nf; q++) {
        int32_t f = S->ford[q], m = P->flen[f], lo = 0;
        const int32_t *L = P->fv + P->foff[f];
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
}

/* The canonical positions of P's vertices into c, in vord's order. */
static void cell_vertices(const scratch *S, vcell *c)
{
    const poly *P = &S->p;
    double R = sqrt(P->r2);
    for (int32_t m = 0; m < c->nv; m++) {
        int32_t k = S->vord[m];
        vertex_canon(P, S->vfac + S->voff[k], S->voff[k + 1] - S->voff[k], P->x + 3 * k, R,
                     c->x + 3 * m);
    }
}

/* Volume, centroid and inertia about the centroid of c from its own vertices and loops. */
static void cell_moments(vcell *c)
{
    double s[10] = {0}, m[6];
    for (int32_t f = 0; f < c->nf; f++)
        loop_moments(c->x, c->fv + c->foff[f], c->foff[f + 1] - c->foff[f], s);
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
 * *out, or an error status. */
static gp_status cell_pack(scratch *S, vcell **out)
{
    const poly *P = &S->p;
    if (canon_reserve(S)) return GP_ERR_NOMEM;
    if (vertex_faces(S)) return GP_ERR_INTERNAL;
    sort_unique(S->cut, &S->ncut);
    int32_t nnb = 0, nv = P->nv - P->nfree;
    for (int32_t f = 0; f < P->nf; f++) nnb += P->ftag[f] >= 0;
    size_t ni = (size_t)(P->nf + 1) + (size_t)P->nl + (size_t)P->nf + (size_t)nnb + (size_t)S->ncut;
    vcell *c = malloc(sizeof(vcell) + 3 * (size_t)nv * sizeof(double) + ni * sizeof(int32_t));
    if (!c) return GP_ERR_NOMEM;
    c->nv = nv;
    c->nf = P->nf;
    c->nl = P->nl;
    c->ncut = S->ncut;
    c->x = (double *)(c + 1);
    c->foff = (int32_t *)(c->x + 3 * nv);
    c->fv = c->foff + P->nf + 1;
    c->ftag = c->fv + P->nl;
    c->nb = c->ftag + P->nf;
    face_order(S);
    cell_loops(S, c);
    cell_vertices(S, c);
    c->nnb = 0;
    for (int32_t f = 0; f < P->nf; f++)
        if (c->ftag[f] >= 0) c->nb[c->nnb++] = c->ftag[f]; /* ascending: the faces are by tag */
    c->cut = c->nb + c->nnb;
    if (S->ncut > 0) memcpy(c->cut, S->cut, (size_t)S->ncut * sizeof(int32_t)); /* NULL when 0 */
    cell_moments(c);
    *out = c;
    return GP_OK;
}

/* Cell i computed from the current seeds: GP_OK and *out, or an error status. */
static gp_status cell_compute(gp_voronoi3d *v, uint32_t i, vcell **out)
{
    scratch *S = &v->s;
    S->ncut = 0;
    if (cell_start(v, i)) return GP_ERR_NOMEM;
    int rc = cell_search(v, i);
    if (rc == -1) return GP_ERR_NOMEM;
    if (rc == -3) return GP_ERR_INVALID;
    if (rc) return GP_ERR_INTERNAL;
    for (int32_t f = 0; f < S->p.nf; f++)
        if (S->p.ftag[f] <= TAG_BBOX + 5) return GP_ERR_INTERNAL;
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

/* The half-spaces of a convex or cylinder container, unit normals, into v->pl (caller frame). */
static gp_status container_planes(gp_voronoi3d *v, const gp_voronoi3d_container *c, gp_error *err)
{
    size_t m = c->kind == GP_VORONOI3D_CONVEX ? c->nplanes : (c->facets ? c->facets : 64) + 2;
    if (c->kind == GP_VORONOI3D_CONVEX && (m < 4 || !c->planes))
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: a convex container needs >= 4 planes");
    if (c->kind == GP_VORONOI3D_CYLINDER &&
        (!(c->radius > 0) || !(c->z1 > c->z0) || m < 5 || !isfinite(c->radius + c->z0 + c->z1 +
                                                                      c->axis[0] + c->axis[1])))
        return gp_error_set(err, GP_ERR_INVALID,
                            "voronoi3d: a cylinder needs radius > 0, z1 > z0, facets >= 3");
    if (m > 100000) return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: too many planes");
    v->pl = malloc(4 * m * sizeof(double));
    if (!v->pl) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    v->nplanes = (int32_t)m;
    for (size_t k = 0; k < m; k++) {
        double *p = v->pl + 4 * k;
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
        if (!(nn > 0) || !isfinite(nn) || !isfinite(p[3]))
            return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: plane %zu is not a half-space", k);
        for (int q = 0; q < 4; q++) p[q] /= nn;
    }
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
    for (int32_t f = 0; f < S->p.nf; f++)
        if (S->p.ftag[f] <= TAG_BBOX + 5) return 1;
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
            for (int a = 0; a < 3 && P->ref[k] >= 0; a++) {
                double x = P->x[3 * k + a] + ctr[a];
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

/* v's frame, planes, volume and starting box from the caller's container. */
static gp_status container_setup(gp_voronoi3d *v, const gp_voronoi3d_container *c, gp_error *err)
{
    v->kind = c->kind;
    double lo[3], hi[3];
    if (c->kind == GP_VORONOI3D_BOX) {
        for (int a = 0; a < 3; a++)
            if (!(c->hi[a] > c->lo[a]) || !isfinite(c->hi[a] - c->lo[a]))
                return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: box needs lo < hi (axis %d)", a);
        memcpy(lo, c->lo, sizeof lo);
        memcpy(hi, c->hi, sizeof hi);
    } else if (c->kind == GP_VORONOI3D_CONVEX || c->kind == GP_VORONOI3D_CYLINDER) {
        gp_status st = container_planes(v, c, err);
        if (!st) st = container_bbox(v, lo, hi, err);
        if (st) return st;
    } else {
        return gp_error_set(err, GP_ERR_INVALID, "voronoi3d: unknown container kind");
    }
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
    double ctr[3] = {0.5 * v->L[0], 0.5 * v->L[1], 0.5 * v->L[2]}, g[3], m[6];
    int rc = container_cut(v, ctr, 0.6 * fmax(v->L[0], fmax(v->L[1], v->L[2])));
    if (rc) return gp_error_set(err, rc == -1 ? GP_ERR_NOMEM : GP_ERR_INTERNAL,
                                "voronoi3d: the container could not be rebuilt");
    poly_moments(&v->s.p, &v->cvol, g, m);
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
            gp_status st = cell_compute(v, i, &v->cell[i]);
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
    free(S->buf);
    free(S->d);
    free(S->cls);
    free(S->remap);
    free(S->xe);
    free(S->xs);
    free(S->cf);
    free(S->ct);
    free(S->cdead);
    free(S->cd);
    free(S->cd2);
    free(S->cnt);
    free(S->cut);
    free(S->voff);
    free(S->vkey);
    free(S->vfac);
    free(S->vord);
    free(S->ford);
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
    gp_status st = cell_compute(v, j, &c);
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
