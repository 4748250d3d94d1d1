/* gp_adstat.c -- incremental Anderson-Darling statistic on a treap. See gp_adstat.h.
 *
 * Nodes are the element ids themselves (arrays indexed by id, NIL = SIZE_MAX), so there is no
 * allocation after create. Insert and remove are split/merge on the key (u, id); every node on
 * the way is re-aggregated from its children.
 */
#include "gp_adstat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#define NIL SIZE_MAX

typedef struct node {
    double u, g, h, w, x;  /* key, logs of the value, w = g - h, the extra */
    double sw, sr, sg, sh, sx; /* subtree: sum w, rank-weighted sum of w, sum g, h, extra */
    size_t left, right, cnt;
    uint64_t prio;
    int present;
} node;

struct gp_adstat {
    node *t;
    size_t cap, root;
};

/* splitmix64 finaliser: a fixed, well-mixed priority per id */
static uint64_t prio_of(size_t id)
{
    uint64_t z = (uint64_t)id + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

gp_adstat *gp_adstat_create(size_t capacity, gp_error *err)
{
    gp_adstat *s = calloc(1, sizeof *s);
    if (s) s->t = calloc(capacity ? capacity : 1, sizeof *s->t);
    if (!s || !s->t) {
        gp_adstat_destroy(s);
        gp_error_set(err, GP_ERR_NOMEM, "adstat: out of memory");
        return NULL;
    }
    s->cap = capacity;
    s->root = NIL;
    for (size_t i = 0; i < capacity; i++) s->t[i].prio = prio_of(i);
    return s;
}

void gp_adstat_destroy(gp_adstat *s)
{
    if (!s) return;
    free(s->t);
    free(s);
}

static void pull(node *t, size_t x)
{
    node *n = &t[x];
    size_t cl = 0, l = n->left, r = n->right;
    double sw = n->w, sg = n->g, sh = n->h, sx = n->x, sr = 0.0;
    if (l != NIL) {
        cl = t[l].cnt;
        sw += t[l].sw;
        sg += t[l].sg;
        sh += t[l].sh;
        sx += t[l].sx;
        sr += t[l].sr;
    }
    double k = (double)(cl + 1);
    sr += k * n->w;
    size_t c = cl + 1;
    if (r != NIL) {
        c += t[r].cnt;
        sw += t[r].sw;
        sg += t[r].sg;
        sh += t[r].sh;
        sx += t[r].sx;
        sr += t[r].sr + k * t[r].sw;
    }
    n->sx = sx;
    n->cnt = c;
    n->sw = sw;
    n->sg = sg;
    n->sh = sh;
    n->sr = sr;
}

/* key of node x is less than key (u, id) */
static int less(const node *t, size_t x, double u, size_t id)
{
    return t[x].u < u || (t[x].u == u && x < id);
}

/* splits x into keys < (u, id) and the rest */
static void split(node *t, size_t x, double u, size_t id, size_t *a, size_t *b)
{
    if (x == NIL) {
        *a = *b = NIL;
        return;
    }
    if (less(t, x, u, id)) {
        split(t, t[x].right, u, id, &t[x].right, b);
        *a = x;
    } else {
        split(t, t[x].left, u, id, a, &t[x].left);
        *b = x;
    }
    pull(t, x);
}

static size_t merge(node *t, size_t a, size_t b)
{
    if (a == NIL) return b;
    if (b == NIL) return a;
    if (t[a].prio > t[b].prio) {
        t[a].right = merge(t, t[a].right, b);
        pull(t, a);
        return a;
    }
    t[b].left = merge(t, a, t[b].left);
    pull(t, b);
    return b;
}

/* inserts the detached node x under root r (treap insertion by priority) */
static size_t insert(node *t, size_t r, size_t x)
{
    if (r == NIL) return x;
    if (t[x].prio > t[r].prio) {
        split(t, r, t[x].u, x, &t[x].left, &t[x].right);
        pull(t, x);
        return x;
    }
    if (less(t, r, t[x].u, x)) t[r].right = insert(t, t[r].right, x);
    else t[r].left = insert(t, t[r].left, x);
    pull(t, r);
    return r;
}

/* removes node x (present) from the subtree r */
static size_t erase(node *t, size_t r, size_t x)
{
    if (r == x) return merge(t, t[x].left, t[x].right);
    if (less(t, r, t[x].u, x)) t[r].right = erase(t, t[r].right, x);
    else t[r].left = erase(t, t[r].left, x);
    pull(t, r);
    return r;
}

void gp_adstat_remove(gp_adstat *s, size_t id)
{
    if (!s || id >= s->cap || !s->t[id].present) return;
    s->root = erase(s->t, s->root, id);
    s->t[id].present = 0;
}

#define PATH_MAX_DEPTH 128

/* A present node whose new key keeps its place in the order: the tree's shape is the same
 * (it depends on the order and the priorities only), so the values are changed in place and
 * the path to the root re-aggregated -- the same bits as a remove and insert, at a fraction
 * of the cost. Returns 0 when the key would move past a neighbour (or the path is too deep). */
static int set_in_place(gp_adstat *s, size_t id, double u, double g, double h, double x)
{
    node *t = s->t;
    size_t path[PATH_MAX_DEPTH], d = 0, pred = NIL, succ = NIL, y = s->root;
    while (y != id) {
        if (y == NIL || d == PATH_MAX_DEPTH) return 0;
        path[d++] = y;
        if (less(t, y, t[id].u, id)) {
            pred = y;
            y = t[y].right;
        } else {
            succ = y;
            y = t[y].left;
        }
    }
    for (y = t[id].left; y != NIL; y = t[y].right) pred = y;
    for (y = t[id].right; y != NIL; y = t[y].left) succ = y;
    if ((pred != NIL && !less(t, pred, u, id)) || (succ != NIL && less(t, succ, u, id))) return 0;
    t[id].u = u;
    t[id].g = g;
    t[id].h = h;
    t[id].x = x;
    t[id].w = g - h;
    pull(t, id);
    while (d > 0) pull(t, path[--d]);
    return 1;
}

void gp_adstat_set(gp_adstat *s, size_t id, double u, double g, double h, double x)
{
    if (!s || id >= s->cap) return;
    node *n = &s->t[id];
    if (n->present && n->u == u && n->g == g && n->h == h && n->x == x) return;
    if (n->present && set_in_place(s, id, u, g, h, x)) return;
    gp_adstat_remove(s, id);
    n->u = u;
    n->g = g;
    n->h = h;
    n->x = x;
    n->w = g - h;
    n->left = n->right = NIL;
    pull(s->t, id);
    n->present = 1;
    s->root = insert(s->t, s->root, id);
}

size_t gp_adstat_count(const gp_adstat *s) { return s && s->root != NIL ? s->t[s->root].cnt : 0; }

double gp_adstat_a2(const gp_adstat *s)
{
    size_t n = gp_adstat_count(s);
    if (n == 0) return 0.0;
    const node *r = &s->t[s->root];
    double N = (double)n;
    return -N - (2.0 * r->sr - r->sg + (2.0 * N + 1.0) * r->sh) / N;
}

double gp_adstat_sum_extra(const gp_adstat *s)
{
    return gp_adstat_count(s) ? s->t[s->root].sx : 0.0;
}

double gp_adstat_floor(size_t n)
{
    if (n == 0) return 0.0;
    double N = (double)n, sum = 0.0;
    for (size_t i = 1; i <= n; i++) {
        double u = (2.0 * (double)i - 1.0) / (2.0 * N);
        /* ln u_(i) + ln(1 - u_(N+1-i)) = 2 ln u_(i) by symmetry */
        sum += (2.0 * (double)i - 1.0) * 2.0 * log(u);
    }
    return -N - sum / N;
}

/* elements of the tree strictly below (key, id) -- the element id itself excluded -- and the
 * w-sum of those strictly above */
static void rank_query(const gp_adstat *s, double key, size_t id, size_t *below, double *above)
{
    const node *t = s->t;
    size_t c = 0, x = s->root;
    double a = 0.0;
    while (x != NIL) {
        size_t l = t[x].left, r = t[x].right;
        if (x == id && t[x].u == key) {
            c += l != NIL ? t[l].cnt : 0;
            a += r != NIL ? t[r].sw : 0.0;
            break;
        }
        if (less(t, x, key, id)) {
            c += (l != NIL ? t[l].cnt : 0) + 1;
            x = r;
        } else {
            a += t[x].w + (r != NIL ? t[r].sw : 0.0);
            x = l;
        }
    }
    *below = c;
    *above = a;
}

static int key_less(double ua, size_t ia, double ub, size_t ib)
{
    return ua < ub || (ua == ub && ia < ib);
}

/* one side of a change (the k old or the k new values), sorted by key */
typedef struct side {
    size_t k;
    double key[GP_ADSTAT_IF_MAX], w[GP_ADSTAT_IF_MAX], wcum[GP_ADSTAT_IF_MAX + 1];
    size_t id[GP_ADSTAT_IF_MAX];
} side;

static void side_sort(side *sd, size_t k, const size_t *ids, const double *key, const double *w)
{
    sd->k = k;
    for (size_t i = 0; i < k; i++) { /* insertion sort: a few dozen at most */
        size_t j = i;
        while (j > 0 && key_less(key[i], ids[i], sd->key[j - 1], sd->id[j - 1])) {
            sd->key[j] = sd->key[j - 1];
            sd->id[j] = sd->id[j - 1];
            sd->w[j] = sd->w[j - 1];
            j--;
        }
        sd->key[j] = key[i];
        sd->id[j] = ids[i];
        sd->w[j] = w[i];
    }
    sd->wcum[0] = 0.0;
    for (size_t i = 0; i < k; i++) sd->wcum[i + 1] = sd->wcum[i] + sd->w[i];
}

/* elements of the side strictly below (key, id) */
static size_t side_below(const side *sd, double key, size_t id)
{
    size_t lo = 0, hi = sd->k;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (key_less(sd->key[mid], sd->id[mid], key, id)) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Sum over one side of count_base_below(z) w_z + wsum_base_above(z), plus the pairs inside the
 * side (each pair counts the larger one's w), where the base is the tree without the old side:
 * the tree's counts (rank_query) less the old elements strictly below / above z. */
static double side_pairs(const gp_adstat *s, const side *sd, const side *old)
{
    double p = 0.0;
    for (size_t i = 0; i < sd->k; i++) {
        size_t below;
        double above;
        rank_query(s, sd->key[i], sd->id[i], &below, &above);
        size_t ob = side_below(old, sd->key[i], sd->id[i]);
        size_t oe = ob < old->k && old->key[ob] == sd->key[i] && old->id[ob] == sd->id[i] ? ob + 1 : ob;
        below -= ob;
        above -= old->wcum[old->k] - old->wcum[oe];
        p += (double)below * sd->w[i] + above + (double)i * sd->w[i];
    }
    return p;
}

double gp_adstat_a2_if(const gp_adstat *s, size_t k, const size_t *ids, const double *key,
                       const double *g, const double *h, const double *extra, double *sum_extra)
{
    size_t n = gp_adstat_count(s);
    if (n == 0) return 0.0;
    const node *t = s->t, *r = &t[s->root];
    double ko[GP_ADSTAT_IF_MAX], wo[GP_ADSTAT_IF_MAX], wn[GP_ADSTAT_IF_MAX];
    if (k > GP_ADSTAT_IF_MAX) return NAN;
    side so, sn;
    double dg = 0.0, dh = 0.0, dw = 0.0, dx = 0.0;
    for (size_t i = 0; i < k; i++) {
        const node *o = &t[ids[i]];
        ko[i] = o->u;
        wo[i] = o->w;
        wn[i] = g[i] - h[i];
        dg += g[i] - o->g;
        dh += h[i] - o->h;
        dw += wn[i] - o->w;
        dx += extra[i] - o->x;
    }
    side_sort(&so, k, ids, ko, wo);
    side_sort(&sn, k, ids, key, wn);
    double dr = dw + side_pairs(s, &sn, &so) - side_pairs(s, &so, &so);
    if (sum_extra) *sum_extra = r->sx + dx;
    double N = (double)n;
    return -N - (2.0 * (r->sr + dr) - (r->sg + dg) + (2.0 * N + 1.0) * (r->sh + dh)) / N;
}
