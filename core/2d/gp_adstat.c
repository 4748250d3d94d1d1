/* gp_adstat.c -- incremental Anderson-Darling statistic in exact fixed point on sorted blocks.
 * See gp_adstat.h for the algorithm and its guarantees; this file is the data structure.
 *
 * Layout. The present elements, ordered by (key, id), are cut into blocks of at most BMAX;
 * a block keeps its keys, ids, fixed w's and the sums of its w's before every CH-th element
 * (cpre), so that a prefix sum inside a block is one cpre plus fewer than CH w's, and an
 * insert or erase is a memmove and BMAX / CH updates.
 *
 * The directory lists the blocks in order in two levels, so that no change to it costs more
 * than O(sqrt(blocks)): pages of at most PMAX entries (a block's pool index and first (key,
 * id), and the count and w-sum of the page's entries before it), and a page table in key order
 * (each page's first (key, id) and entry count) with a Fenwick tree of the pages' counts and
 * w-sums. A key is found by a search in the page table (its keys a few KB: the nearest cache)
 * and one in the page's keys, compared at once; an element already present is found without
 * search, from records kept along (its block, per id; a block's page and entry). A rank query
 * is then a search in the block, a Fenwick prefix over pages and one in-page prefix: a few
 * cache lines, where a balanced tree walks ~log2 N nodes scattered over the heap
 * (docs/design/adstat.md). A change of a block's count or w-sum adds to the prefixes after it
 * in its page and to log2(pages) Fenwick nodes.
 *
 * Balance: every block is non-empty and any two neighbours hold more than BMERGE together
 * (else they are merged), so there are at most 2 n / (BMERGE + 1) + 1 blocks; pages obey the
 * same rule with PMERGE entries, so there are at most 2 blocks / (PMERGE + 1) + 1 of them.
 * That bounds both pools, allocated once at create (pages of them never reached are never
 * touched), so that set and remove never allocate. A full block is split in halves before an
 * insert into it, a full page before an entry goes into it. Blocks and pages are identified by
 * pool index, the directory holds the order; a split or merge moves at most a page's entries
 * and the page table's tail, and rebuilds the Fenwick tree over pages from there.
 *
 * All sums are integers (i128), so their values do not depend on the order in which they were
 * formed nor on how the blocks and pages happen to be cut: the statistic is a function of the
 * set.
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
#define PMAX 32                   /* directory entries a page holds: its keys are four cache
                                   * lines, compared at once (docs/design/adstat.md) */
#define PMERGE (PMAX / 2)         /* neighbouring pages holding no more entries together
                                   * merge; at most PMAX / 2, so that the halves of a split
                                   * page are in balance with any neighbour */
#define TSPAN 16                  /* page-table keys compared at once, after halving */

/* A count c and a w-sum w in one integer, c 2^93 + w: any w-sum of a subset of the elements
 * is below 2^92 in magnitude (2^29 elements, |w| < 2^63) and any count at most 2^29, so the
 * sum of such values is the value of the sums, one load gives both, and they stay inside
 * i128. */
#define CW_SHIFT 93

static i128 cw(int64_t c, i128 w) { return w + (i128)c * ((i128)1 << CW_SHIFT); }

/* the count of a value whose count is not negative (the w-sum is then above -2^92) */
static size_t cw_count(i128 v) { return (size_t)((v + ((i128)1 << (CW_SHIFT - 1))) >> CW_SHIFT); }

static i128 cw_sum(i128 v) { return v - (i128)cw_count(v) * ((i128)1 << CW_SHIFT); }

typedef struct block {
    uint16_t n, j; /* elements; its entry in its page */
    uint32_t page; /* its page's pool index */
    double key[BMAX];
    uint32_t id[BMAX];
    int64_t w[BMAX];
    i128 cpre[NCH + 1]; /* cpre[c] = w[0] + ... + w[min(CH c, n) - 1]; cpre[NCH] the total */
} block;

/* A page of the directory: consecutive blocks, as many as the table says. The count and
 * w-sum of the entries before each one (pre, as cw; pre[m] the page's own) are kept, so that a
 * query reads one value and never the blocks before its own. Keys past the last entry are
 * +inf: no key is below them, so the search in a page compares all PMAX slots and need not
 * know how many are used. */
typedef struct page {
    _Alignas(64) double key[PMAX]; /* each entry's block's first key and id */
    uint32_t blk[PMAX];            /* its pool index */
    uint32_t id[PMAX];
    i128 pre[PMAX + 1];
} page;

/* a block's place in the directory (page position p in the table, entry j in the page) and
 * its pool index k, read with the place so that reaching the block needs no second look */
typedef struct dpos {
    size_t p, j;
    uint32_t k;
} dpos;

struct gp_adstat {
    size_t cap;
    /* per id: the key and fixed logs of a present element (one cache line, not four) */
    struct elem {
        double key;
        int64_t g, h;
        int on;
        uint32_t blk; /* the pool index of its block, so that finding it needs no search */
    } *el;
    /* extras: a segment tree of fixed shape over ids (leaf P + id), so the sum is a function
     * of the set too */
    double *xt;
    size_t P;
    /* blocks: the pool, its bump and free stack; nb of them in the directory */
    block *pool;
    size_t pcap, pused, nfree, nb;
    uint32_t *freel;
    /* pages: the pool, its bump and free stack; the table of the np in use, in key order (pool
     * index, entries, first key and id; tkey is +inf for TSPAN slots past np, so that the
     * search need not stop at the end), and a Fenwick tree (1-based) over table positions of
     * the pages' counts and w-sums, as cw */
    page *pg;
    size_t gcap, gused, gnfree, np;
    uint32_t *gfreel, *gpos, *tpage, *tm, *tid; /* gpos: a page's table position, by pool index */
    double *tkey;
    i128 *fen;
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
        s->pcap = 2 * c / (BMERGE + 1) + 3;        /* the balance bound, and one for a split */
        s->gcap = 2 * s->pcap / (PMERGE + 1) + 3; /* the same for pages of those blocks */
        s->el = calloc(c, sizeof *s->el);
        s->xt = calloc(2 * s->P, sizeof *s->xt);
        s->pool = calloc(s->pcap, sizeof *s->pool);
        s->freel = malloc(s->pcap * sizeof *s->freel);
        s->pg = aligned_alloc(_Alignof(page), s->gcap * sizeof *s->pg); /* keys on line starts */
        s->gfreel = malloc(s->gcap * sizeof *s->gfreel);
        s->gpos = malloc(s->gcap * sizeof *s->gpos);
        s->tpage = malloc(s->gcap * sizeof *s->tpage);
        s->tm = malloc(s->gcap * sizeof *s->tm);
        s->tid = malloc(s->gcap * sizeof *s->tid);
        s->tkey = malloc((s->gcap + TSPAN) * sizeof *s->tkey);
        s->fen = malloc((s->gcap + 1) * sizeof *s->fen);
    }
    if (!s || !s->el || !s->xt || !s->pool || !s->freel || !s->pg || !s->gfreel || !s->gpos || !s->tpage ||
        !s->tm || !s->tid || !s->tkey || !s->fen) {
        gp_adstat_destroy(s);
        gp_error_set(err, GP_ERR_NOMEM, "adstat: out of memory");
        return NULL;
    }
    for (size_t p = 0; p < s->gcap + TSPAN; p++) s->tkey[p] = INFINITY;
    return s;
}

void gp_adstat_destroy(gp_adstat *s)
{
    if (!s) return;
    free(s->el);
    free(s->xt);
    free(s->pool);
    free(s->freel);
    free(s->pg);
    free(s->gfreel);
    free(s->gpos);
    free(s->tpage);
    free(s->tm);
    free(s->tid);
    free(s->tkey);
    free(s->fen);
    free(s);
}

/* ------------------------------------------------------------------------------------------ */
/* searches                                                                                    */

static int key_less(double ua, uint32_t ia, double ub, uint32_t ib)
{
    return ua < ub || (ua == ub && ia < ib);
}

typedef double v2d __attribute__((vector_size(16)));
typedef int64_t v2i __attribute__((vector_size(16)));

/* How many of the n keys k[] (n even, a constant where it is called) are below key: every
 * comparison at once, two to an instruction, where a binary search would wait for each level's
 * load before the next. */
static size_t count_below(const double *k, size_t n, double key)
{
    v2i acc = {0, 0};
    v2d x = {key, key};
    for (size_t i = 0; i < n; i += 2) {
        v2d v;
        memcpy(&v, &k[i], sizeof v);
        acc -= (v2i)(v < x);
    }
    return (size_t)(acc[0] + acc[1]);
}

/* Of sorted first keys k[] and ids[] (n of them, keys +inf for TSPAN slots past n), the last
 * not above (key, id), or 0. Halvings on the key alone (the comparison feeds a conditional
 * move; a branch per level would be mispredicted half the time) narrow it to TSPAN keys, then
 * they are counted at once: the last one below key is the last of the count, and every key
 * past the window is not below key. Then a step over equal keys by id (ties are rare). */
static size_t last_not_above(const double *k, const uint32_t *ids, size_t n, double key, uint32_t id)
{
    size_t base = 0, m = n;
    while (m > TSPAN) {
        size_t half = m / 2;
        base = k[base + half] < key ? base + half : base;
        m -= half;
    }
    size_t c = count_below(&k[base], TSPAN, key);
    base += c - (c > 0);
    while (base + 1 < n && k[base + 1] == key && ids[base + 1] <= id) base++;
    return base;
}

/* the same in a page of m entries (its PMAX keys at once) */
static size_t page_search(const page *g, size_t m, double key, uint32_t id)
{
    size_t c = count_below(g->key, PMAX, key), base = c - (c > 0);
    while (base + 1 < m && g->key[base + 1] == key && g->id[base + 1] <= id) base++;
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

/* ------------------------------------------------------------------------------------------ */
/* blocks                                                                                      */

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

/* count and w-sum of b, as cw */
static i128 block_cw(const block *b) { return cw(b->n, b->cpre[NCH]); }

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
    b->n = (uint16_t)(n + 1);
}

static void block_erase(block *b, size_t pos)
{
    size_t n = b->n;
    for (size_t c = pos / CH + 1; c <= NCH; c++) /* chunk c loses w[pos], gains the next one */
        b->cpre[c] += (CH * c < n ? b->w[CH * c] : 0) - (i128)b->w[pos];
    memmove(&b->key[pos], &b->key[pos + 1], (n - pos - 1) * sizeof b->key[0]);
    memmove(&b->id[pos], &b->id[pos + 1], (n - pos - 1) * sizeof b->id[0]);
    memmove(&b->w[pos], &b->w[pos + 1], (n - pos - 1) * sizeof b->w[0]);
    b->n = (uint16_t)(n - 1);
}

/* the elements of block k from position j on belong to it (they moved there) */
static void block_own(gp_adstat *s, uint32_t k, size_t j)
{
    const block *b = &s->pool[k];
    for (; j < b->n; j++) s->el[b->id[j]].blk = k;
}

/* appends block b's elements to block a */
static void block_append(gp_adstat *s, uint32_t a, uint32_t b)
{
    block *x = &s->pool[a];
    const block *y = &s->pool[b];
    size_t na = x->n;
    memcpy(&x->key[na], y->key, y->n * sizeof y->key[0]);
    memcpy(&x->id[na], y->id, y->n * sizeof y->id[0]);
    memcpy(&x->w[na], y->w, y->n * sizeof y->w[0]);
    x->n = (uint16_t)(na + y->n);
    block_sums(x);
    block_own(s, a, na);
}

static uint32_t pool_take(gp_adstat *s)
{
    uint32_t p = s->nfree > 0 ? s->freel[--s->nfree] : (uint32_t)s->pused++;
    s->pool[p].n = 0;
    block_sums(&s->pool[p]);
    return p;
}

/* ------------------------------------------------------------------------------------------ */
/* Fenwick tree over page positions                                                            */

/* Rebuilds the Fenwick tree from table position a on (after a page split or merge there: the
 * nodes of earlier positions cover earlier pages only, which have not changed). Each node is
 * its page's value plus its children's nodes, added in increasing order; the children below
 * a+1 whose parents are not are the prefix chain of a. O(np - a + log np). */
static void fen_build_from(gp_adstat *s, size_t a)
{
    for (size_t i = a + 1; i <= s->np; i++) s->fen[i] = s->pg[s->tpage[i - 1]].pre[s->tm[i - 1]];
    size_t chain[64], nc = 0;
    for (size_t c = a; c > 0; c &= c - 1) chain[nc++] = c;
    while (nc > 0) {
        size_t c = chain[--nc], p = c + (c & (~c + 1));
        if (p <= s->np) s->fen[p] += s->fen[c];
    }
    for (size_t i = a + 1; i <= s->np; i++) {
        size_t p = i + (i & (~i + 1));
        if (p <= s->np) s->fen[p] += s->fen[i];
    }
}

static void fen_add(gp_adstat *s, size_t p, i128 v)
{
    for (size_t i = p + 1; i <= s->np; i += i & (~i + 1)) s->fen[i] += v;
}

/* count and w-sum of the pages before table position p, as cw */
static i128 fen_prefix(const gp_adstat *s, size_t p)
{
    i128 v = 0;
    for (size_t i = p; i > 0; i &= i - 1) v += s->fen[i];
    return v;
}

/* ------------------------------------------------------------------------------------------ */
/* directory: reading                                                                          */

static page *page_at(const gp_adstat *s, size_t p) { return &s->pg[s->tpage[p]]; }

static block *block_at(const gp_adstat *s, dpos d) { return &s->pool[d.k]; }

static dpos dir_at(const gp_adstat *s, size_t p, size_t j)
{
    dpos d = {p, j, page_at(s, p)->blk[j]};
    return d;
}

/* Where the block holding (key, id) is or would go: the last whose first element is not above
 * it, or the first block. The page's keys and pool indices are asked for as soon as the page
 * is known (a few lines, far at large N), so that the search in it waits for one miss. */
static dpos find_block(const gp_adstat *s, double key, uint32_t id)
{
    size_t p = last_not_above(s->tkey, s->tid, s->np, key, id);
    const page *g = page_at(s, p);
    for (size_t j = 0; j < PMAX; j += 64 / sizeof g->key[0]) __builtin_prefetch(&g->key[j]);
    for (size_t j = 0; j < PMAX; j += 64 / sizeof g->blk[0]) __builtin_prefetch(&g->blk[j]);
    return dir_at(s, p, page_search(g, s->tm[p], key, id));
}

/* the position of block k, from its own record of it: no search */
static dpos locate(const gp_adstat *s, uint32_t k)
{
    dpos d = {s->gpos[s->pool[k].page], s->pool[k].j, k};
    return d;
}

/* the neighbours of *d in block order; 0 at either end */
static int dir_next(const gp_adstat *s, dpos *d)
{
    if (d->j + 1 < s->tm[d->p])
        *d = dir_at(s, d->p, d->j + 1);
    else if (d->p + 1 < s->np)
        *d = dir_at(s, d->p + 1, 0);
    else
        return 0;
    return 1;
}

static int dir_prev(const gp_adstat *s, dpos *d)
{
    if (d->j > 0)
        *d = dir_at(s, d->p, d->j - 1);
    else if (d->p > 0)
        *d = dir_at(s, d->p - 1, s->tm[d->p - 1] - 1);
    else
        return 0;
    return 1;
}

/* the first (key, id) of the block after d; 0 when d is the last */
static int next_first(const gp_adstat *s, dpos d, double *key, uint32_t *id)
{
    if (d.j + 1 < s->tm[d.p]) {
        const page *g = page_at(s, d.p);
        *key = g->key[d.j + 1];
        *id = g->id[d.j + 1];
        return 1;
    }
    if (d.p + 1 == s->np) return 0;
    *key = s->tkey[d.p + 1];
    *id = s->tid[d.p + 1];
    return 1;
}

/* count and w-sum of the blocks before d */
static void dir_prefix(const gp_adstat *s, dpos d, size_t *c, i128 *w)
{
    i128 v = fen_prefix(s, d.p) + page_at(s, d.p)->pre[d.j];
    *c = cw_count(v);
    *w = cw_sum(v);
}

/* elements of the block at d, from the directory (its block may be far from every cache) */
static size_t dir_count(const gp_adstat *s, dpos d)
{
    const page *g = page_at(s, d.p);
    return cw_count(g->pre[d.j + 1] - g->pre[d.j]);
}

/* ------------------------------------------------------------------------------------------ */
/* directory: changes                                                                          */

/* The entries from j on of the page at table position p gained v (a count and w-sum, as cw)
 * before them (a block before them changed), and so did the page. */
static void page_add(gp_adstat *s, size_t p, size_t j, i128 v)
{
    page *g = page_at(s, p);
    for (size_t m = s->tm[p]; j <= m; j++) g->pre[j] += v;
    fen_add(s, p, v);
}

/* the block at d gained dc elements of w-sum dw */
static void dir_add(gp_adstat *s, dpos d, int64_t dc, i128 dw) { page_add(s, d.p, d.j + 1, cw(dc, dw)); }

/* the directory's first (key, id) of the block at d, after its first element changed */
static void dir_key(gp_adstat *s, dpos d)
{
    page *g = page_at(s, d.p);
    const block *b = &s->pool[g->blk[d.j]];
    g->key[d.j] = b->key[0];
    g->id[d.j] = b->id[0];
    if (d.j > 0) return;
    s->tkey[d.p] = b->key[0];
    s->tid[d.p] = b->id[0];
}

static uint32_t page_take(gp_adstat *s)
{
    uint32_t q = s->gnfree > 0 ? s->gfreel[--s->gnfree] : (uint32_t)s->gused++;
    for (size_t j = 0; j < PMAX; j++) s->pg[q].key[j] = INFINITY;
    s->pg[q].pre[0] = 0;
    return q;
}

/* puts page q, holding m entries, at table position p, shifting the rest up */
static void table_insert(gp_adstat *s, size_t p, uint32_t q, size_t m)
{
    size_t r = s->np - p;
    memmove(&s->tpage[p + 1], &s->tpage[p], r * sizeof s->tpage[0]);
    memmove(&s->tm[p + 1], &s->tm[p], r * sizeof s->tm[0]);
    memmove(&s->tkey[p + 1], &s->tkey[p], r * sizeof s->tkey[0]);
    memmove(&s->tid[p + 1], &s->tid[p], r * sizeof s->tid[0]);
    s->tpage[p] = q;
    s->tm[p] = (uint32_t)m;
    s->tkey[p] = s->pg[q].key[0];
    s->tid[p] = s->pg[q].id[0];
    s->np++;
    for (; p < s->np; p++) s->gpos[s->tpage[p]] = (uint32_t)p;
}

/* takes the page at table position p out and frees it */
static void table_erase(gp_adstat *s, size_t p)
{
    s->gfreel[s->gnfree++] = s->tpage[p];
    size_t r = s->np - p - 1;
    memmove(&s->tpage[p], &s->tpage[p + 1], r * sizeof s->tpage[0]);
    memmove(&s->tm[p], &s->tm[p + 1], r * sizeof s->tm[0]);
    memmove(&s->tkey[p], &s->tkey[p + 1], r * sizeof s->tkey[0]);
    memmove(&s->tid[p], &s->tid[p + 1], r * sizeof s->tid[0]);
    s->tkey[--s->np] = INFINITY;
    for (; p < s->np; p++) s->gpos[s->tpage[p]] = (uint32_t)p;
}

/* the blocks of entries from j on of page q record their place */
static void entries_own(gp_adstat *s, uint32_t q, size_t j, size_t m)
{
    for (; j < m; j++) {
        block *b = &s->pool[s->pg[q].blk[j]];
        b->page = q;
        b->j = (uint16_t)j;
    }
}

/* copies m entries of page qa from position from to page qb at position at; qb's prefixes go
 * on from its entry at, qa's differences added to them */
static void entries_copy(gp_adstat *s, uint32_t qb, size_t at, uint32_t qa, size_t from, size_t m)
{
    page *b = &s->pg[qb];
    const page *a = &s->pg[qa];
    memcpy(&b->key[at], &a->key[from], m * sizeof a->key[0]);
    memcpy(&b->blk[at], &a->blk[from], m * sizeof a->blk[0]);
    memcpy(&b->id[at], &a->id[from], m * sizeof a->id[0]);
    for (size_t j = 1; j <= m; j++) b->pre[at + j] = b->pre[at] + (a->pre[from + j] - a->pre[from]);
    entries_own(s, qb, at, at + m);
}

/* moves the upper half of the full page at table position p into a new page at p + 1 */
static void page_split(gp_adstat *s, size_t p)
{
    uint32_t q = page_take(s);
    page *a = page_at(s, p);
    size_t m = s->tm[p], h = m / 2;
    entries_copy(s, q, 0, s->tpage[p], h, m - h);
    for (size_t j = h; j < m; j++) a->key[j] = INFINITY;
    s->tm[p] = (uint32_t)h;
    table_insert(s, p + 1, q, m - h);
    fen_build_from(s, p);
}

/* appends the page at table position p + 1 to the one at p */
static void page_merge(gp_adstat *s, size_t p)
{
    entries_copy(s, s->tpage[p], s->tm[p], s->tpage[p + 1], 0, s->tm[p + 1]);
    s->tm[p] += s->tm[p + 1];
    table_erase(s, p + 1);
    fen_build_from(s, p);
}

/* Restores the balance around table position p after its page lost an entry: an empty page
 * goes; a page whose neighbour and it hold <= PMERGE entries together is merged with it. */
static void page_rebalance(gp_adstat *s, size_t p)
{
    if (s->tm[p] == 0) {
        table_erase(s, p);
        fen_build_from(s, p);
        return;
    }
    if (p + 1 < s->np && s->tm[p] + s->tm[p + 1] <= PMERGE) page_merge(s, p);
    if (p > 0 && s->tm[p - 1] + s->tm[p] <= PMERGE) page_merge(s, p - 1);
}

/* puts block k at d (its page has room), shifting the page's entries from d.j up */
static void entry_insert(gp_adstat *s, dpos d, uint32_t k)
{
    page *g = page_at(s, d.p);
    size_t r = s->tm[d.p] - d.j;
    memmove(&g->key[d.j + 1], &g->key[d.j], r * sizeof g->key[0]);
    memmove(&g->blk[d.j + 1], &g->blk[d.j], r * sizeof g->blk[0]);
    memmove(&g->id[d.j + 1], &g->id[d.j], r * sizeof g->id[0]);
    memmove(&g->pre[d.j + 1], &g->pre[d.j], (r + 1) * sizeof g->pre[0]);
    g->blk[d.j] = k;
    s->tm[d.p]++;
    s->nb++;
    entries_own(s, s->tpage[d.p], d.j, s->tm[d.p]);
    dir_key(s, d);
    page_add(s, d.p, d.j + 1, block_cw(&s->pool[k]));
}

/* puts block k right after the block at d, splitting d's page first when it is full */
static void dir_insert_after(gp_adstat *s, dpos d, uint32_t k)
{
    if (s->tm[d.p] == PMAX) {
        page_split(s, d.p);
        size_t h = s->tm[d.p];
        if (d.j >= h) {
            d.p++;
            d.j -= h;
        }
    }
    d.j++;
    entry_insert(s, d, k);
}

/* takes the block at d out of the directory and frees it */
static void dir_erase(gp_adstat *s, dpos d)
{
    page *g = page_at(s, d.p);
    s->freel[s->nfree++] = g->blk[d.j];
    page_add(s, d.p, d.j + 1, g->pre[d.j] - g->pre[d.j + 1]);
    size_t r = s->tm[d.p] - d.j - 1;
    memmove(&g->key[d.j], &g->key[d.j + 1], r * sizeof g->key[0]);
    memmove(&g->blk[d.j], &g->blk[d.j + 1], r * sizeof g->blk[0]);
    memmove(&g->id[d.j], &g->id[d.j + 1], r * sizeof g->id[0]);
    memmove(&g->pre[d.j + 1], &g->pre[d.j + 2], r * sizeof g->pre[0]);
    g->key[--s->tm[d.p]] = INFINITY;
    s->nb--;
    entries_own(s, s->tpage[d.p], d.j, s->tm[d.p]);
    if (d.j == 0 && s->tm[d.p] > 0) {
        s->tkey[d.p] = g->key[0];
        s->tid[d.p] = g->id[0];
    }
    page_rebalance(s, d.p);
}

/* the first page and block, empty, for a first element */
static void dir_init(gp_adstat *s)
{
    uint32_t q = page_take(s);
    page *g = &s->pg[q];
    g->blk[0] = pool_take(s);
    g->pre[1] = 0;
    s->tpage[0] = q;
    s->gpos[q] = 0;
    entries_own(s, q, 0, 1);
    s->tm[0] = 1;
    s->np = 1;
    s->nb = 1;
    s->fen[1] = 0;
}

/* moves the upper half of the full block at d into a new block right after it; returns the
 * new block's pool index */
static uint32_t split(gp_adstat *s, dpos d)
{
    uint32_t k = pool_take(s);
    block *a = block_at(s, d), *b = &s->pool[k];
    size_t h = a->n / 2, m = a->n - h;
    memcpy(b->key, &a->key[h], m * sizeof a->key[0]);
    memcpy(b->id, &a->id[h], m * sizeof a->id[0]);
    memcpy(b->w, &a->w[h], m * sizeof a->w[0]);
    b->n = (uint16_t)m;
    a->n = (uint16_t)h;
    block_sums(a);
    block_sums(b);
    block_own(s, k, 0);
    page_add(s, d.p, d.j + 1, -block_cw(b));
    dir_insert_after(s, d, k);
    return k;
}

/* appends the block at e to the one at d (its predecessor) and frees it */
static void merge(gp_adstat *s, dpos d, dpos e)
{
    page_add(s, d.p, d.j + 1, block_cw(block_at(s, e)));
    block_append(s, d.k, e.k);
    dir_erase(s, e);
}

/* Restores the balance around the block at d after it changed: an empty block goes; a block
 * whose neighbour and it hold <= BMERGE together is merged with it. The counts come from the
 * directory, so that a block in balance costs no look at its neighbours. Merges may move the
 * pages, so the block is located again. */
static void rebalance(gp_adstat *s, dpos d)
{
    size_t n = dir_count(s, d);
    if (n == 0) {
        dir_erase(s, d);
        return;
    }
    dpos e = d;
    if (dir_next(s, &e) && n + dir_count(s, e) <= BMERGE) {
        n += dir_count(s, e);
        merge(s, d, e);
        d = locate(s, d.k);
    }
    e = d;
    if (dir_prev(s, &e) && dir_count(s, e) + n <= BMERGE) merge(s, e, d);
}

/* ------------------------------------------------------------------------------------------ */
/* insert, remove                                                                              */

/* count below and w-sum of the elements before position pos of the block at d */
static void rank_at(const gp_adstat *s, dpos d, size_t pos, size_t *below, i128 *wbelow)
{
    dir_prefix(s, d, below, wbelow);
    *below += pos;
    *wbelow += block_prefix(block_at(s, d), pos);
}

/* Inserts (key, id, w), absent. R gains the new element's rank times w plus the w's above it
 * (each of which moves up one rank). A full block is split first; the halves may then be
 * light enough to merge with their outer neighbours. */
static void tree_insert(gp_adstat *s, double key, uint32_t id, int64_t w)
{
    if (s->nb == 0) dir_init(s);
    dpos d = find_block(s, key, id);
    uint32_t left = UINT32_MAX, right = 0;
    if (block_at(s, d)->n == BMAX) {
        left = d.k;
        right = split(s, d);
        d = locate(s, key_less(key, id, s->pool[right].key[0], s->pool[right].id[0]) ? left : right);
    }
    block *b = block_at(s, d);
    s->el[id].blk = d.k;
    size_t pos = lower_bound(b, key, id), below;
    i128 wbelow;
    rank_at(s, d, pos, &below, &wbelow);
    s->R += (i128)(below + 1) * w + (s->W - wbelow);
    block_insert(b, pos, key, id, w);
    if (pos == 0) dir_key(s, d);
    s->W += w;
    s->n++;
    dir_add(s, d, 1, w);
    if (left == UINT32_MAX) return;
    rebalance(s, locate(s, right)); /* the right half and its right neighbour, */
    rebalance(s, locate(s, left));  /* the left half and its left one */
}

/* Removes (key, id, w), present; the inverse of tree_insert, so R comes back exactly. */
static void tree_remove(gp_adstat *s, double key, uint32_t id, int64_t w)
{
    dpos d = locate(s, s->el[id].blk);
    block *b = block_at(s, d);
    size_t pos = lower_bound(b, key, id), below;
    i128 wbelow;
    rank_at(s, d, pos, &below, &wbelow);
    s->W -= w;
    s->n--;
    s->R -= (i128)(below + 1) * w + (s->W - wbelow);
    block_erase(b, pos);
    if (pos == 0 && b->n > 0) dir_key(s, d);
    dir_add(s, d, -1, -(i128)w);
    rebalance(s, d);
}

/* A present element whose new key stays in its block (strictly between the block's first
 * element and the next block's): erase and insert inside the block, no directory search and
 * one prefix for both, no change to the directory's shape. R is updated as by tree_remove then
 * tree_insert, so it is the same integer. Returns 0, nothing done, when the key leaves the
 * block. */
static int tree_move_in_block(gp_adstat *s, double ko, uint32_t id, int64_t wo, double kn, int64_t wn)
{
    dpos d = locate(s, s->el[id].blk);
    const page *g = page_at(s, d.p);
    double nk;
    uint32_t nid;
    if (((d.p > 0 || d.j > 0) && !key_less(g->key[d.j], g->id[d.j], kn, id)) ||
        (next_first(s, d, &nk, &nid) && !key_less(kn, id, nk, nid)))
        return 0;
    block *b = block_at(s, d);
    size_t p = lower_bound(b, ko, id), c;
    i128 wd;
    dir_prefix(s, d, &c, &wd);
    i128 wb = wd + block_prefix(b, p);
    s->W -= wo;
    s->R -= (i128)(c + p + 1) * wo + (s->W - wb);
    block_erase(b, p);
    size_t q = lower_bound(b, kn, id);
    wb = wd + block_prefix(b, q);
    s->R += (i128)(c + q + 1) * wn + (s->W - wb);
    s->W += wn;
    block_insert(b, q, kn, id, wn);
    dir_key(s, d);
    dir_add(s, d, 0, (i128)wn - wo);
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
 * w-sum of those strictly above, in the block at d (the caller's position for it) whose
 * preceding blocks hold c elements of w-sum wd. */
static void rank_in(const gp_adstat *s, dpos d, size_t c, i128 wd, double key, uint32_t id,
                    size_t *below, i128 *above)
{
    const block *b = block_at(s, d);
    size_t pos = lower_bound(b, key, id);
    size_t eq = pos < b->n && b->key[pos] == key && b->id[pos] == id;
    *below = c + pos;
    *above = s->W - wd - block_prefix(b, pos + eq);
}

/* 1 when (key, id) lies between the first and the last element of the block at d (or below
 * the first block's last), so that it belongs to the block (find_block would say d); 0 may
 * still be the block, found then by a search. From the block alone: its lines are on their
 * way, the page's may not be. */
static int in_block(const gp_adstat *s, dpos d, double key, uint32_t id)
{
    const block *b = block_at(s, d);
    return (d.p + d.j == 0 || !key_less(key, id, b->key[0], b->id[0])) &&
           !key_less(b->key[b->n - 1], b->id[b->n - 1], key, id);
}

static int same_pos(dpos a, dpos b) { return a.p == b.p && a.j == b.j; }

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

/* Both values of element id into the sides: the old one at position d (it is in the set), the
 * new one at dn (d itself when it falls in the same block: one prefix read for both). */
static void element_ranks(const gp_adstat *s, uint32_t id, double kn, int64_t wn, dpos d, dpos dn,
                          side *so, side *sn)
{
    double ko = s->el[id].key;
    size_t c, below;
    i128 wd, above;
    dir_prefix(s, d, &c, &wd);
    rank_in(s, d, c, wd, ko, id, &below, &above);
    side_add(so, ko, id, s->el[id].g - s->el[id].h, below, above);
    if (!same_pos(dn, d)) dir_prefix(s, dn, &c, &wd);
    rank_in(s, dn, c, wd, kn, id, &below, &above);
    side_add(sn, kn, id, wn, below, above);
}

static void prefetch_block(const block *b)
{
    for (size_t j = 0; j < BMAX; j += 64 / sizeof(double)) __builtin_prefetch(&b->key[j]);
    __builtin_prefetch(&b->cpre[0]);
    __builtin_prefetch(&b->cpre[NCH]);
    __builtin_prefetch(&b->w[BMAX / 2]);
}

/* the block at d and its in-page prefix (dir_prefix) */
static void prefetch_at(const gp_adstat *s, dpos d)
{
    __builtin_prefetch(&page_at(s, d.p)->pre[d.j]);
    prefetch_block(block_at(s, d));
}

/* The blocks of the old and the new value of each present element ids[i] (d[i], dn[i]), found
 * once for the queries that follow: the old one from the element's record, the new one by a
 * search unless it falls in the same block. Above 64 blocks their cache lines are asked for at
 * once, the old values' blocks first (their places are known before any search): the queries
 * themselves are chains of dependent loads (a search in a block of 0.7 KB), and at N = 100,000
 * the blocks are far from every cache level but the last (they are in key order: the ~9 cells
 * of a step have unrelated keys), so one after the other each would wait its full latency. */
static void find_blocks(const gp_adstat *s, size_t k, const size_t *ids, const double *key, dpos *d,
                        dpos *dn)
{
    int far = s->nb > 64; /* below, the blocks stay in the nearest caches */
    for (size_t i = 0; far && i < k; i++)
        if (ids[i] < s->cap) __builtin_prefetch(&s->el[ids[i]]);
    for (size_t i = 0; far && i < k; i++)
        if (ids[i] < s->cap && s->el[ids[i]].on) prefetch_block(&s->pool[s->el[ids[i]].blk]);
    for (size_t i = 0; i < k; i++) {
        if (ids[i] >= s->cap || !s->el[ids[i]].on) continue;
        d[i] = locate(s, s->el[ids[i]].blk);
        if (far) __builtin_prefetch(&page_at(s, d[i].p)->pre[d[i].j]);
        dn[i] = in_block(s, d[i], key[i], (uint32_t)ids[i]) ? d[i] : find_block(s, key[i], (uint32_t)ids[i]);
        if (far && !same_pos(dn[i], d[i])) prefetch_at(s, dn[i]);
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
    dpos d[GP_ADSTAT_IF_MAX], dn[GP_ADSTAT_IF_MAX];
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

/* every page: its pool index, size, balance with the next, the table's order and first key,
 * the +inf past its entries and past the table, its prefixes' start, the Fenwick prefix before
 * it against the pages' own sums; the page and block counts against the pools. Returns the
 * failing check's number, 0 if none */
static int check_pages(const gp_adstat *s)
{
    size_t nb = 0;
    i128 sum = 0;
    if (s->np > s->gcap) return 13;
    for (size_t p = 0; p < s->np; p++) {
        if (s->tpage[p] >= s->gused || s->gpos[s->tpage[p]] != p) return 14;
        const page *g = page_at(s, p);
        size_t m = s->tm[p];
        if (m == 0 || m > PMAX) return 15;
        if (p + 1 < s->np && m + s->tm[p + 1] <= PMERGE) return 16;
        if (s->tkey[p] != g->key[0] || s->tid[p] != g->id[0]) return 17;
        if (p > 0 && !key_less(s->tkey[p - 1], s->tid[p - 1], s->tkey[p], s->tid[p])) return 18;
        for (size_t j = 0; j < PMAX; j++)
            if (j < m ? g->blk[j] >= s->pused : g->key[j] != INFINITY) return 19;
        if (g->pre[0] != 0 || fen_prefix(s, p) != sum) return 20;
        sum += g->pre[m];
        nb += m;
    }
    for (size_t p = s->np; p < s->np + TSPAN; p++)
        if (s->tkey[p] != INFINITY) return 21;
    if (nb != s->nb || s->np + s->gnfree != s->gused || s->nb + s->nfree != s->pused) return 22;
    if (fen_prefix(s, s->np) != sum || sum != cw((int64_t)s->n, s->W)) return 23;
    return 0;
}

/* every block: its size, balance with the next, directory key and its record of its place,
 * cpre against its w's, the directory's count and w-sum before it and its own, its elements in
 * order and as recorded per id (with their block); returns the failing check's number, 0 if
 * none */
static int check_blocks(const gp_adstat *s, size_t *count, i128 *W, i128 *R, i128 *G, i128 *H)
{
    double pk = -INFINITY;
    uint32_t pid = 0;
    int first = 1, more = s->np > 0;
    for (dpos d = more ? dir_at(s, 0, 0) : (dpos){0, 0, 0}; more;) {
        const page *g = page_at(s, d.p);
        const block *b = block_at(s, d);
        dpos e = d;
        more = dir_next(s, &e);
        if (b->n == 0 || b->n > BMAX) return 1;
        if (more && b->n + block_at(s, e)->n <= BMERGE) return 2;
        if (g->key[d.j] != b->key[0] || g->id[d.j] != b->id[0]) return 3;
        if (b->page != s->tpage[d.p] || b->j != d.j) return 3;
        block t = *b;
        block_sums(&t);
        if (memcmp(t.cpre, b->cpre, sizeof t.cpre) != 0) return 4;
        size_t c;
        i128 dw;
        dir_prefix(s, d, &c, &dw);
        if (c != *count || dw != *W || g->pre[d.j + 1] - g->pre[d.j] != block_cw(b)) return 5;
        for (size_t j = 0; j < b->n; j++) {
            uint32_t id = b->id[j];
            if (!first && !key_less(pk, pid, b->key[j], id)) return 6;
            if (id >= s->cap || !s->el[id].on || s->el[id].key != b->key[j] || b->w[j] != s->el[id].g - s->el[id].h) return 7;
            if (s->el[id].blk != d.k) return 7;
            first = 0;
            pk = b->key[j];
            pid = id;
            ++*count;
            *W += b->w[j];
            *R += (i128)*count * b->w[j];
            *G += s->el[id].g;
            *H += s->el[id].h;
        }
        d = e;
    }
    return 0;
}

int gp_adstat_check(const gp_adstat *s)
{
    if (!s) return 0;
    size_t count = 0, on = 0;
    i128 W = 0, R = 0, G = 0, H = 0;
    int rc = check_pages(s);
    if (rc) return rc;
    rc = check_blocks(s, &count, &W, &R, &G, &H);
    if (rc) return rc;
    if ((s->nb == 0) != (s->n == 0) || (s->np == 0) != (s->n == 0) || s->nb > s->pcap) return 8;
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
