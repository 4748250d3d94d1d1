/* test_trace.c -- gp_trace: marching-squares outlines of rendered shapes against their
 * analytic area and perimeter, components (4-connectivity, border, size, holes, islands), and
 * the PGM reader (P2 file on disk, P5 8- and 16-bit in memory, malformed files). */
#include "gp_geom.h"
#include "gp_test.h"
#include "gp_trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* pixel (c, r) of a w x h image: its centre in the traced frame (y up) */
static gp_vec2 centre(size_t c, size_t r, size_t h)
{
    return (gp_vec2){(double)c + 0.5, (double)h - (double)r - 0.5};
}

/* sets every pixel whose centre is inside poly (gp_poly_contains) */
static void render_poly(unsigned char *img, size_t w, size_t h, const gp_vec2 *poly, size_t n)
{
    for (size_t r = 0; r < h; r++)
        for (size_t c = 0; c < w; c++)
            if (gp_poly_contains(poly, n, centre(c, r, h)))
                img[r * w + c] = 1;
}

static void render_disc(unsigned char *img, size_t w, size_t h, gp_vec2 o, double R, int val)
{
    for (size_t r = 0; r < h; r++)
        for (size_t c = 0; c < w; c++) {
            gp_vec2 p = centre(c, r, h);
            if (hypot(p.x - o.x, p.y - o.y) < R)
                img[r * w + c] = (unsigned char)val;
        }
}

static size_t count_set(const unsigned char *img, size_t n)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        k += img[i] != 0;
    return k;
}

static void test_disc(void)
{
    enum { W = 240, H = 240 };
    unsigned char *img = calloc(W * H, 1);
    const double R = 100.0; /* 200 px across */
    render_disc(img, W, H, (gp_vec2){120.3, 119.6}, R, 1);
    gp_trace_result res;
    gp_error e;
    CHECK(gp_trace_image(img, W, H, NULL, &res, &e) == GP_OK);
    CHECK(res.n == 1 && res.ncomponents == 1 && res.nborder == 0 && res.nsmall == 0);
    if (res.n == 1) {
        const gp_trace_outline *o = &res.outlines[0];
        double a = gp_poly_signed_area(o->pts, o->n), P = gp_poly_perimeter(o->pts, o->n);
        printf("disc R = 100 px: area %.1f (pi R^2 = %.1f, %+.3f %%), perimeter %.2f "
               "(2 pi R = %.2f, %+.2f %%), %zu vertices, %zu pixels\n",
               a, PI * R * R, 100 * (a / (PI * R * R) - 1), P, 2 * PI * R,
               100 * (P / (2 * PI * R) - 1), o->n, o->pixels);
        CHECK(a > 0); /* counter-clockwise */
        CHECK_REL(a, PI * R * R, 0.01);
        CHECK_REL(P, 2 * PI * R, 0.06); /* the chamfered staircase: <= ~5.5 % too long */
        CHECK(P > 2 * PI * R);
        CHECK(o->pixels == count_set(img, W * H));
        CHECK(o->holes == 0 && o->touches_border == 0);
        CHECK(gp_poly_is_simple(o->pts, o->n));
        /* the 0.5 iso-line lies within one pixel of the circle */
        for (size_t k = 0; k < o->n; k++)
            CHECK_NEAR(hypot(o->pts[k].x - 120.3, o->pts[k].y - 119.6), R, 1.0);
    }
    gp_trace_result_free(&res);
    free(img);
}

/* An axis-aligned rectangle: pixel count minus 1/8 per chamfered corner, exactly. */
static void test_rectangle(void)
{
    enum { W = 80, H = 60 };
    unsigned char img[W * H] = {0};
    for (size_t r = 10; r < 40; r++)
        for (size_t c = 7; c < 57; c++)
            img[r * W + c] = 255;
    gp_trace_result res;
    CHECK(gp_trace_image(img, W, H, NULL, &res, NULL) == GP_OK);
    CHECK(res.n == 1);
    if (res.n == 1) {
        const gp_trace_outline *o = &res.outlines[0];
        CHECK(o->n == 8); /* four sides, four chamfers */
        CHECK_NEAR(gp_poly_signed_area(o->pts, o->n), 1500.0 - 4 * 0.125, 1e-12);
        CHECK_NEAR(gp_poly_perimeter(o->pts, o->n), 2 * (50 + 30) - 4 + 4 * sqrt(0.5), 1e-12);
        CHECK(o->col == 7 && o->row == 10);
        /* in the y-up frame: x from 7 to 57, y from H - 40 = 20 to H - 10 = 50 */
        gp_vec2 lo, hi;
        gp_poly_bbox(o->pts, o->n, &lo, &hi, NULL);
        CHECK_NEAR(lo.x, 7.0, 1e-12);
        CHECK_NEAR(hi.x, 57.0, 1e-12);
        CHECK_NEAR(lo.y, 20.0, 1e-12);
        CHECK_NEAR(hi.y, 50.0, 1e-12);
    }
    gp_trace_result_free(&res);
}

/* A rotated regular hexagon rendered by point-in-polygon: area and perimeter. */
static void test_hexagon(void)
{
    enum { W = 260, H = 240 };
    unsigned char *img = calloc(W * H, 1);
    gp_vec2 hex[6];
    const double R = 100.0, rot = 0.3;
    for (int k = 0; k < 6; k++)
        hex[k] = (gp_vec2){130 + R * cos(rot + k * PI / 3), 118 + R * sin(rot + k * PI / 3)};
    render_poly(img, W, H, hex, 6);
    gp_trace_result res;
    CHECK(gp_trace_image(img, W, H, NULL, &res, NULL) == GP_OK);
    CHECK(res.n == 1);
    if (res.n == 1) {
        const gp_trace_outline *o = &res.outlines[0];
        double a = gp_poly_signed_area(o->pts, o->n), P = gp_poly_perimeter(o->pts, o->n);
        double a0 = gp_poly_area(hex, 6), P0 = gp_poly_perimeter(hex, 6);
        printf("hexagon R = 100 px at 0.3 rad: area %+.3f %%, perimeter %+.2f %%\n",
               100 * (a / a0 - 1), 100 * (P / P0 - 1));
        CHECK_REL(a, a0, 0.01);
        CHECK_REL(P, P0, 0.06);
        CHECK(gp_poly_is_simple(o->pts, o->n));
    }
    gp_trace_result_free(&res);
    free(img);
}

/* Seven grains: five kept, one on the border, one too small. */
static void test_components(void)
{
    enum { W = 300, H = 200 };
    unsigned char *img = calloc(W * H, 1);
    const double xs[5] = {40, 110, 180, 250, 70}, ys[5] = {50, 50, 60, 50, 140};
    for (int k = 0; k < 5; k++)
        render_disc(img, W, H, (gp_vec2){xs[k], ys[k]}, 20 + 2 * k, 1);
    render_disc(img, W, H, (gp_vec2){299, 150}, 15, 1); /* cut by the right edge */
    render_disc(img, W, H, (gp_vec2){200, 150}, 3, 1);  /* ~28 pixels */
    gp_trace_result res;
    gp_error e;
    CHECK(gp_trace_image(img, W, H, NULL, &res, &e) == GP_OK);
    CHECK(res.ncomponents == 7);
    CHECK(res.n == 5);
    CHECK(res.nborder == 1);
    CHECK(res.nsmall == 1);
    for (size_t i = 0; i < res.n; i++) {
        const gp_trace_outline *o = &res.outlines[i];
        CHECK(gp_poly_signed_area(o->pts, o->n) > 0);
        CHECK(gp_poly_is_simple(o->pts, o->n));
    }
    /* raster order of the first pixels: the top grain (y = 140, radius 28) comes first */
    if (res.n == 5)
        CHECK_NEAR(gp_poly_area(res.outlines[0].pts, res.outlines[0].n), PI * 28 * 28,
                   0.01 * PI * 28 * 28);
    gp_trace_result_free(&res);

    gp_trace_params p;
    gp_trace_params_defaults(&p);
    p.keep_border = 1;
    p.min_pixels = 1;
    CHECK(gp_trace_image(img, W, H, &p, &res, &e) == GP_OK);
    CHECK(res.n == 7 && res.nborder == 0 && res.nsmall == 0);
    size_t nb = 0;
    for (size_t i = 0; i < res.n; i++)
        nb += res.outlines[i].touches_border;
    CHECK(nb == 1);
    gp_trace_result_free(&res);
    free(img);
}

/* Two squares meeting at one corner are two grains (4-connectivity), and each outline is simple. */
static void test_diagonal(void)
{
    enum { W = 40, H = 40 };
    unsigned char img[W * H] = {0};
    for (size_t r = 5; r < 20; r++)
        for (size_t c = 5; c < 20; c++)
            img[r * W + c] = 1;
    for (size_t r = 20; r < 35; r++)
        for (size_t c = 20; c < 35; c++)
            img[r * W + c] = 1;
    gp_trace_result res;
    CHECK(gp_trace_image(img, W, H, NULL, &res, NULL) == GP_OK);
    CHECK(res.n == 2);
    for (size_t i = 0; i < res.n; i++) {
        CHECK_NEAR(gp_poly_signed_area(res.outlines[i].pts, res.outlines[i].n), 225 - 0.5, 1e-12);
        CHECK(gp_poly_is_simple(res.outlines[i].pts, res.outlines[i].n));
    }
    CHECK(res.n != 2 || !gp_poly_overlap(res.outlines[0].pts, res.outlines[0].n,
                                        res.outlines[1].pts, res.outlines[1].n));
    gp_trace_result_free(&res);
}

/* A ring: one outline (the outer circle), its hole reported; a grain in the hole is traced. */
static void test_holes(void)
{
    enum { W = 200, H = 200 };
    unsigned char *img = calloc(W * H, 1);
    render_disc(img, W, H, (gp_vec2){100, 100}, 80, 1);
    render_disc(img, W, H, (gp_vec2){100, 100}, 40, 0);
    size_t hole = 0;
    for (size_t r = 0; r < H; r++)
        for (size_t c = 0; c < W; c++) {
            gp_vec2 p = centre(c, r, H);
            hole += hypot(p.x - 100, p.y - 100) < 40;
        }
    gp_trace_result res;
    CHECK(gp_trace_image(img, W, H, NULL, &res, NULL) == GP_OK);
    CHECK(res.n == 1);
    if (res.n == 1) {
        CHECK(res.outlines[0].holes == 1);
        CHECK(res.outlines[0].hole_pixels == hole);
        CHECK_REL(gp_poly_area(res.outlines[0].pts, res.outlines[0].n), PI * 80 * 80, 0.01);
    }
    gp_trace_result_free(&res);

    render_disc(img, W, H, (gp_vec2){100, 100}, 20, 1); /* an island in the hole */
    CHECK(gp_trace_image(img, W, H, NULL, &res, NULL) == GP_OK);
    CHECK(res.n == 2);
    if (res.n == 2) {
        CHECK(res.outlines[0].holes == 1);
        CHECK(res.outlines[1].holes == 0);
        CHECK_REL(gp_poly_area(res.outlines[1].pts, res.outlines[1].n), PI * 20 * 20, 0.02);
    }
    gp_trace_result_free(&res);
    free(img);
}

static void test_small_images(void)
{
    unsigned char one[9] = {0, 0, 0, 0, 1, 0, 0, 0, 0};
    gp_trace_params p;
    gp_trace_params_defaults(&p);
    p.min_pixels = 1;
    gp_trace_result res;
    CHECK(gp_trace_image(one, 3, 3, &p, &res, NULL) == GP_OK);
    CHECK(res.n == 1);
    if (res.n == 1) {
        CHECK(res.outlines[0].n == 4); /* a diamond through the four edge midpoints */
        CHECK_NEAR(gp_poly_signed_area(res.outlines[0].pts, res.outlines[0].n), 0.5, 1e-15);
    }
    gp_trace_result_free(&res);
    unsigned char full[4] = {1, 1, 1, 1}, empty[4] = {0};
    CHECK(gp_trace_image(full, 2, 2, &p, &res, NULL) == GP_OK);
    CHECK(res.n == 0 && res.nborder == 1);
    gp_trace_result_free(&res);
    CHECK(gp_trace_image(empty, 2, 2, &p, &res, NULL) == GP_OK);
    CHECK(res.n == 0 && res.ncomponents == 0);
    gp_trace_result_free(&res);
    gp_error e;
    CHECK(gp_trace_image(NULL, 2, 2, &p, &res, &e) == GP_ERR_INVALID);
    CHECK(gp_trace_image(empty, 0, 2, &p, &res, &e) == GP_ERR_INVALID);
    CHECK(gp_trace_image(empty, (size_t)1 << 20, (size_t)1 << 20, &p, &res, &e) == GP_ERR_INVALID);
    CHECK(res.n == 0 && res.outlines == NULL);
}

/* the directory of this source file, where data/ lives */
static void data_path(char *out, size_t cap, const char *name)
{
    const char *slash = strrchr(__FILE__, '/');
    int len = slash ? (int)(slash - __FILE__) : 1;
    snprintf(out, cap, "%.*s/data/%s", len, slash ? __FILE__ : ".", name);
}

static unsigned char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char *b = malloc(1 << 16);
    *len = b ? fread(b, 1, 1 << 16, f) : 0;
    fclose(f);
    return b;
}

/* tests/core/2d/data/trace_grains.pgm: P2, 24 x 16, maxval 9, dark grains (0) on a bright
 * background (9): a 6 x 5 block, a plus of 13 pixels, a 3 x 2 grain on the border, one pixel. */
static void test_pgm_file(void)
{
    char path[1024];
    data_path(path, sizeof path, "trace_grains.pgm");
    size_t len = 0;
    unsigned char *buf = read_file(path, &len);
    CHECK(buf != NULL);
    if (!buf) {
        fprintf(stderr, "cannot read %s\n", path);
        return;
    }
    gp_trace_gray g;
    gp_error e;
    CHECK(gp_trace_pgm_parse(buf, len, &g, &e) == GP_OK);
    CHECK(g.w == 24 && g.h == 16 && g.maxval == 9);
    unsigned char mask[24 * 16];
    CHECK(gp_trace_threshold(&g, 5, 1, mask, &e) == GP_OK);
    CHECK(count_set(mask, 24 * 16) == 30 + 13 + 6 + 1);
    gp_trace_params p;
    gp_trace_params_defaults(&p);
    p.min_pixels = 5;
    gp_trace_result res;
    CHECK(gp_trace_image(mask, g.w, g.h, &p, &res, &e) == GP_OK);
    CHECK(res.ncomponents == 4 && res.n == 2 && res.nborder == 1 && res.nsmall == 1);
    if (res.n == 2) {
        CHECK(res.outlines[0].pixels == 30 && res.outlines[1].pixels == 13);
        CHECK_NEAR(gp_poly_area(res.outlines[0].pts, res.outlines[0].n), 30 - 0.5, 1e-12);
        /* the plus: 13 pixels; 8 convex corners (two per arm tip) each cut by 1/8, 4 concave
         * corners at the centre each filled by 1/8 */
        CHECK_NEAR(gp_poly_area(res.outlines[1].pts, res.outlines[1].n), 13 - 8 * 0.125 + 4 * 0.125,
                   1e-12);
    }
    gp_trace_result_free(&res);
    gp_trace_gray_free(&g);
    free(buf);
}

static void test_pgm_memory(void)
{
    /* P5, 8 bit, a comment in the header */
    const unsigned char p5[] = "P5\n# made by hand\n3 2\n255\n\x00\x10\xff\x01\x02\x03";
    gp_trace_gray g;
    gp_error e;
    CHECK(gp_trace_pgm_parse(p5, sizeof p5 - 1, &g, &e) == GP_OK);
    CHECK(g.w == 3 && g.h == 2 && g.maxval == 255);
    if (g.v)
        CHECK(g.v[0] == 0 && g.v[1] == 16 && g.v[2] == 255 && g.v[5] == 3);
    unsigned char mask[6];
    CHECK(gp_trace_threshold(&g, 2, 0, mask, &e) == GP_OK);
    CHECK(mask[0] == 0 && mask[1] == 1 && mask[2] == 1 && mask[3] == 0 && mask[4] == 0 &&
          mask[5] == 1);
    gp_trace_gray_free(&g);
    CHECK(g.v == NULL);
    /* P5, 16 bit, most significant byte first */
    const unsigned char p16[] = "P5 2 1 1000 \x03\xe8\x00\x07";
    CHECK(gp_trace_pgm_parse(p16, sizeof p16 - 1, &g, &e) == GP_OK);
    if (g.v)
        CHECK(g.v[0] == 1000 && g.v[1] == 7);
    gp_trace_gray_free(&g);
    /* P2 with comments between values */
    const char p2[] = "P2 3 1 # w h\n 7\n 1 # one\n 7 0\n";
    CHECK(gp_trace_pgm_parse(p2, strlen(p2), &g, &e) == GP_OK);
    if (g.v)
        CHECK(g.v[0] == 1 && g.v[1] == 7 && g.v[2] == 0);
    gp_trace_gray_free(&g);
    /* malformed */
    const char *bad[] = {"P6 1 1 255 x", "P5 2 2 255 \x01\x02\x03", "P2 2 1 5 1 6",
                         "P2 2 1 5 1", "P2 0 1 5", "P2 1 1 70000 1", "P5 1 1 255", "P2 2x 1 5 1 1",
                         "P3"};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        CHECK(gp_trace_pgm_parse(bad[k], strlen(bad[k]), &g, &e) == GP_ERR_INVALID);
        CHECK(g.v == NULL && g.w == 0);
    }
    CHECK(gp_trace_pgm_parse(NULL, 10, &g, &e) == GP_ERR_INVALID);
}

int main(void)
{
    test_disc();
    test_rectangle();
    test_hexagon();
    test_components();
    test_diagonal();
    test_holes();
    test_small_images();
    test_pgm_file();
    test_pgm_memory();
    return gp_test_summary();
}
