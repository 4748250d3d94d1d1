/* gp_adstat.c -- incremental Anderson-Darling statistic in exact fixed point on sorted blocks.
 * See gp_adstat.h for the algorithm and its guarantees; this file is the data structure.
 *
 * Layout. The present elements, ordered by (key, id), are cut into blocks of at most BMAX;
 * a block keeps its keys, ids, fixed w's and the sums of its w's before every CH-th element
 * (cpre), so that a prefix sum inside a block is one cpre plus fewer than CH w's, and an
 * insert or erase is a memmove and BMAX / CH updates. The directory lists the blocks in order
 * with each one's first (key, id) for the binary search, and a Fenwick tree over directory
 * positions gives the count and w-sum of the blocks before a position. A rank query is then
 * two binary searches (directory, block) and one Fenwick prefix: a few cache lines, where a
 * balanced tree walks ~log2 N nodes scattered over the heap (docs/design/adstat.md).
 *
 * Balance: every block is non-empty and any two neighbours hold more than BMERGE together
 * (else they are merged), so there are at most 2 n / (BMERGE + 1) + 1 blocks. That bounds the
 * pool, allocated once at create (calloc: pages never reached are never touched), so that set
 * and remove never allocate. A full block is split in halves before an insert into it. Blocks are
 * identified by pool index, the directory holds the order; restructuring rebuilds the Fenwick
 * tree from the first position it touched (O(blocks) at worst, half that on average).
 *
 * All sums are integers (i128), so their values do not depend on the order in which they were
 * formed nor on how the blocks happen to be cut: the statistic is a function of the set.
 */
#include "gp_adstat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

__extension__ typedef __int128 i128;

#define FIX_BITS 46
#define FIX_SCALE 0x1p46          /* g and h in units of 2^-46 */
#define LOG_LIMIT 65535.0         /* |g|, |h| clamped to 2^16 - 1: |fixed w| < 2^63 */
#define CAP_MAX ((size_t)1 << 29) /* N^2 2^63 + ...: the sums of a2_of stay inside i128 */
#define BMAX 32                   /* elements a block holds: larger blocks take no fewer
                                   * instructions a step, and an insert or erase moves half the
                                   * bytes of the next size up (docs/design/adstat.md) */
#define BMERGE 20                 /* neighbours holding no more than BMERGE together merge:
                                   * low, so that merges are rare */
#define CH 8                      /* elements per prefix-sum chunk of a block */
#define NCH (BMAX / CH)

typedef struct block {
    uint32_t n;
    double key[BMAX];
    uint32_t id[BMAX];
    int64_t w[BMAX];
    i128 cpre[NCH + 1]; /* cpre[c] = w[0] + ... + w[min(CH c, n) - 1]; cpre[NCH] the total */
} block;

struct gp_adstat {
    size_t cap;
    /* per id: the key and fixed logs of a present element (one cache line, not four) */
    struct elem {
        double key;
        int64_t g, h;
        int on;
    } *el;
    /* extras: a segment tree of fixed shape over ids (leaf P + id), so the sum is a function
     * of the set too */
    double *xt;
    size_t P;
    /* blocks: the pool, its bump and free stack, the directory in key order */
    block *pool;
    size_t pcap, pused, nfree, nb;
    uint32_t *freel, *dir, *did;
    double *dkey;
    int64_t *fc; /* Fenwick (1-based) over directory positions: counts, w-sums */
    i128 *fw;
    /* totals: count, sums of g, h, w, and R = sum_i i w_(i) */
    size_t n;
    i128 G, H, W, R;
};

/* ------------------------------------------------------------------------------------------ */
/* fixed point                                                                                 */

/* g or h in units of 2^-46, clamped (also NaN, to the lower limit): rounding to nearest of an
 * exact product, so the same double always gives the same integer */
static int64_t fix(double v)
{
    if (!(v >= -LOG_LIMIT)) v = -LOG_LIMIT;
    if (v > LOG_LIMIT) v = LOG_LIMIT;
    return (int64_t)llrint(v * FIX_SCALE);
}

/* A^2 = -N - (2R - G + (2N + 1) H) / (N S) for sums in units 1/S: formed exactly as one
 * integer, rounded once to double, divided once */
static double a2_of(size_t n, i128 R, i128 G, i128 H)
{
    if (n == 0) return 0.0;
    i128 N = (i128)n;
    i128 num = N * N * ((i128)1 << FIX_BITS) + 2 * R - G + (2 * N + 1) * H;
    return -(double)num / ((double)n * FIX_SCALE);
}

/* ------------------------------------------------------------------------------------------ */
/* create, destroy                                                                             */

gp_adstat *gp_adstat_create(size_t capacity, gp_error *err)
{
    if (capacity > CAP_MAX) {
        gp_error_set(err, GP_ERR_INVALID, "adstat: capacity %zu above %zu", capacity, CAP_MAX);
        return NULL;
    }
    gp_adstat *s = calloc(1, sizeof *s);
    size_t c = capacity ? capacity : 1;
    if (s) {
        s->cap = capacity;
        for (s->P = 1; s->P < c;) s->P *= 2;
        s->pcap = 2 * c / (BMERGE + 1) + 3; /* the balance bound, and one for a split */
        s->el = calloc(c, sizeof *s->el);
        s->xt = calloc(2 * s->P, sizeof *s->xt);
        s->pool = calloc(s->pcap, sizeof *s->pool);
        s->freel = malloc(s->pcap * sizeof *s->freel);
        s->dir = malloc(s->pcap * sizeof *s->dir);
        s->did = malloc(s->pcap * sizeof *s->did);
        s->dkey = malloc(s->pcap * sizeof *s->dkey);
        s->fc = malloc((s->pcap + 1) * sizeof *s->fc);
        s->fw = malloc((s->pcap + 1) * sizeof *s->fw);
    }
    if (!s || !s->el || !s->xt || !s->pool || !s->freel || !s->dir ||
        !s->did || !s->dkey || !s->fc || !s->fw) {
        gp_adstat_destroy(s);
        gp_error_set(err, GP_ERR_NOMEM, "adstat: out of memory");
        return NULL;
    }
    return s;
}

void gp_adstat_destroy(gp_adstat *s)
{
    if (!s) return;
    free(s->el);
    free(s->xt);
    free(s->pool);
    free(s->freel);
    free(s->dir);
    free(s->did);
    free(s->dkey);
    free(s->fc);
    free(s->fw);
    free(s);
}

/* ------------------------------------------------------------------------------------------ */
/* Fenwick tree over directory positions                                                       */

/* Rebuilds the Fenwick tree from directory position a on (after a split or merge there: the
 * nodes of earlier positions cover earlier blocks only, which have not changed). Each node is
 * its block's value plus its children's nodes, added in increasing order; the children below
 * a+1 whose parents are not are the prefix chain of a. O(nb - a + log nb). */
static void fen_build_from(gp_adstat *s, size_t a)
{
    for (size_t i = a + 1; i <= s->nb; i++) {
        const block *b = &s->pool[s->dir[i - 1]];
        s->fc[i] = b->n;
        s->fw[i] = b->cpre[NCH];
    }
    size_t chain[64], nc = 0;
    for (size_t c = a; c > 0; c &= c - 1) chain[nc++] = c;
    while (nc > 0) {
        size_t c = chain[--nc], p = c + (c & (~c + 1));
        if (p <= s->nb) {
            s->fc[p] += s->fc[c];
            s->fw[p] += s->fw[c];
        }
    }
    for (size_t i = a + 1; i <= s->nb; i++) {
        size_t p = i + (i & (~i + 1));
        if (p <= s->nb) {
            s->fc[p] += s->fc[i];
            s->fw[p] += s->fw[i];
        }
    }
}

static void fen_add(gp_adstat *s, size_t d, int64_t dc, i128 dw)
{
    for (size_t i = d + 1; i <= s->nb; i += i & (~i + 1)) {
        s->fc[i] += dc;
        s->fw[i] += dw;
    }
}

/* count and w-sum of the blocks before directory position d */
static void fen_prefix(const gp_adstat *s, size_t d, size_t *c, i128 *w)
{
    int64_t cc = 0;
    i128 ww = 0;
    for (size_t i = d; i > 0; i &= i - 1) {
        cc += s->fc[i];
        ww += s->fw[i];
    }
    *c = (size_t)cc;
    *w = ww;
}

/* ------------------------------------------------------------------------------------------ */
/* blocks                                                                                      */

static int key_less(double ua, uint32_t ia, double ub, uint32_t ib)
{
    return ua < ub || (ua == ub && ia < ib);
}

/* The searches below are branch-free halvings on the key alone (the comparison feeds a
 * conditional move; a branch per level would be mispredicted half the time), then a step over
 * equal keys by id (ties are rare). */

/* the directory position of the block where (key, id) is or would go: the last whose first
 * element is not above it, or 0 */
static size_t find_block(const gp_adstat *s, double key, uint32_t id)
{
    const double *k = s->dkey;
    size_t base = 0, n = s->nb;
    while (n > 1) { /* the last first key below key, or 0 */
        size_t half = n / 2;
        base = k[base + half] < key ? base + half : base;
        n -= half;
    }
    while (base + 1 < s->nb && k[base + 1] == key && s->did[base + 1] <= id) base++;
    return base;
}

/* elements of b strictly below (key, id) */
static size_t lower_bound(const block *b, double key, uint32_t id)
{
    const double *k = b->key;
    size_t base = 0, n = b->n;
    if (n == 0) return 0;
    while (n > 1) {
        size_t half = n / 2;
        base = k[base + half] < key ? base + half : base;
        n -= half;
    }
    base += k[base] < key;
    while (base < b->n && k[base] == key && b->id[base] < id) base++;
    return base;
}

/* w[0] + ... + w[pos - 1] of block b */
static i128 block_prefix(const block *b, size_t pos)
{
    size_t c = pos / CH;
    i128 p = b->cpre[c];
    for (size_t j = c * CH; j < pos; j++) p += b->w[j];
    return p;
}

static void block_sums(block *b)
{
    b->cpre[0] = 0;
    for (size_t c = 0; c < NCH; c++) {
        i128 t = b->cpre[c];
        for (size_t j = c * CH; j < (c + 1) * CH && j < b->n; j++) t += b->w[j];
        b->cpre[c + 1] = t;
    }
}

static void block_insert(block *b, size_t pos, double key, uint32_t id, int64_t w)
{
    size_t n = b->n;
    for (size_t c = pos / CH + 1; c <= NCH; c++) /* chunk c gains w, loses its last element */
        b->cpre[c] += (i128)w - (CH * c - 1 < n ? b->w[CH * c - 1] : 0);
    memmove(&b->key[pos + 1], &b->key[pos], (n - pos) * sizeof b->key[0]);
    memmove(&b->id[pos + 1], &b->id[pos], (n - pos) * sizeof b->id[0]);
    memmove(&b->w[pos + 1], &b->w[pos], (n - pos) * sizeof b->w[0]);
    b->key[pos] = key;
    b->id[pos] = id;
    b->w[pos] = w;
    b->n = (uint32_t)(n + 1);
}

static void block_erase(block *b, size_t pos)
{
    size_t n = b->n;
    for (size_t c = pos / CH + 1; c <= NCH; c++) /* chunk c loses w[pos], gains the next one */
        b->cpre[c] += (CH * c < n ? b->w[CH * c] : 0) - (i128)b->w[pos];
    memmove(&b->key[pos], &b->key[pos + 1], (n - pos - 1) * sizeof b->key[0]);
    memmove(&b->id[pos], &b->id[pos + 1], (n - pos - 1) * sizeof b->id[0]);
    memmove(&b->w[pos], &b->w[pos + 1], (n - pos - 1) * sizeof b->w[0]);
    b->n = (uint32_t)(n - 1);
}

/* appends b's elements to a */
static void block_append(block *a, const block *b)
{
    size_t na = a->n;
    memcpy(&a->key[na], b->key, b->n * sizeof b->key[0]);
    memcpy(&a->id[na], b->id, b->n * sizeof b->id[0]);
    memcpy(&a->w[na], b->w, b->n * sizeof b->w[0]);
    a->n = (uint32_t)(na + b->n);
    block_sums(a);
}

static uint32_t pool_take(gp_adstat *s)
{
    uint32_t p = s->nfree > 0 ? s->freel[--s->nfree] : (uint32_t)s->pused++;
    s->pool[p].n = 0;
    block_sums(&s->pool[p]);
    return p;
}

/* puts block p at directory position d, shifting the rest up */
static void dir_insert(gp_adstat *s, size_t d, uint32_t p)
{
    size_t m = s->nb - d;
    memmove(&s->dir[d + 1], &s->dir[d], m * sizeof s->dir[0]);
    memmove(&s->did[d + 1], &s->did[d], m * sizeof s->did[0]);
    memmove(&s->dkey[d + 1], &s->dkey[d], m * sizeof s->dkey[0]);
    s->dir[d] = p;
    s->dkey[d] = s->pool[p].key[0];
    s->did[d] = s->pool[p].id[0];
    s->nb++;
}

/* takes the block at directory position d out and frees it */
static void dir_erase(gp_adstat *s, size_t d)
{
    s->freel[s->nfree++] = s->dir[d];
    size_t m = s->nb - d - 1;
    memmove(&s->dir[d], &s->dir[d + 1], m * sizeof s->dir[0]);
    memmove(&s->did[d], &s->did[d + 1], m * sizeof s->did[0]);
    memmove(&s->dkey[d], &s->dkey[d + 1], m * sizeof s->dkey[0]);
    s->nb--;
}

/* moves the upper half of the full block at d into a new block at d + 1 */
static void split(gp_adstat *s, size_t d)
{
    uint32_t p = pool_take(s);
    block *a = &s->pool[s->dir[d]], *b = &s->pool[p];
    size_t h = a->n / 2, m = a->n - h;
    memcpy(b->key, &a->key[h], m * sizeof a->key[0]);
    memcpy(b->id, &a->id[h], m * sizeof a->id[0]);
    memcpy(b->w, &a->w[h], m * sizeof a->w[0]);
    b->n = (uint32_t)m;
    a->n = (uint32_t)h;
    block_sums(a);
    block_sums(b);
    dir_insert(s, d + 1, p);
}

/* Restores the balance around directory position d after its block changed: an empty block
 * goes; a block whose neighbour and it hold <= BMERGE together is merged with it. Returns 1
 * when the directory changed (the Fenwick tree is then rebuilt by the caller). */
static int rebalance(gp_adstat *s, size_t d)
{
    block *b = &s->pool[s->dir[d]];
    if (b->n == 0) {
        dir_erase(s, d);
        return 1;
    }
    int changed = 0;
    if (d + 1 < s->nb && b->n + s->pool[s->dir[d + 1]].n <= BMERGE) {
        block_append(b, &s->pool[s->dir[d + 1]]);
        dir_erase(s, d + 1);
        changed = 1;
    }
    if (d > 0 && s->pool[s->dir[d - 1]].n + b->n <= BMERGE) {
        block_append(&s->pool[s->dir[d - 1]], b);
        dir_erase(s, d);
        changed = 1;
    }
    return changed;
}

/* ------------------------------------------------------------------------------------------ */
/* insert, remove                                                                              */

/* count below and w-sum of the elements before directory position d, position pos in it */
static void rank_at(const gp_adstat *s, size_t d, size_t pos, size_t *below, i128 *wbelow)
{
    const block *b = &s->pool[s->dir[d]];
    fen_prefix(s, d, below, wbelow);
    *below += pos;
    *wbelow += block_prefix(b, pos);
}

/* Inserts (key, id, w), absent. R gains the new element's rank times w plus the w's above it
 * (each of which moves up one rank). A full block is split first; the halves may then be
 * light enough to merge with their outer neighbours. */
static void tree_insert(gp_adstat *s, double key, uint32_t id, int64_t w)
{
    if (s->nb == 0) dir_insert(s, 0, pool_take(s));
    size_t d = find_block(s, key, id), left = SIZE_MAX;
    if (s->pool[s->dir[d]].n == BMAX) {
        split(s, d);
        fen_build_from(s, d);
        left = d;
        if (!key_less(key, id, s->dkey[d + 1], s->did[d + 1])) d++;
    }
    block *b = &s->pool[s->dir[d]];
    size_t pos = lower_bound(b, key, id), below;
    i128 wbelow;
    rank_at(s, d, pos, &below, &wbelow);
    s->R += (i128)(below + 1) * w + (s->W - wbelow);
    block_insert(b, pos, key, id, w);
    if (pos == 0) {
        s->dkey[d] = key;
        s->did[d] = id;
    }
    s->W += w;
    s->n++;
    fen_add(s, d, 1, w);
    if (left == SIZE_MAX) return;
    int changed = rebalance(s, left + 1); /* the right half and its right neighbour first, */
    changed |= rebalance(s, left);        /* so that `left` still names the left half */
    if (changed) fen_build_from(s, left > 0 ? left - 1 : 0);
}

/* Removes (key, id, w), present; the inverse of tree_insert, so R comes back exactly. */
static void tree_remove(gp_adstat *s, double key, uint32_t id, int64_t w)
{
    size_t d = find_block(s, key, id);
    block *b = &s->pool[s->dir[d]];
    size_t pos = lower_bound(b, key, id), below;
    i128 wbelow;
    rank_at(s, d, pos, &below, &wbelow);
    s->W -= w;
    s->n--;
    s->R -= (i128)(below + 1) * w + (s->W - wbelow);
    block_erase(b, pos);
    if (pos == 0 && b->n > 0) {
        s->dkey[d] = b->key[0];
        s->did[d] = b->id[0];
    }
    fen_add(s, d, -1, -(i128)w);
    if (rebalance(s, d)) fen_build_from(s, d > 0 ? d - 1 : 0);
}

/* A present element whose new key stays in its block (strictly between the block's first
 * element and the next block's): erase and insert inside the block, one directory search and
 * one Fenwick prefix for both, no change to the directory. R is updated as by tree_remove then
 * tree_insert, so it is the same integer. Returns 0, nothing done, when the key leaves the
 * block. */
static int tree_move_in_block(gp_adstat *s, double ko, uint32_t id, int64_t wo, double kn, int64_t wn)
{
    size_t d = find_block(s, ko, id);
    if ((d > 0 && !key_less(s->dkey[d], s->did[d], kn, id)) ||
        (d + 1 < s->nb && !key_less(kn, id, s->dkey[d + 1], s->did[d + 1])))
        return 0;
    block *b = &s->pool[s->dir[d]];
    size_t p = lower_bound(b, ko, id), c;
    i128 wd;
    fen_prefix(s, d, &c, &wd);
    i128 wb = wd + block_prefix(b, p);
    s->W -= wo;
    s->R -= (i128)(c + p + 1) * wo + (s->W - wb);
    block_erase(b, p);
    size_t q = lower_bound(b, kn, id);
    wb = wd + block_prefix(b, q);
    s->R += (i128)(c + q + 1) * wn + (s->W - wb);
    s->W += wn;
    block_insert(b, q, kn, id, wn);
    s->dkey[d] = b->key[0];
    s->did[d] = b->id[0];
    fen_add(s, d, 0, (i128)wn - wo);
    return 1;
}

static void extra_put(gp_adstat *s, size_t id, double x)
{
    size_t i = s->P + id;
    s->xt[i] = x;
    for (i /= 2; i > 0; i /= 2) s->xt[i] = s->xt[2 * i] + s->xt[2 * i + 1];
}

void gp_adstat_remove(gp_adstat *s, size_t id)
{
    if (!s || id >= s->cap || !s->el[id].on) return;
    tree_remove(s, s->el[id].key, (uint32_t)id, s->el[id].g - s->el[id].h);
    s->G -= s->el[id].g;
    s->H -= s->el[id].h;
    s->el[id].on = 0;
    extra_put(s, id, 0.0);
}

void gp_adstat_set(gp_adstat *s, size_t id, double key, double g, double h, double x)
{
    if (!s || id >= s->cap) return;
    int64_t gf = fix(g), hf = fix(h);
    if (!s->el[id].on || s->el[id].key != key || s->el[id].g != gf || s->el[id].h != hf) {
        int moved = 0;
        if (s->el[id].on) {
            moved = tree_move_in_block(s, s->el[id].key, (uint32_t)id, s->el[id].g - s->el[id].h, key, gf - hf);
            if (!moved) tree_remove(s, s->el[id].key, (uint32_t)id, s->el[id].g - s->el[id].h);
            s->G -= s->el[id].g;
            s->H -= s->el[id].h;
        }
        if (!moved) tree_insert(s, key, (uint32_t)id, gf - hf);
        s->G += gf;
        s->H += hf;
        s->el[id].key = key;
        s->el[id].g = gf;
        s->el[id].h = hf;
        s->el[id].on = 1;
    }
    if (memcmp(&s->xt[s->P + id], &x, sizeof x) != 0) extra_put(s, id, x);
}

size_t gp_adstat_count(const gp_adstat *s) { return s ? s->n : 0; }

double gp_adstat_a2(const gp_adstat *s) { return s ? a2_of(s->n, s->R, s->G, s->H) : 0.0; }

double gp_adstat_sum_extra(const gp_adstat *s) { return s && s->n ? s->xt[1] : 0.0; }

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

/* ------------------------------------------------------------------------------------------ */
/* what-if                                                                                     */

/* The count of elements strictly below (key, id) -- the element id itself excluded -- and the
 * w-sum of those strictly above, in block d (the caller's directory position for it) whose
 * preceding blocks hold c elements of w-sum wd. */
static void rank_in(const gp_adstat *s, size_t d, size_t c, i128 wd, double key, uint32_t id,
                    size_t *below, i128 *above)
{
    const block *b = &s->pool[s->dir[d]];
    size_t pos = lower_bound(b, key, id);
    size_t eq = pos < b->n && b->key[pos] == key && b->id[pos] == id;
    *below = c + pos;
    *above = s->W - wd - block_prefix(b, pos + eq);
}

/* 1 when (key, id) belongs to directory position d (find_block would say d) */
static int in_block(const gp_adstat *s, size_t d, double key, uint32_t id)
{
    return (d == 0 || !key_less(key, id, s->dkey[d], s->did[d])) &&
           (d + 1 == s->nb || key_less(key, id, s->dkey[d + 1], s->did[d + 1]));
}

/* One side of a change (the k old or the k new values), sorted by (key, id), with each value's
 * count below and w-sum above in the set as it is (rank_in). */
typedef struct side {
    size_t k;
    double key[GP_ADSTAT_IF_MAX];
    uint32_t id[GP_ADSTAT_IF_MAX];
    int64_t w[GP_ADSTAT_IF_MAX];
    size_t below[GP_ADSTAT_IF_MAX];
    i128 above[GP_ADSTAT_IF_MAX];
    i128 wcum[GP_ADSTAT_IF_MAX + 1];
} side;

/* adds a value in its place (insertion: a few dozen at most) */
static void side_add(side *sd, double key, uint32_t id, int64_t w, size_t below, i128 above)
{
    size_t j = sd->k++;
    while (j > 0 && key_less(key, id, sd->key[j - 1], sd->id[j - 1])) {
        sd->key[j] = sd->key[j - 1];
        sd->id[j] = sd->id[j - 1];
        sd->w[j] = sd->w[j - 1];
        sd->below[j] = sd->below[j - 1];
        sd->above[j] = sd->above[j - 1];
        j--;
    }
    sd->key[j] = key;
    sd->id[j] = id;
    sd->w[j] = w;
    sd->below[j] = below;
    sd->above[j] = above;
}

static void side_sums(side *sd)
{
    sd->wcum[0] = 0;
    for (size_t i = 0; i < sd->k; i++) sd->wcum[i + 1] = sd->wcum[i] + sd->w[i];
}

/* Sum over one side of count_base_below(z) w_z + wsum_base_above(z), plus the pairs inside the
 * side (each pair counts the larger one's w), where the base is the set without the old side:
 * the set's counts less the old elements strictly below / above z (a merge walk: both sides
 * are sorted; for the old side itself, i below and the rest above). */
static i128 side_pairs(const side *sd, const side *old)
{
    i128 p = 0;
    size_t j = 0;
    for (size_t i = 0; i < sd->k; i++) {
        size_t ob = i, oe = i + 1;
        if (sd != old) {
            while (j < old->k && key_less(old->key[j], old->id[j], sd->key[i], sd->id[i])) j++;
            ob = j;
            oe = j + (j < old->k && old->key[j] == sd->key[i] && old->id[j] == sd->id[i]);
        }
        i128 above = sd->above[i] - (old->wcum[old->k] - old->wcum[oe]);
        p += (i128)(sd->below[i] - ob + i) * sd->w[i] + above;
    }
    return p;
}

/* Both values of element id into the sides: the old one at directory position d (it is in
 * the set), the new one at dn (d itself when it falls in the same block: one Fenwick prefix
 * for both). */
static void element_ranks(const gp_adstat *s, uint32_t id, double kn, int64_t wn, size_t d, size_t dn,
                          side *so, side *sn)
{
    double ko = s->el[id].key;
    size_t c, below;
    i128 wd, above;
    fen_prefix(s, d, &c, &wd);
    rank_in(s, d, c, wd, ko, id, &below, &above);
    side_add(so, ko, id, s->el[id].g - s->el[id].h, below, above);
    if (dn != d) fen_prefix(s, dn, &c, &wd);
    rank_in(s, dn, c, wd, kn, id, &below, &above);
    side_add(sn, kn, id, wn, below, above);
}

static void prefetch_block(const block *b)
{
    for (size_t j = 0; j < BMAX; j += 64 / sizeof(double)) __builtin_prefetch(&b->key[j]);
    __builtin_prefetch(&b->cpre[0]);
    __builtin_prefetch(&b->cpre[NCH / 2]);
    __builtin_prefetch(&b->w[b->n / 2]);
}

/* The blocks of the old and the new value of each present element ids[i] (d[i], dn[i]), found
 * once for the queries that follow. Above 64 blocks their cache lines are asked for at once:
 * the queries themselves are chains of dependent loads (a directory search, then a search in
 * a block of 0.7 KB), and at N = 100,000 the blocks are far from every cache level but the
 * last (they are in key order: the ~9 cells of a step have unrelated keys), so one after the
 * other each would wait its full latency. */
static void find_blocks(const gp_adstat *s, size_t k, const size_t *ids, const double *key, size_t *d,
                        size_t *dn)
{
    int far = s->nb > 64; /* below, the blocks stay in the nearest caches */
    for (size_t i = 0; far && i < k; i++)
        if (ids[i] < s->cap) __builtin_prefetch(&s->el[ids[i]]);
    for (size_t i = 0; i < k; i++) {
        if (ids[i] >= s->cap || !s->el[ids[i]].on) continue;
        d[i] = find_block(s, s->el[ids[i]].key, (uint32_t)ids[i]);
        dn[i] = in_block(s, d[i], key[i], (uint32_t)ids[i]) ? d[i] : find_block(s, key[i], (uint32_t)ids[i]);
        if (far) prefetch_block(&s->pool[s->dir[d[i]]]);
        if (far && dn[i] != d[i]) prefetch_block(&s->pool[s->dir[dn[i]]]);
    }
}

void gp_adstat_warm(const gp_adstat *s, const uint32_t *ids, size_t m)
{
    for (size_t j = 0; s && j < m; j++)
        if (ids[j] < s->cap) {
            __builtin_prefetch(&s->el[ids[j]]);
            __builtin_prefetch(&s->xt[s->P + ids[j]]);
        }
}

double gp_adstat_a2_if(const gp_adstat *s, size_t k, const size_t *ids, const double *key,
                       const double *g, const double *h, const double *extra, double *sum_extra)
{
    size_t n = gp_adstat_count(s);
    if (n == 0) return 0.0;
    if (k > GP_ADSTAT_IF_MAX) return NAN;
    size_t d[GP_ADSTAT_IF_MAX], dn[GP_ADSTAT_IF_MAX];
    find_blocks(s, k, ids, key, d, dn);
    side so, sn;
    so.k = sn.k = 0;
    i128 dg = 0, dh = 0;
    double dx = 0.0;
    for (size_t i = 0; i < k; i++) {
        size_t id = ids[i];
        if (id >= s->cap || !s->el[id].on) return NAN;
        int64_t gf = fix(g[i]), hf = fix(h[i]);
        dg += (i128)gf - s->el[id].g;
        dh += (i128)hf - s->el[id].h;
        dx += extra[i] - s->xt[s->P + id];
        element_ranks(s, (uint32_t)id, key[i], gf - hf, d[i], dn[i], &so, &sn);
    }
    side_sums(&so);
    side_sums(&sn);
    i128 dr = sn.wcum[k] - so.wcum[k] + side_pairs(&sn, &so) - side_pairs(&so, &so);
    if (sum_extra) *sum_extra = s->xt[1] + dx;
    return a2_of(n, s->R + dr, s->G + dg, s->H + dh);
}

/* ------------------------------------------------------------------------------------------ */
/* self-check                                                                                  */

/* every block: its size, balance with the next, directory key, cpre against its w's, its
 * elements in order and as recorded per id; returns the failing check's number, 0 if none */
static int check_blocks(const gp_adstat *s, size_t *count, i128 *W, i128 *R, i128 *G, i128 *H)
{
    double pk = -INFINITY;
    uint32_t pid = 0;
    int first = 1;
    for (size_t d = 0; d < s->nb; d++) {
        const block *b = &s->pool[s->dir[d]];
        if (b->n == 0 || b->n > BMAX) return 1;
        if (d + 1 < s->nb && b->n + s->pool[s->dir[d + 1]].n <= BMERGE) return 2;
        if (s->dkey[d] != b->key[0] || s->did[d] != b->id[0]) return 3;
        block t = *b;
        block_sums(&t);
        if (memcmp(t.cpre, b->cpre, sizeof t.cpre) != 0) return 4;
        size_t c;
        i128 fw;
        fen_prefix(s, d, &c, &fw);
        if (c != *count || fw != *W) return 5;
        for (size_t j = 0; j < b->n; j++) {
            uint32_t id = b->id[j];
            if (!first && !key_less(pk, pid, b->key[j], id)) return 6;
            if (id >= s->cap || !s->el[id].on || s->el[id].key != b->key[j] || b->w[j] != s->el[id].g - s->el[id].h) return 7;
            first = 0;
            pk = b->key[j];
            pid = id;
            ++*count;
            *W += b->w[j];
            *R += (i128)*count * b->w[j];
            *G += s->el[id].g;
            *H += s->el[id].h;
        }
    }
    return 0;
}

int gp_adstat_check(const gp_adstat *s)
{
    if (!s) return 0;
    size_t count = 0, on = 0;
    i128 W = 0, R = 0, G = 0, H = 0;
    int rc = check_blocks(s, &count, &W, &R, &G, &H);
    if (rc) return rc;
    if ((s->nb == 0) != (s->n == 0) || s->nb > s->pcap) return 8;
    if (count != s->n || W != s->W || R != s->R || G != s->G || H != s->H) return 9;
    for (size_t id = 0; id < s->cap; id++) {
        on += s->el[id].on != 0;
        if (!s->el[id].on && s->xt[s->P + id] != 0.0) return 10;
    }
    if (on != s->n) return 11;
    for (size_t i = 1; i < s->P; i++) {
        double x = s->xt[2 * i] + s->xt[2 * i + 1];
        if (memcmp(&x, &s->xt[i], sizeof x) != 0) return 12;
    }
    return 0;
}
