/* test_adstat.c -- the incremental Anderson-Darling statistic (gp_adstat.h) against a
 * brute-force A^2 recomputed from the sorted values after every kind of change, the structure's
 * own recount (gp_adstat_check) through splits and merges of its blocks, bit-exact restores,
 * history independence, the what-if equal bit for bit to the change, clamping, the floor and
 * ties. */
#include "gp_adstat.h"
#include "gp_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* the test's own generator (splitmix64), so that it needs no other module */
static uint64_t rng_state = 12345;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double unif(void) { return ((double)(rnd() >> 11) + 0.5) / 9007199254740992.0; } /* (0, 1) */
static size_t below(size_t n) { return (size_t)(rnd() % n); }

/* a mirror of the elements present: u (the key), the extra, presence */
typedef struct mirror {
    size_t cap;
    double *u, *x;
    int *on;
} mirror;

static void put(gp_adstat *s, mirror *m, size_t id, double u, double x)
{
    gp_adstat_set(s, id, u, log(u), log1p(-u), x);
    m->u[id] = u;
    m->x[id] = x;
    m->on[id] = 1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* A^2 = -N - (1/N) sum_i (2i - 1) [ln u_(i) + ln(1 - u_(N+1-i))] from n values */
static double a2_brute(const double *v, size_t n)
{
    if (n == 0) return 0.0;
    double *u = malloc(n * sizeof *u), sum = 0;
    memcpy(u, v, n * sizeof *u);
    qsort(u, n, sizeof *u, cmp_double);
    for (size_t i = 1; i <= n; i++) sum += (2.0 * i - 1) * (log(u[i - 1]) + log1p(-u[n - i]));
    free(u);
    return -(double)n - sum / (double)n;
}

/* checks the object against the mirror: count, A^2 and the sum of extras */
static void check_against(const gp_adstat *s, const mirror *m)
{
    double *u = malloc((m->cap + 1) * sizeof *u), sx = 0;
    size_t n = 0;
    for (size_t i = 0; i < m->cap; i++)
        if (m->on[i]) {
            u[n++] = m->u[i];
            sx += m->x[i];
        }
    CHECK(gp_adstat_count(s) == n);
    CHECK(gp_adstat_check(s) == 0);
    double a2 = gp_adstat_a2(s), b = a2_brute(u, n);
    /* relative to A^2, or to the size of the sum it is cancelled from when A^2 is small */
    CHECK_NEAR(a2, b, 1e-9 * fabs(b) + 1e-12 * (double)n);
    CHECK_NEAR(gp_adstat_sum_extra(s), sx, 1e-12 * (double)(n + 1));
    free(u);
}

/* random sequences of new ids, updates (small moves and jumps across the set) and removes */
static void test_random_sets(void)
{
    const size_t sizes[] = {1, 2, 3, 10, 1000};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        size_t n = sizes[k], cap = 2 * n, steps = n < 100 ? 400 : 20 * n;
        mirror m = {cap, calloc(cap, sizeof(double)), calloc(cap, sizeof(double)), calloc(cap, sizeof(int))};
        gp_adstat *s = gp_adstat_create(cap, NULL);
        CHECK(s != NULL && gp_adstat_count(s) == 0 && gp_adstat_a2(s) == 0.0 && gp_adstat_sum_extra(s) == 0.0);
        for (size_t i = 0; i < n; i++) put(s, &m, i, unif(), unif());
        check_against(s, &m);
        for (size_t t = 0; t < steps; t++) {
            size_t id = below(cap), r = below(10);
            if (r < 2) {
                gp_adstat_remove(s, id);
                m.on[id] = 0;
            } else if (r < 6 && m.on[id]) { /* a small move, mostly staying between its neighbours */
                double u = m.u[id] * (1 + 1e-4 * (unif() - 0.5));
                put(s, &m, id, u < 1 ? u : m.u[id], unif());
            } else {
                put(s, &m, id, unif(), unif());
            }
            if (n < 100 || t % 97 == 0) check_against(s, &m);
        }
        check_against(s, &m);
        /* out-of-range ids and absent ids are ignored */
        gp_adstat_set(s, cap, 0.5, log(0.5), log(0.5), 1.0);
        gp_adstat_remove(s, cap + 3);
        for (size_t id = 0; id < cap; id++)
            if (!m.on[id]) {
                gp_adstat_remove(s, id);
                break;
            }
        check_against(s, &m);
        /* empty again */
        for (size_t id = 0; id < cap; id++) gp_adstat_remove(s, id);
        CHECK(gp_adstat_count(s) == 0 && gp_adstat_a2(s) == 0.0 && gp_adstat_sum_extra(s) == 0.0);
        gp_adstat_destroy(s);
        free(m.u);
        free(m.x);
        free(m.on);
    }
    /* by hand: one value u has A^2 = -1 - ln u - ln(1 - u) */
    gp_adstat *s = gp_adstat_create(5, NULL);
    gp_adstat_set(s, 3, 0.2, log(0.2), log(0.8), 7.0);
    CHECK_NEAR(gp_adstat_a2(s), -1 - log(0.2) - log(0.8), 3e-14); /* g, h in units of 2^-46 */
    CHECK(gp_adstat_sum_extra(s) == 7.0);
    gp_adstat_destroy(s);
}

static int same_bits(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* setting elements back restores A^2 and the extra sum bit for bit, and a history of changes
 * leaves the same bits as building the final set from scratch in another order */
static void test_bit_exact(void)
{
    const size_t n = 1000;
    mirror m = {n, calloc(n, sizeof(double)), calloc(n, sizeof(double)), calloc(n, sizeof(int))};
    gp_adstat *s = gp_adstat_create(n, NULL);
    for (size_t i = 0; i < n; i++) put(s, &m, i, unif(), unif() * 100);
    int restored = 1, rebuilt = 1;
    for (int round = 0; round < 200; round++) {
        double a2 = gp_adstat_a2(s), sx = gp_adstat_sum_extra(s);
        size_t ids[20];
        double ou[20], ox[20];
        for (int j = 0; j < 20; j++) {
            ids[j] = below(n); /* repeats allowed: the first old value is the one put back */
            ou[j] = m.u[ids[j]];
            ox[j] = m.x[ids[j]];
            for (int i = 0; i < j; i++)
                if (ids[i] == ids[j]) {
                    ou[j] = ou[i];
                    ox[j] = ox[i];
                }
            double u = j % 3 == 0 ? unif() : m.u[ids[j]] * (1 + 1e-6 * (unif() - 0.5));
            if (j == 5) u = ou[j] < 0.5 ? 0.999 : 0.001; /* past most of the set */
            if (j == 7) {
                gp_adstat_remove(s, ids[j]);
                m.on[ids[j]] = 0;
                continue;
            }
            put(s, &m, ids[j], u < 1 ? u : 0.5, unif() * 100);
        }
        check_against(s, &m);
        for (int j = 19; j > 0; j--) { /* back in a shuffled order */
            size_t i = below((size_t)j + 1);
            size_t ti = ids[i];
            double tu = ou[i], tx = ox[i];
            ids[i] = ids[j], ou[i] = ou[j], ox[i] = ox[j];
            ids[j] = ti, ou[j] = tu, ox[j] = tx;
        }
        for (int j = 0; j < 20; j++) put(s, &m, ids[j], ou[j], ox[j]);
        restored &= same_bits(gp_adstat_a2(s), a2) && same_bits(gp_adstat_sum_extra(s), sx);
        /* and some history kept: move a few elements for good */
        for (int j = 0; j < 5; j++) put(s, &m, below(n), unif(), unif() * 100);
    }
    CHECK(restored);
    /* the same set built from scratch, inserted in reverse: the same bits */
    gp_adstat *f = gp_adstat_create(n, NULL);
    for (size_t i = n; i-- > 0;)
        if (m.on[i]) gp_adstat_set(f, i, m.u[i], log(m.u[i]), log1p(-m.u[i]), m.x[i]);
    rebuilt &= same_bits(gp_adstat_a2(f), gp_adstat_a2(s)) && same_bits(gp_adstat_sum_extra(f), gp_adstat_sum_extra(s));
    CHECK(rebuilt);
    check_against(s, &m);
    /* and the sums do differ with the set (the bitwise checks above can fail) */
    double a2 = gp_adstat_a2(s);
    size_t id = 0;
    while (!m.on[id]) id++;
    put(s, &m, id, m.u[id] * (1 - 1e-9), m.x[id]);
    CHECK(gp_adstat_a2(s) != a2);
    gp_adstat_destroy(f);
    gp_adstat_destroy(s);
    free(m.u);
    free(m.x);
    free(m.on);
}

static void test_floor(void)
{
    CHECK_NEAR(gp_adstat_floor(1), -1 - 2 * log(0.5), 1e-15);
    CHECK_NEAR(gp_adstat_floor(1), 0.38629436111989057, 1e-15);
    CHECK(gp_adstat_floor(0) == 0.0);
    const size_t sizes[] = {1, 2, 3, 7, 100, 1000};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        size_t n = sizes[k];
        double *u = malloc(n * sizeof *u), *v = malloc(n * sizeof *v), fl = gp_adstat_floor(n);
        for (size_t i = 0; i < n; i++) u[i] = (2.0 * i + 1) / (2.0 * n);
        CHECK_NEAR(fl, a2_brute(u, n), 1e-12 * (1 + fl));
        CHECK(fl > 0);
        gp_adstat *s = gp_adstat_create(n, NULL);
        for (size_t i = 0; i < n; i++) gp_adstat_set(s, i, u[i], log(u[i]), log1p(-u[i]), 0);
        CHECK_NEAR(gp_adstat_a2(s), fl, 1e-12 * (double)n);
        /* nothing scores below it: random sets, and the ideal set perturbed */
        const double slack = 1e-12 * (double)n;
        int above = 1;
        for (int t = 0; t < 300; t++) {
            double amp = t < 100 ? 0 : 0.3 / (double)n * (t < 200 ? 1 : 1e-2);
            for (size_t i = 0; i < n; i++) {
                v[i] = amp == 0 ? unif() : u[i] + amp * (unif() - 0.5);
                gp_adstat_set(s, i, v[i], log(v[i]), log1p(-v[i]), 0);
            }
            above &= a2_brute(v, n) >= fl - slack && gp_adstat_a2(s) >= fl - slack;
        }
        CHECK(above);
        gp_adstat_destroy(s);
        free(u);
        free(v);
    }
}

/* tied keys (with equal logs, as the header asks) in any id order */
static void test_ties(void)
{
    const size_t n = 60;
    const double vals[3] = {0.2, 0.5, 0.7};
    double u[60], a2[4];
    for (size_t i = 0; i < n; i++) u[i] = vals[i % 3];
    double b = a2_brute(u, n);
    for (int order = 0; order < 4; order++) {
        /* order 0, 1: the same id -> value map inserted forwards and backwards; 2, 3: the
         * values dealt to the ids in other patterns */
        gp_adstat *s = gp_adstat_create(n, NULL);
        for (size_t j = 0; j < n; j++) {
            size_t i = order == 1 ? n - 1 - j : j;
            double v = order < 2 ? u[i] : order == 2 ? vals[i / 20] : vals[(i + i / 3) % 3];
            gp_adstat_set(s, i, v, log(v), log1p(-v), v);
        }
        a2[order] = gp_adstat_a2(s);
        CHECK_REL(a2[order], b, 1e-12);
        CHECK_NEAR(gp_adstat_sum_extra(s), 20 * (0.2 + 0.5 + 0.7), 1e-12);
        /* every element moved to the middle value and back, one by one */
        for (size_t i = 0; i < n; i++) {
            double v = order < 2 ? u[i] : order == 2 ? vals[i / 20] : vals[(i + i / 3) % 3];
            gp_adstat_set(s, i, 0.5, log(0.5), log1p(-0.5), 0.5);
            gp_adstat_set(s, i, v, log(v), log1p(-v), v);
        }
        CHECK(same_bits(gp_adstat_a2(s), a2[order]));
        gp_adstat_destroy(s);
    }
    CHECK(same_bits(a2[0], a2[1]));
    /* all equal: A^2 of n copies of u */
    gp_adstat *s = gp_adstat_create(n, NULL);
    double all[60];
    for (size_t i = 0; i < n; i++) {
        all[i] = 0.5;
        gp_adstat_set(s, n - 1 - i, 0.5, log(0.5), log(0.5), 0);
    }
    CHECK_REL(gp_adstat_a2(s), a2_brute(all, n), 1e-12);
    CHECK_REL(gp_adstat_a2(s), -(double)n - 2 * (double)n * log(0.5), 1e-12); /* sum (2i-1) = n^2 */
    gp_adstat_destroy(s);
}

/* gp_adstat_a2_if: the A^2 a change would give, judged without making it, equals the A^2
 * after making it -- for small moves, jumps across the set, unchanged elements in the batch,
 * and batches of 1 to GP_ADSTAT_IF_MAX elements; the set is left untouched */
/* u, or with levels > 0 the middle of its 1/levels class: ties of key (with equal logs), many
 * to a key, across a block's chunks and across blocks */
static double level(double u, double levels)
{
    return levels > 0 ? (floor(u * levels) + 0.5) / levels : u;
}

/* n values: 500 (a few blocks) and 5,000 (many blocks, a batch's values in different ones) */
static void test_a2_if_n(size_t n, double levels)
{
    gp_adstat *s = gp_adstat_create(n, NULL);
    mirror m = {n, calloc(n, sizeof(double)), calloc(n, sizeof(double)), calloc(n, sizeof(int))};
    for (size_t i = 0; i < n; i++) put(s, &m, i, level(unif(), levels), unif());
    size_t ids[GP_ADSTAT_IF_MAX];
    double key[GP_ADSTAT_IF_MAX], g[GP_ADSTAT_IF_MAX], h[GP_ADSTAT_IF_MAX], x[GP_ADSTAT_IF_MAX];
    for (int round = 0; round < 400; round++) {
        size_t k = 1 + below(GP_ADSTAT_IF_MAX);
        for (size_t i = 0; i < k; i++) { /* distinct ids */
            size_t id;
            int dup;
            do {
                id = below(n);
                dup = 0;
                for (size_t j = 0; j < i; j++) dup |= ids[j] == id;
            } while (dup);
            ids[i] = id;
            double u = round % 3 == 0 ? unif() : m.u[id] + 1e-3 * (unif() - 0.5);
            if (i % 7 == 3) u = m.u[id]; /* unchanged */
            u = level(fmin(fmax(u, 1e-9), 1 - 1e-9), levels);
            key[i] = u;
            g[i] = log(u);
            h[i] = log1p(-u);
            x[i] = unif();
        }
        double before = gp_adstat_a2(s), sx = 0.0;
        double judged = gp_adstat_a2_if(s, k, ids, key, g, h, x, &sx);
        CHECK(gp_adstat_a2(s) == before);
        for (size_t i = 0; i < k; i++) put(s, &m, ids[i], key[i], x[i]);
        double after = gp_adstat_a2(s);
        /* both are the same exact integer rounded once */
        CHECK(same_bits(judged, after));
        CHECK_NEAR(sx, gp_adstat_sum_extra(s), 1e-9);
        check_against(s, &m);
    }
    CHECK(isnan(gp_adstat_a2_if(s, GP_ADSTAT_IF_MAX + 1, ids, key, g, h, x, NULL)));
    free(m.u);
    free(m.x);
    free(m.on);
    gp_adstat_destroy(s);
}

static void test_a2_if(void)
{
    test_a2_if_n(500, 0);
    test_a2_if_n(5000, 0);
    test_a2_if_n(5000, 256);
}

/* Block splits and merges: sorted runs in both directions (every insert into the same block),
 * thinning out every other element and whole runs (merges), small moves that stay in their
 * block and jumps that leave it; the structure recounts itself (gp_adstat_check) and A^2 is
 * checked against the brute force along the way, down to empty and up again. */
static void test_structure(void)
{
    const size_t n = 3000;
    mirror m = {n, calloc(n, sizeof(double)), calloc(n, sizeof(double)), calloc(n, sizeof(int))};
    gp_adstat *s = gp_adstat_create(n, NULL);
    int ok = 1;
    for (int round = 0; round < 2; round++) {
        for (size_t i = 0; i < n / 2; i++) { /* ascending, then descending keys */
            size_t id = round ? n / 2 - 1 - i : i;
            put(s, &m, id, (0.5 + (double)i) / (double)n, 1.0);
            if (i % 101 == 0) ok &= gp_adstat_check(s) == 0;
        }
        for (size_t i = n / 2; i < n; i++) put(s, &m, i, 1.0 - (0.5 + (double)(i - n / 2)) / (double)n, 2.0);
        check_against(s, &m);
        for (size_t id = 0; id < n; id += 2) { /* every other: blocks thin out and merge */
            gp_adstat_remove(s, id);
            m.on[id] = 0;
            if (id % 202 == 0) ok &= gp_adstat_check(s) == 0;
        }
        check_against(s, &m);
        for (size_t t = 0; t < 4000; t++) { /* small moves (mostly in the block) and jumps */
            size_t id = below(n);
            double u = m.on[id] && t % 4 ? m.u[id] + 1e-4 * (unif() - 0.5) : unif();
            put(s, &m, id, fmin(fmax(u, 1e-6), 1 - 1e-6), unif());
            if (t % 97 == 0) check_against(s, &m);
        }
        for (size_t id = 0; id < n; id++) /* a run of ids, then the rest, down to empty */
            if (id < n / 3 || id % 3 == 0) {
                gp_adstat_remove(s, id);
                m.on[id] = 0;
            }
        check_against(s, &m);
        for (size_t id = 0; id < n; id++) {
            gp_adstat_remove(s, id);
            m.on[id] = 0;
            if (id % 307 == 0) ok &= gp_adstat_check(s) == 0;
        }
        check_against(s, &m);
        CHECK(gp_adstat_count(s) == 0 && gp_adstat_a2(s) == 0.0);
    }
    CHECK(ok);
    gp_adstat_destroy(s);
    free(m.u);
    free(m.x);
    free(m.on);
}

/* Many directory pages (50,000 elements: ~2,000 blocks in pages of up to 32): filled in random
 * order, churned by removes, small moves and jumps, thinned to a twentieth (pages merge), a
 * sorted run into one narrow range (one page splits again and again), then emptied; the
 * structure recounts itself (gp_adstat_check) and A^2 is checked against the brute force at
 * intervals, and the what-if against the change bit for bit. */
static void test_many_pages(void)
{
    const size_t n = 50000, cap = 60000;
    mirror m = {cap, calloc(cap, sizeof(double)), calloc(cap, sizeof(double)), calloc(cap, sizeof(int))};
    gp_adstat *s = gp_adstat_create(cap, NULL);
    int ok = 1;
    for (size_t i = 0; i < n; i++) {
        put(s, &m, below(cap), unif(), unif());
        if (i % 5000 == 4999) check_against(s, &m);
    }
    for (size_t t = 0; t < 200000; t++) {
        size_t id = below(cap), r = below(10);
        if (r < 2) {
            gp_adstat_remove(s, id);
            m.on[id] = 0;
        } else if (r < 6 && m.on[id]) {
            double u = m.u[id] * (1 + 1e-3 * (unif() - 0.5));
            put(s, &m, id, u < 1 ? u : m.u[id], unif());
        } else {
            put(s, &m, id, unif(), unif());
        }
        if (t % 2500 == 0) ok &= gp_adstat_check(s) == 0;
        if (t % 20000 == 0) check_against(s, &m);
    }
    check_against(s, &m);
    size_t ids[GP_ADSTAT_IF_MAX];
    double key[GP_ADSTAT_IF_MAX], g[GP_ADSTAT_IF_MAX], h[GP_ADSTAT_IF_MAX], x[GP_ADSTAT_IF_MAX];
    int same = 1;
    for (int round = 0; round < 50; round++) { /* the what-if, far and near moves */
        size_t k = 0;
        for (size_t id = below(cap); k < 16; id = (id + 1 + below(997)) % cap) {
            int dup = 0;
            for (size_t j = 0; j < k; j++) dup |= ids[j] == id;
            if (!m.on[id] || dup) continue;
            double u = k % 2 ? unif() : fmin(fmax(m.u[id] + 1e-4 * (unif() - 0.5), 1e-9), 1 - 1e-9);
            ids[k] = id;
            key[k] = u;
            g[k] = log(u);
            h[k] = log1p(-u);
            x[k++] = unif();
        }
        double judged = gp_adstat_a2_if(s, k, ids, key, g, h, x, NULL);
        for (size_t i = 0; i < k; i++) put(s, &m, ids[i], key[i], x[i]);
        same &= same_bits(judged, gp_adstat_a2(s));
    }
    CHECK(same);
    check_against(s, &m);
    for (size_t id = 0; id < cap; id++) /* thinned out: pages merge */
        if (m.on[id] && below(20) != 0) {
            gp_adstat_remove(s, id);
            m.on[id] = 0;
            if (id % 1000 == 0) ok &= gp_adstat_check(s) == 0;
        }
    check_against(s, &m);
    for (size_t i = 0, id = 0; i < 20000; id++) /* a sorted run into (0.4, 0.4 + 1e-6) */
        if (!m.on[id]) {
            put(s, &m, id, 0.4 + 1e-6 * (double)i++ / 20000.0, 1.0);
            if (i % 2000 == 0) ok &= gp_adstat_check(s) == 0;
        }
    check_against(s, &m);
    for (size_t id = 0; id < cap; id++) {
        gp_adstat_remove(s, id);
        m.on[id] = 0;
        if (id % 3000 == 0) ok &= gp_adstat_check(s) == 0;
    }
    check_against(s, &m);
    CHECK(ok);
    CHECK(gp_adstat_count(s) == 0 && gp_adstat_a2(s) == 0.0);
    gp_adstat_destroy(s);
    free(m.u);
    free(m.x);
    free(m.on);
}

/* g and h are taken to multiples of 2^-46 and clamped to [-65535, 65535] (NaN to the lower
 * end): a value deeper in a tail than that counts as at the limit, and A^2 stays finite */
static void test_clamp(void)
{
    gp_adstat *s = gp_adstat_create(3, NULL), *t = gp_adstat_create(3, NULL);
    gp_adstat_set(s, 0, 0.5, log(0.5), log(0.5), 0);
    gp_adstat_set(t, 0, 0.5, log(0.5), log(0.5), 0);
    gp_adstat_set(s, 1, 1e-300, -1e6, -1e-300, 0);
    gp_adstat_set(t, 1, 1e-300, -65535.0, 0.0, 0);
    CHECK(same_bits(gp_adstat_a2(s), gp_adstat_a2(t)));
    /* two values: u_(1) = tiny (g = -65535, h = 0) and 0.5: A^2 = -2 - (1/2)[(g_1 + h_2) + 3 (g_2 + h_1)] */
    CHECK_NEAR(gp_adstat_a2(s), -2 - 0.5 * ((-65535.0 + log(0.5)) + 3 * (log(0.5) + 0.0)), 1e-9);
    gp_adstat_set(s, 2, 0.9, NAN, log(0.1), 0);
    gp_adstat_set(t, 2, 0.9, -65535.0, log(0.1), 0);
    CHECK(same_bits(gp_adstat_a2(s), gp_adstat_a2(t)) && isfinite(gp_adstat_a2(s)));
    CHECK(gp_adstat_check(s) == 0 && gp_adstat_check(t) == 0);
    /* a change below the resolution 2^-46 leaves A^2 as it was; one above it does not (g on
     * the grid, so that the small change cannot round across a half) */
    gp_adstat *r = gp_adstat_create(1, NULL);
    gp_adstat_set(r, 0, 0.5, -0.75, -0.5, 0);
    double a2 = gp_adstat_a2(r);
    CHECK(a2 == -1 + 0.75 + 0.5);
    gp_adstat_set(r, 0, 0.5, -0.75 + 0x1p-49, -0.5, 0);
    CHECK(same_bits(gp_adstat_a2(r), a2));
    gp_adstat_set(r, 0, 0.5, -0.75 + 0x1p-44, -0.5, 0);
    CHECK(gp_adstat_a2(r) == a2 - 0x1p-44);
    gp_adstat_destroy(r);
    /* the 128-bit sums are sized for 2^29 elements: more is refused */
    gp_error e;
    CHECK(gp_adstat_create(((size_t)1 << 29) + 1, &e) == NULL && e.code == GP_ERR_INVALID);
    gp_adstat_destroy(s);
    gp_adstat_destroy(t);
}

int main(void)
{
    test_a2_if();
    test_random_sets();
    test_structure();
    test_many_pages();
    test_clamp();
    test_bit_exact();
    test_floor();
    test_ties();
    return gp_test_summary();
}
