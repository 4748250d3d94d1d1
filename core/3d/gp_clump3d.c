/* gp_clump3d.c -- a clump of overlapping spheres inside a 3D grain. See gp_clump3d.h.
 *
 * Layout: vector helpers; the point-triangle distance; the mesh (checks, integrals, the vertices'
 * triangles, the tree of triangle boxes and its nearest-triangle query); the voxel grid
 * (crossings, inside, the nearest-vertex transform); the sphere fit (shrinking ball); the
 * greedy's bit counts and heap; the union's lines; the figures of merit; the greedy (medial
 * candidates and the choice); the build.
 *
 * Frames: the mesh is moved to its principal frame ("internal" coordinates R^T (x - centroid));
 * the voxel grid works in grid units (x - o) / h, in which voxel centres are the integer
 * points.
 */
#include "gp_clump3d.h"

#include "gp_mesh3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CL_PI 3.14159265358979323846
#define CL_DEFAULT_VOXELS 8192 /* voxel centres inside the grain, about */
#define CL_MIN_VOXELS 1000
#define CL_MAX_VOXELS 262144
#define CL_MAX_SPHERES 1000
#define CL_BOX_FACTOR 16       /* the grid holds at most this many times `voxels` voxels */
#define CL_RIDGE 0.8           /* a centre rising this fast towards a neighbour is not medial */
#define CL_SWEEPS 2            /* raster sweeps of the nearest-vertex transform */
#define CL_FIT_STEPS 32        /* shrinking-ball steps at most */
#define CL_FIT_TOL 1e-7        /* a ball is maximal when no point is nearer than (1 - this) R */
#define CL_ASCENT 96           /* the first sphere's tries up the distance, at most */
#define CL_SHRINK (1.0 - 1e-12) /* radius = this times the distance */
#define CL_LEAF 4              /* triangles a leaf of the tree */
#define CL_STACK 128
#define CL_LINES 128           /* the union's lines across the larger side of its box */
#define CL_SAME 1e-12          /* two balls closer than this (times r) in centre and radius: one */

/* ------------------------------------------------------------------------------------------ */
/* vectors                                                                                     */

static inline double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double mind(double a, double b)
{
    return a < b ? a : b;
}

static inline double maxd(double a, double b)
{
    return a > b ? a : b;
}

/* floor and ceil of x as integers, for |x| < 2^62 (the library's are calls on baseline x86-64) */
static inline long ifloor(double x)
{
    long i = (long)x;
    return (double)i > x ? i - 1 : i;
}

static inline long iceil(double x)
{
    long i = (long)x;
    return (double)i < x ? i + 1 : i;
}

static inline double dist2_3(const double *a, const double *b)
{
    double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

/* ------------------------------------------------------------------------------------------ */
/* point-triangle distance (Ericson, Real-Time Collision Detection, 5.1.5)                     */

typedef struct cl_tri {
    double a[3], ab[3], ac[3];
    double abab, abac, acac;
    int flat; /* zero area (to 1e-12 in angle): distance to its edges */
} cl_tri;

static void tri_set(cl_tri *g, const double *a, const double *b, const double *c)
{
    for (int k = 0; k < 3; k++) {
        g->a[k] = a[k];
        g->ab[k] = b[k] - a[k];
        g->ac[k] = c[k] - a[k];
    }
    g->abab = dot3(g->ab, g->ab);
    g->abac = dot3(g->ab, g->ac);
    g->acac = dot3(g->ac, g->ac);
    double cr = g->abab * g->acac - g->abac * g->abac; /* |ab x ac|^2 */
    g->flat = !(cr > 1e-24 * g->abab * g->acac);
}

/* squared distance from p to the segment a + s d, s in [0, 1]; *s_out the parameter */
static double seg_dist2(const double p[3], const double a[3], const double d[3], double dd,
                        double *s_out)
{
    double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double s = dd > 0 ? dot3(ap, d) / dd : 0;
    s = s < 0 ? 0 : (s > 1 ? 1 : s);
    double e[3] = {ap[0] - s * d[0], ap[1] - s * d[1], ap[2] - s * d[2]};
    *s_out = s;
    return dot3(e, e);
}

static double tri_dist2_flat(const cl_tri *g, const double p[3], double q[3])
{
    double b[3] = {g->a[0] + g->ab[0], g->a[1] + g->ab[1], g->a[2] + g->ab[2]};
    double bc[3] = {g->ac[0] - g->ab[0], g->ac[1] - g->ab[1], g->ac[2] - g->ab[2]};
    double s0, s1, s2;
    double d0 = seg_dist2(p, g->a, g->ab, g->abab, &s0);
    double d1 = seg_dist2(p, g->a, g->ac, g->acac, &s1);
    double d2 = seg_dist2(p, b, bc, dot3(bc, bc), &s2);
    double best = d0;
    const double *o = g->a, *d = g->ab;
    double s = s0;
    if (d1 < best) best = d1, o = g->a, d = g->ac, s = s1;
    if (d2 < best) best = d2, o = b, d = bc, s = s2;
    if (q)
        for (int k = 0; k < 3; k++) q[k] = o[k] + s * d[k];
    return best;
}

/* Squared distance from p to the triangle; q (may be NULL) its nearest point. */
static double tri_dist2(const cl_tri *g, const double p[3], double q[3])
{
    if (g->flat) return tri_dist2_flat(g, p, q);
    double ap[3] = {p[0] - g->a[0], p[1] - g->a[1], p[2] - g->a[2]};
    double d1 = dot3(g->ab, ap), d2 = dot3(g->ac, ap), s, u;
    if (d1 <= 0 && d2 <= 0) {
        s = 0, u = 0;
    } else {
        double d3 = d1 - g->abab, d4 = d2 - g->abac;
        double vc = d1 * d4 - d3 * d2;
        if (d3 >= 0 && d4 <= d3) {
            s = 1, u = 0;
        } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            s = d1 / (d1 - d3), u = 0;
        } else {
            double d5 = d1 - g->abac, d6 = d2 - g->acac;
            double vb = d5 * d2 - d1 * d6;
            if (d6 >= 0 && d5 <= d6) {
                s = 0, u = 1;
            } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
                s = 0, u = d2 / (d2 - d6);
            } else {
                double va = d3 * d6 - d5 * d4;
                if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
                    u = (d4 - d3) / ((d4 - d3) + (d5 - d6));
                    s = 1 - u;
                } else {
                    double den = va + vb + vc;
                    s = vb / den, u = vc / den;
                }
            }
        }
    }
    double e[3];
    for (int k = 0; k < 3; k++) e[k] = ap[k] - s * g->ab[k] - u * g->ac[k];
    if (q)
        for (int k = 0; k < 3; k++) q[k] = g->a[k] + s * g->ab[k] + u * g->ac[k];
    return dot3(e, e);
}

/* ------------------------------------------------------------------------------------------ */
/* the mesh                                                                                    */

typedef struct cl_node {
    double lo[3], hi[3];
    int32_t kid;            /* the first child (the second is kid + 1), or -1 for a leaf */
    uint32_t first, count;  /* a leaf's triangles: order[first .. first + count) */
} cl_node;

typedef struct cl_mesh {
    size_t nv, nt;
    double *v;        /* internal coordinates, 3 a vertex */
    const uint32_t *t;
    cl_tri *geo;
    cl_node *nodes;
    uint32_t *order;
    size_t nnodes;
    size_t *vt_off;   /* the triangles around vertex v: vt_tri[vt_off[v] .. vt_off[v + 1]) */
    uint32_t *vt_tri;
} cl_mesh;

static void mesh_free(cl_mesh *m)
{
    free(m->v);
    free(m->geo);
    free(m->nodes);
    free(m->order);
    free(m->vt_off);
    free(m->vt_tri);
    memset(m, 0, sizeof *m);
}

/* Every directed edge once and its reverse once: closed, edge-manifold, consistently oriented.
 * Returns 0, 1 (a directed edge twice), 2 (an edge without its reverse), -1 (no memory). */
static int check_closed(const uint32_t *tri, size_t nv, size_t nt, size_t *bad)
{
    size_t *off = calloc(nv + 1, sizeof *off);
    uint32_t *to = malloc(3 * nt * sizeof *to), *fill = calloc(nv, sizeof *fill);
    int rc = 0;
    if (!off || !to || !fill) {
        rc = -1;
        goto done;
    }
    for (size_t f = 0; f < nt; f++)
        for (int e = 0; e < 3; e++) off[tri[3 * f + e] + 1]++;
    for (size_t i = 0; i < nv; i++) off[i + 1] += off[i];
    for (size_t f = 0; f < nt; f++)
        for (int e = 0; e < 3; e++) {
            uint32_t a = tri[3 * f + e], b = tri[3 * f + (e + 1) % 3];
            to[off[a] + fill[a]++] = b;
        }
    for (size_t a = 0; a < nv && !rc; a++) {
        for (size_t k = off[a]; k < off[a + 1] && !rc; k++) {
            uint32_t b = to[k];
            size_t same = 0, back = 0;
            for (size_t l = off[a]; l < off[a + 1]; l++) same += to[l] == b;
            for (size_t l = off[b]; l < off[b + 1]; l++) back += to[l] == a;
            if (same != 1) rc = 1, *bad = a;
            else if (back != 1) rc = 2, *bad = a;
        }
    }
done:
    free(off);
    free(to);
    free(fill);
    return rc;
}

/* Volume, first and second moments of the solid bounded by the triangles, relative to o
 * (tetrahedra from o; s2 = xx yy zz xy xz yz).
 * Why not gp_mesh3d_mass_properties, the same integral: it refuses clockwise meshes, which
 * gp_clump3d_mesh_body measures with their signs and gp_clump3d_build refuses by name, and it
 * sums about the vertices' mean, so its last bits differ (to 1e-14 on the test grains). The
 * principal frame comes from these moments, and a last-bit change turns the frame of a grain
 * with two equal moments (a needle, a torus: a different clump) and moves the spheres of the
 * others by rounding (the lammps, liggghts and yade exports of a fv3d pack change). */
static void mesh_moments(const double *v, const uint32_t *tri, size_t nt, const double o[3],
                         double *vol, double s1[3], double s2[6])
{
    double v6 = 0, a1[3] = {0, 0, 0}, a2[6] = {0, 0, 0, 0, 0, 0};
    for (size_t f = 0; f < nt; f++) {
        const double *A = v + 3 * tri[3 * f], *B = v + 3 * tri[3 * f + 1],
                     *C = v + 3 * tri[3 * f + 2];
        double a[3], b[3], c[3], s[3];
        for (int k = 0; k < 3; k++) {
            a[k] = A[k] - o[k];
            b[k] = B[k] - o[k];
            c[k] = C[k] - o[k];
            s[k] = a[k] + b[k] + c[k];
        }
        double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        v6 += det;
        for (int k = 0; k < 3; k++) a1[k] += det * s[k];
        static const int P[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
        for (int q = 0; q < 6; q++) {
            int i = P[q][0], j = P[q][1];
            a2[q] += det * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
        }
    }
    *vol = v6 / 6;
    for (int k = 0; k < 3; k++) s1[k] = a1[k] / 24;
    for (int q = 0; q < 6; q++) s2[q] = a2[q] / 120;
}

/* A body from volume and moments about o (o in the caller's frame). */
static void body_from_moments(double vol, const double s1[3], const double s2[6],
                              const double o[3], gp_clump3d_body *b)
{
    memset(b, 0, sizeof *b);
    b->volume = vol;
    if (vol == 0) return;
    double g[3] = {s1[0] / vol, s1[1] / vol, s1[2] / vol};
    double cxx = s2[0] - vol * g[0] * g[0], cyy = s2[1] - vol * g[1] * g[1];
    double czz = s2[2] - vol * g[2] * g[2], cxy = s2[3] - vol * g[0] * g[1];
    double cxz = s2[4] - vol * g[0] * g[2], cyz = s2[5] - vol * g[1] * g[2];
    for (int k = 0; k < 3; k++) b->centroid[k] = o[k] + g[k];
    b->inertia[0] = cyy + czz;
    b->inertia[4] = cxx + czz;
    b->inertia[8] = cxx + cyy;
    b->inertia[1] = b->inertia[3] = -cxy;
    b->inertia[2] = b->inertia[6] = -cxz;
    b->inertia[5] = b->inertia[7] = -cyz;
}

static gp_status check_arrays(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                              gp_error *err)
{
    if (!xyz) return gp_error_set(err, GP_ERR_INVALID, "clump3d: xyz (the vertices) is NULL");
    if (!tri) return gp_error_set(err, GP_ERR_INVALID, "clump3d: tri (the triangles) is NULL");
    if (nv < 4) return gp_error_set(err, GP_ERR_INVALID, "clump3d: nv = %zu vertices, need >= 4", nv);
    if (nt < 4)
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: nt = %zu triangles, need >= 4", nt);
    if (nv > 0x7fffffff || nt > 0x7fffffff / 3)
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: mesh too large (nv %zu, nt %zu)", nv, nt);
    for (size_t i = 0; i < 3 * nv; i++)
        if (!isfinite(xyz[i]))
            return gp_error_set(err, GP_ERR_INVALID, "clump3d: vertex %zu is not finite", i / 3);
    for (size_t f = 0; f < nt; f++) {
        uint32_t a = tri[3 * f], b = tri[3 * f + 1], c = tri[3 * f + 2];
        if (a >= nv || b >= nv || c >= nv)
            return gp_error_set(err, GP_ERR_INVALID,
                                "clump3d: triangle %zu has a vertex index >= nv = %zu", f, nv);
        if (a == b || b == c || a == c)
            return gp_error_set(err, GP_ERR_INVALID, "clump3d: triangle %zu repeats a vertex", f);
    }
    return GP_OK;
}

gp_status gp_clump3d_mesh_body(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                               gp_clump3d_body *body, gp_error *err)
{
    if (!body) return gp_error_set(err, GP_ERR_INVALID, "clump3d: body is NULL");
    memset(body, 0, sizeof *body);
    gp_status st = check_arrays(xyz, nv, tri, nt, err);
    if (st) return st;
    double lo[3], hi[3], o[3], vol, s1[3], s2[6];
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = xyz[k];
    for (size_t i = 1; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = mind(lo[k], xyz[3 * i + k]);
            hi[k] = maxd(hi[k], xyz[3 * i + k]);
        }
    for (int k = 0; k < 3; k++) o[k] = 0.5 * (lo[k] + hi[k]);
    mesh_moments(xyz, tri, nt, o, &vol, s1, s2);
    body_from_moments(vol, s1, s2, o, body);
    return GP_OK;
}

/* The triangles around each vertex (CSR). */
static int vertex_triangles(cl_mesh *m)
{
    m->vt_off = calloc(m->nv + 1, sizeof *m->vt_off);
    m->vt_tri = malloc(3 * m->nt * sizeof *m->vt_tri);
    if (!m->vt_off || !m->vt_tri) return -1;
    for (size_t f = 0; f < 3 * m->nt; f++) m->vt_off[m->t[f] + 1]++;
    for (size_t v = 0; v < m->nv; v++) m->vt_off[v + 1] += m->vt_off[v];
    for (size_t f = 0; f < 3 * m->nt; f++) m->vt_tri[m->vt_off[m->t[f]]++] = (uint32_t)(f / 3);
    for (size_t v = m->nv; v > 0; v--) m->vt_off[v] = m->vt_off[v - 1];
    m->vt_off[0] = 0;
    return 0;
}

/* --- the tree: triangles in Morton order of their centroids, halved down to CL_LEAF --- */

static void node_box(cl_mesh *m, cl_node *n)
{
    for (int k = 0; k < 3; k++) n->lo[k] = INFINITY, n->hi[k] = -INFINITY;
    for (uint32_t i = n->first; i < n->first + n->count; i++) {
        const uint32_t *f = m->t + 3 * m->order[i];
        for (int e = 0; e < 3; e++)
            for (int k = 0; k < 3; k++) {
                double x = m->v[3 * f[e] + k];
                if (x < n->lo[k]) n->lo[k] = x;
                if (x > n->hi[k]) n->hi[k] = x;
            }
    }
}

static void tree_build_node(cl_mesh *m, int32_t at, uint32_t first, uint32_t count)
{
    cl_node *n = &m->nodes[at];
    n->first = first;
    n->count = count;
    if (count <= CL_LEAF) {
        n->kid = -1;
        node_box(m, n);
        return;
    }
    int32_t kid = (int32_t)m->nnodes;
    m->nnodes += 2;
    n->kid = kid;
    uint32_t half = count / 2;
    tree_build_node(m, kid, first, half);
    tree_build_node(m, kid + 1, first + half, count - half);
    n = &m->nodes[at];
    for (int k = 0; k < 3; k++) {
        n->lo[k] = mind(m->nodes[kid].lo[k], m->nodes[kid + 1].lo[k]);
        n->hi[k] = maxd(m->nodes[kid].hi[k], m->nodes[kid + 1].hi[k]);
    }
}

static uint32_t spread10(uint32_t x)
{
    x &= 0x3ff;
    x = (x | (x << 16)) & 0x030000ff;
    x = (x | (x << 8)) & 0x0300f00f;
    x = (x | (x << 4)) & 0x030c30c3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
}

static int tree_build(cl_mesh *m)
{
    size_t nt = m->nt;
    uint32_t *code = malloc(nt * sizeof *code), *tmp = malloc(nt * sizeof *tmp);
    uint32_t *ctmp = malloc(nt * sizeof *ctmp);
    m->order = malloc(nt * sizeof *m->order);
    m->nodes = malloc(nt * sizeof *m->nodes); /* leaves hold >= 2 triangles: < nt nodes */
    int ok = code && tmp && ctmp && m->order && m->nodes;
    if (ok) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t f = 0; f < nt; f++)
            for (int e = 0; e < 3; e++)
                for (int k = 0; k < 3; k++) {
                    double x = m->v[3 * m->t[3 * f + e] + k];
                    lo[k] = mind(lo[k], x);
                    hi[k] = maxd(hi[k], x);
                }
        for (size_t f = 0; f < nt; f++) {
            uint32_t c = 0;
            for (int k = 0; k < 3; k++) {
                double x = (m->v[3 * m->t[3 * f] + k] + m->v[3 * m->t[3 * f + 1] + k] +
                            m->v[3 * m->t[3 * f + 2] + k]) / 3;
                double u = hi[k] > lo[k] ? (x - lo[k]) / (hi[k] - lo[k]) * 1023.0 : 0;
                uint32_t q = u <= 0 ? 0 : (u >= 1023 ? 1023 : (uint32_t)u);
                c |= spread10(q) << (2 - k);
            }
            code[f] = c;
            m->order[f] = (uint32_t)f;
        }
        /* LSD radix sort, 3 passes of 10 bits: stable, so ties keep the triangle order */
        for (int pass = 0; pass < 3; pass++) {
            size_t cnt[1025];
            memset(cnt, 0, sizeof cnt);
            int sh = 10 * pass;
            for (size_t f = 0; f < nt; f++) cnt[((code[f] >> sh) & 1023) + 1]++;
            for (int b = 0; b < 1024; b++) cnt[b + 1] += cnt[b];
            for (size_t f = 0; f < nt; f++) {
                size_t at = cnt[(code[f] >> sh) & 1023]++;
                tmp[at] = m->order[f];
                ctmp[at] = code[f];
            }
            memcpy(m->order, tmp, nt * sizeof *tmp);
            memcpy(code, ctmp, nt * sizeof *ctmp);
        }
        m->nnodes = 1;
        tree_build_node(m, 0, 0, (uint32_t)nt);
    }
    free(code);
    free(tmp);
    free(ctmp);
    return ok ? 0 : -1;
}

static inline double box_dist2(const cl_node *n, const double p[3])
{
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double d = p[k] < n->lo[k] ? n->lo[k] - p[k] : (p[k] > n->hi[k] ? p[k] - n->hi[k] : 0);
        s += d * d;
    }
    return s;
}

/* The nearest triangle to p among those nearer than sqrt(best): returns the least squared
 * distance (best if none is nearer), *bt and q (may be NULL) updated when one is. */
static double tree_nearest(const cl_mesh *m, const double p[3], double best, int32_t *bt,
                           double q[3])
{
    int32_t st[CL_STACK];
    double lb[CL_STACK];
    int sp = 0;
    st[sp] = 0;
    lb[sp++] = box_dist2(&m->nodes[0], p);
    while (sp) {
        sp--;
        if (lb[sp] >= best) continue;
        const cl_node *n = &m->nodes[st[sp]];
        if (n->kid < 0) {
            for (uint32_t i = n->first; i < n->first + n->count; i++) {
                uint32_t t = m->order[i];
                double qq[3], d = tri_dist2(&m->geo[t], p, qq);
                if (d < best) {
                    best = d;
                    *bt = (int32_t)t;
                    if (q) memcpy(q, qq, sizeof qq);
                }
            }
            continue;
        }
        double l0 = box_dist2(&m->nodes[n->kid], p), l1 = box_dist2(&m->nodes[n->kid + 1], p);
        int32_t near = n->kid, far = n->kid + 1;
        if (l1 < l0) {
            double x = l0;
            l0 = l1;
            l1 = x;
            near = n->kid + 1, far = n->kid;
        }
        if (l1 < best && sp < CL_STACK) st[sp] = far, lb[sp++] = l1;
        if (l0 < best && sp < CL_STACK) st[sp] = near, lb[sp++] = l0;
    }
    return best;
}

/* ------------------------------------------------------------------------------------------ */
/* the voxel grid                                                                              */

typedef struct cl_grid {
    size_t n[3], total, W; /* voxels along x, y, z (a margin of one outside voxel each side) */
    double h, o[3];        /* voxel (i, j, k) has its centre at o + h (i, j, k) */
    double *g;             /* the vertices in grid units, 3 a vertex */
    uint8_t *inside;
    double *d2;            /* squared distance to the vertex near[] (INFINITY: none yet) */
    int32_t *near;         /* the nearest surface vertex found, -1 none */
    uint64_t *unc;         /* uncovered inside centres: row (j, k) is W words from (j + ny k) W */
} cl_grid;

static void grid_free(cl_grid *G)
{
    free(G->g);
    free(G->inside);
    free(G->d2);
    free(G->near);
    free(G->unc);
    memset(G, 0, sizeof *G);
}

static inline void voxel_centre(const cl_grid *G, size_t i, size_t j, size_t k, double p[3])
{
    p[0] = G->o[0] + G->h * (double)i;
    p[1] = G->o[1] + G->h * (double)j;
    p[2] = G->o[2] + G->h * (double)k;
}

typedef struct cl_cross {
    double t;     /* along the axis, grid units */
    int32_t tri;
    int32_t s;    /* +1: the triangle faces +axis (the line leaves), -1: it enters */
    uint32_t col;
} cl_cross;

typedef struct cl_xs {
    cl_cross *x, *tmp;
    size_t n, cap;
    size_t *off; /* per column, ncol + 1 */
} cl_xs;

/* The signed edge function of the directed edge x -> y at P, computed from the edge's
 * lower-indexed vertex so that both triangles of an edge get the same number. */
static inline double edge_fn(const double *g, uint32_t x, uint32_t y, int b, int c, double pb,
                             double pc)
{
    uint32_t u = x < y ? x : y, w = x < y ? y : x;
    const double *U = g + 3 * u, *Wv = g + 3 * w;
    double e = (Wv[b] - U[b]) * (pc - U[c]) - (Wv[c] - U[c]) * (pb - U[b]);
    return x < y ? e : -e;
}

/* Whether a point on the directed edge x -> y (f == 0) counts as inside the triangle of
 * orientation s: as if moved by (1, eps) in (b, c). */
static inline int edge_tie(const double *g, uint32_t x, uint32_t y, int b, int c, int s)
{
    double db = s * (g[3 * y + b] - g[3 * x + b]), dc = s * (g[3 * y + c] - g[3 * x + c]);
    return dc < 0 || (dc == 0 && db > 0);
}

static int xs_push(cl_xs *xs, double t, int32_t tri, int32_t s, uint32_t col)
{
    if (xs->n == xs->cap) {
        size_t cap = xs->cap ? 2 * xs->cap : 4096;
        cl_cross *x = realloc(xs->x, cap * sizeof *x);
        if (!x) return -1;
        xs->x = x;
        xs->cap = cap;
    }
    xs->x[xs->n].t = t;
    xs->x[xs->n].tri = tri;
    xs->x[xs->n].s = s;
    xs->x[xs->n].col = col;
    xs->n++;
    return 0;
}

/* The crossings of the lines of voxel centres along axis a with the mesh, sorted by column
 * (j + n_b k over the axes b = a + 1, c = a + 2, cyclically) and along each column by (t, tri). */
static int scan_axis(const cl_mesh *m, const cl_grid *G, int a, cl_xs *xs)
{
    int b = (a + 1) % 3, c = (a + 2) % 3;
    size_t nb = G->n[b], nc = G->n[c], ncol = nb * nc;
    const double *g = G->g;
    xs->n = 0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *v = m->t + 3 * f;
        const double *A = g + 3 * v[0], *B = g + 3 * v[1], *C = g + 3 * v[2];
        double area = (B[b] - A[b]) * (C[c] - A[c]) - (B[c] - A[c]) * (C[b] - A[b]);
        if (area == 0) continue;
        int s = area > 0 ? 1 : -1;
        double bmin = mind(A[b], mind(B[b], C[b])), bmax = maxd(A[b], maxd(B[b], C[b]));
        double cmin = mind(A[c], mind(B[c], C[c])), cmax = maxd(A[c], maxd(B[c], C[c]));
        long jb0 = iceil(bmin), jb1 = ifloor(bmax), jc0 = iceil(cmin), jc1 = ifloor(cmax);
        if (jb0 < 0) jb0 = 0;
        if (jc0 < 0) jc0 = 0;
        if (jb1 > (long)nb - 1) jb1 = (long)nb - 1;
        if (jc1 > (long)nc - 1) jc1 = (long)nc - 1;
        for (long jc = jc0; jc <= jc1; jc++)
            for (long jb = jb0; jb <= jb1; jb++) {
                double pb = (double)jb, pc = (double)jc;
                double f0 = s * edge_fn(g, v[1], v[2], b, c, pb, pc);
                if (f0 < 0 || (f0 == 0 && !edge_tie(g, v[1], v[2], b, c, s))) continue;
                double f1 = s * edge_fn(g, v[2], v[0], b, c, pb, pc);
                if (f1 < 0 || (f1 == 0 && !edge_tie(g, v[2], v[0], b, c, s))) continue;
                double f2 = s * edge_fn(g, v[0], v[1], b, c, pb, pc);
                if (f2 < 0 || (f2 == 0 && !edge_tie(g, v[0], v[1], b, c, s))) continue;
                double sum = f0 + f1 + f2;
                double t = sum > 0 ? (f0 * A[a] + f1 * B[a] + f2 * C[a]) / sum
                                   : (A[a] + B[a] + C[a]) / 3;
                uint32_t col = (uint32_t)((size_t)jb + nb * (size_t)jc);
                if (xs_push(xs, t, (int32_t)f, s, col)) return -1;
            }
    }
    /* counting sort by column, then insertion sort of each column by (t, tri) */
    free(xs->off);
    xs->off = calloc(ncol + 1, sizeof *xs->off);
    cl_cross *tmp = realloc(xs->tmp, (xs->n ? xs->n : 1) * sizeof *tmp);
    if (!xs->off || !tmp) return -1;
    xs->tmp = tmp;
    for (size_t i = 0; i < xs->n; i++) xs->off[xs->x[i].col + 1]++;
    for (size_t i = 0; i < ncol; i++) xs->off[i + 1] += xs->off[i];
    size_t *fill = malloc((ncol ? ncol : 1) * sizeof *fill);
    if (!fill) return -1;
    memcpy(fill, xs->off, ncol * sizeof *fill);
    for (size_t i = 0; i < xs->n; i++) tmp[fill[xs->x[i].col]++] = xs->x[i];
    free(fill);
    memcpy(xs->x, tmp, xs->n * sizeof *tmp);
    for (size_t col = 0; col < ncol; col++) {
        cl_cross *x = xs->x + xs->off[col];
        size_t cnt = xs->off[col + 1] - xs->off[col];
        for (size_t i = 1; i < cnt; i++) {
            cl_cross key = x[i];
            size_t j = i;
            while (j > 0 && (x[j - 1].t > key.t || (x[j - 1].t == key.t && x[j - 1].tri > key.tri))) {
                x[j] = x[j - 1];
                j--;
            }
            x[j] = key;
        }
    }
    return 0;
}

static inline size_t vidx(const cl_grid *G, size_t i, size_t j, size_t k)
{
    return i + G->n[0] * (j + G->n[1] * k);
}

/* Inside centres from the x lines' winding numbers. Returns their count. */
static size_t classify(cl_grid *G, const cl_xs *xs)
{
    size_t nx = G->n[0], ny = G->n[1], nz = G->n[2], count = 0;
    memset(G->inside, 0, G->total);
    for (size_t k = 0; k < nz; k++)
        for (size_t j = 0; j < ny; j++) {
            size_t col = j + ny * k, m = xs->off[col], end = xs->off[col + 1];
            long w = 0;
            for (size_t i = 0; i < nx; i++) {
                while (m < end && xs->x[m].t < (double)i) w -= xs->x[m++].s;
                if (w > 0) {
                    G->inside[vidx(G, i, j, k)] = 1;
                    count++;
                }
            }
        }
    return count;
}

static inline void try_vertex(const cl_mesh *m, cl_grid *G, size_t id, const double p[3],
                              uint32_t v)
{
    double d2 = dist2_3(p, m->v + 3 * (size_t)v);
    if (d2 < G->d2[id] || (d2 == G->d2[id] && (int32_t)v < G->near[id])) {
        G->d2[id] = d2;
        G->near[id] = (int32_t)v;
    }
}

/* Seeds of the nearest-vertex transform: the eight centres around each surface vertex, and
 * the two centres next to each crossing of an x line (its triangle's vertices). */
static void seed_vertices(const cl_mesh *m, cl_grid *G, const cl_xs *xs)
{
    long n0 = (long)G->n[0], n1 = (long)G->n[1], n2 = (long)G->n[2];
    for (size_t v = 0; v < m->nv; v++) {
        if (m->vt_off[v] == m->vt_off[v + 1]) continue; /* a vertex of no triangle */
        const double *g = G->g + 3 * v;
        long i0 = ifloor(g[0]), j0 = ifloor(g[1]), k0 = ifloor(g[2]);
        for (int c = 0; c < 8; c++) {
            long i = i0 + (c & 1), j = j0 + ((c >> 1) & 1), k = k0 + (c >> 2);
            if (i < 0 || j < 0 || k < 0 || i >= n0 || j >= n1 || k >= n2) continue;
            size_t id = vidx(G, (size_t)i, (size_t)j, (size_t)k);
            if (!G->inside[id]) continue;
            double p[3];
            voxel_centre(G, (size_t)i, (size_t)j, (size_t)k, p);
            try_vertex(m, G, id, p, (uint32_t)v);
        }
    }
    for (size_t q = 0; q < xs->n; q++) {
        const cl_cross *x = &xs->x[q];
        size_t j = x->col % G->n[1], k = x->col / G->n[1];
        long fl = ifloor(x->t);
        for (long i = fl; i <= fl + 1; i++) {
            if (i < 0 || i >= n0) continue;
            size_t id = vidx(G, (size_t)i, j, k);
            if (!G->inside[id]) continue;
            double p[3];
            voxel_centre(G, (size_t)i, j, k, p);
            for (int e = 0; e < 3; e++) try_vertex(m, G, id, p, m->t[3 * (size_t)x->tri + e]);
        }
    }
}

/* Nearest-vertex transform: raster sweeps, forward then backward, each inside centre trying
 * the nearest vertices of the 13 neighbours already swept. */
static void sweep(const cl_mesh *m, cl_grid *G, int backward)
{
    size_t nx = G->n[0], ny = G->n[1], nz = G->n[2];
    long off[13];
    int no = 0;
    for (int dk = -1; dk <= 1; dk++)
        for (int dj = -1; dj <= 1; dj++)
            for (int di = -1; di <= 1; di++) {
                if (!(dk < 0 || (dk == 0 && dj < 0) || (dk == 0 && dj == 0 && di < 0))) continue;
                long o = di + (long)nx * (dj + (long)ny * dk);
                off[no++] = backward ? -o : o;
            }
    for (size_t kk = 1; kk + 1 < nz; kk++)
        for (size_t jj = 1; jj + 1 < ny; jj++) {
            size_t j = backward ? ny - 1 - jj : jj, k = backward ? nz - 1 - kk : kk;
            for (size_t ii = 1; ii + 1 < nx; ii++) {
                size_t i = backward ? nx - 1 - ii : ii;
                size_t id = vidx(G, i, j, k);
                if (!G->inside[id]) continue;
                double p[3];
                voxel_centre(G, i, j, k, p);
                int32_t cur = G->near[id];
                for (int q = 0; q < no; q++) {
                    int32_t v = G->near[(size_t)((long)id + off[q])];
                    if (v >= 0 && v != cur) try_vertex(m, G, id, p, (uint32_t)v), cur = G->near[id];
                }
            }
        }
}

/* ------------------------------------------------------------------------------------------ */
/* the sphere fit: the largest ball tangent at p's nearest surface point, centre on its ray     */

/* The triangles nearer than sqrt(r2) to c, into list; returns their count. */
static size_t tree_within(const cl_mesh *m, const double c[3], double r2, uint32_t *list)
{
    int32_t st[CL_STACK];
    int sp = 0;
    size_t n = 0;
    st[sp++] = 0;
    while (sp) {
        const cl_node *nd = &m->nodes[st[--sp]];
        if (box_dist2(nd, c) >= r2) continue;
        if (nd->kid < 0) {
            for (uint32_t i = nd->first; i < nd->first + nd->count; i++)
                if (tri_dist2(&m->geo[m->order[i]], c, NULL) < r2) list[n++] = m->order[i];
            continue;
        }
        if (sp + 2 <= CL_STACK) {
            st[sp++] = nd->kid + 1;
            st[sp++] = nd->kid;
        }
    }
    return n;
}

/* The sphere of a candidate p (internal coordinates): the largest ball tangent to the mesh at
 * q, the nearest surface point to p (found from the triangle `hint` down), with its centre on
 * the ray from q through p, at most R_max = |p - q| + step (and r_cap). The tangent balls B(q + R n, R) are nested, so
 * the triangles that can enter any of them are those that enter the largest: one range query,
 * then shrinking steps on that list (a ball tangent at q shrunk to pass through the nearest
 * listed point to its centre, until none is nearer), each step keeping only the triangles
 * that enter its ball. The ball found is free of the surface; it
 * is kept when it holds p (then its centre lies on p's side: inside), else the ball of p and
 * its exact distance. Returns 0, or -1 when p is on the surface. */
static int fit_sphere(const cl_mesh *m, const double p[3], int32_t hint, double step,
                      double r_cap, uint32_t *list, double c_out[3], double *r_out)
{
    double q[3], n[3];
    int32_t t = hint;
    double d2 = hint >= 0 ? tri_dist2(&m->geo[hint], p, q) : INFINITY;
    d2 = tree_nearest(m, p, d2, &t, q);
    double d = sqrt(d2);
    if (!(d > 0) || t < 0) return -1;
    {
        for (int k = 0; k < 3; k++) n[k] = (p[k] - q[k]) / d;
        double R = mind(d + step, r_cap);
        if (R < d) R = d;
        double c[3] = {q[0] + R * n[0], q[1] + R * n[1], q[2] + R * n[2]};
        size_t nl = tree_within(m, c, R * R, list);
        for (int it = 0; it < CL_FIT_STEPS; it++) {
            double e2 = INFINITY, qq[3] = {0, 0, 0};
            for (int k = 0; k < 3; k++) c[k] = q[k] + R * n[k];
            /* the next ball lies in this one: keep only the triangles that enter it */
            size_t keep = 0;
            for (size_t l = 0; l < nl; l++) {
                double x[3], d2 = tri_dist2(&m->geo[list[l]], c, x);
                if (d2 < e2) e2 = d2, memcpy(qq, x, sizeof qq);
                if (d2 < R * R) list[keep++] = list[l];
            }
            nl = keep;
            double e = sqrt(e2);
            if (e >= R * (1 - CL_FIT_TOL)) {
                /* free: no listed point nearer than R, the others are beyond the largest ball */
                double r = mind(e, R);
                if (fabs(R - d) < r) {
                    memcpy(c_out, c, sizeof c);
                    *r_out = r;
                    return 0;
                }
                break;
            }
            double w[3] = {qq[0] - q[0], qq[1] - q[1], qq[2] - q[2]};
            double wn = dot3(w, n);
            if (!(wn > 0)) break;
            double Rn = dot3(w, w) / (2 * wn);
            if (!(Rn < R)) break;
            R = Rn;
        }
    }
    /* the ball of p */
    memcpy(c_out, p, 3 * sizeof *p);
    *r_out = d;
    return 0;
}

/* The first sphere, (c, r) from fit_sphere, moved up the distance to the surface towards a local
 * maximum (the largest inscribed ball near it): a step s along the mean of the unit vectors from
 * the near surface points (those within r + s / 2 of c) to c; kept when the exact distance grows
 * (then s grows by half), else s halves; from s = step down to 1e-9 r, at most CL_ASCENT tries.
 * The triangles within r + 2 s of c hold the nearest of any point within s of c: listed by a
 * range query after each move, filtered when s halves. A move shorter than r stays in the ball
 * of c, free of the surface, so the centre stays inside. */
static void ascend_sphere(const cl_mesh *m, double step, uint32_t *list, double c[3], double *r)
{
    double s = mind(step, 0.5 * *r), R = *r;
    size_t nl = tree_within(m, c, (R + 2 * s) * (R + 2 * s), list);
    for (int it = 0; it < CL_ASCENT && s > 1e-9 * R; it++) {
        double g[3] = {0, 0, 0}, near = (R + 0.5 * s) * (R + 0.5 * s);
        double reach = (R + 2 * s) * (R + 2 * s);
        size_t keep = 0;
        for (size_t l = 0; l < nl; l++) {
            double q[3], d2 = tri_dist2(&m->geo[list[l]], c, q);
            if (d2 >= reach) continue;
            list[keep++] = list[l];
            if (d2 >= near || !(d2 > 0)) continue;
            double d = sqrt(d2);
            for (int k = 0; k < 3; k++) g[k] += (c[k] - q[k]) / d;
        }
        nl = keep;
        double gn = sqrt(dot3(g, g));
        if (!(gn > 0)) break;
        double x[3] = {c[0] + s * g[0] / gn, c[1] + s * g[1] / gn, c[2] + s * g[2] / gn};
        double e2 = INFINITY;
        for (size_t l = 0; l < nl; l++) e2 = mind(e2, tri_dist2(&m->geo[list[l]], x, NULL));
        double e = sqrt(e2);
        if (e > R) {
            memcpy(c, x, sizeof x);
            R = e;
            s = mind(1.5 * s, 0.5 * R);
            nl = tree_within(m, c, (R + 2 * s) * (R + 2 * s), list);
        } else {
            s *= 0.5;
        }
    }
    *r = R;
}

/* ------------------------------------------------------------------------------------------ */
/* the greedy                                                                                  */

static inline uint32_t popc(uint64_t x)
{
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return (uint32_t)((x * 0x0101010101010101ull) >> 56);
}

/* Marks the centres in the ball (grid units) covered. */
static void ball_clear(cl_grid *G, const double c[3], double rho)
{
    long nx = (long)G->n[0], ny = (long)G->n[1], nz = (long)G->n[2];
    long k0 = iceil(c[2] - rho), k1 = ifloor(c[2] + rho);
    long j0 = iceil(c[1] - rho), j1 = ifloor(c[1] + rho);
    if (k0 < 0) k0 = 0;
    if (k1 > nz - 1) k1 = nz - 1;
    if (j0 < 0) j0 = 0;
    if (j1 > ny - 1) j1 = ny - 1;
    double rr = rho * rho;
    for (long k = k0; k <= k1; k++) {
        double dz = (double)k - c[2], rz = rr - dz * dz;
        if (rz < 0) continue;
        for (long j = j0; j <= j1; j++) {
            double dy = (double)j - c[1], w2 = rz - dy * dy;
            if (w2 < 0) continue;
            double w = sqrt(w2);
            long i0 = iceil(c[0] - w), i1 = ifloor(c[0] + w);
            if (i0 < 0) i0 = 0;
            if (i1 > nx - 1) i1 = nx - 1;
            if (i0 > i1) continue;
            uint64_t *row = G->unc + G->W * ((size_t)j + (size_t)ny * (size_t)k);
            size_t a = (size_t)i0, b = (size_t)i1, wa = a >> 6, wb = b >> 6;
            uint64_t ma = ~0ull << (a & 63), mb = ~0ull >> (63 - (b & 63));
            if (wa == wb) {
                row[wa] &= ~(ma & mb);
            } else {
                row[wa] &= ~ma;
                for (size_t q = wa + 1; q < wb; q++) row[q] = 0;
                row[wb] &= ~mb;
            }
        }
    }
}

/* The uncovered centres within sqrt(s2) (an integer, grid units) of the voxel centre (i, j, k):
 * row (dy, dz) spans dx^2 <= s2 - dy^2 - dz^2, its half-width isq[s2 - dy^2 - dz^2] from a table
 * of integer square roots (isq[s] = floor(sqrt(s)), s <= s2). */
static uint32_t ball_count_at(const cl_grid *G, long i, long j, long k, long s2,
                              const uint16_t *isq)
{
    long nx = (long)G->n[0], ny = (long)G->n[1], nz = (long)G->n[2], r = isq[s2];
    uint32_t cnt = 0;
    for (long dz = -r; dz <= r; dz++) {
        long kk = k + dz, rz = s2 - dz * dz;
        if (kk < 0 || kk >= nz) continue;
        long ry = isq[rz];
        for (long dy = -ry; dy <= ry; dy++) {
            long jj = j + dy;
            if (jj < 0 || jj >= ny) continue;
            long w = isq[rz - dy * dy], i0 = i - w, i1 = i + w;
            if (i0 < 0) i0 = 0;
            if (i1 > nx - 1) i1 = nx - 1;
            const uint64_t *row = G->unc + G->W * ((size_t)jj + (size_t)ny * (size_t)kk);
            size_t a = (size_t)i0, b = (size_t)i1, wa = a >> 6, wb = b >> 6;
            uint64_t ma = ~0ull << (a & 63), mb = ~0ull >> (63 - (b & 63));
            if (wa == wb) {
                cnt += popc(row[wa] & ma & mb);
            } else {
                cnt += popc(row[wa] & ma);
                for (size_t q = wa + 1; q < wb; q++) cnt += popc(row[q]);
                cnt += popc(row[wb] & mb);
            }
        }
    }
    return cnt;
}

typedef struct cl_heap {
    uint32_t *item; /* candidate numbers */
    size_t n;
    const uint32_t *key;
} cl_heap;

/* a before b: larger key, then the lower candidate (= lower voxel index) */
static inline int heap_before(const cl_heap *h, uint32_t a, uint32_t b)
{
    return h->key[a] > h->key[b] || (h->key[a] == h->key[b] && a < b);
}

static void heap_down(cl_heap *h, size_t i)
{
    for (;;) {
        size_t l = 2 * i + 1, r = l + 1, m = i;
        if (l < h->n && heap_before(h, h->item[l], h->item[m])) m = l;
        if (r < h->n && heap_before(h, h->item[r], h->item[m])) m = r;
        if (m == i) return;
        uint32_t x = h->item[i];
        h->item[i] = h->item[m];
        h->item[m] = x;
        i = m;
    }
}

static void heap_pop(cl_heap *h)
{
    h->item[0] = h->item[--h->n];
    if (h->n) heap_down(h, 0);
}

/* ------------------------------------------------------------------------------------------ */
/* the union: lines along x on a square grid in (y, z), the union of the chords exact          */

typedef struct cl_iv {
    double a, b;
} cl_iv;

static int iv_cmp(const void *x, const void *y)
{
    const cl_iv *p = x, *q = y;
    return (p->a > q->a) - (p->a < q->a);
}

/* by start; the union of the intervals does not depend on the order of equal starts */
static void iv_sort(cl_iv *v, size_t n)
{
    if (n > 32) {
        qsort(v, n, sizeof *v, iv_cmp);
        return;
    }
    for (size_t i = 1; i < n; i++) {
        cl_iv k = v[i];
        size_t j = i;
        while (j > 0 && v[j - 1].a > k.a) {
            v[j] = v[j - 1];
            j--;
        }
        v[j] = k;
    }
}

/* moments of a ball about o, added to (V, S, Q): Q = xx yy zz xy xz yz */
static void add_ball(const gp_clump3d_sphere *b, const double o[3], double *V, double S[3],
                     double Q[6])
{
    static const int P[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    double r = b->r, v = 4.0 / 3.0 * CL_PI * r * r * r, q = 0.2 * v * r * r;
    double a[3] = {b->x - o[0], b->y - o[1], b->z - o[2]};
    *V += v;
    for (int k = 0; k < 3; k++) S[k] += a[k] * v;
    for (int k = 0; k < 6; k++) Q[k] += a[P[k][0]] * a[P[k][1]] * v + (k < 3 ? q : 0);
}

gp_status gp_clump3d_union(const gp_clump3d_sphere *s, size_t n, gp_clump3d_body *body,
                           gp_error *err)
{
    if (!body) return gp_error_set(err, GP_ERR_INVALID, "clump3d: body is NULL");
    memset(body, 0, sizeof *body);
    if (n == 0) return GP_OK;
    if (!s) return gp_error_set(err, GP_ERR_INVALID, "clump3d: spheres is NULL with n = %zu", n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(s[i].x) || !isfinite(s[i].y) || !isfinite(s[i].z) || !isfinite(s[i].r))
            return gp_error_set(err, GP_ERR_INVALID, "clump3d: sphere %zu is not finite", i);
        if (s[i].r < 0)
            return gp_error_set(err, GP_ERR_INVALID, "clump3d: sphere %zu has r < 0", i);
    }
    /* per ball: 0 skipped (r = 0, the same ball as an earlier one, inside another ball),
     * 1 alone (overlaps no kept ball: exact), 2 on the grid */
    uint8_t *kind = malloc(n);
    size_t *list = malloc(n * sizeof *list);
    cl_iv *iv = NULL;
    size_t *cnt = NULL, *act = NULL;
    if (!kind || !list) goto nomem;
    double o[3] = {0, 0, 0};
    size_t kept = 0;
    for (size_t i = 0; i < n; i++) {
        kind[i] = s[i].r > 0;
        for (size_t j = 0; j < n && kind[i]; j++) {
            if (j == i || s[j].r == 0) continue;
            double dc = sqrt((s[i].x - s[j].x) * (s[i].x - s[j].x) +
                             (s[i].y - s[j].y) * (s[i].y - s[j].y) +
                             (s[i].z - s[j].z) * (s[i].z - s[j].z));
            double tol = CL_SAME * maxd(s[i].r, s[j].r);
            int same = dc <= tol && fabs(s[i].r - s[j].r) <= tol;
            if (same ? j < i : dc + s[i].r <= s[j].r) kind[i] = 0;
        }
        if (kind[i]) {
            o[0] += s[i].x, o[1] += s[i].y, o[2] += s[i].z;
            kept++;
        }
    }
    if (!kept) goto done;
    for (int k = 0; k < 3; k++) o[k] /= (double)kept;
    double V = 0, S[3] = {0, 0, 0}, Q[6] = {0, 0, 0, 0, 0, 0};
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t ng = 0;
    for (size_t i = 0; i < n; i++) {
        if (!kind[i]) continue;
        for (size_t j = 0; j < n && kind[i] == 1; j++) {
            if (j == i || !kind[j]) continue;
            double dx = s[i].x - s[j].x, dy = s[i].y - s[j].y, dz = s[i].z - s[j].z;
            double rs = s[i].r + s[j].r;
            if (dx * dx + dy * dy + dz * dz < rs * rs) kind[i] = 2;
        }
        if (kind[i] == 1) {
            add_ball(&s[i], o, &V, S, Q);
            continue;
        }
        list[ng++] = i;
        double c[3] = {s[i].x, s[i].y, s[i].z};
        for (int k = 0; k < 3; k++) {
            lo[k] = mind(lo[k], c[k] - s[i].r);
            hi[k] = maxd(hi[k], c[k] + s[i].r);
        }
    }
    if (ng) {
        /* lines at the centres of square cells of side w over the grid balls' box in (y, z) */
        double w = maxd(hi[1] - lo[1], hi[2] - lo[2]) / CL_LINES;
        size_t ny = (size_t)ceil((hi[1] - lo[1]) / w), nz = (size_t)ceil((hi[2] - lo[2]) / w);
        if (ny < 1) ny = 1;
        if (nz < 1) nz = 1;
        double y0 = 0.5 * (lo[1] + hi[1]) - 0.5 * w * (double)ny;
        double z0 = 0.5 * (lo[2] + hi[2]) - 0.5 * w * (double)nz;
        size_t cap = 0;
        cnt = calloc(ny + 1, sizeof *cnt);
        act = malloc(ng * sizeof *act);
        if (!cnt || !act) goto nomem;
        double v = 0, s1[3] = {0, 0, 0}, s2[6] = {0, 0, 0, 0, 0, 0}, w12 = w * w / 12;
        for (size_t b = 0; b < nz; b++) {
            double z = z0 + w * ((double)b + 0.5);
            size_t na = 0;
            for (size_t q = 0; q < ng; q++) {
                const gp_clump3d_sphere *sp = &s[list[q]];
                if (fabs(z - sp->z) < sp->r) act[na++] = list[q];
            }
            if (!na) continue;
            /* two passes over the row's balls: count the chords of each line, then place them */
            memset(cnt, 0, (ny + 1) * sizeof *cnt);
            for (int pass = 0; pass < 2; pass++) {
                for (size_t q = 0; q < na; q++) {
                    const gp_clump3d_sphere *sp = &s[act[q]];
                    double dz = z - sp->z, rr = sp->r * sp->r - dz * dz;
                    if (!(rr > 0)) continue;
                    double rho = sqrt(rr);
                    long a0 = iceil((sp->y - rho - y0) / w - 0.5);
                    long a1 = ifloor((sp->y + rho - y0) / w - 0.5);
                    if (a0 < 0) a0 = 0;
                    if (a1 > (long)ny - 1) a1 = (long)ny - 1;
                    for (long a = a0; a <= a1; a++) {
                        double dy = y0 + w * ((double)a + 0.5) - sp->y, h2 = rr - dy * dy;
                        if (!(h2 > 0)) continue;
                        size_t at = (size_t)a;
                        if (pass == 0) {
                            cnt[at + 1]++;
                        } else {
                            double hw = sqrt(h2);
                            iv[cnt[at]].a = sp->x - hw - o[0];
                            iv[cnt[at]++].b = sp->x + hw - o[0];
                        }
                    }
                }
                if (pass == 0) {
                    for (size_t a = 0; a < ny; a++) cnt[a + 1] += cnt[a];
                    if (cnt[ny] > cap) {
                        cl_iv *x = realloc(iv, cnt[ny] * sizeof *iv);
                        if (!x) goto nomem;
                        iv = x;
                        cap = cnt[ny];
                    }
                }
            }
            /* after the second pass cnt[a] is the end of line a's chords, cnt[a - 1] (or 0)
             * their start */
            double zr = z - o[2];
            for (size_t a = 0; a < ny; a++) {
                size_t from = a ? cnt[a - 1] : 0, to = cnt[a];
                if (from == to) continue;
                cl_iv *x = iv + from;
                size_t m = to - from;
                iv_sort(x, m);
                double m0 = 0, m1 = 0, m2 = 0, ca = x[0].a, cb = x[0].b;
                for (size_t q = 1; q <= m; q++) {
                    if (q < m && x[q].a <= cb) {
                        if (x[q].b > cb) cb = x[q].b;
                        continue;
                    }
                    m0 += cb - ca;
                    m1 += 0.5 * (cb * cb - ca * ca);
                    m2 += (cb * cb * cb - ca * ca * ca) / 3;
                    if (q < m) ca = x[q].a, cb = x[q].b;
                }
                double yr = y0 + w * ((double)a + 0.5) - o[1];
                v += m0;
                s1[0] += m1;
                s1[1] += yr * m0;
                s1[2] += zr * m0;
                s2[0] += m2;
                s2[1] += (yr * yr + w12) * m0;
                s2[2] += (zr * zr + w12) * m0;
                s2[3] += yr * m1;
                s2[4] += zr * m1;
                s2[5] += yr * zr * m0;
            }
        }
        double ww = w * w;
        V += v * ww;
        for (int k = 0; k < 3; k++) S[k] += s1[k] * ww;
        for (int k = 0; k < 6; k++) Q[k] += s2[k] * ww;
    }
    body_from_moments(V, S, Q, o, body);
done:
    free(kind);
    free(list);
    free(iv);
    free(cnt);
    free(act);
    return GP_OK;
nomem:
    free(kind);
    free(list);
    free(iv);
    free(cnt);
    free(act);
    return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
}

/* ------------------------------------------------------------------------------------------ */
/* figures of merit                                                                            */

/* Eigenvalues (ascending) and unit eigenvectors (the columns of E, row-major) of a symmetric
 * 3 x 3 tensor (gp_mesh3d's cyclic Jacobi). */
static void eigen3(const double I[9], double lam[3], double E[9])
{
    double vec[3][3];
    gp_mesh3d_eigen_sym3(I, lam, vec);
    for (int k = 0; k < 3; k++)
        for (int r = 0; r < 3; r++) E[3 * r + k] = vec[k][r];
}

void gp_clump3d_compare(const gp_clump3d_body *body, const gp_clump3d_body *ref,
                        double *volume_error, double *inertia_error,
                        double *inertia_shape_error, double *centroid_offset)
{
    double ve = NAN, ie = NAN, se = NAN, co = NAN;
    if (body && ref && ref->volume > 0) {
        double lb[3], lr[3], dn = 0, ds = 0, nr = 0;
        double E[9];
        eigen3(body->inertia, lb, E);
        eigen3(ref->inertia, lr, E);
        double sc = body->volume > 0 ? ref->volume / body->volume : NAN;
        for (int k = 0; k < 3; k++) {
            dn += (lb[k] - lr[k]) * (lb[k] - lr[k]);
            ds += (sc * lb[k] - lr[k]) * (sc * lb[k] - lr[k]);
            nr += lr[k] * lr[k];
        }
        ve = (body->volume - ref->volume) / ref->volume;
        ie = nr > 0 ? sqrt(dn / nr) : NAN;
        se = nr > 0 ? sqrt(ds / nr) : NAN;
        double req = cbrt(3 * ref->volume / (4 * CL_PI));
        co = sqrt(dist2_3(body->centroid, ref->centroid)) / req;
    }
    if (volume_error) *volume_error = ve;
    if (inertia_error) *inertia_error = ie;
    if (inertia_shape_error) *inertia_shape_error = se;
    if (centroid_offset) *centroid_offset = co;
}

/* ------------------------------------------------------------------------------------------ */
/* the build                                                                                   */

void gp_clump3d_params_defaults(gp_clump3d_params *p)
{
    if (!p) return;
    p->spheres_max = 30;
    p->min_radius_ratio = 0.1;
    p->voxels = 0;
}

void gp_clump3d_result_free(gp_clump3d_result *r)
{
    if (!r) return;
    free(r->spheres);
    memset(r, 0, sizeof *r);
}

static gp_status check_params(const gp_clump3d_params *p, gp_error *err)
{
    if (p->spheres_max < 1 || p->spheres_max > CL_MAX_SPHERES)
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: spheres_max = %zu, need 1 .. %d",
                            p->spheres_max, CL_MAX_SPHERES);
    if (!(p->min_radius_ratio > 0 && p->min_radius_ratio <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: min_radius_ratio = %g, need (0, 1]",
                            p->min_radius_ratio);
    if (p->voxels != 0 && (p->voxels < CL_MIN_VOXELS || p->voxels > CL_MAX_VOXELS))
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: voxels = %zu, need 0 or %d .. %d",
                            p->voxels, CL_MIN_VOXELS, CL_MAX_VOXELS);
    return GP_OK;
}

static gp_status check_grain(const gp_clump3d_body *g, double vmesh, gp_error *err)
{
    int fin = isfinite(g->volume);
    for (int k = 0; k < 3; k++) fin &= isfinite(g->centroid[k]);
    for (int k = 0; k < 9; k++) fin &= isfinite(g->inertia[k]);
    if (!fin) return gp_error_set(err, GP_ERR_INVALID, "clump3d: grain has a value not finite");
    if (!(g->volume > 0))
        return gp_error_set(err, GP_ERR_INVALID, "clump3d: grain volume = %g, need > 0", g->volume);
    if (fabs(g->volume - vmesh) > 1e-6 * vmesh)
        return gp_error_set(err, GP_ERR_INVALID,
                            "clump3d: grain volume = %.9g differs from the mesh's %.9g", g->volume,
                            vmesh);
    return GP_OK;
}

/* The greedy of the header's steps 4-6 on a ready grid; spheres in internal coordinates. */
static gp_status greedy(const cl_mesh *m, cl_grid *G, const gp_clump3d_params *par,
                        gp_clump3d_result *out, gp_error *err)
{
    size_t nx = G->n[0], ny = G->n[1];
    double h = G->h, *dt = NULL;
    uint32_t *cand = NULL, *key = NULL, *item = NULL, *list = NULL, *lat = NULL;
    uint16_t *isq = NULL;
    size_t nlat = 0;
    int32_t *stamp = NULL, *ctri = NULL;
    double *crad = NULL;
    gp_status st = GP_OK;
    dt = malloc(G->total * sizeof *dt);
    if (!dt) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    double dmax = 0;
    for (size_t id = 0; id < G->total; id++) {
        dt[id] = G->inside[id] ? sqrt(G->d2[id]) : -1;
        if (dt[id] > dmax) dmax = dt[id];
    }
    /* candidates: medial centres */
    long noff[26];
    double nlen[26];
    int no = 0;
    for (int dk = -1; dk <= 1; dk++)
        for (int dj = -1; dj <= 1; dj++)
            for (int di = -1; di <= 1; di++) {
                if (!di && !dj && !dk) continue;
                noff[no] = di + (long)nx * (dj + (long)ny * dk);
                nlen[no++] = CL_RIDGE * h * sqrt((double)(di * di + dj * dj + dk * dk));
            }
    size_t nc = 0;
    uint8_t *med = G->inside; /* inside is not needed any more: it becomes "medial" */
    for (size_t id = 0; id < G->total; id++) {
        if (!(dt[id] > 0)) {
            med[id] = 0;
            continue;
        }
        int is = 1;
        for (int q = 0; q < no && is; q++) {
            double dq = dt[(size_t)((long)id + noff[q])];
            if (dq - dt[id] >= nlen[q]) is = 0;
        }
        med[id] = (uint8_t)is;
        nc += (size_t)is;
    }
    out->candidates = nc;
    if (nc == 0) {
        free(dt);
        return gp_error_set(err, GP_ERR_DEGENERATE, "clump3d: no voxel centre inside the grain");
    }
    cand = malloc(nc * sizeof *cand);
    key = malloc(nc * sizeof *key);
    item = malloc(nc * sizeof *item);
    stamp = malloc(nc * sizeof *stamp);
    crad = malloc(nc * sizeof *crad);
    ctri = malloc(nc * sizeof *ctri);
    list = malloc(m->nt * sizeof *list);
    out->spheres = malloc(par->spheres_max * sizeof *out->spheres);
    if (!cand || !key || !item || !stamp || !crad || !ctri || !list || !out->spheres) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* lat[s]: the lattice points within sqrt(s) of a lattice point, the gain of a ball of
     * radius^2 in [s, s + 1) (grid units) about a voxel centre before anything is covered: the
     * keys the heap starts from */
    nlat = (size_t)ifloor(dmax * dmax / (h * h)) + 2;
    lat = calloc(nlat, sizeof *lat);
    isq = malloc(nlat * sizeof *isq); /* nlat < 2^16: dmax / h < (grid voxels)^(1/3) / 2 */
    if (!lat || !isq) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto done;
    }
    {
        long L = ifloor(sqrt((double)nlat)) + 1;
        for (long k = -L; k <= L; k++)
            for (long j = -L; j <= L; j++)
                for (long i = -L; i <= L; i++) {
                    size_t q = (size_t)(i * i + j * j + k * k);
                    if (q < nlat) lat[q]++;
                }
        for (size_t q = 1; q < nlat; q++) lat[q] += lat[q - 1];
        for (size_t q = 0, r = 0; q < nlat; q++) {
            while ((r + 1) * (r + 1) <= q) r++;
            isq[q] = (uint16_t)r;
        }
    }
    {
        size_t c = 0;
        for (size_t id = 0; id < G->total; id++) {
            if (!med[id]) continue;
            /* the candidate's radius: the exact distance to the triangles around its nearest
             * vertex (still >= the distance to the surface) */
            size_t i = id % nx, j = (id / nx) % ny, k = id / (nx * ny);
            double p[3], best = G->d2[id];
            int32_t bt = -1;
            voxel_centre(G, i, j, k, p);
            if (G->near[id] >= 0) {
                uint32_t v = (uint32_t)G->near[id];
                for (size_t e = m->vt_off[v]; e < m->vt_off[v + 1]; e++) {
                    double d2 = tri_dist2(&m->geo[m->vt_tri[e]], p, NULL);
                    if (bt < 0 || d2 < best) best = d2, bt = (int32_t)m->vt_tri[e];
                }
            }
            crad[c] = sqrt(best);
            ctri[c] = bt;
            double rho = crad[c] / h;
            size_t s2 = (size_t)ifloor(rho * rho);
            cand[c] = (uint32_t)id;
            key[c] = lat[s2 < nlat ? s2 : nlat - 1];
            stamp[c] = -1;
            item[c] = (uint32_t)c;
            c++;
        }
    }
    cl_heap H = {item, nc, key};
    for (size_t i = nc / 2; i-- > 0;) heap_down(&H, i);
    double r1 = 0, ratio = par->min_radius_ratio;
    double rcap = dmax + 0.8660254037844387 * h; /* no inscribed ball is larger */
    size_t ns = 0;
    while (H.n && ns < par->spheres_max) {
        uint32_t c = H.item[0];
        if (key[c] == 0) break;
        size_t id = cand[c];
        if (stamp[c] != (int32_t)ns) {
            if (ns > 0 && crad[c] < ratio * r1) {
                heap_pop(&H);
                continue;
            }
            size_t i = id % nx, j = (id / nx) % ny, k = id / (nx * ny);
            double rr = crad[c] / h;
            key[c] = ball_count_at(G, (long)i, (long)j, (long)k, ifloor(rr * rr), isq);
            stamp[c] = (int32_t)ns;
            if (key[c] == 0) heap_pop(&H);
            else heap_down(&H, 0);
            continue;
        }
        heap_pop(&H);
        size_t i = id % nx, j = (id / nx) % ny, k = id / (nx * ny);
        double p[3], cs[3], r;
        voxel_centre(G, i, j, k, p);
        if (fit_sphere(m, p, ctri[c], h, rcap, list, cs, &r)) continue;
        if (ns == 0) ascend_sphere(m, 0.5 * h, list, cs, &r);
        r *= CL_SHRINK;
        if (ns == 0) {
            r1 = r;
        } else {
            if (r > r1) r = r1;
            if (r < ratio * r1) continue;
        }
        gp_clump3d_sphere *sp = &out->spheres[ns++];
        sp->x = cs[0], sp->y = cs[1], sp->z = cs[2], sp->r = r;
        double cg[3] = {(cs[0] - G->o[0]) / h, (cs[1] - G->o[1]) / h, (cs[2] - G->o[2]) / h};
        ball_clear(G, cg, r / h);
        /* a counted gain stays exact when the candidate's ball misses the new sphere */
        for (size_t q = 0; q < H.n; q++) {
            uint32_t e = H.item[q];
            if (stamp[e] != (int32_t)ns - 1) continue;
            size_t ie = cand[e];
            double dx = (double)(ie % nx) - cg[0], dy = (double)((ie / nx) % ny) - cg[1];
            double dz = (double)(ie / (nx * ny)) - cg[2], reach = crad[e] / h + r / h + 1e-9;
            if (dx * dx + dy * dy + dz * dz > reach * reach) stamp[e] = (int32_t)ns;
        }
    }
    out->nspheres = ns;
    out->capped = ns == par->spheres_max && H.n > 0 && key[H.item[0]] > 0;
done:
    free(dt);
    free(cand);
    free(key);
    free(item);
    free(stamp);
    free(crad);
    free(ctri);
    free(list);
    free(lat);
    free(isq);
    return st;
}

gp_status gp_clump3d_build(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                           const gp_clump3d_body *grain, const gp_clump3d_params *params,
                           gp_clump3d_result *out, gp_error *err)
{
    if (!out) return gp_error_set(err, GP_ERR_INVALID, "clump3d: out is NULL");
    memset(out, 0, sizeof *out);
    gp_clump3d_params par;
    gp_clump3d_params_defaults(&par);
    if (params) par = *params;
    gp_status st = check_params(&par, err);
    if (st) return st;
    st = check_arrays(xyz, nv, tri, nt, err);
    if (st) return st;

    cl_mesh M;
    cl_grid G;
    cl_xs xs;
    memset(&M, 0, sizeof M);
    memset(&G, 0, sizeof G);
    memset(&xs, 0, sizeof xs);
    size_t bad = 0;
    int rc = check_closed(tri, nv, nt, &bad);
    if (rc < 0) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    if (rc == 1)
        return gp_error_set(err, GP_ERR_INVALID,
                            "clump3d: tri: a directed edge from vertex %zu occurs twice (not "
                            "manifold or not consistently oriented)", bad);
    if (rc == 2)
        return gp_error_set(err, GP_ERR_INVALID,
                            "clump3d: tri: an edge from vertex %zu has no reverse (mesh not closed "
                            "or not consistently oriented)", bad);

    double lo[3], hi[3], shift[3], diag = 0, R[9];
    for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t f = 0; f < 3 * nt; f++)
        for (int k = 0; k < 3; k++) {
            lo[k] = mind(lo[k], xyz[3 * tri[f] + k]);
            hi[k] = maxd(hi[k], xyz[3 * tri[f] + k]);
        }
    for (int k = 0; k < 3; k++) {
        shift[k] = 0.5 * (lo[k] + hi[k]);
        diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    diag = sqrt(diag);
    M.nv = nv;
    M.nt = nt;
    M.t = tri;
    M.v = malloc(3 * nv * sizeof *M.v);
    if (!M.v) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto fail;
    }
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) M.v[3 * i + k] = xyz[3 * i + k] - shift[k];
    double vol;
    {
        double zero[3] = {0, 0, 0}, s1[3], s2[6];
        mesh_moments(M.v, tri, nt, zero, &vol, s1, s2);
        if (!(fabs(vol) > 1e-12 * diag * diag * diag)) {
            st = gp_error_set(err, GP_ERR_DEGENERATE,
                              "clump3d: the mesh encloses no volume (V = %g, box diagonal %g)", vol,
                              diag);
            goto fail;
        }
        if (vol < 0) {
            st = gp_error_set(err, GP_ERR_INVALID,
                              "clump3d: tri: the triangles are clockwise seen from outside "
                              "(volume %g < 0)", vol);
            goto fail;
        }
        body_from_moments(vol, s1, s2, shift, &out->grain);
        /* the principal frame: internal coordinates are R^T (x - centroid), R's columns the
         * mesh's principal axes, the longest first, each turned so that the vertices' third
         * moment along it is >= 0 (the frame turns with the grain), the third their cross
         * product */
        double lam[3], g[3];
        eigen3(out->grain.inertia, lam, R);
        for (int k = 0; k < 3; k++) g[k] = out->grain.centroid[k] - shift[k];
        for (int a = 0; a < 2; a++) {
            double m3 = 0;
            for (size_t i = 0; i < nv; i++) {
                double u = 0;
                for (int k = 0; k < 3; k++) u += (M.v[3 * i + k] - g[k]) * R[3 * k + a];
                m3 += u * u * u;
            }
            if (m3 < 0)
                for (int k = 0; k < 3; k++) R[3 * k + a] = -R[3 * k + a];
        }
        R[2] = R[3] * R[7] - R[6] * R[4];
        R[5] = R[6] * R[1] - R[0] * R[7];
        R[8] = R[0] * R[4] - R[3] * R[1];
        for (int k = 0; k < 3; k++) shift[k] = out->grain.centroid[k];
        for (size_t i = 0; i < nv; i++) {
            double x[3];
            for (int k = 0; k < 3; k++) x[k] = xyz[3 * i + k] - shift[k];
            for (int a = 0; a < 3; a++)
                M.v[3 * i + a] = R[a] * x[0] + R[3 + a] * x[1] + R[6 + a] * x[2];
        }
        for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
        for (size_t f = 0; f < 3 * nt; f++)
            for (int k = 0; k < 3; k++) {
                lo[k] = mind(lo[k], M.v[3 * tri[f] + k]);
                hi[k] = maxd(hi[k], M.v[3 * tri[f] + k]);
            }
        if (grain) {
            st = check_grain(grain, vol, err);
            if (st) goto fail;
            out->grain = *grain;
        }
    }

    /* the grid */
    {
        size_t target = par.voxels ? par.voxels : CL_DEFAULT_VOXELS;
        double h = cbrt(vol / (double)target);
        double box = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        double hb = cbrt(box / ((double)CL_BOX_FACTOR * (double)target));
        if (hb > h) h = hb;
        size_t m3[3];
        for (;;) {
            double tot = 1;
            for (int k = 0; k < 3; k++) {
                double mk = ceil((hi[k] - lo[k]) / h);
                if (mk < 1) mk = 1;
                m3[k] = (size_t)mk;
                tot *= mk + 2;
            }
            if (tot <= (double)CL_BOX_FACTOR * (double)target) break;
            h *= 1.02;
        }
        G.h = h;
        G.total = 1;
        for (int k = 0; k < 3; k++) {
            G.n[k] = m3[k] + 2;
            G.o[k] = 0.5 * (lo[k] + hi[k]) - h * 0.5 * (double)(m3[k] + 1);
            G.total *= G.n[k];
        }
        G.W = (G.n[0] + 63) / 64;
        G.g = malloc(3 * nv * sizeof *G.g);
        G.inside = malloc(G.total);
        G.d2 = malloc(G.total * sizeof *G.d2);
        G.near = malloc(G.total * sizeof *G.near);
        G.unc = calloc(G.W * G.n[1] * G.n[2], sizeof *G.unc);
        M.geo = malloc(nt * sizeof *M.geo);
        if (!G.g || !G.inside || !G.d2 || !G.near || !G.unc || !M.geo || tree_build(&M) ||
            vertex_triangles(&M)) {
            st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
            goto fail;
        }
        for (size_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++) G.g[3 * i + k] = (M.v[3 * i + k] - G.o[k]) / h;
        for (size_t f = 0; f < nt; f++)
            tri_set(&M.geo[f], M.v + 3 * tri[3 * f], M.v + 3 * tri[3 * f + 1],
                    M.v + 3 * tri[3 * f + 2]);
        for (size_t id = 0; id < G.total; id++) G.d2[id] = INFINITY, G.near[id] = -1;
    }
    if (scan_axis(&M, &G, 0, &xs)) {
        st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        goto fail;
    }
    out->voxels_inside = classify(&G, &xs);
    if (out->voxels_inside == 0) {
        st = gp_error_set(err, GP_ERR_DEGENERATE,
                          "clump3d: the grain is too thin for a voxel centre inside (h = %g)", G.h);
        goto fail;
    }
    seed_vertices(&M, &G, &xs);
    for (int s = 0; s < CL_SWEEPS; s++) sweep(&M, &G, s & 1);
    for (size_t id = 0; id < G.total; id++) {
        if (!G.inside[id] || G.near[id] >= 0) continue;
        /* not reached (a pocket the sweeps missed): the nearest triangle's nearest vertex */
        size_t i = id % G.n[0], j = (id / G.n[0]) % G.n[1], k = id / (G.n[0] * G.n[1]);
        double p[3];
        int32_t t = -1;
        voxel_centre(&G, i, j, k, p);
        tree_nearest(&M, p, INFINITY, &t, NULL);
        for (int e = 0; e < 3 && t >= 0; e++) try_vertex(&M, &G, id, p, tri[3 * (size_t)t + e]);
    }
    for (size_t k = 0; k < G.n[2]; k++)
        for (size_t j = 0; j < G.n[1]; j++)
            for (size_t i = 0; i < G.n[0]; i++)
                if (G.inside[vidx(&G, i, j, k)])
                    G.unc[G.W * (j + G.n[1] * k) + (i >> 6)] |= 1ull << (i & 63);
    st = greedy(&M, &G, &par, out, err);
    if (st) goto fail;
    if (out->nspheres == 0) {
        st = gp_error_set(err, GP_ERR_DEGENERATE, "clump3d: no sphere fits inside the grain");
        goto fail;
    }
    {
        size_t left = 0;
        for (size_t q = 0; q < G.W * G.n[1] * G.n[2]; q++) left += popc(G.unc[q]);
        out->covered = 1.0 - (double)left / (double)out->voxels_inside;
    }
    out->voxel = G.h;
    out->r_max = 0;
    out->r_min = INFINITY;
    /* the union measured in the principal frame (so its figures do not depend on how the
     * grain is turned), then turned back */
    st = gp_clump3d_union(out->spheres, out->nspheres, &out->clump, err);
    if (st) goto fail;
    {
        gp_clump3d_body *b = &out->clump;
        double c[3] = {b->centroid[0], b->centroid[1], b->centroid[2]}, RI[9];
        for (int i = 0; i < 3; i++)
            b->centroid[i] = shift[i] + R[3 * i] * c[0] + R[3 * i + 1] * c[1] + R[3 * i + 2] * c[2];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                RI[3 * i + j] = R[3 * i] * b->inertia[j] + R[3 * i + 1] * b->inertia[3 + j] +
                                R[3 * i + 2] * b->inertia[6 + j];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                b->inertia[3 * i + j] = RI[3 * i] * R[3 * j] + RI[3 * i + 1] * R[3 * j + 1] +
                                        RI[3 * i + 2] * R[3 * j + 2];
    }
    for (size_t q = 0; q < out->nspheres; q++) {
        gp_clump3d_sphere *sp = &out->spheres[q];
        double c[3] = {sp->x, sp->y, sp->z};
        sp->x = shift[0] + R[0] * c[0] + R[1] * c[1] + R[2] * c[2];
        sp->y = shift[1] + R[3] * c[0] + R[4] * c[1] + R[5] * c[2];
        sp->z = shift[2] + R[6] * c[0] + R[7] * c[1] + R[8] * c[2];
        out->r_max = maxd(out->r_max, sp->r);
        out->r_min = mind(out->r_min, sp->r);
    }
    gp_clump3d_compare(&out->clump, &out->grain, &out->volume_error, &out->inertia_error,
                       &out->inertia_shape_error, &out->centroid_offset);
    mesh_free(&M);
    grid_free(&G);
    free(xs.x);
    free(xs.tmp);
    free(xs.off);
    return GP_OK;
fail:
    mesh_free(&M);
    grid_free(&G);
    free(xs.x);
    free(xs.tmp);
    free(xs.off);
    gp_clump3d_result_free(out);
    return st;
}
