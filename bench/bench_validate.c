/* bench_validate.c -- the spec validator's time against the size of a request body (issue #14,
 * item 3: "one 1 MB body costs 25 s of CPU on an HTTP thread").
 *
 * Each row is one 2D spec whose container is built to be expensive for a polygon check, then
 * parsed (jansson) and validated (gp_spec_validate: schema, defaults, the polygon sweep, the
 * work budget and the other semantic checks), as POST /v1/jobs does on an HTTP thread:
 *   zigzag x    rings of (i, i % 2) closed through a far point (at most 10,000 points a ring,
 *               the schema's bound; 40k and 100k edges are 4 and 10 rings, holes in the outer);
 *   stack y     zigzag rings stacked along y that share their x range: every edge overlaps
 *               every other one in x, which made the former check (edges sorted by x, pairs
 *               whose x ranges overlap) quadratic -- the 1 MB body;
 *   comb y      teeth 1,000 long, the zigzag x rows turned a quarter: long parallel edges;
 *   stack comb  the stacked rings with 1,000-long teeth: long edges that all share their
 *               x range and every grid cell or bounding box (what makes a grid or box test
 *               quadratic);
 *   holes       992 holes (50-gons) in a square: the containment of every hole;
 *   ... cross   the same with one vertex moved so that two edges of the last ring cross
 *               (refused at that ring's pointer).
 * Columns: edges, body size, CPU seconds of the thread to parse and to validate (best of 3
 * below 1 s), and the verdict (ok, or the pointer of the 422).
 *
 * Before (the former check, O(E^2) pairs for stacked rings, with a point-in-ring test per pair
 * of holes), valid. s on the same rows, same machine:
 *   zigzag x 0.027 / 0.11 / 0.26; stack y 0.44 / 4.4 / 42; comb y 6.0; stack comb 48;
 *   holes 0.21; stack y, cross 0.42 / 0.88; stack comb, cross 1.0.
 * After: every row at most 0.032 s (100,000 edges: 0.015-0.032 s, about what jansson takes to
 * parse the body), a plane sweep in O(E log E) (core/2d/gp_rings.c, called by schema/gp_spec2d.c).
 *
 * Usage: bench_validate */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <jansson.h>

#include "gp_spec.h"

/* CPU seconds of this thread: what a request costs its HTTP thread, whatever else the machine
 * runs */
static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct buf {
    char *s;
    size_t len, cap;
} buf;

static void put(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(buf *b, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
        va_end(ap);
        if (n >= 0 && b->len + (size_t)n < b->cap) {
            b->len += (size_t)n;
            return;
        }
        b->cap = 2 * b->cap + 4096;
        b->s = realloc(b->s, b->cap);
        if (!b->s) exit(1);
    }
}

static void point(buf *b, int swap, double x, double y, int *first)
{
    if (swap) {
        double t = x;
        x = y;
        y = t;
    }
    put(b, "%s[%.10g,%.10g]", *first ? "" : ",", x, y);
    *first = 0;
}

#define P 10000 /* points of a ring (the schema's bound) */

/* rings zigzags of amplitude amp: the outer ring, then nholes holes below its zigzag; cross:
 * one spike in the last ring */
static char *zigzag_spec(int nholes, double amp, int swap, int cross, size_t *edges)
{
    buf b = {0};
    double gap = amp + 10, L = gap * (nholes + 1) + 10;
    int mid = P / 2;
    put(&b, "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 100, \"container\": {\"polygon\": [");
    int first = 1;
    for (int i = 0; i <= P - 3; i++) {
        double y = (i % 2) * amp;
        if (cross && nholes == 0 && i == mid + 1) y = -L - 1;
        point(&b, swap, i, y, &first);
    }
    point(&b, swap, P - 3, -L, &first);
    point(&b, swap, 0, -L, &first);
    *edges = P;
    put(&b, "], \"holes\": [");
    for (int k = 1; k <= nholes; k++) {
        put(&b, "%s[", k > 1 ? "," : "");
        first = 1;
        double y0 = -gap * k;
        for (int i = 2; i <= P - 4; i++) {
            double y = y0 + (i % 2) * amp;
            if (cross && k == nholes && i == mid + 1) y = y0 - 6;
            point(&b, swap, i, y, &first);
        }
        point(&b, swap, mid, y0 - 5, &first);
        put(&b, "]");
        *edges += P - 4;
    }
    put(&b, "]}}");
    return b.s;
}

/* rings stacked along y that share their x range: the outer ring's left side a zigzag of
 * amplitude 1 (x -10 .. -9), its right side at x = amp + 10; hole k a zigzag x = amp (i % 2),
 * y = y0 + i, closed through a far point on the left; cross: a spike through the last ring's
 * closing edge */
static char *stack_spec(int nholes, double amp, int cross, size_t *edges)
{
    buf b = {0};
    int top = 10 * (P - 3);
    put(&b, "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 100, \"container\": {\"polygon\": [");
    int first = 1;
    for (int i = 0; i <= P - 3; i++) {
        double x = -10 + (i % 2);
        if (cross && nholes == 0 && i == P / 2 + 1) x = amp + 15;
        point(&b, 0, x, 10.0 * i, &first);
    }
    point(&b, 0, amp + 10, top, &first);
    point(&b, 0, amp + 10, 0, &first);
    *edges = P;
    put(&b, "], \"holes\": [");
    for (int k = 0; k < nholes; k++) {
        put(&b, "%s[", k ? "," : "");
        first = 1;
        double y0 = 100 + k * (P + 100.0);
        for (int i = 0; i <= P - 6; i++) {
            double x = amp * (i % 2);
            if (cross && k == nholes - 1 && i == 4999) x = -6;
            point(&b, 0, x, y0 + i, &first);
        }
        point(&b, 0, -5, y0 + 4997, &first);
        put(&b, "]");
        *edges += P - 4;
    }
    put(&b, "]}}");
    return b.s;
}

/* 992 holes, 50-gons of radius 40 on a 100 grid, in a 3,200 x 3,100 square */
static char *holes_spec(size_t *edges)
{
    buf b = {0};
    put(&b, "{\"kind\": \"fourier-voronoi-2d\", \"particles\": 100, \"container\": {\"polygon\": "
            "[[0,0],[3200,0],[3200,3100],[0,3100]], \"holes\": [");
    *edges = 4;
    int k = 0;
    for (int i = 0; i < 32; i++)
        for (int j = 0; j < 31; j++, k++) {
            put(&b, "%s[", k ? "," : "");
            int first = 1;
            for (int a = 0; a < 50; a++) {
                double t = 6.283185307179586 * a / 50;
                point(&b, 0, 50 + 100 * i + 40 * cos(t), 50 + 100 * j + 40 * sin(t), &first);
            }
            put(&b, "]");
            *edges += 50;
        }
    put(&b, "]}}");
    return b.s;
}

static void row(const char *name, char *text, size_t edges)
{
    double t0 = now();
    json_error_t e;
    json_t *spec = json_loads(text, 0, &e);
    double parse = now() - t0;
    if (!spec) {
        printf("| %-17s | bad JSON: %s |\n", name, e.text);
        free(text);
        return;
    }
    double best = 1e30;
    gp_spec_problem p;
    int rc = 0;
    for (int rep = 0; rep < 3; rep++) {
        t0 = now();
        rc = gp_spec_validate(spec, &p);
        double t = now() - t0;
        if (t < best) best = t;
        if (t > 1) break;
    }
    char verdict[300];
    /* the status as the server chooses it from the code (server/http/http.c) */
    int status = strcmp(p.code, "internal") ? 422 : 500;
    if (rc) snprintf(verdict, sizeof verdict, "%d %s %s", status, p.code, p.pointer);
    else snprintf(verdict, sizeof verdict, "ok");
    if (rc && getenv("VERBOSE")) fprintf(stderr, "%s\n", p.message);
    printf("| %-17s | %7zu | %7.0f | %8.4f | %8.4f | %-35s |\n", name, edges,
           (double)strlen(text) / 1024, parse, best, verdict);
    json_decref(spec);
    free(text);
}

int main(void)
{
    printf("spec validation time against the body (gp_spec_validate; CPU seconds of the thread)\n\n");
    printf("| %-17s | %7s | %7s | %8s | %8s | %-35s |\n", "container", "edges", "body KB",
           "parse s", "valid. s", "result");
    printf("|-------------------|---------|---------|----------|----------|-------------------------------------|\n");
    size_t ne;
    char *t;
    int sizes[3] = {0, 3, 9};
    for (int k = 0; k < 3; k++) {
        t = zigzag_spec(sizes[k], 1, 0, 0, &ne);
        row("zigzag x", t, ne);
    }
    for (int k = 0; k < 3; k++) {
        t = stack_spec(sizes[k], 1, 0, &ne);
        row("stack y", t, ne);
    }
    t = zigzag_spec(9, 1000, 1, 0, &ne);
    row("comb y", t, ne);
    t = stack_spec(9, 1000, 0, &ne);
    row("stack comb", t, ne);
    t = holes_spec(&ne);
    row("holes", t, ne);
    t = stack_spec(0, 1, 1, &ne);
    row("stack y, cross", t, ne);
    t = stack_spec(9, 1, 1, &ne);
    row("stack y, cross", t, ne);
    t = stack_spec(9, 1000, 1, &ne);
    row("stack comb, cross", t, ne);
    return 0;
}
