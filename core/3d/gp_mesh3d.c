/* gp_mesh3d.c -- closed triangle meshes. See gp_mesh3d.h.
 *
 * Layout: the mesh object and its check, the icosphere, mass properties, the 3 x 3
 * eigensolver and the principal axes, the convex hull (exact predicates on a snapped grid).
 */
#include "gp_mesh3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct gp_mesh3d {
    size_t nv, nt;
    double *xyz;
    uint32_t *tri;
};

/* ------------------------------------------------------------------------------------------ */
/* the object                                                                                  */

static gp_mesh3d *mesh_alloc(size_t nv, size_t nt, gp_error *err)
{
    gp_mesh3d *m = calloc(1, sizeof *m);
    if (m) {
        m->xyz = malloc(3 * nv * sizeof(double));
        m->tri = malloc(3 * nt * sizeof(uint32_t));
    }
    if (!m || !m->xyz || !m->tri) {
        gp_mesh3d_destroy(m);
        gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        return NULL;
    }
    m->nv = nv;
    m->nt = nt;
    return m;
}

void gp_mesh3d_destroy(gp_mesh3d *m)
{
    if (!m) return;
    free(m->xyz);
    free(m->tri);
    free(m);
}

size_t gp_mesh3d_vertex_count(const gp_mesh3d *m) { return m ? m->nv : 0; }
size_t gp_mesh3d_triangle_count(const gp_mesh3d *m) { return m ? m->nt : 0; }
const double *gp_mesh3d_vertices(const gp_mesh3d *m) { return m ? m->xyz : NULL; }
const uint32_t *gp_mesh3d_triangles(const gp_mesh3d *m) { return m ? m->tri : NULL; }

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

static gp_status check_indices(size_t nv, const uint32_t *tri, size_t nt, gp_error *err)
{
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *v = tri + 3 * t;
        if (v[0] >= nv || v[1] >= nv || v[2] >= nv)
            return gp_error_set(err, GP_ERR_INVALID, "triangle %zu has an index >= %zu", t, nv);
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
            return gp_error_set(err, GP_ERR_INVALID, "triangle %zu repeats a vertex", t);
    }
    return GP_OK;
}

gp_status gp_mesh3d_check(size_t nv, const uint32_t *tri, size_t nt, gp_error *err)
{
    if (!tri || nt < 4) return gp_error_set(err, GP_ERR_INVALID, "a closed mesh needs >= 4 triangles");
    gp_status st = check_indices(nv, tri, nt, err);
    if (st) return st;
    uint64_t *e = malloc(3 * nt * sizeof *e);
    if (!e) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++)
            e[3 * t + k] = (uint64_t)tri[3 * t + k] << 32 | tri[3 * t + (k + 1) % 3];
    qsort(e, 3 * nt, sizeof *e, cmp_u64);
    st = GP_OK;
    for (size_t k = 0; k < 3 * nt && !st; k++) {
        uint64_t rev = e[k] << 32 | e[k] >> 32;
        if (k + 1 < 3 * nt && e[k + 1] == e[k])
            st = gp_error_set(err, GP_ERR_INVALID, "edge (%u, %u) is used twice in one direction",
                              (unsigned)(e[k] >> 32), (unsigned)e[k]);
        else if (!bsearch(&rev, e, 3 * nt, sizeof *e, cmp_u64))
            st = gp_error_set(err, GP_ERR_INVALID, "edge (%u, %u) has no reverse: the mesh is not closed",
                              (unsigned)(e[k] >> 32), (unsigned)e[k]);
    }
    free(e);
    return st;
}

gp_mesh3d *gp_mesh3d_create(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                            gp_error *err)
{
    if (!xyz || nv < 4 || nv > UINT32_MAX) {
        gp_error_set(err, GP_ERR_INVALID, "a closed mesh needs 4 .. 2^32 - 1 vertices");
        return NULL;
    }
    for (size_t i = 0; i < 3 * nv; i++)
        if (!isfinite(xyz[i])) {
            gp_error_set(err, GP_ERR_INVALID, "vertex %zu is not finite", i / 3);
            return NULL;
        }
    if (gp_mesh3d_check(nv, tri, nt, err)) return NULL;
    gp_mesh3d *m = mesh_alloc(nv, nt, err);
    if (!m) return NULL;
    memcpy(m->xyz, xyz, 3 * nv * sizeof(double));
    memcpy(m->tri, tri, 3 * nt * sizeof(uint32_t));
    return m;
}

/* ------------------------------------------------------------------------------------------ */
/* the icosphere                                                                               */

/* Open-addressing map from an undirected edge to its midpoint vertex. */
typedef struct edge_map {
    uint64_t *key; /* (lo << 32 | hi) + 1, 0 = empty */
    uint32_t *val;
    size_t mask;
} edge_map;

static uint32_t midpoint(edge_map *em, gp_mesh3d *m, uint32_t a, uint32_t b)
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    uint64_t key = ((uint64_t)lo << 32 | hi) + 1;
    size_t h = (size_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & em->mask;
    while (em->key[h] && em->key[h] != key) h = (h + 1) & em->mask;
    if (em->key[h]) return em->val[h];
    const double *p = m->xyz + 3 * (size_t)a, *q = m->xyz + 3 * (size_t)b;
    double x = p[0] + q[0], y = p[1] + q[1], z = p[2] + q[2];
    double s = 1.0 / sqrt(x * x + y * y + z * z);
    uint32_t v = (uint32_t)m->nv++;
    m->xyz[3 * (size_t)v] = x * s;
    m->xyz[3 * (size_t)v + 1] = y * s;
    m->xyz[3 * (size_t)v + 2] = z * s;
    em->key[h] = key;
    em->val[h] = v;
    return v;
}

static void icosahedron(gp_mesh3d *m)
{
    static const double P = 1.6180339887498948482;
    static const double v[12][3] = {
        {-1, P, 0}, {1, P, 0}, {-1, -P, 0}, {1, -P, 0}, {0, -1, P}, {0, 1, P},
        {0, -1, -P}, {0, 1, -P}, {P, 0, -1}, {P, 0, 1}, {-P, 0, -1}, {-P, 0, 1}};
    static const uint32_t t[20][3] = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    double s = 1.0 / sqrt(1.0 + P * P);
    for (int i = 0; i < 12; i++)
        for (int k = 0; k < 3; k++) m->xyz[3 * i + k] = v[i][k] * s;
    memcpy(m->tri, t, sizeof t);
    m->nv = 12;
    m->nt = 20;
}

/* One subdivision of m's nt triangles into out (room for 4 nt), new vertices appended to m. */
static void subdivide(gp_mesh3d *m, edge_map *em, uint32_t *out)
{
    for (size_t t = 0; t < m->nt; t++) {
        uint32_t a = m->tri[3 * t], b = m->tri[3 * t + 1], c = m->tri[3 * t + 2];
        uint32_t ab = midpoint(em, m, a, b), bc = midpoint(em, m, b, c), ca = midpoint(em, m, c, a);
        uint32_t q[12] = {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca};
        memcpy(out + 12 * t, q, sizeof q);
    }
}

gp_mesh3d *gp_mesh3d_icosphere(unsigned level, gp_error *err)
{
    if (level > GP_MESH3D_ICOSPHERE_LEVEL_MAX) {
        gp_error_set(err, GP_ERR_INVALID, "icosphere level %u > %d", level, GP_MESH3D_ICOSPHERE_LEVEL_MAX);
        return NULL;
    }
    size_t p4 = (size_t)1 << (2 * level), nv = 10 * p4 + 2, nt = 20 * p4;
    gp_mesh3d *m = mesh_alloc(nv, nt, err);
    edge_map em = {0};
    size_t cap = 1;
    while (cap < 4 * nt) cap <<= 1; /* > 2.6 x the 1.5 nt edges of the last level */
    uint32_t *next = m ? malloc(3 * nt * sizeof *next) : NULL;
    em.key = next ? calloc(cap, sizeof *em.key) : NULL;
    em.val = em.key ? malloc(cap * sizeof *em.val) : NULL;
    em.mask = cap - 1;
    if (m && !em.val) gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    if (m && em.val) {
        icosahedron(m);
        for (unsigned l = 0; l < level; l++) {
            subdivide(m, &em, next);
            m->nt *= 4;
            uint32_t *sw = m->tri;
            m->tri = next;
            next = sw;
        }
    }
    free(next);
    free(em.key);
    free(em.val);
    if (m && !em.val) {
        gp_mesh3d_destroy(m);
        return NULL;
    }
    return m;
}

/* ------------------------------------------------------------------------------------------ */
/* mass properties                                                                             */

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static gp_status mass_check(const double *xyz, size_t nv, const uint32_t *tri, size_t nt,
                            gp_error *err)
{
    if (!xyz || !tri || nv < 4 || nt < 4)
        return gp_error_set(err, GP_ERR_INVALID, "a closed mesh needs >= 4 vertices and triangles");
    for (size_t i = 0; i < 3 * nv; i++)
        if (!isfinite(xyz[i])) return gp_error_set(err, GP_ERR_INVALID, "vertex %zu is not finite", i / 3);
    for (size_t i = 0; i < 3 * nt; i++)
        if (tri[i] >= nv) return gp_error_set(err, GP_ERR_INVALID, "triangle %zu has an index >= %zu", i / 3, nv);
    return GP_OK;
}

/* Sums over the tetrahedra (ref, a, b, c): 6 V, 24 first moment, 120 second moment, 2 area. */
static void mass_sums(const double *xyz, const uint32_t *tri, size_t nt, const double ref[3],
                      double *v6, double s1[3], double s2[9], double *a2)
{
    for (size_t t = 0; t < nt; t++) {
        double p[3][3], s[3], bc[3], e1[3], e2[3], n[3];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) p[j][k] = xyz[3 * (size_t)tri[3 * t + j] + k] - ref[k];
        cross3(p[1], p[2], bc);
        double d = dot3(p[0], bc);
        for (int k = 0; k < 3; k++) {
            s[k] = p[0][k] + p[1][k] + p[2][k];
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        *v6 += d;
        for (int i = 0; i < 3; i++) {
            s1[i] += d * s[i];
            for (int j = i; j < 3; j++)
                s2[3 * i + j] += d * (p[0][i] * p[0][j] + p[1][i] * p[1][j] + p[2][i] * p[2][j] + s[i] * s[j]);
        }
        cross3(e1, e2, n);
        *a2 += sqrt(dot3(n, n));
    }
}

gp_status gp_mesh3d_mass_properties(const double *xyz, size_t nv, const uint32_t *tri,
                                    size_t nt, gp_mesh3d_mass *out, gp_error *err)
{
    gp_status st = mass_check(xyz, nv, tri, nt, err);
    if (st) return st;
    double ref[3] = {0, 0, 0}, v6 = 0, s1[3] = {0, 0, 0}, s2[9] = {0}, a2 = 0;
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) ref[k] += xyz[3 * i + k];
    for (int k = 0; k < 3; k++) ref[k] /= (double)nv;
    mass_sums(xyz, tri, nt, ref, &v6, s1, s2, &a2);
    double V = v6 / 6.0;
    if (!(V > 0) || !isfinite(V))
        return gp_error_set(err, GP_ERR_DEGENERATE, "the mesh encloses no positive volume (%g): inside out or flat", V);
    double g[3], M[9];
    for (int k = 0; k < 3; k++) g[k] = s1[k] / 24.0 / V;
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++) {
            M[3 * i + j] = s2[3 * i + j] / 120.0 - V * g[i] * g[j];
            M[3 * j + i] = M[3 * i + j];
        }
    double tr = M[0] + M[4] + M[8];
    for (int i = 0; i < 9; i++) out->inertia[i] = (i % 4 == 0 ? tr : 0.0) - M[i];
    for (int k = 0; k < 3; k++) out->centroid[k] = ref[k] + g[k];
    out->volume = V;
    out->area = 0.5 * a2;
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* eigen-decomposition and principal axes                                                      */

/* One Jacobi rotation zeroing a[p][q] (a symmetric, v the accumulated rotation, rows = vectors'
 * components: v[k][j] is component k of vector j). */
static void jacobi_rotate(double a[3][3], double v[3][3], int p, int q)
{
    if (a[p][q] == 0.0) return;
    double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
    double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
    double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
    for (int k = 0; k < 3; k++) { /* columns p, q of a R */
        double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
    }
    for (int k = 0; k < 3; k++) { /* rows p, q of R^T (a R) */
        double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
    }
    a[p][q] = a[q][p] = 0.0;
    for (int k = 0; k < 3; k++) {
        double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
    }
}

void gp_mesh3d_eigen_sym3(const double m[9], double values[3], double vectors[3][3])
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) a[i][j] = j >= i ? m[3 * i + j] : m[3 * j + i];
    for (int sweep = 0; sweep < 64; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off == 0.0 || off <= 1e-18 * diag) break;
        jacobi_rotate(a, v, 0, 1);
        jacobi_rotate(a, v, 0, 2);
        jacobi_rotate(a, v, 1, 2);
    }
    int idx[3] = {0, 1, 2};
    for (int i = 1; i < 3; i++) /* insertion sort, increasing values, stable */
        for (int j = i; j > 0 && a[idx[j]][idx[j]] < a[idx[j - 1]][idx[j - 1]]; j--) {
            int t = idx[j];
            idx[j] = idx[j - 1];
            idx[j - 1] = t;
        }
    for (int j = 0; j < 3; j++) {
        values[j] = a[idx[j]][idx[j]];
        for (int k = 0; k < 3; k++) vectors[j][k] = v[k][idx[j]];
    }
}

/* Flips u so that its component of largest magnitude (the first such) is positive. */
static void orient_axis(double u[3])
{
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(u[i]) > fabs(u[k])) k = i;
    if (u[k] < 0)
        for (int i = 0; i < 3; i++) u[i] = -u[i];
}

gp_status gp_mesh3d_principal_axes(const double *xyz, size_t nv, const gp_mesh3d_mass *mass,
                                   gp_mesh3d_axes *out, gp_error *err)
{
    if (!xyz || nv == 0 || !mass) return gp_error_set(err, GP_ERR_INVALID, "no points or no mass properties");
    for (int i = 0; i < 9; i++)
        if (!isfinite(mass->inertia[i])) return gp_error_set(err, GP_ERR_INVALID, "inertia not finite");
    double val[3], vec[3][3], lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    gp_mesh3d_eigen_sym3(mass->inertia, val, vec);
    for (size_t i = 0; i < nv; i++) {
        double r[3] = {xyz[3 * i] - mass->centroid[0], xyz[3 * i + 1] - mass->centroid[1],
                       xyz[3 * i + 2] - mass->centroid[2]};
        for (int j = 0; j < 3; j++) {
            double s = dot3(r, vec[j]);
            lo[j] = s < lo[j] ? s : lo[j];
            hi[j] = s > hi[j] ? s : hi[j];
        }
    }
    if (!isfinite(hi[0] - lo[0]) || !isfinite(hi[1] - lo[1]) || !isfinite(hi[2] - lo[2]))
        return gp_error_set(err, GP_ERR_INVALID, "a point is not finite");
    int idx[3] = {0, 1, 2};
    for (int i = 1; i < 3; i++) /* decreasing extent, stable (ties: smaller moment first) */
        for (int j = i; j > 0 && hi[idx[j]] - lo[idx[j]] > hi[idx[j - 1]] - lo[idx[j - 1]]; j--) {
            int t = idx[j];
            idx[j] = idx[j - 1];
            idx[j - 1] = t;
        }
    for (int j = 0; j < 3; j++) {
        out->extent[j] = hi[idx[j]] - lo[idx[j]];
        out->moment[j] = val[idx[j]];
        memcpy(out->axis[j], vec[idx[j]], sizeof out->axis[j]);
    }
    orient_axis(out->axis[0]);
    orient_axis(out->axis[1]);
    cross3(out->axis[0], out->axis[1], out->axis[2]);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* convex hull                                                                                 */

__extension__ typedef __int128 i128;

#define HULL_GRID 1099511627776.0 /* 2^40: the grid's coordinates are below it */
#define HULL_FILTER 2e-15         /* > 7 2^-53: the floating-point orientation's error bound */

/* A face; its slot is reused once the face is gone. */
typedef struct hface {
    double nd[3];   /* the exact normal n = (q1 - q0) x (q2 - q0) on the grid, outward, rounded */
    double off;     /* nd . q0 */
    double bound;   /* the filter's error bound for any grid point (orient_face) */
    uint32_t v[3];  /* counter-clockwise seen from outside */
    int32_t nb[3];  /* the face across edge (v[k], v[k + 1]) */
    int32_t head;   /* first point of its conflict list, -1 when empty */
    uint32_t mark;  /* == the hull's stamp when visible from the current eye */
    int32_t alive;
} hface;

typedef struct hull {
    size_t n;
    const double *p;      /* the caller's points */
    int64_t *q;           /* snapped, 3 per point */
    double *qd;           /* the same as doubles (exact: below 2^41) */
    int32_t *next;        /* conflict lists */
    double *dist;         /* a point's height above its face (for the farthest) */
    int32_t *start, *end; /* per vertex: the new face whose horizon edge starts / ends there */
    uint32_t *seen;       /* per vertex: the stamp of the last horizon it started an edge of */
    hface *f;
    int32_t *freef;       /* free face slots (capacity fcap) */
    size_t nf, fcap, nfree;
    int32_t *todo;        /* faces that were given conflict points (some gone since) */
    size_t ntodo, tcap;
    int32_t *stack, *vis, *cone, *pend; /* scratch (pend: n) */
    size_t scap;
    uint32_t stamp;
    double ref[3];        /* a point inside: the mean of the first simplex */
} hull;

static void exact_normal(const hull *h, const uint32_t v[3], i128 n[3])
{
    const int64_t *a = h->q + 3 * (size_t)v[0], *b = h->q + 3 * (size_t)v[1], *c = h->q + 3 * (size_t)v[2];
    int64_t u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = (i128)u[1] * w[2] - (i128)u[2] * w[1];
    n[1] = (i128)u[2] * w[0] - (i128)u[0] * w[2];
    n[2] = (i128)u[0] * w[1] - (i128)u[1] * w[0];
}

/* n (|n| < 2^84: a normal's component) to a double, within half an ulp: its two halves are
 * exact doubles (the high one below 2^52), added with one rounding. */
static double i128_to_double(i128 n)
{
    return (double)(int64_t)(n >> 32) * 4294967296.0 + (double)(int64_t)(n & 0xffffffff);
}

/* Any n to a double of the same sign (an orientation, |n| < 2^124). */
static double i128_sign_double(i128 n)
{
    unsigned __int128 m = n < 0 ? -(unsigned __int128)n : (unsigned __int128)n;
    double d = (double)(uint64_t)(m >> 64) * 18446744073709551616.0 + (double)(uint64_t)m;
    return n < 0 ? -d : d;
}

/* Exact orientation of point i against the plane of v (|n| < 2^82, |q - a| <= 2^40: the sum
 * stays below 2^124). */
static i128 orient_exact(const hull *h, const uint32_t v[3], size_t i)
{
    i128 n[3];
    exact_normal(h, v, n);
    const int64_t *a = h->q + 3 * (size_t)v[0], *p = h->q + 3 * i;
    return n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) + n[2] * (p[2] - a[2]);
}

/* Point i's height above face f's plane (times |n|), as a double whose sign is always right:
 * the floating-point value nd . q_i - nd . q0 when its error bound proves the sign (the
 * coordinates are exact doubles below 2^40, nd is within half an ulp of n: the error is below
 * 7 2^-53 (sum |nd_k| 2^40 + sum |nd_k q0_k|), f->bound), the exact 128-bit value otherwise. */
static double orient_face(const hull *h, const hface *f, size_t i)
{
    const double *p = h->qd + 3 * i;
    double o = f->nd[0] * p[0] + f->nd[1] * p[1] + f->nd[2] * p[2] - f->off;
    if (fabs(o) > f->bound) return o;
    return i128_sign_double(orient_exact(h, f->v, i));
}

static void face_normal(const hull *h, hface *f)
{
    i128 n[3];
    exact_normal(h, f->v, n);
    const double *a = h->qd + 3 * (size_t)f->v[0];
    double offabs = 0, nabs = 0;
    f->off = 0;
    for (int k = 0; k < 3; k++) {
        f->nd[k] = i128_to_double(n[k]);
        f->off += f->nd[k] * a[k];
        offabs += fabs(f->nd[k] * a[k]);
        nabs += fabs(f->nd[k]);
    }
    f->bound = HULL_FILTER * (nabs * HULL_GRID + offabs);
}

/* A new face (a, b, c) in a free slot or a new one; its index, or -1 when out of memory. */
static int32_t add_face(hull *h, uint32_t a, uint32_t b, uint32_t c)
{
    if (!h->nfree && h->nf == h->fcap) {
        size_t cap = h->fcap ? 2 * h->fcap : 64;
        if (cap > INT32_MAX) return -1;
        hface *nf = realloc(h->f, cap * sizeof *nf);
        if (nf) h->f = nf;
        int32_t *fr = realloc(h->freef, cap * sizeof *fr);
        if (fr) h->freef = fr;
        if (!nf || !fr) return -1;
        h->fcap = cap;
    }
    int32_t id = h->nfree ? h->freef[--h->nfree] : (int32_t)h->nf++;
    hface *f = h->f + id;
    f->v[0] = a;
    f->v[1] = b;
    f->v[2] = c;
    f->nb[0] = f->nb[1] = f->nb[2] = -1;
    f->head = -1;
    f->mark = 0;
    f->alive = 1;
    face_normal(h, f);
    return id;
}

static int push_todo(hull *h, int32_t fi)
{
    if (h->ntodo == h->tcap) {
        size_t cap = h->tcap ? 2 * h->tcap : 64;
        int32_t *t = realloc(h->todo, cap * sizeof *t);
        if (!t) return 0;
        h->todo = t;
        h->tcap = cap;
    }
    h->todo[h->ntodo++] = fi;
    return 1;
}

/* Puts point i on the first face of faces[0 .. nfaces-1] it lies strictly above (or drops it:
 * it is inside). 0 when out of memory. */
static int assign(hull *h, size_t i, const int32_t *faces, size_t nfaces)
{
    for (size_t k = 0; k < nfaces; k++) {
        hface *f = h->f + faces[k];
        double o = orient_face(h, f, i);
        if (o > 0) {
            if (f->head < 0 && !push_todo(h, faces[k])) return 0;
            h->dist[i] = o;
            h->next[i] = f->head;
            f->head = (int32_t)i;
            return 1;
        }
    }
    return 1;
}

/* Snaps the points to the grid; 0 when they are all the same point. */
static int snap_points(hull *h)
{
    double lo[3], hi[3], ext = 0;
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = h->p[k];
    for (size_t i = 1; i < h->n; i++)
        for (int k = 0; k < 3; k++) {
            double x = h->p[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (int k = 0; k < 3; k++) ext = hi[k] - lo[k] > ext ? hi[k] - lo[k] : ext;
    if (!(ext > 0)) return 0;
    int e;
    frexp(ext, &e); /* ext < 2^e: a power-of-two scale keeps exact coordinates exact */
    double scale = ldexp(1.0, 40 - e);
    for (size_t i = 0; i < h->n; i++)
        for (int k = 0; k < 3; k++) {
            h->q[3 * i + k] = (int64_t)llround((h->p[3 * i + k] - lo[k]) * scale);
            h->qd[3 * i + k] = (double)h->q[3 * i + k];
        }
    return 1;
}

static double sq_len_cross(const hull *h, size_t i0, size_t i1, size_t i)
{
    uint32_t v[3] = {(uint32_t)i0, (uint32_t)i1, (uint32_t)i};
    i128 n[3];
    exact_normal(h, v, n);
    double x = i128_to_double(n[0]), y = i128_to_double(n[1]), z = i128_to_double(n[2]);
    return x * x + y * y + z * z;
}

/* Four points not coplanar on the grid into t; 0 when there are none. */
static int initial_simplex(hull *h, size_t t[4])
{
    const int64_t *q = h->q;
    size_t i0 = 0, i1 = 0, i2 = 0, i3 = 0;
    for (size_t i = 1; i < h->n; i++)
        if (q[3 * i] < q[3 * i0]) i0 = i;
    i128 best = 0;
    for (size_t i = 0; i < h->n; i++) {
        i128 d = 0;
        for (int k = 0; k < 3; k++) d += (i128)(q[3 * i + k] - q[3 * i0 + k]) * (q[3 * i + k] - q[3 * i0 + k]);
        if (d > best) best = d, i1 = i;
    }
    if (best == 0) return 0;
    double bd = 0;
    for (size_t i = 0; i < h->n; i++) {
        double d = sq_len_cross(h, i0, i1, i);
        if (d > bd) bd = d, i2 = i;
    }
    if (bd == 0) return 0;
    uint32_t v[3] = {(uint32_t)i0, (uint32_t)i1, (uint32_t)i2};
    best = 0;
    for (size_t i = 0; i < h->n; i++) {
        i128 o = orient_exact(h, v, i);
        if (o < 0) o = -o;
        if (o > best) best = o, i3 = i;
    }
    if (best == 0) return 0;
    t[0] = i0, t[1] = i1, t[2] = i2, t[3] = i3;
    return 1;
}

/* Links face a's edge (u, v) to the face b holding (v, u). */
static void link_faces(hull *h, int32_t a, int32_t b)
{
    hface *fa = h->f + a, *fb = h->f + b;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (fa->v[i] == fb->v[(j + 1) % 3] && fa->v[(i + 1) % 3] == fb->v[j]) {
                fa->nb[i] = b;
                fb->nb[j] = a;
            }
}

/* The simplex t as four outward faces, every other point on the first face it is above. */
static int build_simplex(hull *h, const size_t t[4])
{
    static const int fv[4][4] = {{0, 1, 2, 3}, {0, 3, 1, 2}, {1, 3, 2, 0}, {0, 2, 3, 1}};
    int32_t id[4];
    for (int k = 0; k < 4; k++) {
        uint32_t a = (uint32_t)t[fv[k][0]], b = (uint32_t)t[fv[k][1]], c = (uint32_t)t[fv[k][2]];
        if ((id[k] = add_face(h, a, b, c)) < 0) return 0;
        if (orient_face(h, h->f + id[k], t[fv[k][3]]) > 0) { /* the fourth point must be below */
            hface *f = h->f + id[k];
            f->v[1] = c;
            f->v[2] = b;
            face_normal(h, f);
        }
        for (int j = 0; j < 3; j++) h->ref[j] += 0.25 * h->p[3 * t[k] + j];
    }
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++) link_faces(h, id[a], id[b]);
    for (size_t i = 0; i < h->n; i++)
        if (i != t[0] && i != t[1] && i != t[2] && i != t[3] && !assign(h, i, id, 4)) return 0;
    return 1;
}

static int grow_scratch(hull *h, size_t need)
{
    if (need <= h->scap) return 1;
    size_t cap = 2 * need;
    int32_t *a = realloc(h->stack, cap * sizeof *a);
    if (a) h->stack = a;
    int32_t *b = realloc(h->vis, cap * sizeof *b);
    if (b) h->vis = b;
    int32_t *c = realloc(h->cone, cap * sizeof *c);
    if (c) h->cone = c;
    if (!a || !b || !c) return 0;
    h->scap = cap;
    return 1;
}

/* The faces visible from eye (strictly), from face f0 across edges: into h->vis; their count,
 * or -1 when out of memory. */
static long visible_faces(hull *h, int32_t f0, size_t eye)
{
    size_t nvis = 0, top = 0;
    h->stamp++;
    h->f[f0].mark = h->stamp;
    h->stack[top++] = f0;
    while (top) {
        int32_t fi = h->stack[--top];
        if (!grow_scratch(h, nvis + top + 4)) return -1;
        h->vis[nvis++] = fi;
        for (int k = 0; k < 3; k++) {
            hface *g = h->f + h->f[fi].nb[k];
            if (g->mark != h->stamp && orient_face(h, g, eye) > 0) {
                g->mark = h->stamp;
                h->stack[top++] = h->f[fi].nb[k];
            }
        }
    }
    return (long)nvis;
}

/* The fan from eye to the horizon of the visible faces (still in place); the new faces'
 * indices in h->cone[0 .. *nnew - 1]. 1, 0 out of memory, -1 a broken horizon. */
static int make_cone(hull *h, size_t nvis, size_t eye, size_t *nnew)
{
    static const int next3[3] = {1, 2, 0};
    size_t cnt = 0;
    for (size_t k = 0; k < nvis; k++) {
        int32_t fi = h->vis[k];
        for (int e = 0; e < 3; e++) {
            int32_t gi = h->f[fi].nb[e];
            if (h->f[gi].mark == h->stamp) continue;
            uint32_t a = h->f[fi].v[e], b = h->f[fi].v[next3[e]];
            if (h->seen[a] == h->stamp) return -1; /* a vertex twice on the horizon */
            h->seen[a] = h->stamp;
            int32_t ni = add_face(h, a, b, (uint32_t)eye);
            if (ni < 0 || !grow_scratch(h, cnt + 1)) return 0;
            hface *g = h->f + gi;
            for (int j = 0; j < 3; j++)
                if (g->nb[j] == fi) g->nb[j] = ni;
            h->f[ni].nb[0] = gi;
            h->start[a] = ni;
            h->end[b] = ni;
            h->cone[cnt++] = ni;
        }
    }
    for (size_t k = 0; k < cnt; k++) {
        hface *f = h->f + h->cone[k];
        if (h->seen[f->v[1]] != h->stamp) return -1; /* the horizon is not closed */
        f->nb[1] = h->start[f->v[1]];
        f->nb[2] = h->end[f->v[0]];
    }
    *nnew = cnt;
    return 1;
}

/* Adds the farthest point of face f0's conflict list. 1 done, 0 out of memory, -1 broken. */
static int add_point(hull *h, int32_t f0)
{
    size_t eye = (size_t)h->f[f0].head;
    for (int32_t i = h->f[f0].head; i >= 0; i = h->next[i])
        if (h->dist[i] > h->dist[eye]) eye = (size_t)i;
    long nvis = visible_faces(h, f0, eye);
    if (nvis < 0) return 0;
    size_t npend = 0;
    for (long k = 0; k < nvis; k++) { /* their points, but the eye, wait for the new faces */
        hface *f = h->f + h->vis[k];
        for (int32_t i = f->head; i >= 0; i = h->next[i])
            if ((size_t)i != eye) h->pend[npend++] = i;
        f->head = -1;
    }
    size_t nnew = 0;
    int r = make_cone(h, (size_t)nvis, eye, &nnew);
    if (r <= 0) return r;
    for (size_t k = 0; k < npend; k++)
        if (!assign(h, (size_t)h->pend[k], h->cone, nnew)) return 0;
    for (long k = 0; k < nvis; k++) { /* the visible faces go; their slots are free */
        h->f[h->vis[k]].alive = 0;
        h->freef[h->nfree++] = h->vis[k];
    }
    return 1;
}

static void hull_free(hull *h)
{
    free(h->q);
    free(h->qd);
    free(h->next);
    free(h->dist);
    free(h->start);
    free(h->end);
    free(h->seen);
    free(h->f);
    free(h->freef);
    free(h->todo);
    free(h->stack);
    free(h->vis);
    free(h->cone);
    free(h->pend);
}

/* Builds the hull of pts into h. GP_OK with faces, or GP_OK with h->nf == 0 for a flat or
 * empty hull; else an error. The caller frees h with hull_free() in every case. */
static gp_status hull_build(hull *h, const double *pts, size_t n, gp_error *err)
{
    memset(h, 0, sizeof *h);
    if (n && !pts) return gp_error_set(err, GP_ERR_INVALID, "no points");
    if (n > INT32_MAX) return gp_error_set(err, GP_ERR_INVALID, "too many points (%zu)", n);
    for (size_t i = 0; i < 3 * n; i++)
        if (!isfinite(pts[i])) return gp_error_set(err, GP_ERR_INVALID, "point %zu is not finite", i / 3);
    h->n = n;
    h->p = pts;
    if (n < 4) return GP_OK;
    h->q = malloc(3 * n * sizeof *h->q);
    h->qd = malloc(3 * n * sizeof *h->qd);
    h->next = malloc(n * sizeof *h->next);
    h->dist = malloc(n * sizeof *h->dist);
    h->start = malloc(n * sizeof *h->start);
    h->end = malloc(n * sizeof *h->end);
    h->seen = calloc(n, sizeof *h->seen);
    h->pend = malloc(n * sizeof *h->pend);
    if (!h->q || !h->qd || !h->next || !h->dist || !h->start || !h->end || !h->seen || !h->pend || !grow_scratch(h, 64))
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    size_t t[4];
    if (!snap_points(h) || !initial_simplex(h, t)) return GP_OK;
    if (!build_simplex(h, t)) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    while (h->ntodo) {
        int32_t fi = h->todo[--h->ntodo];
        if (!h->f[fi].alive || h->f[fi].head < 0) continue; /* gone, or its slot reused */
        int r = add_point(h, fi);
        if (r == 0) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        if (r < 0) return gp_error_set(err, GP_ERR_INTERNAL, "convex hull: the horizon is not a simple loop");
    }
    return GP_OK;
}

gp_status gp_mesh3d_hull_volume(const double *pts, size_t n, double *volume, gp_error *err)
{
    hull h;
    gp_status st = hull_build(&h, pts, n, err);
    double v6 = 0;
    for (size_t fi = 0; !st && fi < h.nf; fi++) {
        if (!h.f[fi].alive) continue;
        double p[3][3], bc[3];
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) p[j][k] = pts[3 * (size_t)h.f[fi].v[j] + k] - h.ref[k];
        cross3(p[1], p[2], bc);
        v6 += dot3(p[0], bc);
    }
    hull_free(&h);
    if (!st && volume) *volume = v6 / 6.0;
    return st;
}

gp_mesh3d *gp_mesh3d_hull(const double *pts, size_t n, gp_error *err)
{
    hull h;
    gp_mesh3d *m = NULL;
    gp_status st = hull_build(&h, pts, n, err);
    if (!st && !h.nf) gp_error_set(err, GP_ERR_DEGENERATE, "the points' convex hull is flat or empty");
    size_t nt = 0, nv = 0;
    for (size_t fi = 0; !st && fi < h.nf; fi++) nt += h.f[fi].alive != 0;
    if (!st && nt) m = mesh_alloc(n, nt, err);
    if (m) {
        int32_t *id = h.start; /* reused: the point -> hull vertex map */
        for (size_t i = 0; i < n; i++) id[i] = -1;
        size_t t = 0;
        for (size_t fi = 0; fi < h.nf; fi++) {
            if (!h.f[fi].alive) continue;
            for (int k = 0; k < 3; k++) {
                uint32_t v = h.f[fi].v[k];
                if (id[v] < 0) {
                    id[v] = (int32_t)nv;
                    memcpy(m->xyz + 3 * nv++, pts + 3 * (size_t)v, 3 * sizeof(double));
                }
                m->tri[3 * t + k] = (uint32_t)id[v];
            }
            t++;
        }
        m->nv = nv;
    }
    hull_free(&h);
    return m;
}
