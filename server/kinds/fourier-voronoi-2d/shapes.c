/* shapes.c -- POST /v1/shapes/analyze: outlines or a traced image -> their spectrum (see
 * shapes.h). */
#include "kinds/fourier-voronoi-2d/shapes.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_outline.h"
#include "gp_spec.h"
#include "gp_specimen2d.h"
#include "gp_trace.h"

/* the image form's most grains: the schema's shape.outlines maxItems (a number of the JSON
 * schema, which C cannot include); the least is GP_SHAPE_OUTLINES_MIN, the job's own */
#define SHAPES_IMAGE_GRAINS_MAX 10000

/* The most work one request may ask for, in outlines at 128 rays: a request is answered at once
 * (no job, no cancel), so its work is bounded. The descriptors cost about np^2 per outline (the
 * ODEC of gp_shape_describe_fourier): measured 0.5 ms at 128 rays, 8 ms at 1024, 0.24 s at
 * 4096. n (np / 128)^2 <= 40,000 is every set the API allows at the default 128 rays (and
 * 10,000 outlines at 256), 625 at 1024, 39 at 4096: about 10 s at most. */
#define SHAPES_WORK_MAX 40000.0

/* what the request is answered with: the answer or the error object, and its status; the
 * client it goes to */
typedef struct answer {
    json_t *j;
    int status;
    const gpd_shapes_client *client;
} answer;

/* ------------------------------------------------------------------ errors */

/* json_string needs valid UTF-8 (a message cut inside a character, a key quoted from the
 * body): bytes >= 0x80 become '?' rather than losing the whole string */
static json_t *safe_string(char *s)
{
    json_t *j = json_string(s);
    if (j) return j;
    for (char *p = s; *p; p++)
        if ((unsigned char)*p >= 0x80) *p = '?';
    return json_string(s);
}

/* The API's error object into a (pointer NULL: none); returns -1 so that callers can
 * `return fail(...)`. */
static int fail(answer *a, int status, const char *code, const char *pointer, const char *fmt,
                ...) __attribute__((format(printf, 5, 6)));

static int fail(answer *a, int status, const char *code, const char *pointer, const char *fmt,
                ...)
{
    char msg[768], ptr[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    json_t *e = json_object();
    if (e) {
        json_object_set_new(e, "code", json_string(code));
        json_object_set_new(e, "message", safe_string(msg));
        if (pointer) {
            snprintf(ptr, sizeof ptr, "%s", pointer);
            json_object_set_new(e, "pointer", safe_string(ptr));
        }
    }
    json_decref(a->j);
    a->j = e ? json_pack("{s:o}", "error", e) : NULL;
    a->status = status;
    return -1;
}

static int oom(answer *a) { return fail(a, 500, "internal", NULL, "out of memory"); }

/* the client left during the analysis: no answer */
static int gone(answer *a)
{
    json_decref(a->j);
    a->j = NULL;
    a->status = SHAPES_CLIENT_GONE;
    return -1;
}

/* A problem of the wrapped spec (read_spec) as one of the body: the spec's pointer with
 * "/shape" dropped (/shape/outlines/3 -> /outlines/3), also where the message starts with it
 * ("<pointer>: expected ..."); "internal" is a 500, anything else a 422 as at a submit. */
static int fail_problem(answer *a, const gp_spec_problem *p)
{
    if (!strcmp(p->code, "internal"))
        return fail(a, 500, "internal", NULL, "%s", p->message[0] ? p->message : "internal");
    const char *ptr = p->pointer, *msg = p->message;
    const char *mine = !strncmp(ptr, "/shape/", 7) ? ptr + 6 : !strcmp(ptr, "/shape") ? "" : ptr;
    size_t pl = strlen(ptr);
    if (pl && !strncmp(msg, ptr, pl) && !strncmp(msg + pl, ": ", 2)) msg += pl + 2;
    else if (!strncmp(msg, "spec: ", 6)) msg += 6;
    return fail(a, 422, p->code[0] ? p->code : "invalid_spec", mine, "%s: %s",
                mine[0] ? mine : "body", msg);
}

/* ------------------------------------------------------------------ the body */

/* RFC 6901: "~" and "/" of a member's name escaped, cut to fit out */
static void pointer_of_key(const char *key, char *out, size_t n)
{
    size_t k = 0;
    if (n < 2) return;
    out[k++] = '/';
    for (const char *c = key; *c && k + 3 < n; c++) {
        if (*c == '~' || *c == '/') {
            out[k++] = '~';
            out[k++] = *c == '~' ? '0' : '1';
        } else {
            out[k++] = *c;
        }
    }
    out[k] = '\0';
}

/* The members of the body: outlines or image (one of them), contour_points; -1 when
 * answered (422) */
static int body_members(const json_t *doc, const json_t **outl, const json_t **img,
                        const json_t **cp, answer *a)
{
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)doc, key, v) {
        if (!strcmp(key, "outlines")) *outl = v;
        else if (!strcmp(key, "image")) *img = v;
        else if (!strcmp(key, "contour_points")) *cp = v;
        else {
            char ptr[128];
            pointer_of_key(key, ptr, sizeof ptr);
            return fail(a, 422, "invalid_spec", ptr, "%s: unknown member; expected \"outlines\" "
                        "or \"image\" (and optionally \"contour_points\")", ptr);
        }
    }
    if (*outl && *img)
        return fail(a, 422, "invalid_spec", "/image", "/image: cannot be combined with "
                    "\"outlines\"; give one of them");
    if (!*outl && !*img)
        return fail(a, 422, "invalid_spec", "", "expected {\"outlines\": [[[x, y], ...], ...]} "
                    "or {\"image\": {\"pgm\": \"<base64>\", ...}}");
    if (*outl && !json_is_array(*outl))
        return fail(a, 422, "invalid_spec", "/outlines", "/outlines: expected an array of "
                    "outlines [[[x, y], ...], ...]");
    if (*img && !json_is_object(*img))
        return fail(a, 422, "invalid_spec", "/image", "/image: expected an object "
                    "{\"pgm\": \"<base64 of a PGM file>\", \"grains\", \"threshold\", "
                    "\"pixel_size\"}");
    return 0;
}

/* The body's outlines (if any) and contour_points as a spec of the 2D kind:
 * {"kind", "contour_points", "shape": {"outlines"}}, the values shared with the body, not
 * copied. Why a spec: its validation is then the submit's own, bounds and all (shapes.h). */
static json_t *wrap_spec(const json_t *outl, const json_t *cp)
{
    json_t *spec = json_object();
    int bad = !spec || json_object_set_new(spec, "kind", json_string(gp_spec_kinds()[0]));
    if (!bad && cp) bad = json_object_set(spec, "contour_points", (json_t *)cp);
    if (!bad && outl)
        bad = json_object_set_new(spec, "shape", json_pack("{s:O}", "outlines", (json_t *)outl));
    if (!bad) return spec;
    json_decref(spec);
    return NULL;
}

/* The wrapped spec validated (gp_spec_with_defaults) and read into s (which then owns copies
 * of the outlines); -1 when answered. s is always freeable. */
static int read_spec(const json_t *outl, const json_t *cp, gp_spec2d *s, answer *a)
{
    memset(s, 0, sizeof *s);
    json_t *spec = wrap_spec(outl, cp);
    if (!spec) return oom(a);
    gp_spec_problem p;
    memset(&p, 0, sizeof p);
    json_t *eff = gp_spec_with_defaults(spec, &p);
    json_decref(spec);
    int rc = eff ? gp_spec2d_read(eff, s, &p) : -1;
    json_decref(eff);
    return rc ? fail_problem(a, &p) : 0;
}

/* ------------------------------------------------------------------ the answer */

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static json_t *num_array(const double *v, size_t n)
{
    json_t *arr = json_array();
    for (size_t i = 0; arr && i < n; i++)
        if (json_array_append_new(arr, num(v[i]))) {
            json_decref(arr);
            return NULL;
        }
    return arr;
}

/* the indices of the outlines with flag */
static json_t *indices_with(const gp_outline_set_result *res, unsigned flag)
{
    json_t *arr = json_array();
    for (size_t i = 0; arr && i < res->n; i++)
        if ((res->info[i].flags & flag) &&
            json_array_append_new(arr, json_integer((json_int_t)i))) {
            json_decref(arr);
            return NULL;
        }
    return arr;
}

/* the refused outlines: index, reason, and for a traced one its grain's first pixel */
static json_t *refused_list(const gp_outline_set_result *res, const gp_trace_result *tr)
{
    json_t *arr = json_array();
    for (size_t k = 0; arr && k < res->nrefused; k++) {
        size_t i = res->refused[k];
        char msg[GP_ERROR_MESSAGE_MAX];
        snprintf(msg, sizeof msg, "%s", res->info[i].error.message);
        json_t *o = json_pack("{s:I, s:s, s:o}", "index", (json_int_t)i, "code",
                              gp_status_name(res->info[i].error.code), "message",
                              safe_string(msg));
        if (o && tr)
            json_object_set_new(o, "pixel", json_pack("[I, I]", (json_int_t)tr->outlines[i].col,
                                                      (json_int_t)tr->outlines[i].row));
        if (!o || json_array_append_new(arr, o)) {
            json_decref(arr);
            return NULL;
        }
    }
    return arr;
}

static json_t *stat_json(const gp_outline_stat *s)
{
    return json_pack("{s:o, s:o}", "mean", num(s->mean), "sd", num(s->sd));
}

/* The spread a job made from these outlines would give its grains (gp_specimen2d_shape.c:
 * each mode's cov capped at GP_SHAPE_SPREAD_MAX, weighted by the mean amplitudes of modes >= 2;
 * D_1, the pole's offset, is no shape): one figure for the user. */
static double job_spread(const gp_outline_set_result *res)
{
    double num_ = 0.0, den = 0.0;
    for (size_t n = 2; n < res->nmodes; n++) {
        num_ += res->mean[n] * fmin(res->cov[n], GP_SHAPE_SPREAD_MAX);
        den += res->mean[n];
    }
    return den > 0.0 ? num_ / den : 0.0;
}

/* The 200 answer of an analysed set (shapes.h) into a; -1 out of memory */
static int answer_json(const gp_outline_set_result *res, size_t np, const gp_trace_result *tr,
                       answer *a)
{
    json_t *spec = json_pack("{s:o, s:o, s:o, s:o}", "mean", num_array(res->mean, res->nmodes),
                             "cov", num_array(res->cov, res->nmodes), "sd",
                             num_array(res->sd, res->nmodes), "spread", num(job_spread(res)));
    json_t *desc = json_pack("{s:o, s:o, s:o, s:o}", "elongation", stat_json(&res->elongation),
                             "roundness", stat_json(&res->roundness), "circularity",
                             stat_json(&res->circularity), "regularity",
                             stat_json(&res->regularity));
    json_t *j = json_pack("{s:I, s:I, s:I, s:I, s:I, s:o, s:o}", "outlines", (json_int_t)res->n,
                          "analysed", (json_int_t)res->nanalysed, "described",
                          (json_int_t)res->ndescribed, "modes", (json_int_t)res->nmodes,
                          "contour_points", (json_int_t)np, "spectrum", spec, "descriptors",
                          desc);
    int bad = !j;
    bad = bad || json_object_set_new(j, "reversed", indices_with(res, GP_OUTLINE_REVERSED));
    bad = bad || json_object_set_new(j, "pole_moved", indices_with(res, GP_OUTLINE_POLE_MOVED));
    bad = bad || json_object_set_new(j, "deduplicated", indices_with(res, GP_OUTLINE_DEDUPED));
    bad = bad ||
          json_object_set_new(j, "no_descriptors", indices_with(res, GP_OUTLINE_NO_DESCRIPTORS));
    bad = bad || json_object_set_new(j, "refused", refused_list(res, tr));
    if (bad) {
        json_decref(j);
        return oom(a);
    }
    json_decref(a->j);
    a->j = j;
    a->status = 200;
    return 0;
}

/* Too few outlines analysed to make a spectrum (GP_ERR_INFEASIBLE): 422 at base, naming the
 * first refused one and its reason */
static int too_few(const gp_outline_set_result *res, const char *base, answer *a)
{
    size_t i = res->nrefused ? res->refused[0] : 0;
    return fail(a, 422, "invalid_spec", base, "%s: only %zu of %zu outlines could be analysed, "
                "fewer than the %d a spectrum needs%s%zu%s%s", base, res->nanalysed, res->n,
                GP_SHAPE_OUTLINES_MIN, res->nrefused ? "; the first refused, #" : "",
                res->nrefused ? i : 0, res->nrefused ? ": " : "",
                res->nrefused ? res->info[i].error.message : "");
}

/* The set analysed at np rays and np / 2 modes (a job's: gp_specimen2d.c) with descriptors;
 * the answer or the error into a. tr: the traced image the outlines come from, or NULL. */
/* gp_outline_params.progress: a non-zero return (the client has gone) stops the analysis */
static int client_left(void *user, const gp_progress *p)
{
    (void)p;
    const gpd_shapes_client *c = user;
    return c && c->gone && c->gone(c->arg);
}

static int run_analysis(const gp_outline_points *pts, size_t n, size_t np, const char *base,
                        const gp_trace_result *tr, answer *a)
{
    double work = (double)n * ((double)np / 128.0) * ((double)np / 128.0);
    if (work > SHAPES_WORK_MAX)
        return fail(a, 422, "too_large", "/contour_points", "/contour_points: %zu outlines at "
                    "%zu rays are over the work one request may ask for (outlines x "
                    "(contour_points / 128)^2 <= %.0f); give fewer outlines or fewer "
                    "contour_points", n, np, SHAPES_WORK_MAX);
    gp_outline_params op;
    gp_outline_params_defaults(&op);
    op.np = np;
    op.nmodes = np / 2;
    op.descriptors = 1;
    op.min_outlines = GP_SHAPE_OUTLINES_MIN;
    op.progress = client_left;
    op.progress_user = (void *)a->client;
    gp_outline_set_result res;
    gp_error e;
    gp_status st = gp_outline_set_analyze(pts, n, &op, NULL, &res, &e);
    int rc;
    if (st == GP_ERR_CANCELLED) rc = gone(a);
    else if (st == GP_OK) rc = answer_json(&res, np, tr, a);
    else if (st == GP_ERR_INFEASIBLE) rc = too_few(&res, base, a);
    else if (st == GP_ERR_NOMEM) rc = oom(a);
    else rc = fail(a, 500, "internal", NULL, "the analysis failed: %s", e.message);
    gp_outline_set_result_free(&res);
    return rc;
}

/* the outlines form: the spec's outlines (already validated) analysed */
static void analyze_outlines(const gp_spec2d *s, answer *a)
{
    gp_outline_points *pts = malloc((s->noutlines ? s->noutlines : 1) * sizeof *pts);
    if (!pts) {
        oom(a);
        return;
    }
    for (size_t i = 0; i < s->noutlines; i++)
        pts[i] = (gp_outline_points){s->outlines[i].pts, s->outlines[i].n};
    run_analysis(pts, s->noutlines, s->contour_points, "/outlines", NULL, a);
    free(pts);
}

/* ------------------------------------------------------------------ the image form */

typedef struct image_opts {
    const char *pgm;   /* base64 text (a data: URL prefix allowed) */
    size_t pgm_len;
    int dark;          /* grains darker than the threshold (else lighter) */
    int has_threshold;
    double threshold;  /* in grey values; default maxval / 2 */
    double pixel_size; /* length of a pixel's side (default 1) */
} image_opts;

/* image's members (pointers /image/...); -1 when answered */
static int image_options(const json_t *img, image_opts *o, answer *a)
{
    memset(o, 0, sizeof *o);
    o->pixel_size = 1.0;
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)img, key, v) {
        char ptr[160] = "/image";
        pointer_of_key(key, ptr + 6, sizeof ptr - 6);
        if (!strcmp(key, "pgm") && json_is_string(v)) {
            o->pgm = json_string_value(v);
            o->pgm_len = json_string_length(v);
        } else if (!strcmp(key, "grains") && json_is_string(v) &&
                   (!strcmp(json_string_value(v), "dark") ||
                    !strcmp(json_string_value(v), "light"))) {
            o->dark = !strcmp(json_string_value(v), "dark");
        } else if (!strcmp(key, "threshold") && json_is_number(v) && json_number_value(v) >= 0) {
            o->has_threshold = 1;
            o->threshold = json_number_value(v);
        } else if (!strcmp(key, "pixel_size") && json_is_number(v) &&
                   json_number_value(v) > 0 && json_number_value(v) <= 1e9) {
            o->pixel_size = json_number_value(v);
        } else {
            int known = !strcmp(key, "pgm") || !strcmp(key, "grains") ||
                        !strcmp(key, "threshold") || !strcmp(key, "pixel_size");
            return fail(a, 422, "invalid_spec", ptr, "%s: %s", ptr,
                        !known ? "unknown member; expected pgm, grains, threshold, pixel_size"
                        : !strcmp(key, "pgm") ? "expected a string: the base64 of a PGM file"
                        : !strcmp(key, "grains") ? "expected \"light\" or \"dark\""
                        : !strcmp(key, "threshold") ? "expected a grey value >= 0"
                                                    : "expected a number in (0, 1e9]");
        }
    }
    if (!o->pgm)
        return fail(a, 422, "invalid_spec", "/image/pgm", "/image/pgm: required: the base64 "
                    "of a PGM file (P2 or P5)");
    return 0;
}

static int b64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+' || c == '-') return 62; /* '-' and '_': the URL-safe alphabet too */
    if (c == '/' || c == '_') return 63;
    return -1;
}

/* base64 (whitespace skipped, padding optional, a "data:...;base64," prefix dropped) into a
 * new buffer; -1 when answered (422 at /image/pgm, or 500) */
static int b64_decode(const char *s, size_t n, unsigned char **out, size_t *len, answer *a)
{
    const char *comma = n > 5 && !strncmp(s, "data:", 5) ? memchr(s, ',', n) : NULL;
    size_t i = comma ? (size_t)(comma - s) + 1 : 0, k = 0, bits = 0;
    unsigned acc = 0;
    unsigned char *b = malloc(n / 4 * 3 + 3);
    if (!b) return oom(a);
    for (; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
        if (c == '=') break;
        int v = b64_value(c);
        if (v < 0) {
            free(b);
            return fail(a, 422, "invalid_spec", "/image/pgm", "/image/pgm: not base64: "
                        "character %u at offset %zu", c, i);
        }
        acc = (acc << 6) | (unsigned)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            b[k++] = (unsigned char)(acc >> bits);
            acc &= (1u << bits) - 1;
        }
    }
    *out = b;
    *len = k;
    return 0;
}

/* the PGM of o decoded and parsed into g, within SHAPES_IMAGE_SIDE_MAX a side; -1 when
 * answered. The side limit is checked on the header as the parser itself reads it
 * (gp_trace_pgm_header), before any pixel is allocated. */
static int read_pgm(const image_opts *o, gp_trace_gray *g, answer *a)
{
    unsigned char *bytes = NULL;
    size_t n = 0;
    memset(g, 0, sizeof *g);
    if (b64_decode(o->pgm, o->pgm_len, &bytes, &n, a)) return -1;
    int rc = 0;
    gp_trace_pgm_info hdr;
    gp_error e;
    gp_status st = gp_trace_pgm_header(bytes, n, &hdr, &e);
    if (st == GP_OK && (hdr.w > SHAPES_IMAGE_SIDE_MAX || hdr.h > SHAPES_IMAGE_SIDE_MAX)) {
        rc = fail(a, 422, "too_large", "/image/pgm", "/image/pgm: %zu x %zu pixels, over the "
                  "limit of %d x %d", hdr.w, hdr.h, SHAPES_IMAGE_SIDE_MAX,
                  SHAPES_IMAGE_SIDE_MAX);
    } else {
        if (st == GP_OK) st = gp_trace_pgm_parse(bytes, n, g, &e);
        if (st == GP_ERR_NOMEM) rc = oom(a);
        else if (st != GP_OK)
            rc = fail(a, 422, "invalid_spec", "/image/pgm", "/image/pgm: %s", e.message);
    }
    free(bytes);
    return rc;
}

/* The grains of g (light or dark of the threshold) traced into tr, 10 .. 10,000 of them; the
 * threshold used into *level_used; -1 when answered */
static int trace_gray(const gp_trace_gray *g, const image_opts *o, gp_trace_result *tr,
                      double *level_used, answer *a)
{
    memset(tr, 0, sizeof *tr);
    double t = o->has_threshold ? o->threshold : g->maxval / 2.0;
    if (t > g->maxval)
        return fail(a, 422, "invalid_spec", "/image/threshold", "/image/threshold: %g is over "
                    "the image's maxval %u", t, g->maxval);
    *level_used = t;
    /* light: v > t, i.e. v > floor(t); dark: v < t, i.e. v < ceil(t) (a midpoint such as
     * 127.5 then splits the grey values evenly) */
    unsigned level = (unsigned)(o->dark ? ceil(t) : floor(t));
    unsigned char *mask = malloc(g->w * g->h);
    if (!mask) return oom(a);
    gp_error e;
    gp_status st = gp_trace_threshold(g, level, o->dark, mask, &e);
    if (st == GP_OK) st = gp_trace_image(mask, g->w, g->h, NULL, tr, &e);
    free(mask);
    if (st == GP_ERR_NOMEM) return oom(a);
    if (st != GP_OK) return fail(a, 422, "invalid_spec", "/image", "/image: %s", e.message);
    if (tr->n > SHAPES_IMAGE_GRAINS_MAX)
        return fail(a, 422, "too_large", "/image", "/image: %zu grains traced, over the limit "
                    "of %d outlines", tr->n, SHAPES_IMAGE_GRAINS_MAX);
    if (tr->n < GP_SHAPE_OUTLINES_MIN)
        return fail(a, 422, "invalid_spec", "/image", "/image: %zu grain%s traced (%zu "
                    "touching the border and %zu under %d pixels skipped), fewer than the %d a "
                    "spectrum needs; check grains (%s) and threshold (%g)", tr->n,
                    tr->n == 1 ? "" : "s", tr->nborder, tr->nsmall, GP_TRACE_MIN_PIXELS_DEFAULT,
                    GP_SHAPE_OUTLINES_MIN, o->dark ? "dark" : "light", t);
    return 0;
}

/* "traced": what the tracer found, and the grains' area-equivalent diameters in pixel_size
 * units (pixel count based: the outline's staircase is not the grain's area) */
static json_t *traced_json(const gp_trace_result *tr, const gp_trace_gray *g,
                           const image_opts *o, double level)
{
    double s1 = 0.0, s2 = 0.0;
    for (size_t i = 0; i < tr->n; i++) {
        double d = o->pixel_size * sqrt(4.0 * (double)tr->outlines[i].pixels / M_PI);
        s1 += d;
        s2 += d * d;
    }
    double n = (double)tr->n, mean = s1 / n;
    double var = n > 1 ? fmax(0.0, (s2 - n * mean * mean) / (n - 1)) : 0.0;
    return json_pack("{s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:o, s:o, s:s, s:{s:o, s:o}}", "grains",
                     (json_int_t)tr->n, "components", (json_int_t)tr->ncomponents,
                     "skipped_border", (json_int_t)tr->nborder, "skipped_small",
                     (json_int_t)tr->nsmall, "min_pixels",
                     (json_int_t)GP_TRACE_MIN_PIXELS_DEFAULT, "width", (json_int_t)g->w, "height",
                     (json_int_t)g->h, "pixel_size", num(o->pixel_size), "threshold", num(level),
                     "grains_are", o->dark ? "dark" : "light", "diameter", "mean", num(mean),
                     "sd", num(sqrt(var)));
}

/* the traced outlines, scaled by pixel_size in place, analysed; "traced" added to a 200 */
static void analyze_traced(gp_trace_result *tr, const gp_trace_gray *g, const image_opts *o,
                           double level, size_t np, answer *a)
{
    gp_outline_points *pts = malloc(tr->n * sizeof *pts);
    if (!pts) {
        oom(a);
        return;
    }
    for (size_t i = 0; i < tr->n; i++) {
        gp_trace_outline *t = &tr->outlines[i];
        for (size_t k = 0; k < t->n; k++) {
            t->pts[k].x *= o->pixel_size;
            t->pts[k].y *= o->pixel_size;
        }
        pts[i] = (gp_outline_points){t->pts, t->n};
    }
    if (run_analysis(pts, tr->n, np, "/image", tr, a) == 0 &&
        json_object_set_new(a->j, "traced", traced_json(tr, g, o, level)))
        oom(a);
    free(pts);
}

/* the image form: decoded, thresholded, traced, analysed */
static void analyze_image(const json_t *img, size_t np, answer *a)
{
    image_opts o;
    gp_trace_gray g;
    gp_trace_result tr;
    double level = 0.0;
    if (image_options(img, &o, a) || read_pgm(&o, &g, a)) return;
    if (trace_gray(&g, &o, &tr, &level, a) == 0) analyze_traced(&tr, &g, &o, level, np, a);
    gp_trace_result_free(&tr);
    gp_trace_gray_free(&g);
}

/* ------------------------------------------------------------------ the request */

/* the body as a JSON object; NULL when answered (400, 422) */
static json_t *parse_body(const char *body, size_t len, answer *a)
{
    if (!body || len == 0) {
        fail(a, 400, "invalid_json", NULL, "the request body is empty; expected {\"outlines\": "
             "[[[x, y], ...], ...]} or {\"image\": {\"pgm\": \"<base64>\", ...}}");
        return NULL;
    }
    json_error_t je;
    json_t *doc = json_loadb(body, len, JSON_REJECT_DUPLICATES, &je);
    if (!doc) {
        fail(a, 400, "invalid_json", NULL, "malformed JSON at line %d, column %d: %s", je.line,
             je.column, je.text);
        return NULL;
    }
    if (json_is_object(doc)) return doc;
    json_decref(doc);
    fail(a, 422, "invalid_spec", "", "expected a JSON object {\"outlines\": [...]} or "
         "{\"image\": {...}}");
    return NULL;
}

json_t *gpd_shapes_analyze(const char *body, size_t len, const gpd_shapes_client *client,
                           int *status)
{
    answer a = {NULL, 500, client};
    json_t *doc = parse_body(body, len, &a);
    const json_t *outl = NULL, *img = NULL, *cp = NULL;
    if (doc && body_members(doc, &outl, &img, &cp, &a) == 0) {
        gp_spec2d s;
        if (read_spec(outl, cp, &s, &a) == 0) {
            if (outl) analyze_outlines(&s, &a);
            else analyze_image(img, s.contour_points, &a);
        }
        gp_spec2d_free(&s);
    }
    json_decref(doc);
    *status = a.j || a.status == SHAPES_CLIENT_GONE ? a.status : 500;
    return a.j;
}
