/* gp_rings.c -- see gp_rings.h.
 *
 * The sweep. Events are the vertices in (x, y) order; at a vertex, the edges of its ring that
 * start there (their left end) go into the sweep line's status, each tested against its new
 * neighbours, then the edges that end there go out, their two neighbours tested against each
 * other. The status is a treap of edges ordered bottom to top at the sweep line, with the
 * order decided exactly (gp_orient2d); an edge inserted at a point that lies on another edge
 * goes by its direction. Two vertices at one point are a touch at once. The first pair found
 * is the fault; the pair does not depend on the treap's shape, only on the order of the edges.
 *
 * Containment. When the first edge of a ring's leftmost vertex goes in, the edge right below
 * it tells what lies below the ring: nothing (the ring is in no other), or the interior of the
 * ring of that edge or of that ring's parent, by the edge's direction and its ring's
 * orientation. Since no two rings meet (else the sweep stops first), the parent of every ring is
 * settled by the time it is used.
 */
#include "gp_rings.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define SW_NIL UINT32_MAX

/* a < b in the sweep order: by x, then by y */
static int lex_less(gp_vec2 a, gp_vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
static int same_point(gp_vec2 a, gp_vec2 b) { return a.x == b.x && a.y == b.y; }

typedef struct sw_edge {
    gp_vec2 l, r;               /* endpoints, l before r in the sweep order */
    uint32_t ring, i;           /* ring index, edge from vertex i to vertex i + 1 of that ring */
    uint32_t lc, rc, up, prio;  /* the sweep line's status: a treap ordered bottom to top */
} sw_edge;

typedef struct sw_vertex {
    double x, y;
    uint32_t edge;              /* the edge that starts at this vertex (global index) */
} sw_vertex;

/* sw_build puts the arrays of size_t and long right after the edges and the events */
_Static_assert(sizeof(sw_edge) % _Alignof(size_t) == 0 &&
                   sizeof(sw_vertex) % _Alignof(size_t) == 0 && _Alignof(long) <= sizeof(size_t),
               "the sweep's block keeps its arrays aligned");

typedef struct sweep {
    const gp_ring_ref *rings;
    size_t nr, ne;
    void *block;                /* one allocation for the arrays below */
    size_t *first;              /* global index of each ring's edge 0 */
    size_t *minv;               /* each ring's leftmost vertex */
    signed char *ccw;           /* each ring's orientation at its leftmost vertex */
    long *parent;               /* the innermost ring containing each ring (-1: none) */
    sw_edge *e;
    sw_vertex *v;               /* 2 ne: the events, then the sort's scratch */
    uint32_t root;
    uint32_t bad_a, bad_b;      /* the first pair that shares a point it must not */
} sweep;

static int vertex_before(const sw_vertex *u, const sw_vertex *v)
{
    return u->x < v->x || (u->x == v->x && u->y < v->y);
}

/* sorts v[0..n) into the sweep order (a bottom-up merge sort, tmp of n items: qsort's calls
 * through a pointer would be a large share of the whole check; docs/design/geometry.md) */
static void sort_vertices(sw_vertex *v, sw_vertex *tmp, size_t n)
{
    sw_vertex *a = v, *b = tmp;
    for (size_t w = 1; w < n; w *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * w) {
            size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi) b[k++] = vertex_before(&a[j], &a[i]) ? a[j++] : a[i++];
            while (i < mid) b[k++] = a[i++];
            while (j < hi) b[k++] = a[j++];
        }
        sw_vertex *t = a;
        a = b;
        b = t;
    }
    if (a != v) memcpy(v, a, n * sizeof *v);
}

/* the vertices of a ring edge: from a to b */
static gp_vec2 edge_from(const sweep *s, uint32_t g)
{
    return s->rings[s->e[g].ring].pts[s->e[g].i];
}

static gp_vec2 edge_to(const sweep *s, uint32_t g)
{
    const gp_ring_ref *r = &s->rings[s->e[g].ring];
    return r->pts[(s->e[g].i + 1) % r->n];
}

/* g then h are consecutive edges of one ring (h starts where g ends) */
static int follows(const sweep *s, uint32_t g, uint32_t h)
{
    const sw_edge *a = &s->e[g], *b = &s->e[h];
    return a->ring == b->ring && (a->i + 1) % s->rings[a->ring].n == b->i;
}

/* sign of each coordinate of q - v: exact, since a difference of doubles rounds to zero only
 * when it is zero */
static int same_direction(gp_vec2 v, gp_vec2 a, gp_vec2 b)
{
    double ax = a.x - v.x, ay = a.y - v.y, bx = b.x - v.x, by = b.y - v.y;
    if (ax != 0) return (ax > 0) == (bx > 0) && bx != 0;
    return (ay > 0) == (by > 0) && by != 0;
}

/* edges g and h share a point they must not: consecutive edges (which share their common
 * vertex) only when they fold back onto each other (collinear and overlapping); any other two
 * when the closed segments meet */
static int pair_bad(const sweep *s, uint32_t g, uint32_t h)
{
    if (follows(s, h, g)) {
        uint32_t t = g;
        g = h;
        h = t;
    }
    if (follows(s, g, h)) {
        gp_vec2 v = edge_to(s, g), a = edge_from(s, g), b = edge_to(s, h);
        return gp_orient2d(v, a, b) == 0 && same_direction(v, a, b);
    }
    return gp_segments_intersect(s->e[g].l, s->e[g].r, s->e[h].l, s->e[h].r);
}

static int sw_check(sweep *s, uint32_t g, uint32_t h)
{
    if (g == SW_NIL || h == SW_NIL || !pair_bad(s, g, h)) return 0;
    s->bad_a = g;
    s->bad_b = h;
    return 1;
}

/* b, being inserted at its left end, lies above t (in the tree) on the sweep line. When b starts
 * on t (the common vertex of consecutive edges, or a touch that the neighbour test reports), b
 * goes by its direction. */
static int sw_above(const sweep *s, uint32_t b, uint32_t t)
{
    const sw_edge *B = &s->e[b], *T = &s->e[t];
    int o = gp_orient2d(T->l, T->r, B->l);
    if (o == 0) o = gp_orient2d(T->l, T->r, B->r);
    return o >= 0;
}

static void sw_set_child(sweep *s, uint32_t parent, uint32_t old, uint32_t child)
{
    if (parent == SW_NIL) s->root = child;
    else if (s->e[parent].lc == old) s->e[parent].lc = child;
    else s->e[parent].rc = child;
    if (child != SW_NIL) s->e[child].up = parent;
}

/* rotates x above its parent */
static void sw_rotate_up(sweep *s, uint32_t x)
{
    sw_edge *e = s->e;
    uint32_t p = e[x].up, g = e[p].up;
    if (e[p].lc == x) {
        e[p].lc = e[x].rc;
        if (e[x].rc != SW_NIL) e[e[x].rc].up = p;
        e[x].rc = p;
    } else {
        e[p].rc = e[x].lc;
        if (e[x].lc != SW_NIL) e[e[x].lc].up = p;
        e[x].lc = p;
    }
    e[p].up = x;
    sw_set_child(s, g, p, x);
}

static void sw_insert(sweep *s, uint32_t b)
{
    sw_edge *e = s->e;
    e[b].lc = e[b].rc = SW_NIL;
    uint32_t cur = s->root, parent = SW_NIL;
    int right = 0;
    while (cur != SW_NIL) {
        parent = cur;
        right = sw_above(s, b, cur);
        cur = right ? e[cur].rc : e[cur].lc;
    }
    e[b].up = parent;
    if (parent == SW_NIL) s->root = b;
    else if (right) e[parent].rc = b;
    else e[parent].lc = b;
    while (e[b].up != SW_NIL && e[e[b].up].prio < e[b].prio) sw_rotate_up(s, b);
}

static void sw_remove(sweep *s, uint32_t b)
{
    sw_edge *e = s->e;
    while (e[b].lc != SW_NIL && e[b].rc != SW_NIL) {
        uint32_t c = e[e[b].lc].prio > e[e[b].rc].prio ? e[b].lc : e[b].rc;
        sw_rotate_up(s, c);
    }
    sw_set_child(s, e[b].up, b, e[b].lc != SW_NIL ? e[b].lc : e[b].rc);
}

/* the next edge below (dir 0) or above (dir 1) b on the sweep line, or SW_NIL */
static uint32_t sw_next(const sweep *s, uint32_t b, int dir)
{
    const sw_edge *e = s->e;
    uint32_t c = dir ? e[b].rc : e[b].lc;
    if (c != SW_NIL) {
        while ((dir ? e[c].lc : e[c].rc) != SW_NIL) c = dir ? e[c].lc : e[c].rc;
        return c;
    }
    while (e[b].up != SW_NIL && (dir ? e[e[b].up].rc : e[e[b].up].lc) == b) b = e[b].up;
    return e[b].up;
}

/* the ring whose interior is right above edge g (its own ring, or that ring's parent) */
static long ring_above(const sweep *s, uint32_t g)
{
    uint32_t r = s->e[g].ring;
    int rightward = lex_less(edge_from(s, g), edge_to(s, g));
    /* a counter-clockwise ring has its interior left of each edge: above a rightward one */
    return (s->ccw[r] > 0) == rightward ? (long)r : s->parent[r];
}

/* allocates the sweep's arrays and fills the edges, the events (unsorted), each ring's
 * leftmost vertex and orientation there; 0, or -1 out of memory (or too many edges) */
static int sw_build(sweep *s, const gp_ring_ref *rings, size_t nr)
{
    memset(s, 0, sizeof *s);
    s->rings = rings;
    s->nr = nr;
    for (size_t r = 0; r < nr; r++) s->ne += rings[r].n;
    if (s->ne >= SW_NIL) return -1;
    /* the arrays in one block, those of 8-byte items first, the bytes of ccw last */
    size_t edges = s->ne * sizeof *s->e, events = 2 * s->ne * sizeof *s->v;
    size_t per_ring = sizeof *s->first + sizeof *s->minv + sizeof *s->parent;
    char *m = s->block = malloc(edges + events + nr * per_ring + nr);
    if (!m) return -1;
    s->e = (sw_edge *)m;
    s->v = (sw_vertex *)(m + edges);
    s->first = (size_t *)(m + edges + events);
    s->minv = s->first + nr;
    s->parent = (long *)(s->minv + nr);
    s->ccw = (signed char *)(s->parent + nr);
    /* treap priorities from a generator seeded per call, so that no input can steer the tree's
     * shape (its depth) */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t rng = ((uint64_t)ts.tv_nsec * 0x9E3779B97F4A7C15ull) ^ (uint64_t)(uintptr_t)s->e;
    rng |= 1;
    size_t k = 0;
    for (size_t r = 0; r < nr; r++) {
        const gp_ring_ref *g = &rings[r];
        s->first[r] = k;
        s->minv[r] = 0;
        for (size_t i = 0; i < g->n; i++, k++) {
            gp_vec2 a = g->pts[i], b = g->pts[(i + 1) % g->n];
            int fwd = lex_less(a, b);
            sw_edge *ed = &s->e[k];
            ed->l = fwd ? a : b;
            ed->r = fwd ? b : a;
            ed->ring = (uint32_t)r;
            ed->i = (uint32_t)i;
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            ed->prio = (uint32_t)(rng >> 32);
            s->v[k] = (sw_vertex){a.x, a.y, (uint32_t)k};
            if (lex_less(a, g->pts[s->minv[r]])) s->minv[r] = i;
        }
        /* the orientation at the leftmost vertex (collinear with both neighbours only when the
         * edges there fold back, which the sweep reports) */
        size_t m = s->minv[r];
        s->ccw[r] = (signed char)gp_orient2d(g->pts[(m + g->n - 1) % g->n], g->pts[m],
                                             g->pts[(m + 1) % g->n]);
        s->parent[r] = -1;
    }
    s->root = s->bad_a = s->bad_b = SW_NIL;
    return 0;
}

/* the event at v[q]: the edges that start here go in (against the edges that end here, still
 * in), then the edges that end here go out. 1 when a pair meets where it must not. */
static int sw_event(sweep *s, size_t q)
{
    sw_edge *e = s->e;
    gp_vec2 at = {s->v[q].x, s->v[q].y};
    uint32_t out = s->v[q].edge;
    const gp_ring_ref *g = &s->rings[e[out].ring];
    uint32_t in = (uint32_t)(s->first[e[out].ring] + (e[out].i + g->n - 1) % g->n);
    if (q + 1 < s->ne && s->v[q + 1].x == at.x && s->v[q + 1].y == at.y) {
        /* two vertices at one point: the edges that start there touch */
        s->bad_a = out;
        s->bad_b = s->v[q + 1].edge;
        return 1;
    }
    int leftmost = e[out].i == s->minv[e[out].ring];
    uint32_t both[2] = {in, out};
    for (int t = 0; t < 2; t++) {
        uint32_t b = both[t];
        if (!same_point(e[b].l, at)) continue;
        sw_insert(s, b);
        uint32_t below = sw_next(s, b, 0);
        if (leftmost && t == 0) /* a ring's first edge: what lies right below the ring */
            s->parent[e[b].ring] = below == SW_NIL ? -1 : ring_above(s, below);
        if (sw_check(s, b, below) || sw_check(s, b, sw_next(s, b, 1))) return 1;
    }
    for (int t = 0; t < 2; t++) {
        uint32_t b = both[t];
        if (!same_point(e[b].r, at)) continue;
        uint32_t below = sw_next(s, b, 0), above = sw_next(s, b, 1);
        sw_remove(s, b);
        if (sw_check(s, below, above)) return 1;
    }
    return 0;
}

/* the pair found, as a fault: the lower ring (or the lower edge of one ring) first */
static void sw_fault(const sweep *s, gp_rings_fault *f)
{
    const sw_edge *e = s->e;
    uint32_t a = s->bad_a, b = s->bad_b;
    if (e[a].ring > e[b].ring || (e[a].ring == e[b].ring && e[a].i > e[b].i)) {
        uint32_t t = a;
        a = b;
        b = t;
    }
    if (follows(s, b, a)) { /* b is followed by a: name b first */
        uint32_t t = a;
        a = b;
        b = t;
    }
    f->kind = follows(s, a, b) ? GP_RINGS_FOLD : GP_RINGS_CROSS;
    f->ring = e[a].ring;
    f->edge = e[a].i;
    f->ring2 = e[b].ring;
    f->edge2 = e[b].i;
}

/* The sweep over all edges of the rings: 1 with *f at the first pair of edges that meet where
 * they must not, else 0 with parent[r] = the innermost ring containing ring r (-1: none;
 * parent has nr entries). -1 out of memory. */
static int sweep_rings(const gp_ring_ref *rings, size_t nr, long *parent, gp_rings_fault *f)
{
    sweep s;
    if (sw_build(&s, rings, nr)) {
        free(s.block);
        return -1;
    }
    sort_vertices(s.v, s.v + s.ne, s.ne);
    int bad = 0;
    for (size_t q = 0; q < s.ne && !bad; q++) bad = sw_event(&s, q);
    if (bad) sw_fault(&s, f);
    else memcpy(parent, s.parent, nr * sizeof *parent);
    free(s.block);
    return bad;
}

/* invariant 1: at least 3 points, an extent, not all on one line (an area-style tolerance:
 * the points' distance from the line through the first and the farthest point, relative to
 * that squared length) */
static int ring_degenerate(const gp_ring_ref *g)
{
    double minx = INFINITY, maxx = -INFINITY, miny = INFINITY, maxy = -INFINITY;
    for (size_t i = 0; i < g->n; i++) {
        minx = fmin(minx, g->pts[i].x);
        maxx = fmax(maxx, g->pts[i].x);
        miny = fmin(miny, g->pts[i].y);
        maxy = fmax(maxy, g->pts[i].y);
    }
    double scale = fmax(maxx - minx, maxy - miny);
    size_t far = 0;
    double dfar = 0;
    for (size_t i = 1; i < g->n; i++) {
        double dx = g->pts[i].x - g->pts[0].x, dy = g->pts[i].y - g->pts[0].y;
        if (dx * dx + dy * dy > dfar) {
            dfar = dx * dx + dy * dy;
            far = i;
        }
    }
    int collinear = 1;
    for (size_t i = 1; i < g->n && far; i++) {
        gp_vec2 a = g->pts[0], b = g->pts[far], q = g->pts[i];
        double o = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        if (fabs(o) > 1e-12 * dfar) collinear = 0;
    }
    return g->n < 3 || !(scale > 0) || collinear;
}

/* invariant 3: |area| above 1e-12 of the squared extent about the first point */
static int ring_no_area(const gp_ring_ref *g)
{
    double scale = 0;
    for (size_t i = 1; i < g->n; i++)
        scale = fmax(scale, fmax(fabs(g->pts[i].x - g->pts[0].x), fabs(g->pts[i].y - g->pts[0].y)));
    return !(fabs(gp_poly_signed_area(g->pts, g->n)) > 1e-12 * scale * scale);
}

/* invariant 4 for hole r: its chain of enclosing rings holds ring 0 and no hole (at most
 * nr steps: the chains are short work); sets *f when it does not */
static int hole_misplaced(const long *parent, size_t nr, size_t r, gp_rings_fault *f)
{
    int in_outer = 0;
    long in_hole = -1;
    size_t guard = 0;
    for (long c = parent[r]; c >= 0 && guard <= nr; c = parent[c], guard++) {
        if (c == 0) in_outer = 1;
        else if (in_hole < 0 || c < in_hole) in_hole = c;
    }
    if (in_outer && in_hole < 0) return 0;
    f->ring = r;
    f->kind = in_outer ? GP_RINGS_HOLE_IN_HOLE : GP_RINGS_HOLE_OUTSIDE;
    if (in_outer) f->ring2 = (size_t)in_hole;
    return 1;
}

static gp_status report(const gp_rings_fault *f, gp_error *err)
{
    switch (f->kind) {
    case GP_RINGS_DEGENERATE:
        return gp_error_set(err, GP_ERR_INVALID, "ring %zu has no area (fewer than 3 points, "
                            "or all of them collinear or repeated)", f->ring);
    case GP_RINGS_FOLD:
        return gp_error_set(err, GP_ERR_INVALID, "ring %zu is not simple: edges %zu and %zu fold "
                            "back onto each other", f->ring, f->edge, f->edge2);
    case GP_RINGS_CROSS:
        return gp_error_set(err, GP_ERR_INVALID, "edge %zu of ring %zu crosses or touches edge "
                            "%zu of ring %zu", f->edge, f->ring, f->edge2, f->ring2);
    case GP_RINGS_NO_AREA:
        return gp_error_set(err, GP_ERR_INVALID, "ring %zu has no area", f->ring);
    case GP_RINGS_HOLE_OUTSIDE:
        return gp_error_set(err, GP_ERR_INVALID, "ring %zu (a hole) is not inside ring 0",
                            f->ring);
    case GP_RINGS_HOLE_IN_HOLE:
        return gp_error_set(err, GP_ERR_INVALID, "ring %zu (a hole) lies inside ring %zu",
                            f->ring, f->ring2);
    default:
        gp_error_clear(err);
        return GP_OK;
    }
}

gp_status gp_rings_check(const gp_ring_ref *rings, size_t nrings, gp_rings_fault *fault,
                         gp_error *err)
{
    gp_rings_fault local;
    gp_rings_fault *f = fault ? fault : &local;
    memset(f, 0, sizeof *f);
    if (!rings || nrings == 0) {
        f->kind = GP_RINGS_DEGENERATE;
        return report(f, err);
    }
    for (size_t r = 0; r < nrings; r++) {
        if (!ring_degenerate(&rings[r])) continue;
        f->kind = GP_RINGS_DEGENERATE;
        f->ring = r;
        return report(f, err);
    }
    long *parent = malloc(nrings * sizeof *parent);
    int rc = parent ? sweep_rings(rings, nrings, parent, f) : -1;
    if (rc < 0) {
        free(parent);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory checking %zu rings", nrings);
    }
    for (size_t r = 0; r < nrings && rc == 0; r++) {
        if (!ring_no_area(&rings[r])) continue;
        f->kind = GP_RINGS_NO_AREA;
        f->ring = r;
        rc = 1;
    }
    for (size_t r = 1; r < nrings && rc == 0; r++) rc = hole_misplaced(parent, nrings, r, f);
    free(parent);
    return report(f, err);
}
