/* fuzz_pgm_check.h -- one input through the PGM reader and the tracer (core/2d/gp_trace.h), with
 * their contracts checked. Shared by the libFuzzer target (fuzz/fuzz_pgm.c, which aborts on a
 * broken contract) and the regression ctest (tests/core/2d/test_trace_regressions.c, which
 * counts it as a failed check), so a reproducer runs the very same calls under the normal
 * build.
 *
 * Every input is a PGM file's bytes, as POST /v1/shapes/analyze decodes them from base64:
 *   - gp_trace_pgm_header and gp_trace_pgm_parse agree: a header the header reader refuses is
 *     refused by the parser with the same message (one header reader, so the daemon's side
 *     limit sees the sizes the parser allocates for); a header it reads is sane (sides >= 1,
 *     w h <= GP_TRACE_MAX_PIXELS, maxval 1 .. 65535, the data offset inside the input,
 *     data_min as gp_trace.h says);
 *   - the parser returns GP_OK or GP_ERR_INVALID (never out of memory: what it allocates is
 *     bounded by the input), refuses data shorter than data_min, zeroes its output on error;
 *     on success the image is the header's, takes at most about twice the input's bytes,
 *     every value is <= maxval, and a P5 image's values are the bytes of the input;
 *   - an image of at most GP_FUZZ_PGM_TRACE_PIXELS pixels is thresholded (light and dark
 *     grains at maxval / 2) and traced twice (the defaults; every component, border and
 *     single pixels included): the components add up (traced + border + small), every
 *     outline is a counter-clockwise polygon inside the image whose area is its pixel count
 *     up to n / 8 (gp_trace.h: the chamfers; with holes, at least its pixels and holes'), its
 *     first pixel is one of its grain's.
 * Everything is freed: under ASan (libFuzzer, GP_SANITIZE) a leak is a failure too.
 */
#ifndef GP_FUZZ_PGM_CHECK_H
#define GP_FUZZ_PGM_CHECK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_geom.h"
#include "gp_trace.h"

/* the largest image traced: the tracer is O(w h), and larger images add no new paths */
#define GP_FUZZ_PGM_TRACE_PIXELS (1u << 16)

/* outcome of one input, for reporting */
typedef struct gp_fuzz_pgm_result {
    int header_ok;   /* gp_trace_pgm_header said GP_OK */
    int parsed_ok;   /* gp_trace_pgm_parse said GP_OK */
    gp_error error;  /* the parser's refusal */
    size_t w, h;     /* the header's sizes when read */
} gp_fuzz_pgm_result;

/* NULL when the header read from an input of size bytes is sane */
static const char *gp_fuzz_pgm_header_broken(const gp_trace_pgm_info *hd, size_t size)
{
    if (hd->w < 1 || hd->h < 1 || hd->w > GP_TRACE_MAX_PIXELS / hd->h)
        return "header: a side is 0 or w h is over GP_TRACE_MAX_PIXELS";
    if (hd->maxval < 1 || hd->maxval > 65535) return "header: maxval out of 1 .. 65535";
    if (hd->data > size) return "header: the data offset is past the input";
    size_t n = hd->w * hd->h;
    size_t want = hd->binary ? n * (hd->maxval > 255 ? 2 : 1) : 2 * n - 1;
    if (hd->data_min != want) return "header: data_min is not the bytes the values take";
    return NULL;
}

/* NULL when the parsed image g agrees with its header and input */
static const char *gp_fuzz_pgm_image_broken(const gp_trace_gray *g, const gp_trace_pgm_info *hd,
                                            const uint8_t *data, size_t size)
{
    if (size - hd->data < hd->data_min) return "parse: accepted data shorter than data_min";
    if (!g->v || g->w != hd->w || g->h != hd->h || g->maxval != hd->maxval)
        return "parse: the image is not the header's";
    size_t n = g->w * g->h;
    if (n * sizeof *g->v > 2 * size + 2) return "parse: the image takes over twice the input";
    for (size_t i = 0; i < n; i++) {
        if (g->v[i] > g->maxval) return "parse: a value over maxval";
        if (hd->binary) {
            size_t at = hd->data + (g->maxval > 255 ? 2 * i : i);
            unsigned want = g->maxval > 255 ? ((unsigned)data[at] << 8) | data[at + 1] : data[at];
            if (g->v[i] != want) return "parse: a P5 value is not the input's bytes";
        }
    }
    return NULL;
}

/* NULL when a trace of mask (w x h) with p holds its invariants */
static const char *gp_fuzz_pgm_trace_broken(const unsigned char *mask, size_t w, size_t h,
                                            const gp_trace_params *p)
{
    gp_trace_result tr;
    gp_error e;
    gp_status st = gp_trace_image(mask, w, h, p, &tr, &e);
    if (st != GP_OK) return st == GP_ERR_NOMEM ? NULL : "trace: refused a parsed image";
    const char *broken = NULL;
    size_t set = 0, pixels = 0;
    for (size_t i = 0; i < w * h; i++) set += mask[i] != 0;
    if (tr.n + tr.nborder + tr.nsmall != tr.ncomponents)
        broken = "trace: traced + border + small != components";
    if (p->keep_border && p->min_pixels <= 1 && tr.n != tr.ncomponents)
        broken = "trace: keeping every component left one out";
    for (size_t i = 0; i < tr.n && !broken; i++) {
        const gp_trace_outline *o = &tr.outlines[i];
        pixels += o->pixels;
        if (!o->pts || o->n < 3 || o->pixels < 1) broken = "trace: an outline of < 3 vertices";
        else if (o->col >= w || o->row >= h || !mask[o->row * w + o->col])
            broken = "trace: an outline's first pixel is not a grain pixel";
        else if (o->hole_pixels > w * h || (o->holes == 0) != (o->hole_pixels == 0))
            broken = "trace: holes and hole pixels disagree";
        for (size_t k = 0; k < o->n && !broken; k++)
            if (!(o->pts[k].x >= 0 && o->pts[k].x <= (double)w && o->pts[k].y >= 0 &&
                  o->pts[k].y <= (double)h))
                broken = "trace: a vertex outside the image";
        if (broken) break;
        /* the outer outline encloses the grain, its holes and any grain inside those */
        double area = gp_poly_area(o->pts, o->n), chamfers = (double)o->n / 8 + 1e-9;
        double inside = (double)(o->pixels + o->hole_pixels);
        if (!(area > 0)) broken = "trace: an outline that is not counter-clockwise";
        else if (area < inside - chamfers || area > (double)(w * h))
            broken = "trace: an outline's area is below its pixels and holes, or over the image";
        else if (o->holes == 0 && area > inside + chamfers)
            broken = "trace: an outline without holes has an area over its pixel count";
    }
    if (!broken && pixels > set) broken = "trace: more grain pixels traced than set";
    gp_trace_result_free(&tr);
    return broken;
}

/* NULL when thresholding g both ways and tracing each mask holds the tracer's contracts */
static const char *gp_fuzz_pgm_traces_broken(const gp_trace_gray *g)
{
    unsigned char *mask = malloc(g->w * g->h);
    if (!mask) return NULL;
    const char *broken = NULL;
    gp_trace_params every, defaults;
    gp_trace_params_defaults(&defaults);
    every = defaults;
    every.keep_border = 1;
    every.min_pixels = 1;
    for (int dark = 0; dark < 2 && !broken; dark++) {
        gp_error e;
        if (gp_trace_threshold(g, g->maxval / 2, dark, mask, &e) != GP_OK)
            broken = "threshold: refused a parsed image";
        if (!broken) broken = gp_fuzz_pgm_trace_broken(mask, g->w, g->h, &defaults);
        if (!broken) broken = gp_fuzz_pgm_trace_broken(mask, g->w, g->h, &every);
    }
    free(mask);
    return broken;
}

/* Runs the calls on one input. Returns NULL when every contract holds, else a one-line
 * description of the first one broken. res (may be NULL) gets the verdict. */
static const char *gp_fuzz_pgm_one(const uint8_t *data, size_t size, gp_fuzz_pgm_result *res)
{
    gp_fuzz_pgm_result local;
    if (!res) res = &local;
    memset(res, 0, sizeof *res);
    gp_trace_pgm_info hd;
    gp_error eh, ep;
    gp_status sh = gp_trace_pgm_header(data, size, &hd, &eh);
    gp_trace_gray g;
    gp_status sp = gp_trace_pgm_parse(data, size, &g, &ep);
    res->header_ok = sh == GP_OK;
    res->parsed_ok = sp == GP_OK;
    res->error = ep;
    res->w = hd.w;
    res->h = hd.h;
    const char *broken = NULL;
    if (sp != GP_OK && sp != GP_ERR_INVALID) broken = "parse: neither GP_OK nor GP_ERR_INVALID";
    else if (sh != GP_OK && sh != GP_ERR_INVALID) broken = "header: neither OK nor INVALID";
    else if (sh != GP_OK && (sp != sh || strcmp(eh.message, ep.message)))
        broken = "the parser does not refuse a header as the header reader does";
    else if (sh != GP_OK && (hd.w || hd.h || hd.maxval || hd.data))
        broken = "header: a refused header left sizes";
    else if (sp != GP_OK && (g.v || g.w || g.h || g.maxval))
        broken = "parse: a refusal left an image";
    else if (sh == GP_OK)
        broken = gp_fuzz_pgm_header_broken(&hd, size);
    if (!broken && sh == GP_OK && sp == GP_OK) broken = gp_fuzz_pgm_image_broken(&g, &hd, data, size);
    if (!broken && sh == GP_OK && sp != GP_OK && size - hd.data >= hd.data_min &&
        hd.binary && !strstr(ep.message, "exceeds maxval"))
        broken = "parse: refused a P5 file with its data there and every value within maxval";
    if (!broken && sp == GP_OK && g.w * g.h <= GP_FUZZ_PGM_TRACE_PIXELS)
        broken = gp_fuzz_pgm_traces_broken(&g);
    gp_trace_gray_free(&g);
    return broken;
}

#endif /* GP_FUZZ_PGM_CHECK_H */
