/* test_result_json.c -- the streaming result writer (server/jobs/result_json.h) against jansson.
 *
 * The truth is jansson itself: every value the writer writes is also built as a jansson tree
 * and dumped with json_dumps(JSON_COMPACT | JSON_REAL_PRECISION(17)), the way results were
 * written before the writer; the two texts must be the same bytes. Reals are also read back
 * with strtod and compared bit for bit; the cancel flag must stop the writing within
 * GPD_JW_CANCEL_EVERY pieces; a 2D specimen's result must carry its geometry bit for bit and
 * stop at the flag; the arrays written on several threads (gpd_jw_items) must be the bytes of
 * the plain loop.
 */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_test.h"
#include "kinds/fourier-voronoi-2d/kind_fv2d.h"
#include "jobs/result_json.h"

#define FLAGS (JSON_COMPACT | JSON_REAL_PRECISION(17) | JSON_ENCODE_ANY)

/* the writer's text, taken (NULL when it refused) */
static char *take(gpd_jw *w)
{
    return gpd_jw_take(w, NULL);
}

/* a fixed generator (xorshift64*) */
static uint64_t next_u64(uint64_t *x)
{
    *x ^= *x >> 12;
    *x ^= *x << 25;
    *x ^= *x >> 27;
    return *x * 2685821657736338717ull;
}

static void test_strings(void)
{
    /* every control byte, the two that need a backslash, '/', DEL and UTF-8 */
    char all[64];
    int n = 0;
    for (int c = 1; c < 0x20; c++) all[n++] = (char)c;
    memcpy(all + n, "\"\\/\x7f\xc3\xa9 \xe2\x82\xac", 11);
    all[n + 11] = 0;
    const char *cases[] = {"", "plain", "a\"b", "back\\slash", "tab\tnew\nline", all,
                           "\xf0\x9f\x98\x80 (4-byte UTF-8)"};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        gpd_jw w;
        gpd_jw_init(&w, NULL);
        gpd_jw_string(&w, cases[i]);
        char *got = take(&w);
        json_t *j = json_string(cases[i]);
        char *want = json_dumps(j, FLAGS);
        CHECK(got && want && !strcmp(got, want));
        json_error_t e;
        json_t *back = got ? json_loads(got, JSON_DECODE_ANY, &e) : NULL;
        CHECK(back && !strcmp(json_string_value(back), cases[i]));
        json_decref(back);
        json_decref(j);
        free(got);
        free(want);
    }
    /* escaped keys too, and \u001F in capitals as jansson writes it */
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_begin_object(&w);
    gpd_jw_key(&w, "k\x1f\"");
    gpd_jw_integer(&w, 1);
    gpd_jw_end_object(&w);
    char *got = take(&w);
    CHECK(got && !strcmp(got, "{\"k\\u001F\\\"\":1}"));
    free(got);
}

/* x through the writer and through jansson: the same bytes, and strtod gives x back bit for
 * bit; 1 when both hold */
static int real_matches(double x)
{
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_real(&w, x);
    char *got = take(&w);
    json_t *j = json_real(x);
    char *want = json_dumps(j, FLAGS);
    int ok = got && want && !strcmp(got, want);
    double back = got ? strtod(got, NULL) : NAN;
    ok = ok && memcmp(&back, &x, sizeof x) == 0;
    if (!ok) fprintf(stderr, "real %.17g: writer %s, jansson %s\n", x, got, want);
    json_decref(j);
    free(got);
    free(want);
    return ok;
}

static void test_reals(void)
{
    const double fixed[] = {0.0, -0.0, 1.0, -1.0, 0.1, 1.0 / 3, 100.0, 1e16, 1e17, 123456789012.0,
                            1e300, -1e-300, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
                            1e-5, 1e-4, 1e21, 1e22, 0.5, 65.0, 1e100};
    int ok = 1;
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) ok &= real_matches(fixed[i]);
    CHECK(ok);
    /* random bit patterns: every exponent, subnormals included */
    uint64_t x = 0x9E3779B97F4A7C15ull;
    int random_ok = 1, tried = 0;
    while (tried < 200000) {
        uint64_t bits = next_u64(&x);
        double d;
        memcpy(&d, &bits, sizeof d);
        if (!isfinite(d)) continue;
        random_ok &= real_matches(d);
        tried++;
    }
    CHECK(random_ok);
    /* the specimen's kind of numbers (the writer's own digits, printf's outside 1e-6..1e38):
     * uniform in [0, 1), times every power of ten from 1e-8 to 1e40, both signs, near the
     * ends of the range, whole numbers, and neighbours of powers of ten */
    int range_ok = 1;
    for (int i = 0; i < 300000; i++) {
        double u = (double)(next_u64(&x) >> 11) / 9007199254740992.0;
        double d = u * pow(10, (int)(next_u64(&x) % 49) - 8);
        if (i % 3 == 1) d = -d;
        if (i % 7 == 0) d = floor(d * 1000);
        range_ok &= real_matches(d);
    }
    for (int p = -8; p <= 40; p++) {
        double t = pow(10, p);
        range_ok &= real_matches(t) & real_matches(nextafter(t, 0)) &
                    real_matches(nextafter(t, INFINITY)) & real_matches(-t);
    }
    CHECK(range_ok);
    /* non-finite: null, as gpd_jreal */
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_begin_array(&w);
    gpd_jw_real(&w, NAN);
    gpd_jw_real(&w, INFINITY);
    gpd_jw_real(&w, -INFINITY);
    gpd_jw_real(&w, 2.5);
    gpd_jw_end_array(&w);
    char *got = take(&w);
    CHECK(got && !strcmp(got, "[null,null,null,2.5]"));
    free(got);
}

static void test_integers(void)
{
    const long long v[] = {0, 1, -1, 42, LLONG_MAX, LLONG_MIN};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        gpd_jw w;
        gpd_jw_init(&w, NULL);
        gpd_jw_integer(&w, v[i]);
        char *got = take(&w);
        json_t *j = json_integer(v[i]);
        char *want = json_dumps(j, FLAGS);
        CHECK(got && want && !strcmp(got, want));
        json_decref(j);
        free(got);
        free(want);
    }
}

/* the same nested document through the writer and as a tree: empty containers, arrays of
 * arrays, objects in arrays, every kind of value, and a tree written through gpd_jw_json and
 * gpd_jw_members */
static void test_nesting(void)
{
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    json_t *t = json_object();

    gpd_jw_begin_object(&w);
    gpd_jw_key(&w, "empty_o");
    gpd_jw_begin_object(&w);
    gpd_jw_end_object(&w);
    json_object_set_new(t, "empty_o", json_object());
    gpd_jw_key(&w, "empty_a");
    gpd_jw_begin_array(&w);
    gpd_jw_end_array(&w);
    json_object_set_new(t, "empty_a", json_array());

    const double v[3] = {0.25, -3e-7, 1e22};
    gpd_jw_key(&w, "reals");
    gpd_jw_reals(&w, v, 3);
    json_object_set_new(t, "reals", gpd_jreals(v, 3));
    gpd_jw_key(&w, "none");
    gpd_jw_reals(&w, NULL, 3);
    json_object_set_new(t, "none", gpd_jreals(NULL, 3));

    /* [[{"i": 0, "p": [[0, 0.5], ...]}, ...], ...] */
    gpd_jw_key(&w, "deep");
    gpd_jw_begin_array(&w);
    json_t *deep = json_array();
    for (int a = 0; a < 3; a++) {
        gpd_jw_begin_array(&w);
        json_t *row = json_array();
        for (int b = 0; b < a; b++) {
            gpd_jw_begin_object(&w);
            json_t *o = json_object();
            gpd_jw_key(&w, "i");
            gpd_jw_integer(&w, a * 10 + b);
            json_object_set_new(o, "i", json_integer(a * 10 + b));
            gpd_jw_key(&w, "p");
            gpd_jw_begin_array(&w);
            json_t *p = json_array();
            for (int k = 0; k < b + 1; k++) {
                gpd_jw_begin_array(&w);
                gpd_jw_real(&w, k);
                gpd_jw_real(&w, k + 0.5);
                gpd_jw_end_array(&w);
                json_array_append_new(p, json_pack("[f, f]", (double)k, k + 0.5));
            }
            gpd_jw_end_array(&w);
            json_object_set_new(o, "p", p);
            gpd_jw_key(&w, "s");
            gpd_jw_string(&w, "x");
            json_object_set_new(o, "s", json_string("x"));
            gpd_jw_key(&w, "n");
            gpd_jw_null(&w);
            json_object_set_new(o, "n", json_null());
            gpd_jw_end_object(&w);
            json_array_append_new(row, o);
        }
        gpd_jw_end_array(&w);
        json_array_append_new(deep, row);
    }
    gpd_jw_end_array(&w);
    json_object_set_new(t, "deep", deep);

    /* a tree through the writer: as a value, and as members of the open object */
    json_error_t e;
    json_t *small = json_loads("{\"b\": [1, 2.5, null, true, false, \"s\\n\"], \"a\": {\"z\": {}},"
                               " \"m\": 1e-9}", 0, &e);
    gpd_jw_key(&w, "tree");
    gpd_jw_json(&w, small);
    json_object_set(t, "tree", small);
    gpd_jw_members(&w, small);
    json_object_update(t, small); /* new keys: appended in order, as the writer did */
    gpd_jw_end_object(&w);

    char *got = take(&w);
    char *want = json_dumps(t, FLAGS);
    CHECK(got && want && !strcmp(got, want));
    if (got && want && strcmp(got, want)) fprintf(stderr, "writer: %s\njansson: %s\n", got, want);
    free(got);
    free(want);
    json_decref(small);
    json_decref(t);

    /* an open container, or a key without its value, is no text */
    gpd_jw_init(&w, NULL);
    gpd_jw_begin_array(&w);
    gpd_jw_integer(&w, 1);
    CHECK(take(&w) == NULL);
    gpd_jw_init(&w, NULL);
    gpd_jw_begin_object(&w);
    gpd_jw_key(&w, "k");
    gpd_jw_end_object(&w);
    CHECK(take(&w) == NULL);
    /* deeper than GPD_JW_MAX_DEPTH: refused, not overflowed */
    gpd_jw_init(&w, NULL);
    for (int d = 0; d < GPD_JW_MAX_DEPTH + 5; d++) gpd_jw_begin_array(&w);
    for (int d = 0; d < GPD_JW_MAX_DEPTH + 5; d++) gpd_jw_end_array(&w);
    CHECK(w.state == GPD_JW_INVALID);
    CHECK(take(&w) == NULL);
    gpd_jw_init(&w, NULL);
    for (int d = 0; d < GPD_JW_MAX_DEPTH - 1; d++) gpd_jw_begin_array(&w);
    for (int d = 0; d < GPD_JW_MAX_DEPTH - 1; d++) gpd_jw_end_array(&w);
    got = take(&w);
    CHECK(got && strlen(got) == 2 * (GPD_JW_MAX_DEPTH - 1));
    free(got);
}

static void test_cancel(void)
{
    /* never raised: all of it */
    volatile int flag = 0;
    gpd_jw w;
    gpd_jw_init(&w, &flag);
    gpd_jw_begin_array(&w);
    for (int i = 0; i < 100000; i++) gpd_jw_real(&w, i * 0.5);
    gpd_jw_end_array(&w);
    size_t len = 0;
    char *got = gpd_jw_take(&w, &len);
    json_error_t e;
    json_t *back = got ? json_loadb(got, len, 0, &e) : NULL;
    CHECK(json_array_size(back) == 100000);
    CHECK(json_real_value(json_array_get(back, 99999)) == 49999.5);
    json_decref(back);
    free(got);

    /* raised after 10,000 values: the writer stops within GPD_JW_CANCEL_EVERY more pieces,
     * writes nothing after, and gives no text */
    gpd_jw_init(&w, &flag);
    gpd_jw_begin_array(&w);
    size_t len_at_stop = 0;
    unsigned long pieces_at_raise = 0;
    for (int i = 0; i < 100000; i++) {
        if (i == 10000) {
            __atomic_store_n((int *)&flag, 1, __ATOMIC_RELAXED);
            pieces_at_raise = w.pieces;
        }
        gpd_jw_real(&w, i * 0.5);
        if (w.state != GPD_JW_OK && !len_at_stop) len_at_stop = w.b.len;
    }
    CHECK(w.state == GPD_JW_CANCELLED);
    CHECK(w.pieces > pieces_at_raise && w.pieces - pieces_at_raise <= GPD_JW_CANCEL_EVERY);
    CHECK(len_at_stop > 0 && w.b.len == len_at_stop);
    gpd_jw_end_array(&w);
    CHECK(gpd_jw_take(&w, NULL) == NULL);
    CHECK(w.b.buf == NULL);
    __atomic_store_n((int *)&flag, 0, __ATOMIC_RELAXED);
}

/* gpd_jw_items: element i is {"i": i, "x": [reals]} (a few dozen pieces) */
static void item_obj(gpd_jw *w, size_t i, const void *user)
{
    const double *k = user;
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "i");
    gpd_jw_integer(w, (long long)i);
    gpd_jw_key(w, "x");
    gpd_jw_begin_array(w);
    for (size_t c = 0; c < 1 + i % 29; c++) gpd_jw_real(w, *k * (double)(i + c) / 3.0);
    gpd_jw_end_array(w);
    gpd_jw_end_object(w);
}

/* [before? , items 0 .. n - 1, after?] written by gpd_jw_items on `threads` threads (0: the
 * plain loop), spilled into a file past `spill_at` bytes when it is > 0 */
static char *items_text(size_t n, int threads, size_t block, int before, int after,
                        size_t spill_at, size_t *len)
{
    static const double k = 0.7;
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    if (spill_at) gpd_jw_spill(&w, "/tmp", spill_at);
    gpd_jw_begin_array(&w);
    if (before) gpd_jw_string(&w, "before");
    if (threads == 0)
        for (size_t i = 0; i < n; i++) item_obj(&w, i, &k);
    else
        gpd_jw_items(&w, n, item_obj, &k, threads, block);
    if (after) gpd_jw_null(&w);
    gpd_jw_end_array(&w);
    return gpd_jw_take(&w, len);
}

/* The blocks written by several threads make the loop's bytes: every item count around the
 * block size, 1 to 5 threads (5: blocks of one item), with and without elements before and after, in memory and
 * spilled; and a raised flag stops them, with no text. */
static void test_items(void)
{
    enum { B = 64 };
    const size_t ns[] = {0, 1, B - 1, B, B + 1, 3 * B, 1000, 5003};
    int bad = 0, cases = 0;
    for (size_t a = 0; a < sizeof ns / sizeof ns[0]; a++) {
        for (int ends = 0; ends < 4; ends++) {
            size_t l0 = 0;
            char *want = items_text(ns[a], 0, B, ends & 1, ends & 2, 0, &l0);
            for (int t = 1; t <= 5; t++) {
                size_t l1 = 0;
                char *got = items_text(ns[a], t, t == 5 ? 1 : B, ends & 1, ends & 2,
                                       t == 3 ? 4096 : 0, &l1);
                bad += !want || !got || l0 != l1 || memcmp(want, got, l0) != 0;
                cases++;
                free(got);
            }
            free(want);
        }
    }
    CHECK(cases == 8 * 4 * 5 && bad == 0);
    /* valid JSON with every element in order */
    size_t len = 0;
    char *text = items_text(5003, 3, B, 1, 1, 0, &len);
    json_error_t e;
    json_t *r = text ? json_loadb(text, len, 0, &e) : NULL;
    CHECK(json_array_size(r) == 5005);
    CHECK(json_integer_value(json_object_get(json_array_get(r, 5003), "i")) == 5002);
    json_decref(r);
    free(text);

    /* the flag up from the start: no element, no text */
    static const double k = 0.7;
    volatile int flag = 1;
    gpd_jw w;
    gpd_jw_init(&w, &flag);
    gpd_jw_begin_array(&w);
    gpd_jw_items(&w, 100000, item_obj, &k, 3, B);
    gpd_jw_end_array(&w);
    CHECK(w.state == GPD_JW_CANCELLED && w.b.len == 1); /* "[": each block reads the flag */
    CHECK(gpd_jw_take(&w, NULL) == NULL);
}

/* a synthetic 2D specimen of n grains of NP points each (one shared contour, odd values); returns
 * the JSON spec it stands for (outputs odec), the caller's */
enum { NP = 64 };
static gp_vec2 contour[NP];
static double discs[6] = {0.1, 0.2, 0.05, 0.3, 0.4, 1.0 / 7};

static json_t *specimen(gp_specimen2d *s, gp_spec2d *spec, gp_grain2d *g, size_t n)
{
    memset(s, 0, sizeof *s);
    memset(spec, 0, sizeof *spec);
    for (int k = 0; k < NP; k++)
        contour[k] = (gp_vec2){0.5 + 0.3 * cos(2 * M_PI * k / NP) / 3,
                               0.5 + 0.2 * sin(2 * M_PI * k / NP) * M_SQRT2};
    for (size_t i = 0; i < n; i++) {
        memset(&g[i], 0, sizeof g[i]);
        g[i].cell = i;
        g[i].contour = contour;
        g[i].ncontour = NP;
        g[i].area = 0.01 + 1e-9 * (double)i;
        g[i].orientation_deg = M_PI * (double)i;
        g[i].discs = discs;
        g[i].ndiscs = 2;
    }
    s->grains = g;
    s->ngrains = n;
    s->imc_threshold = 0.1;
    s->imc_error = 0.05;
    s->solid_fraction = 0.6;
    spec->particles = n;
    spec->outputs = GP_OUT2_ODEC;
    spec->seed = 99;
    return json_pack("{s:[s]}", "outputs", "odec");
}

static void test_result_2d(void)
{
    enum { NG = 3000 };
    static gp_grain2d g[NG];
    gp_specimen2d s;
    gp_spec2d spec;
    json_t *sj = specimen(&s, &spec, g, NG);

    gpd_jw w;
    gpd_jw_init(&w, NULL);
    json_t *head = gpd_result_2d_write(&s, &spec, sj, &w);
    size_t len = 0;
    char *text = gpd_jw_take(&w, &len);
    CHECK(head && text);
    /* the head: the result's small members, in the text's order, without the arrays */
    CHECK(!json_object_get(head, "grains") && json_object_get(head, "stats") &&
          json_object_get(head, "timings"));
    json_error_t e;
    json_t *r = text ? json_loadb(text, len, 0, &e) : NULL;
    const json_t *ga = json_object_get(r, "grains");
    CHECK(json_array_size(ga) == NG);
    /* every coordinate back bit for bit (the last grain's, the first's) */
    int same = 1;
    for (size_t i = 0; i < NG; i += NG - 1) {
        const json_t *gj = json_array_get(ga, i), *c = json_object_get(gj, "contour");
        same &= json_array_size(c) == NP;
        for (int k = 0; k < NP; k++) {
            same &= json_real_value(json_array_get(json_array_get(c, k), 0)) == contour[k].x;
            same &= json_real_value(json_array_get(json_array_get(c, k), 1)) == contour[k].y;
        }
        same &= json_real_value(json_object_get(gj, "orientation_deg")) == g[i].orientation_deg;
        same &= json_real_value(json_array_get(json_array_get(json_object_get(gj, "discs"), 1),
                                               2)) == discs[5];
        same &= json_integer_value(json_object_get(gj, "id")) == (json_int_t)i;
    }
    CHECK(same);
    /* the members before the arrays are the head's, in order */
    const char *key;
    json_t *v;
    int order = 1;
    void *it = json_object_iter(r);
    json_object_foreach(head, key, v)
    {
        order &= it && !strcmp(json_object_iter_key(it), key) && json_equal(v, json_object_iter_value(it));
        it = json_object_iter_next(r, it);
    }
    CHECK(order && it && !strcmp(json_object_iter_key(it), "grains"));
    /* on three threads, the same bytes */
    spec.threads = 3;
    gpd_jw_init(&w, NULL);
    json_decref(gpd_result_2d_write(&s, &spec, sj, &w));
    size_t len3 = 0;
    char *text3 = gpd_jw_take(&w, &len3);
    CHECK(text3 && len3 == len && memcmp(text3, text, len) == 0);
    free(text3);
    spec.threads = 0;
    /* the tree form the tests use is the same text parsed */
    json_t *r2 = gpd_result_2d(&s, &spec, sj, NULL);
    CHECK(json_equal(r, r2));
    json_decref(r2);
    json_decref(r);
    json_decref(head);
    free(text);

    /* cancelled: the head comes back (the caller drops it), the text does not, and the writing
     * stopped at the flag: nothing past the first look at it */
    volatile int flag = 1;
    gpd_jw_init(&w, &flag);
    head = gpd_result_2d_write(&s, &spec, sj, &w);
    CHECK(head != NULL);
    CHECK(w.state == GPD_JW_CANCELLED && w.pieces <= GPD_JW_CANCEL_EVERY);
    CHECK(w.b.len < len / 10);
    CHECK(gpd_jw_take(&w, NULL) == NULL);
    json_decref(head);
    CHECK(gpd_result_2d(&s, &spec, sj, &flag) == NULL);
    json_decref(sj);
}

/* stats.imc_steps: the budget used, whether it was the default, and each run's steps (a law of
 * grains whose cells were resized: two) */
static void test_imc_steps_2d(void)
{
    enum { NG = 4 };
    static gp_grain2d g[NG];
    gp_specimen2d s;
    gp_spec2d spec;
    json_t *sj = specimen(&s, &spec, g, NG);
    spec.imc_max_steps = 12000000;
    spec.imc_max_steps_default = 1;
    s.imc_runs = 2;
    s.imc_steps = 7000123;
    s.imc_steps_resize = 3000100;
    json_t *r = gpd_result_2d(&s, &spec, sj, NULL);
    json_t *want = json_pack("{s:I, s:I, s:b, s:[I, I]}", "max", (json_int_t)12000000,
                             "achieved", (json_int_t)7000123, "default", 1, "runs",
                             (json_int_t)4000023, (json_int_t)3000100);
    CHECK(json_equal(json_object_get(json_object_get(r, "stats"), "imc_steps"), want));
    json_decref(want);
    json_decref(r);
    /* one run, a budget the user gave */
    spec.imc_max_steps = 5000;
    spec.imc_max_steps_default = 0;
    s.imc_runs = 1;
    s.imc_steps = 5000;
    s.imc_steps_resize = 0;
    r = gpd_result_2d(&s, &spec, sj, NULL);
    want = json_pack("{s:I, s:I, s:b, s:[I]}", "max", (json_int_t)5000, "achieved",
                     (json_int_t)5000, "default", 0, "runs", (json_int_t)5000);
    CHECK(json_equal(json_object_get(json_object_get(r, "stats"), "imc_steps"), want));
    json_decref(want);
    json_decref(r);
    json_decref(sj);
}

int main(void)
{
    test_strings();
    test_reals();
    test_integers();
    test_nesting();
    test_cancel();
    test_items();
    test_result_2d();
    test_imc_steps_2d();
    return gp_test_summary();
}
