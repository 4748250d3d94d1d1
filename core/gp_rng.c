/* gp_rng.c -- see gp_rng.h.
 *
 * MT19937 is implemented here after the reference mt19937ar.c (Matsumoto & Nishimura, 2002
 * revision of the seeding), as a gsl_rng_type, so that the state can be seeded with a 128-bit
 * key through init_by_array(). With a 32-bit seed (init_genrand) it produces exactly the words
 * of gsl_rng_mt19937 (checked by the tests). The gsl_rng is built in place (not with
 * gsl_rng_alloc, whose out-of-memory path calls the GSL error handler, which aborts by default).
 */
#include "gp_rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_randist.h>

#define MT_N 624
#define MT_M 397

typedef struct {
    uint32_t mt[MT_N];
    int mti;
} mt_state;

static void mt_init_genrand(mt_state *s, uint32_t seed)
{
    s->mt[0] = seed;
    for (int i = 1; i < MT_N; i++)
        s->mt[i] = 1812433253u * (s->mt[i - 1] ^ (s->mt[i - 1] >> 30)) + (uint32_t)i;
    s->mti = MT_N;
}

static void mt_init_by_array(mt_state *s, const uint32_t *key, int len)
{
    mt_init_genrand(s, 19650218u);
    int i = 1, j = 0;
    for (int k = MT_N > len ? MT_N : len; k; k--) {
        s->mt[i] = (s->mt[i] ^ ((s->mt[i - 1] ^ (s->mt[i - 1] >> 30)) * 1664525u)) + key[j] +
                   (uint32_t)j;
        i++;
        j++;
        if (i >= MT_N) {
            s->mt[0] = s->mt[MT_N - 1];
            i = 1;
        }
        if (j >= len) j = 0;
    }
    for (int k = MT_N - 1; k; k--) {
        s->mt[i] = (s->mt[i] ^ ((s->mt[i - 1] ^ (s->mt[i - 1] >> 30)) * 1566083941u)) - (uint32_t)i;
        i++;
        if (i >= MT_N) {
            s->mt[0] = s->mt[MT_N - 1];
            i = 1;
        }
    }
    s->mt[0] = 0x80000000u; /* MSB is 1, assuring a non-zero initial array */
    s->mti = MT_N;
}

static uint32_t mt_next(mt_state *s)
{
    static const uint32_t mag01[2] = {0u, 0x9908b0dfu};
    if (s->mti >= MT_N) {
        int kk;
        uint32_t y;
        for (kk = 0; kk < MT_N - MT_M; kk++) {
            y = (s->mt[kk] & 0x80000000u) | (s->mt[kk + 1] & 0x7fffffffu);
            s->mt[kk] = s->mt[kk + MT_M] ^ (y >> 1) ^ mag01[y & 1u];
        }
        for (; kk < MT_N - 1; kk++) {
            y = (s->mt[kk] & 0x80000000u) | (s->mt[kk + 1] & 0x7fffffffu);
            s->mt[kk] = s->mt[kk + (MT_M - MT_N)] ^ (y >> 1) ^ mag01[y & 1u];
        }
        y = (s->mt[MT_N - 1] & 0x80000000u) | (s->mt[0] & 0x7fffffffu);
        s->mt[MT_N - 1] = s->mt[MT_M - 1] ^ (y >> 1) ^ mag01[y & 1u];
        s->mti = 0;
    }
    uint32_t y = s->mt[s->mti++];
    y ^= (y >> 11);
    y ^= (y << 7) & 0x9d2c5680u;
    y ^= (y << 15) & 0xefc60000u;
    y ^= (y >> 18);
    return y;
}

/* genrand_res53: [0, 1) with 53-bit resolution */
static double mt_res53(mt_state *s)
{
    uint32_t a = mt_next(s) >> 5, b = mt_next(s) >> 6;
    return ((double)a * 67108864.0 + (double)b) * (1.0 / 9007199254740992.0);
}

/* gsl_rng_type glue. set() mirrors gsl_rng_mt19937 (seed 0 means 4357) so that the type is a
 * drop-in; gp_rng_create() reseeds through init_by_array. */
static void gsl_mt_set(void *vs, unsigned long seed)
{
    if (seed == 0) seed = 4357;
    mt_init_genrand(vs, (uint32_t)(seed & 0xffffffffUL));
}
static unsigned long gsl_mt_get(void *vs) { return mt_next(vs); }
static double gsl_mt_get_double(void *vs) { return mt_res53(vs); }

static const gsl_rng_type gp_mt_type = {"gp_mt19937", 0xffffffffUL, 0, sizeof(mt_state),
                                        &gsl_mt_set, &gsl_mt_get, &gsl_mt_get_double};

struct gp_rng {
    gsl_rng g; /* g.state points at st */
    mt_state st;
};

/* splitmix64 finaliser (Steele, Lea & Flood 2014; Vigna's reference constants) */
static uint64_t splitmix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

void gp_rng_derive_key(uint64_t seed, uint64_t stream, uint32_t key[4])
{
    uint64_t a = splitmix64(splitmix64(seed));
    uint64_t b = splitmix64(splitmix64(a ^ splitmix64(stream)));
    key[0] = (uint32_t)a;
    key[1] = (uint32_t)(a >> 32);
    key[2] = (uint32_t)b;
    key[3] = (uint32_t)(b >> 32);
}

/* a stream seeded by init_by_array(key, len) */
static gp_rng *rng_from_key(const uint32_t *key, int len, gp_error *err)
{
    gp_rng *r = malloc(sizeof *r);
    if (!r) {
        gp_error_set(err, GP_ERR_NOMEM, "rng: out of memory");
        return NULL;
    }
    r->g.type = &gp_mt_type;
    r->g.state = &r->st;
    mt_init_by_array(&r->st, key, len);
    return r;
}

gp_rng *gp_rng_create(uint64_t seed, uint64_t stream, gp_error *err)
{
    uint32_t key[4];
    gp_rng_derive_key(seed, stream, key);
    return rng_from_key(key, 4, err);
}

gp_rng *gp_rng_create_from_key(const uint32_t *key, size_t len, gp_error *err)
{
    if (!key || len == 0 || len > 0x7fffffff) {
        gp_error_set(err, GP_ERR_INVALID, "rng: key must have 1 or more words");
        return NULL;
    }
    return rng_from_key(key, (int)len, err);
}

void gp_rng_destroy(gp_rng *r) { free(r); }

gsl_rng *gp_rng_gsl(gp_rng *r) { return &r->g; }

uint32_t gp_rng_u32(gp_rng *r) { return mt_next(&r->st); }

double gp_rng_uniform(gp_rng *r) { return mt_res53(&r->st); }

double gp_rng_uniform_pos(gp_rng *r)
{
    double u;
    do u = mt_res53(&r->st);
    while (u == 0.0);
    return u;
}

double gp_rng_range(gp_rng *r, double a, double b)
{
    if (!(a < b)) return a;
    double x = a + (b - a) * mt_res53(&r->st);
    /* a + (b - a) u can round up to b (or overflow when b - a does) */
    if (!(x < b)) x = nextafter(b, a);
    if (x < a) x = a;
    return x;
}

static uint64_t rng_u64(gp_rng *r)
{
    uint64_t hi = mt_next(&r->st);
    return (hi << 32) | mt_next(&r->st);
}

unsigned long gp_rng_uint(gp_rng *r, unsigned long n)
{
    if (n <= 1) return 0;
    if (n <= 0xffffffffUL) {
        /* rejection: accept words below the largest multiple of n (at most 2^32 of them) */
        uint32_t m = (uint32_t)n;
        uint32_t lim = (uint32_t)(0x100000000ull - 0x100000000ull % m); /* 0 means 2^32 */
        for (;;) {
            uint32_t w = mt_next(&r->st);
            if (lim == 0 || w < lim) return (unsigned long)(w % m);
        }
    }
    uint64_t m = (uint64_t)n;
    uint64_t rem = (UINT64_MAX % m + 1) % m; /* 2^64 mod m */
    for (;;) {
        uint64_t w = rng_u64(r);
        if (w <= UINT64_MAX - rem) return (unsigned long)(w % m);
    }
}

double gp_rng_gaussian(gp_rng *r, double sigma) { return gsl_ran_gaussian_ziggurat(&r->g, sigma); }

double gp_halton(uint64_t index, unsigned base)
{
    if (base < 2) return NAN;
    /* mirror the digits into an integer while base^k fits in 64 bits: one rounding */
    uint64_t rev = 0, den = 1, i = index;
    while (i > 0 && den <= UINT64_MAX / base) {
        rev = rev * base + i % base;
        den *= base;
        i /= base;
    }
    double r = (double)rev / (double)den;
    /* remaining (higher) digits land below 1/den */
    double f = 1.0 / (double)den / (double)base;
    while (i > 0) {
        r += f * (double)(i % base);
        i /= base;
        f /= (double)base;
    }
    return r < 1.0 ? r : nextafter(1.0, 0.0);
}

void gp_halton2(uint64_t index, double *x, double *y)
{
    if (x) *x = gp_halton(index, 2);
    if (y) *y = gp_halton(index, 3);
}
