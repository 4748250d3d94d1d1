/* svg.c -- SVG pictures of a result as a pull stream (see svg.h): the kind's view is looked up
 * in its table (kind.h) and prepares the picture; the reads hand it out, drawing the items of a
 * geometry view a step at a time. The views are in svg_views2d.c and svg_views3d.c, what they
 * draw with in svg_plot.c, the items they read in svg_items.c. Contours are decimated to about
 * half a pixel (a 10,000-grain packing stays a few MB). */
#include "svg/svg.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "kinds/kind.h"
#include "svg/svg_internal.h"

int svg_part_error(gpd_err *err, gp_svg_part part)
{
    gpd_err_set(err, 500, "cannot read the %s of the result", svg_items_part_name[part]);
    return -1;
}

int svg_open_part(gp_svg *g, const gp_svg_input *in, gp_svg_part part, const char *view,
                  gpd_err *err)
{
    int failed;
    g->items = svg_items_open(in, part, &failed);
    if (g->items) return 0;
    if (failed) return svg_part_error(err, part);
    gpd_err_set(err, 409, "view \"%s\" needs the %s: the spec did not ask for output \"%s\"", view,
                svg_items_part_name[part], svg_items_part_name[part]);
    return -1;
}

int svg_pass_failed(gp_svg *g)
{
    snprintf(g->err, sizeof g->err, "reading the %s failed", svg_items_part_name[g->items->part]);
    return -1;
}

int svg_pass_begin(gp_svg *g)
{
    return g->items->rewind(g->items) == 0 ? 0 : svg_pass_failed(g);
}

int svg_start_steps(gp_svg *g, int (*step)(gp_svg *g), gpd_err *err)
{
    if (svg_pass_begin(g)) return svg_part_error(err, g->items->part);
    g->step = step;
    return 0;
}

void gp_svg_close(gp_svg *g)
{
    if (!g) return;
    gp_svg_items_close(g->items);
    free(g->out.buf);
    free(g->mid.buf);
    free(g->tail.buf);
    free(g->inset.kxy);
    free(g->inset.kept);
    free(g);
}

/* the kind of in: its own, the result's "kind", or guessed from the result's members; NULL
 * (with err) when there is no result or no such kind */
static const gpd_kind *kind_of(const gp_svg_input *in, gpd_err *err)
{
    const json_t *result = in ? in->summary : NULL;
    if (!json_is_object(result)) {
        gpd_err_set(err, 500, "the result is not a JSON object");
        return NULL;
    }
    const char *name = in->kind && *in->kind ? in->kind
                                             : json_string_value(json_object_get(result, "kind"));
    const gpd_kind *k = name ? gpd_kind_find(name) : gpd_kind_guess(result);
    if (!k) gpd_err_set(err, 400, "unknown kind \"%s\"", name);
    return k;
}

gp_svg *gp_svg_open(const gp_svg_input *in, const char *view, const gp_svg_options *opt,
                    gpd_err *err)
{
    gpd_err_set(err, 0, "%s", "");
    const gpd_kind *k = kind_of(in, err);
    if (!k) return NULL;
    char views[256];
    gpd_kind_view_list(k, views, sizeof views);
    int width = opt && opt->width > 0 ? opt->width : 800;
    if (width < 320) width = 320;
    if (width > 4000) width = 4000;
    if (!view || !*view) {
        gpd_err_set(err, 400, "missing view; valid views for %s: %s", k->name, views);
        return NULL;
    }
    const gpd_view *v = gpd_kind_view(k, view);
    if (!v) {
        gpd_err_set(err, 400, "unknown view \"%.63s\"; valid views for %s: %s", view, k->name,
                    views);
        return NULL;
    }
    gp_svg *g = calloc(1, sizeof *g);
    if (!g) {
        gpd_err_set(err, 500, "out of memory");
        return NULL;
    }
    int rc = v->open(g, in, opt, width, err);
    if (rc == 0 && (g->out.oom || g->mid.oom || g->tail.oom)) {
        gpd_err_set(err, 500, "out of memory while drawing");
        rc = -1;
    }
    if (rc) {
        gp_svg_close(g);
        return NULL;
    }
    return g;
}

/* runs one step; 0 more, 1 done, -1 failed */
static int run_step(gp_svg *g)
{
    int r = g->step(g);
    if (r >= 0 && g->out.oom) {
        snprintf(g->err, sizeof g->err, "out of memory while drawing");
        r = -1;
    }
    if (r < 0) {
        if (!g->err[0]) snprintf(g->err, sizeof g->err, "drawing failed");
        g->step = NULL;
        return -1;
    }
    if (r > 0) g->step = NULL;
    return r;
}

int gp_svg_read(gp_svg *g, char *buf, size_t cap, size_t *n)
{
    *n = 0;
    if (g->err[0]) return -1;
    size_t got = 0;
    while (got < cap) {
        if (g->pos < g->out.len) {
            size_t k = g->out.len - g->pos;
            if (k > cap - got) k = cap - got;
            memcpy(buf + got, g->out.buf + g->pos, k);
            g->pos += k;
            got += k;
            continue;
        }
        if (!g->step) break;
        g->out.len = g->pos = 0;
        if (run_step(g) < 0) return -1;
    }
    *n = got;
    return 0;
}

const char *gp_svg_error(const gp_svg *g)
{
    return g->err[0] ? g->err : "no error";
}

char *gp_svg_render(const json_t *result, const char *kind, const char *view,
                    const gp_svg_options *opt, size_t *len, gpd_err *err)
{
    if (len) *len = 0;
    gp_svg_input in = {kind, result, NULL, NULL};
    gp_svg *g = gp_svg_open(&in, view, opt, err);
    if (!g) return NULL;
    /* the whole document in memory: every step appends to the staged text */
    while (g->step)
        if (run_step(g) < 0) {
            gpd_err_set(err, 500, "%s", g->err);
            gp_svg_close(g);
            return NULL;
        }
    char *svg = g->out.buf;
    if (!svg) { /* cannot happen: every view stages its head */
        gp_svg_close(g);
        gpd_err_set(err, 500, "nothing drawn");
        return NULL;
    }
    if (len) *len = g->out.len;
    g->out.buf = NULL;
    gp_svg_close(g);
    return svg;
}
