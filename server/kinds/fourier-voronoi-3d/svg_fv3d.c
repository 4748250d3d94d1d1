/* svg_fv3d.c -- the SVG views of the 3D Fourier-Voronoi kind (kind_fv3d.c):
 *   section      the specimen cut by the plane z = const (?z=, by default the container's
 *                mid-height): each grain's section (the loops where its surface mesh crosses
 *                the plane, filled, coloured by its equivalent diameter), each cell's (a convex
 *                polygon) and the container's; the solid fraction of the cut in the subtitle;
 *   projection   every grain's outline projected on the xy plane (gp_grain3d_projection: the
 *                exact outline of its mesh at 128 angles), coloured by the height of its centre,
 *                half transparent;
 *   size         the CDFs of stats.fit (cells and grains: the target law dashed, achieved
 *                solid) on a log-volume axis, KS against its 5 % critical value; for a sieve law
 *                the grains' passing by mass; the fit lines and the warnings (svg/svg_stats.c,
 *                as the 2D kind's);
 *   descriptors  one histogram each of the grains' elongation, flatness, sphericity and
 *                convexity (stats.descriptors), the mean dashed and the target (the stretch
 *                asked) in red (the panels: svg/svg_stats.c), and the mean 2D descriptors of
 *                the three projections.
 * The statistics views read the summary only. The geometry views read the grains and cells one
 * at a time -- the grains from the job's export pack when it has one (their records and radii,
 * the result's doubles), else, as the cells, from the result (their items' element texts, parsed
 * one by one) -- and draw them whole when they open: what they hold is the picture, whose outlines are decimated to half a
 * pixel, not the result. The grains' directions are made again from stats.mesh.level and
 * stats.shape's stretch (gp_grain3d_basis_create_ex: the same vertices, in the same order, as the
 * result's "icosphere"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_grain3d.h"
#include "gp_mesh3d.h"
#include "gp_voronoi3d.h"
#include "kinds/fourier-voronoi-3d/svg_fv3d.h"
#include "svg/svg_internal.h"
#include "svg/svg_stats.h"

#define PROJ_ANGLES 128 /* points of a projected outline */
#define MIN_PX 0.5      /* outlines decimated to this */

/* ================================================================== size */

/* the unit of a volume axis whose largest value is hi m³: labels from about 10 up */
static const char *volume_unit(double hi, double *factor)
{
    static const struct {
        double f;
        const char *name;
    } u[] = {{1, "m³"}, {1e3, "dm³"}, {1e6, "cm³"}, {1e9, "mm³"}, {1e18, "µm³"}};
    size_t k = 0;
    while (k + 1 < sizeof u / sizeof u[0] && !(hi * u[k].f >= 10)) k++;
    *factor = u[k].f;
    return u[k].name;
}

/* the size view of the 3D kind: the CDFs of the cells' and grains' volumes */
static const svg_stats_size_kind SIZE_3D = {
    "cell_volume", "grain_volume", "Volume distribution: target law vs achieved (CDF)", "volume",
    volume_unit, "equivalent diameter (6V/\xcf\x80)^(1/3) (mm, log scale)", ""};

int svg_fv3d_size(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                  gpd_err *err)
{
    if (svg_stats_size(&g->out, in->summary, width, &SIZE_3D) == 0) return 0;
    gpd_err_set(err, 409, "view \"size\" needs stats.fit.cell_volume or grain_volume with "
                          "their CDFs in the result");
    return -1;
}

/* ================================================================== descriptors */

static const char *const DESC3[4] = {"elongation", "flatness", "sphericity", "convexity"};
static const char *const DESC2[4] = {"elongation", "roundness", "circularity", "regularity"};
static const char *const AXES[3] = {"long", "intermediate", "short"};

/* the mean 2D descriptors of the projections (stats.descriptors.projections) as a table: a row
 * an axis the grains are seen along, a column a descriptor ("mean ± sd") */
static void projection_table(sb *s, const json_t *pr, double x, double y, double w)
{
    double cw = (w - 150) / 4;
    svg_plot_text_at(s, x, y, "start", "class=\"projection\" font-weight=\"bold\"",
                     "projections, seen along");
    for (int q = 0; q < 4; q++)
        svg_plot_text_at(s, x + 150 + cw * q, y, "start", "class=\"projection\" font-weight=\"bold\"",
                         DESC2[q]);
    for (int a = 0; a < 3; a++) {
        double yy = y + 18 * (a + 1);
        char cell[64];
        snprintf(cell, sizeof cell, "the %s axis", AXES[a]);
        svg_plot_text_at(s, x, yy, "start", "class=\"projection\"", cell);
        const json_t *o = json_object_get(pr, AXES[a]);
        for (int q = 0; q < 4; q++) {
            const json_t *d = json_object_get(o, DESC2[q]);
            double m = svg_plot_jnum(json_object_get(d, "mean"), NAN);
            double sd = svg_plot_jnum(json_object_get(d, "sd"), NAN);
            if (isfinite(sd)) snprintf(cell, sizeof cell, "%.3g \xc2\xb1 %.2g", m, sd);
            else snprintf(cell, sizeof cell, "%.3g", m);
            svg_plot_text_at(s, x + 150 + cw * q, yy, "start", "class=\"projection\"", cell);
        }
    }
}

int svg_fv3d_descriptors(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                         int width, gpd_err *err)
{
    const json_t *d = json_object_get(json_object_get(in->summary, "stats"), "descriptors");
    hist h[4];
    double sd[4], target[4];
    int any = 0;
    for (int k = 0; k < 4; k++) {
        const json_t *o = json_object_get(d, DESC3[k]);
        target[k] = svg_plot_jnum(json_object_get(o, "target"), NAN);
        sd[k] = svg_plot_jnum(json_object_get(o, "sd"), NAN);
        if (svg_plot_hist_read(o, &h[k])) memset(&h[k], 0, sizeof h[k]);
        else any = 1;
    }
    if (!any) {
        gpd_err_set(err, 409, "view \"descriptors\" needs the descriptors: the spec did not ask "
                              "for output \"descriptors\"");
        return -1;
    }
    int height = (int)lround(width * 0.75) + 20 + 4 * 18 + 24;
    sb *s = &g->out;
    svg_plot_doc_begin(s, width, height, "Shape descriptors of the grains (3D)");
    svg_stats_desc panels = {DESC3, h, sd, target,
                             "asked (the stretch: elongation I/L, flatness S/I)", 1};
    double y = svg_stats_desc_panels(s, width, &panels);
    const json_t *pr = json_object_get(d, "projections");
    if (pr) projection_table(s, pr, 40, y + 24, width - 60);
    svg_plot_doc_end(s);
    for (int k = 0; k < 4; k++) svg_plot_hist_free(&h[k]);
    return 0;
}

/* ================================================================== geometry */

/* The elements of a part's array one parsed element at a time: from the result's text (a scan
 * source) or from the result in memory (a JSON source). */
typedef struct elems {
    gp_svg_items *it;
    size_t idx;
} elems;

static int elems_begin(elems *e)
{
    e->idx = 0;
    if (e->it->js) return json_scan_array_begin(e->it->js, e->it->off) ? -1 : 0;
    return e->it->arr ? 0 : -1;
}

/* the next element (a new reference), or NULL with *r 0 at the end, -1 on failure */
static json_t *elems_next(elems *e, int *r)
{
    *r = -1;
    if (e->it->js) {
        uint64_t a, b;
        int k = json_scan_array_next(e->it->js, &a, &b);
        if (k <= 0) {
            *r = k;
            return NULL;
        }
        return json_scan_load(e->it->js, a, b);
    }
    if (e->idx >= json_array_size(e->it->arr)) {
        *r = 0;
        return NULL;
    }
    return json_incref(json_array_get(e->it->arr, e->idx++));
}

/* the container's bounds (from the summary's "container"): 0, or -1 when it has none */
static int container_bounds(const json_t *res, double lo[3], double hi[3])
{
    const json_t *c = json_object_get(res, "container");
    const json_t *box = json_object_get(c, "box"), *cyl = json_object_get(c, "cylinder");
    const json_t *poly = json_object_get(json_object_get(c, "polyhedron"), "halfspaces");
    if (box) {
        for (int k = 0; k < 3; k++) {
            lo[k] = 0;
            hi[k] = svg_plot_jnum(json_array_get(box, (size_t)k), NAN);
        }
    } else if (cyl) {
        double r = svg_plot_jnum(json_object_get(cyl, "radius"), NAN);
        lo[0] = lo[1] = -r;
        hi[0] = hi[1] = r;
        lo[2] = 0;
        hi[2] = svg_plot_jnum(json_object_get(cyl, "height"), NAN);
    } else if (poly) {
        size_t m = json_array_size(poly);
        double *pl = malloc((m ? m : 1) * 4 * sizeof *pl);
        if (!pl) return -1;
        for (size_t i = 0; i < m; i++)
            for (size_t k = 0; k < 4; k++)
                pl[4 * i + k] = svg_plot_jnum(json_array_get(json_array_get(poly, i), k), NAN);
        gp_voronoi3d_container cv = gp_voronoi3d_convex(pl, m);
        gp_error e;
        gp_status st = gp_voronoi3d_container_bounds(&cv, lo, hi, &e);
        free(pl);
        if (st != GP_OK) return -1;
    } else {
        return -1;
    }
    for (int k = 0; k < 3; k++)
        if (!(hi[k] > lo[k])) return -1;
    return 0;
}

/* The container's outline in the plane z (x, y pairs into *xy, n points; NULL when it does not
 * reach z): the box's rectangle, the cylinder's 64-gon, the polyhedron's polygon (its box's
 * rectangle clipped by each half-space). malloc'ed. */
static double *container_outline(const json_t *res, const double lo[3], const double hi[3],
                                 double z, size_t *n)
{
    *n = 0;
    if (!(z >= lo[2] && z <= hi[2])) return NULL;
    const json_t *c = json_object_get(res, "container");
    const json_t *cyl = json_object_get(c, "cylinder");
    const json_t *poly = json_object_get(json_object_get(c, "polyhedron"), "halfspaces");
    size_t cap = 4 + 2 * json_array_size(poly) + 64;
    double *xy = malloc(2 * cap * sizeof *xy), *tmp = malloc(2 * cap * sizeof *tmp);
    if (!xy || !tmp) {
        free(xy);
        free(tmp);
        return NULL;
    }
    if (cyl) {
        for (int k = 0; k < 64; k++) {
            xy[2 * k] = hi[0] * cos(2 * M_PI * k / 64);
            xy[2 * k + 1] = hi[0] * sin(2 * M_PI * k / 64);
        }
        *n = 64;
        free(tmp);
        return xy;
    }
    double sq[8] = {lo[0], lo[1], hi[0], lo[1], hi[0], hi[1], lo[0], hi[1]};
    memcpy(xy, sq, sizeof sq);
    size_t m = 4;
    for (size_t i = 0; i < json_array_size(poly) && m > 0; i++) {
        const json_t *row = json_array_get(poly, i);
        double a = svg_plot_jnum(json_array_get(row, 0), 0), b = svg_plot_jnum(json_array_get(row, 1), 0);
        double d = svg_plot_jnum(json_array_get(row, 3), 0) -
                   svg_plot_jnum(json_array_get(row, 2), 0) * z;
        size_t k = 0; /* Sutherland-Hodgman against a x + b y <= d */
        for (size_t j = 0; j < m && k + 2 <= cap; j++) {
            const double *p = xy + 2 * j, *q = xy + 2 * ((j + 1) % m);
            double fp = a * p[0] + b * p[1] - d, fq = a * q[0] + b * q[1] - d;
            if (fp <= 0) tmp[2 * k] = p[0], tmp[2 * k + 1] = p[1], k++;
            if ((fp < 0) != (fq < 0) && fp != fq) {
                double t = fp / (fp - fq);
                tmp[2 * k] = p[0] + t * (q[0] - p[0]);
                tmp[2 * k + 1] = p[1] + t * (q[1] - p[1]);
                k++;
            }
        }
        memcpy(xy, tmp, 2 * k * sizeof *xy);
        m = k;
    }
    free(tmp);
    *n = m;
    if (m < 3) {
        free(xy);
        *n = 0;
        return NULL;
    }
    return xy;
}

static double ring_area(const double *xy, size_t n)
{
    double a = 0;
    for (size_t i = 0; i < n; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % n);
        a += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * a;
}

/* the shared icosphere (stats.mesh.level) and its edges: edge e joins ev[2 e], ev[2 e + 1];
 * triangle t has the edges te[3 t .. 3 t + 2] (its sides ab, bc, ca) */
typedef struct mesh {
    gp_grain3d_basis *b; /* degree 0: the directions and triangles only */
    const double *dir;
    const uint32_t *tri;
    size_t nv, nt, ne;
    uint32_t *ev, *te;
} mesh;

static void mesh_free(mesh *m)
{
    gp_grain3d_basis_destroy(m->b);
    free(m->ev);
    free(m->te);
    memset(m, 0, sizeof *m);
}

typedef struct dedge {
    uint32_t a, b, slot; /* a < b; slot = 3 t + side */
} dedge;

static int cmp_dedge(const void *x, const void *y)
{
    const dedge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->slot > q->slot) - (p->slot < q->slot);
}

static int mesh_init(mesh *m, const json_t *res)
{
    memset(m, 0, sizeof *m);
    const json_t *st = json_object_get(res, "stats"), *shape = json_object_get(st, "shape");
    double level = svg_plot_jnum(json_object_get(json_object_get(st, "mesh"), "level"), NAN);
    double el = svg_plot_jnum(json_object_get(shape, "elongation"), 1);
    double fl = svg_plot_jnum(json_object_get(shape, "flatness"), 1);
    if (!(level >= 0 && level <= GP_MESH3D_ICOSPHERE_LEVEL_MAX)) return -1;
    gp_error e;
    if (!(m->b = gp_grain3d_basis_create_ex((unsigned)level, 0, el, fl, &e))) return -1;
    const gp_mesh3d *g = gp_grain3d_basis_mesh(m->b);
    m->nv = gp_mesh3d_vertex_count(g);
    m->nt = gp_mesh3d_triangle_count(g);
    m->dir = gp_mesh3d_vertices(g);
    m->tri = gp_mesh3d_triangles(g);
    dedge *d = malloc(3 * m->nt * sizeof *d);
    m->ev = malloc(3 * m->nt * sizeof *m->ev);
    m->te = malloc(3 * m->nt * sizeof *m->te);
    if (!d || !m->ev || !m->te) {
        free(d);
        mesh_free(m);
        return -1;
    }
    for (size_t t = 0; t < m->nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            d[3 * t + k] = (dedge){a < b ? a : b, a < b ? b : a, (uint32_t)(3 * t + k)};
        }
    qsort(d, 3 * m->nt, sizeof *d, cmp_dedge);
    for (size_t i = 0; i < 3 * m->nt; i++) {
        if (i == 0 || d[i].a != d[i - 1].a || d[i].b != d[i - 1].b) {
            m->ev[2 * m->ne] = d[i].a;
            m->ev[2 * m->ne + 1] = d[i].b;
            m->ne++;
        }
        m->te[d[i].slot] = (uint32_t)(m->ne - 1);
    }
    free(d);
    return 0;
}

/* a grain of the result: its pose and (output grains) radii */
typedef struct grain3 {
    double c[3], R[9], s, vol, rmax;
    double *r;
    size_t nr;
} grain3;

/* g's rotation from the unit quaternion w (w, x, y, z); its radii cleared */
static void grain_rotation(grain3 *g, const double w[4])
{
    double a = w[0], x = w[1], y = w[2], z = w[3];
    double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - a * z),     2 * (x * z + a * y),
                   2 * (x * y + a * z),     1 - 2 * (x * x + z * z), 2 * (y * z - a * x),
                   2 * (x * z - a * y),     2 * (y * z + a * x),     1 - 2 * (x * x + y * y)};
    memcpy(g->R, M, sizeof M);
    g->nr = 0;
    g->rmax = 0;
}

/* 0 when g has a pose (finite centre and rotation, positive scale), else -1 */
static int grain_posed(const grain3 *g)
{
    for (int k = 0; k < 9; k++)
        if (!isfinite(g->R[k])) return -1;
    return isfinite(g->c[0]) && isfinite(g->c[1]) && isfinite(g->c[2]) && g->s > 0 ? 0 : -1;
}

/* e's members into g (radii copied into g->r, nv of them, when it has them); 0, or -1 when
 * it has no pose */
static int grain_parse(const json_t *e, grain3 *g, size_t nv)
{
    const json_t *c = json_object_get(e, "center"), *q = json_object_get(e, "rotation");
    const json_t *r = json_object_get(e, "radii");
    double w[4];
    for (int k = 0; k < 3; k++) g->c[k] = svg_plot_jnum(json_array_get(c, (size_t)k), NAN);
    for (int k = 0; k < 4; k++) w[k] = svg_plot_jnum(json_array_get(q, (size_t)k), NAN);
    g->s = svg_plot_jnum(json_object_get(e, "scale"), NAN);
    g->vol = svg_plot_jnum(json_object_get(e, "volume"), NAN);
    grain_rotation(g, w);
    if (json_array_size(r) == nv && g->r)
        for (size_t i = 0; i < nv; i++) {
            g->r[i] = svg_plot_jnum(json_array_get(r, i), NAN);
            g->rmax = fmax(g->rmax, g->r[i]);
            g->nr++;
        }
    return grain_posed(g);
}

/* a pack's double as the JSON result gives it: that writes a non-finite one as null (NaN) */
static double finite_or_nan(double v)
{
    return isfinite(v) ? v : NAN;
}

/* Grain k of a fv3d pack into g, the same values as grain_parse gives for the result's element
 * (radii into g->r when the pack's directions are the nv of the mesh). 1, with *ok when it has
 * a pose; -1 when the pack cannot be read. */
static int grain_read(gp_export_reader *pk, uint64_t k, grain3 *g, size_t nv, int *ok)
{
    gp_export_grain3 rec;
    if (gp_export_reader_grain3(pk, k, &rec, NULL)) return -1;
    double w[4];
    for (int j = 0; j < 3; j++) g->c[j] = finite_or_nan(rec.centre[j]);
    for (int j = 0; j < 4; j++) w[j] = finite_or_nan(rec.rotation[j]);
    g->s = finite_or_nan(rec.scale);
    g->vol = finite_or_nan(rec.volume);
    grain_rotation(g, w);
    if (gp_export_reader_info(pk)->npoints == nv && g->r) {
        if (gp_export_reader_radii(pk, k, g->r, NULL)) return -1;
        for (size_t i = 0; i < nv; i++) {
            g->r[i] = finite_or_nan(g->r[i]);
            g->rmax = fmax(g->rmax, g->r[i]);
        }
        g->nr = nv;
    }
    *ok = grain_posed(g) == 0;
    return 1;
}

/* The grains of a geometry view one at a time: from the records of the job's fv3d pack when the
 * items are a pack's (binary doubles: parsing 2,562 radii a grain from the text is most of a
 * view's time), else the result's elements. */
typedef struct grains {
    elems e;
    gp_export_reader *pack; /* NULL: the elements */
    uint64_t k;
} grains;

static int grains_begin(grains *s, gp_svg_items *it)
{
    s->e = (elems){it, 0};
    s->k = 0;
    s->pack = it->e && gp_export_reader_info(it->e)->dim == GP_EXPORT_FV3D ? it->e : NULL;
    return s->pack ? 0 : elems_begin(&s->e);
}

/* the next grain into g (radii, nv of them, when it has them): 1 with *ok when it has a pose,
 * 0 at the end, -1 on failure */
static int grains_next(grains *s, grain3 *g, size_t nv, int *ok)
{
    *ok = 0;
    if (s->pack) {
        if (s->k >= gp_export_reader_info(s->pack)->nitems) return 0;
        return grain_read(s->pack, s->k++, g, nv, ok);
    }
    int r;
    json_t *el = elems_next(&s->e, &r);
    if (!el) return r;
    *ok = grain_parse(el, g, nv) == 0;
    json_decref(el);
    return 1;
}

/* vertex i of g: c + s R r_i d_i */
static void grain_vertex(const grain3 *g, const mesh *m, size_t i, double p[3])
{
    const double *d = m->dir + 3 * i;
    double v[3] = {g->r[i] * d[0], g->r[i] * d[1], g->r[i] * d[2]};
    for (int k = 0; k < 3; k++)
        p[k] = g->c[k] + g->s * (g->R[3 * k] * v[0] + g->R[3 * k + 1] * v[1] + g->R[3 * k + 2] * v[2]);
}

/* the colour of an equivalent diameter d on [dmin, dmax] (log when wide) */
static void diameter_colour(double d, double dmin, double dmax, int logscale, char *c, size_t n)
{
    double t = dmax > dmin ? (logscale ? log(d / dmin) / log(dmax / dmin)
                                       : (d - dmin) / (dmax - dmin))
                           : 0.5;
    svg_plot_ramp(fmax(0, fmin(1, isfinite(t) ? t : 0.5)), c, n);
}

/* the grains' equivalent diameters' range, from stats.fit.grain_volume.range.achieved */
static void diameter_range(const json_t *res, double *dmin, double *dmax)
{
    const json_t *r = json_object_get(json_object_get(json_object_get(json_object_get(
                                          json_object_get(res, "stats"), "fit"), "grain_volume"),
                                      "range"), "achieved");
    double a = svg_plot_jnum(json_array_get(r, 0), NAN), b = svg_plot_jnum(json_array_get(r, 1), NAN);
    *dmin = cbrt(6 * a / M_PI);
    *dmax = cbrt(6 * b / M_PI);
    if (!(*dmax >= *dmin && *dmin > 0)) *dmin = *dmax = 1;
}

/* the scratch of a section: the grain's vertices' heights over the plane, the crossing edges'
 * links and points, the loop's points */
typedef struct cut {
    double *h, *pt, *xy;
    int32_t *link;
    unsigned char *seen;
} cut;

static void cut_free(cut *c)
{
    free(c->h);
    free(c->pt);
    free(c->xy);
    free(c->link);
    free(c->seen);
}

static int cut_init(cut *c, const mesh *m)
{
    c->h = malloc(m->nv * 3 * sizeof *c->h);
    c->pt = malloc(m->ne * 2 * sizeof *c->pt);
    c->xy = malloc((m->ne + 1) * 2 * sizeof *c->xy);
    c->link = malloc(m->ne * 2 * sizeof *c->link);
    c->seen = malloc(m->ne);
    return c->h && c->pt && c->xy && c->link && c->seen ? 0 : -1;
}

/* Grain g's section by the plane z as a path of its loops (the mesh's edges that cross the
 * plane, linked through the triangles they share) into s; its area (m², the loops' |signed
 * areas| summed). 0 when the plane misses it. */
static double grain_section(sb *s, const frame *f, const grain3 *g, const mesh *m, cut *c,
                            double z, const char *colour)
{
    double *P = c->h; /* vertices, 3 each */
    for (size_t i = 0; i < m->nv; i++) grain_vertex(g, m, i, P + 3 * i);
    size_t crossings = 0;
    for (size_t e = 0; e < m->ne; e++) {
        const double *a = P + 3 * m->ev[2 * e], *b = P + 3 * m->ev[2 * e + 1];
        double ha = a[2] - z, hb = b[2] - z;
        c->link[2 * e] = c->link[2 * e + 1] = -1;
        c->seen[e] = 1;
        if ((ha > 0) == (hb > 0)) continue;
        double t = ha / (ha - hb);
        c->pt[2 * e] = a[0] + t * (b[0] - a[0]);
        c->pt[2 * e + 1] = a[1] + t * (b[1] - a[1]);
        c->seen[e] = 0;
        crossings++;
    }
    if (!crossings) return 0;
    for (size_t t = 0; t < m->nt; t++) {
        int32_t x[3];
        int k = 0;
        for (int j = 0; j < 3; j++) {
            uint32_t e = m->te[3 * t + j];
            if (!c->seen[e]) x[k++] = (int32_t)e;
        }
        if (k != 2) continue; /* a triangle the plane crosses has two crossing sides */
        for (int j = 0; j < 2; j++) {
            int32_t e = x[j], o = x[1 - j];
            if (c->link[2 * e] < 0) c->link[2 * e] = o;
            else c->link[2 * e + 1] = o;
        }
    }
    double area = 0;
    svg_plot_sb_printf(s, "<path class=\"grain\" fill=\"%s\" d=\"", colour);
    for (size_t e0 = 0; e0 < m->ne; e0++) {
        if (c->seen[e0]) continue;
        size_t n = 0;
        int32_t prev = -1, e = (int32_t)e0;
        while (e >= 0 && !c->seen[e]) {
            c->seen[e] = 1;
            c->xy[2 * n] = c->pt[2 * e];
            c->xy[2 * n + 1] = c->pt[2 * e + 1];
            n++;
            int32_t nx = c->link[2 * e] != prev ? c->link[2 * e] : c->link[2 * e + 1];
            prev = e;
            e = nx;
        }
        if (n < 3) continue;
        area += fabs(ring_area(c->xy, n));
        svg_plot_sb_puts(s, "M");
        svg_plot_ring_points_xy(s, f, c->xy, n, MIN_PX);
        svg_plot_sb_puts(s, "Z");
    }
    svg_plot_sb_puts(s, "\"/>\n");
    return area;
}

/* Cell e's section by the plane z: the points where its faces' edges cross it, in angle order
 * about their mean (a convex polygon), as a <polygon>. 1 when drawn. */
static int cell_section(sb *s, const frame *f, const json_t *e, double z, double **buf,
                        size_t *cap)
{
    const json_t *vs = json_object_get(e, "vertices"), *fs = json_object_get(e, "faces");
    size_t n = 0, i, j;
    const json_t *face, *v;
    json_array_foreach(fs, i, face) {
        size_t m = json_array_size(face);
        json_array_foreach(face, j, v) {
            const json_t *pa = json_array_get(vs, (size_t)json_integer_value(v));
            const json_t *pb =
                json_array_get(vs, (size_t)json_integer_value(json_array_get(face, (j + 1) % m)));
            double a[3], b[3];
            for (int k = 0; k < 3; k++) {
                a[k] = svg_plot_jnum(json_array_get(pa, (size_t)k), NAN);
                b[k] = svg_plot_jnum(json_array_get(pb, (size_t)k), NAN);
            }
            double ha = a[2] - z, hb = b[2] - z;
            if ((ha > 0) == (hb > 0) || !(ha != hb)) continue;
            if (n + 1 > *cap) {
                size_t nc = *cap ? 2 * *cap : 64;
                double *q = realloc(*buf, 3 * nc * sizeof *q);
                if (!q) return 0;
                *buf = q;
                *cap = nc;
            }
            double t = ha / (ha - hb);
            (*buf)[3 * n] = a[0] + t * (b[0] - a[0]);
            (*buf)[3 * n + 1] = a[1] + t * (b[1] - a[1]);
            n++;
        }
    }
    if (n < 3) return 0;
    double cx = 0, cy = 0;
    for (size_t k = 0; k < n; k++) cx += (*buf)[3 * k], cy += (*buf)[3 * k + 1];
    cx /= (double)n;
    cy /= (double)n;
    for (size_t k = 0; k < n; k++) (*buf)[3 * k + 2] = atan2((*buf)[3 * k + 1] - cy, (*buf)[3 * k] - cx);
    /* insertion sort by angle (a cell has a few dozen crossings), then x, y pairs */
    for (size_t k = 1; k < n; k++)
        for (size_t m = k; m > 0 && (*buf)[3 * m - 1] > (*buf)[3 * m + 2]; m--)
            for (int q = 0; q < 3; q++) {
                double t = (*buf)[3 * m + q];
                (*buf)[3 * m + q] = (*buf)[3 * (m - 1) + q];
                (*buf)[3 * (m - 1) + q] = t;
            }
    for (size_t k = 0; k < n; k++) {
        (*buf)[2 * k] = (*buf)[3 * k];
        (*buf)[2 * k + 1] = (*buf)[3 * k + 1];
    }
    svg_plot_sb_puts(s, "<polygon class=\"cell\" points=\"");
    svg_plot_ring_points_xy(s, f, *buf, n, MIN_PX);
    svg_plot_sb_puts(s, "\"/>\n");
    return 1;
}

/* 1 when the result's outputs have name */
static int has_output(const json_t *res, const char *name)
{
    size_t i;
    const json_t *v;
    json_array_foreach(json_object_get(res, "outputs"), i, v) {
        const char *o = json_string_value(v);
        if (o && !strcmp(o, name)) return 1;
    }
    return 0;
}

/* opens the items of a part when the outputs asked for it (grains: with their radii): NULL
 * when the result has none (*failed when they could not be read) */
static gp_svg_items *open_part(const gp_svg_input *in, gp_svg_part part, int *failed)
{
    *failed = 0;
    if (!has_output(in->summary, part == GP_SVG_CELLS ? "cells" : "grains")) return NULL;
    return svg_items_open(in, part, failed);
}

/* the head of a map view: the frame over the container's xy bounds with two subtitle lines */
static frame map_head(sb *s, const double lo[3], const double hi[3], int width, const char *title,
                      const char *l1, const char *l2)
{
    bounds b = {lo[0], hi[0], lo[1], hi[1]};
    int height;
    frame f = svg_plot_map_frame(b, width, &height);
    f.y0 += 36;
    height += 36;
    svg_plot_doc_begin(s, width, height, title);
    svg_plot_text_at(s, width / 2.0, 42, "middle", "class=\"subtitle\"", l1);
    svg_plot_text_at(s, width / 2.0, 58, "middle", "class=\"subtitle\" fill=\"#444444\"", l2);
    svg_plot_axes(s, &f, "x (m)", "y (m)", 0);
    return f;
}

/* the colour bar of the diameters, in mm below 1 m */
static void diameter_bar(sb *s, const frame *f, double dmin, double dmax, int logscale)
{
    double k = dmax < 1 ? 1000 : 1;
    svg_plot_colorbar(s, f->x0 + f->w + 20, f->y0 + 24, fmin(f->h - 30, 300), dmin * k, dmax * k,
                      0, logscale, k > 1 ? "equivalent diameter (mm)" : "equivalent diameter (m)");
}

/* ---- section ---- */

typedef struct section_ctx {
    double z, lo[3], hi[3];
    size_t grains, cut, cells_cut;
    double grain_area;
} section_ctx;

/* draws the grains cut by the plane (into a body of its own, sized first) */
static int section_grains(sb *s, const frame *f, gp_svg_items *it, const json_t *res,
                          section_ctx *x, gpd_err *err)
{
    mesh m;
    if (mesh_init(&m, res)) {
        gpd_err_set(err, 500, "the result has no valid stats.mesh.level");
        return -1;
    }
    cut c = {0};
    grain3 g = {0};
    g.r = malloc(m.nv * sizeof *g.r);
    int rc = cut_init(&c, &m) || !g.r ? -2 : 0;
    double dmin, dmax;
    diameter_range(res, &dmin, &dmax);
    int logscale = dmax > 4 * dmin;
    grains src;
    if (!rc && grains_begin(&src, it)) rc = -1;
    svg_plot_sb_puts(s, "<g class=\"grains\" stroke=\"#222222\" stroke-width=\"0.6\" "
                        "fill-rule=\"evenodd\">\n");
    int r = 0, ok;
    while (!rc && (r = grains_next(&src, &g, m.nv, &ok)) > 0) {
        if (!ok) continue;
        x->grains++;
        if (g.nr != m.nv || fabs(g.c[2] - x->z) > g.s * g.rmax) continue;
        char col[16];
        diameter_colour(cbrt(6 * g.vol / M_PI), dmin, dmax, logscale, col, sizeof col);
        double a = grain_section(s, f, &g, &m, &c, x->z, col);
        if (a > 0) x->cut++, x->grain_area += a;
    }
    if (!rc && r < 0) rc = -1;
    svg_plot_sb_puts(s, "</g>\n");
    if (!rc) diameter_bar(s, f, dmin, dmax, logscale);
    free(g.r);
    cut_free(&c);
    mesh_free(&m);
    if (rc == -2) gpd_err_set(err, 500, "out of memory");
    else if (rc) svg_part_error(err, GP_SVG_GRAINS);
    return rc ? -1 : 0;
}

static int section_cells(sb *s, const frame *f, gp_svg_items *it, section_ctx *x, gpd_err *err)
{
    elems e = {it, 0};
    if (elems_begin(&e)) return svg_part_error(err, GP_SVG_CELLS);
    svg_plot_sb_puts(s, "<g class=\"cells\" fill=\"none\" stroke=\"#999999\" "
                        "stroke-width=\"0.6\">\n");
    json_t *el;
    int r = 0;
    double *buf = NULL;
    size_t cap = 0;
    while ((el = elems_next(&e, &r))) {
        x->cells_cut += (size_t)cell_section(s, f, el, x->z, &buf, &cap);
        json_decref(el);
    }
    free(buf);
    svg_plot_sb_puts(s, "</g>\n");
    return r < 0 ? svg_part_error(err, GP_SVG_CELLS) : 0;
}

int svg_fv3d_section(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt, int width,
                     gpd_err *err)
{
    const json_t *res = in->summary;
    section_ctx x = {0};
    if (container_bounds(res, x.lo, x.hi)) {
        gpd_err_set(err, 500, "the result has no valid container");
        return -1;
    }
    x.z = 0.5 * (x.lo[2] + x.hi[2]);
    if (opt && opt->has_z) {
        x.z = opt->z;
        if (!(isfinite(x.z) && x.z >= x.lo[2] && x.z <= x.hi[2])) {
            gpd_err_set(err, 400, "z = %g is outside the container: valid z from %g to %g m",
                        x.z, x.lo[2], x.hi[2]);
            return -1;
        }
    }
    int fg = 0, fc = 0;
    gp_svg_items *grains = open_part(in, GP_SVG_GRAINS, &fg);
    gp_svg_items *cells = fg ? NULL : open_part(in, GP_SVG_CELLS, &fc);
    int rc = 0;
    if (fg || fc) rc = svg_part_error(err, fg ? GP_SVG_GRAINS : GP_SVG_CELLS);
    else if (!grains && !cells) {
        gpd_err_set(err, 409, "view \"section\" needs the grains or the cells: the spec asked "
                              "for neither output \"grains\" nor \"cells\"");
        rc = -1;
    }
    /* the drawing goes to a body first: the title and subtitle count what it cut */
    sb body = {0};
    size_t nc = 0;
    double *outline = rc ? NULL : container_outline(res, x.lo, x.hi, x.z, &nc);
    bounds bb = {x.lo[0], x.hi[0], x.lo[1], x.hi[1]};
    int height;
    frame f = svg_plot_map_frame(bb, width, &height);
    f.y0 += 36;
    if (!rc && cells) rc = section_cells(&body, &f, cells, &x, err);
    if (!rc && grains) rc = section_grains(&body, &f, grains, res, &x, err);
    if (!rc) {
        double area = nc ? fabs(ring_area(outline, nc)) : NAN;
        const json_t *sf = json_object_get(json_object_get(res, "stats"), "solid_fraction");
        double sa = svg_plot_jnum(json_object_get(sf, "achieved"), NAN);
        double st = svg_plot_jnum(json_object_get(sf, "target"), NAN);
        char title[200], l1[240], l2[200];
        if (grains)
            snprintf(title, sizeof title, "Section at z = %.4g m: %zu of %zu grains cut", x.z,
                     x.cut, x.grains);
        else
            snprintf(title, sizeof title, "Section at z = %.4g m: %zu cells cut", x.z,
                     x.cells_cut);
        int k = snprintf(l1, sizeof l1, "solid fraction %.3f (target %.3g)", sa, st);
        if (grains && area > 0 && k > 0 && (size_t)k < sizeof l1)
            snprintf(l1 + k, sizeof l1 - (size_t)k, ", of this section %.3f", x.grain_area / area);
        snprintf(l2, sizeof l2, "%s%s", cells ? "cells: grey outlines; " : "",
                 grains ? "grains: coloured by equivalent diameter" : "");
        frame fh = map_head(&g->out, x.lo, x.hi, width, title, l1, l2);
        (void)fh;
        if (outline)
            svg_plot_sb_puts(&g->out, "<g class=\"container\" fill=\"#f4f4f4\" stroke=\"none\">\n");
        if (outline) {
            svg_plot_sb_puts(&g->out, "<polygon points=\"");
            svg_plot_ring_points_xy(&g->out, &f, outline, nc, MIN_PX);
            svg_plot_sb_puts(&g->out, "\"/>\n</g>\n");
        }
        gpd_buf_add(&g->out, body.buf ? body.buf : "", body.len);
        if (outline) {
            svg_plot_sb_puts(&g->out, "<polygon class=\"container-outline\" fill=\"none\" "
                                      "stroke=\"#000000\" stroke-width=\"1.5\" points=\"");
            svg_plot_ring_points_xy(&g->out, &f, outline, nc, MIN_PX);
            svg_plot_sb_puts(&g->out, "\"/>\n");
        }
        svg_plot_doc_end(&g->out);
        if (body.oom) g->out.oom = 1;
    }
    free(body.buf);
    free(outline);
    gp_svg_items_close(grains);
    gp_svg_items_close(cells);
    return rc ? -1 : 0;
}

/* ---- projection ---- */

int svg_fv3d_projection(gp_svg *g, const gp_svg_input *in, const gp_svg_options *opt,
                        int width, gpd_err *err)
{
    const json_t *res = in->summary;
    double lo[3], hi[3];
    if (container_bounds(res, lo, hi)) {
        gpd_err_set(err, 500, "the result has no valid container");
        return -1;
    }
    int failed = 0;
    gp_svg_items *it = open_part(in, GP_SVG_GRAINS, &failed);
    if (!it) {
        if (failed) return svg_part_error(err, GP_SVG_GRAINS);
        gpd_err_set(err, 409, "view \"projection\" needs the grains: the spec did not ask for "
                              "output \"grains\"");
        return -1;
    }
    mesh m;
    if (mesh_init(&m, res)) {
        gp_svg_items_close(it);
        gpd_err_set(err, 500, "the result has no valid stats.mesh.level");
        return -1;
    }
    gp_error e;
    const gp_grain3d_basis *basis = m.b;
    grain3 gr = {0};
    gr.r = malloc(m.nv * sizeof *gr.r);
    gp_vec2 *ct = malloc(PROJ_ANGLES * sizeof *ct);
    double *xy = malloc(2 * PROJ_ANGLES * sizeof *xy);
    int rc = basis && gr.r && ct && xy ? 0 : -2;
    bounds bb = {lo[0], hi[0], lo[1], hi[1]};
    int height;
    frame f = svg_plot_map_frame(bb, width, &height);
    f.y0 += 36;
    sb body = {0};
    size_t drawn = 0, n = 0;
    grains src;
    if (!rc && grains_begin(&src, it)) rc = -1;
    svg_plot_sb_puts(&body, "<g class=\"grains\" stroke=\"#222222\" stroke-width=\"0.5\" "
                            "fill-opacity=\"0.45\">\n");
    int r = 0, ok;
    while (!rc && (r = grains_next(&src, &gr, m.nv, &ok)) > 0) {
        n++;
        if (!ok || gr.nr != m.nv) continue;
        /* the world's x and y axes in the grain's frame: R's first two rows */
        double eu[3] = {gr.R[0], gr.R[1], gr.R[2]}, ev[3] = {gr.R[3], gr.R[4], gr.R[5]};
        if (gp_grain3d_projection(basis, gr.r, eu, ev, PROJ_ANGLES, ct, &e) != GP_OK) continue;
        for (size_t k = 0; k < PROJ_ANGLES; k++) {
            xy[2 * k] = gr.c[0] + gr.s * ct[k].x;
            xy[2 * k + 1] = gr.c[1] + gr.s * ct[k].y;
        }
        char col[16];
        svg_plot_ramp(fmax(0, fmin(1, (gr.c[2] - lo[2]) / (hi[2] - lo[2]))), col, sizeof col);
        svg_plot_sb_printf(&body, "<polygon class=\"grain\" fill=\"%s\" points=\"", col);
        svg_plot_ring_points_xy(&body, &f, xy, PROJ_ANGLES, MIN_PX);
        svg_plot_sb_puts(&body, "\"/>\n");
        drawn++;
    }
    if (!rc && r < 0) rc = -1;
    svg_plot_sb_puts(&body, "</g>\n");
    if (!rc) {
        char title[160], l1[200];
        snprintf(title, sizeof title, "Grains projected on the xy plane: %zu of %zu", drawn, n);
        snprintf(l1, sizeof l1, "each grain's outline seen along z, coloured by the height of its "
                                "centre, half transparent");
        map_head(&g->out, lo, hi, width, title, l1, "");
        size_t nc = 0;
        const json_t *cyl = json_object_get(json_object_get(res, "container"), "cylinder");
        double *outline = container_outline(res, lo, hi, 0.5 * (lo[2] + hi[2]), &nc);
        if (outline && (cyl || json_object_get(json_object_get(res, "container"), "box"))) {
            svg_plot_sb_puts(&g->out, "<polygon class=\"container-outline\" fill=\"#f4f4f4\" "
                                      "stroke=\"#000000\" stroke-width=\"1.5\" points=\"");
            svg_plot_ring_points_xy(&g->out, &f, outline, nc, MIN_PX);
            svg_plot_sb_puts(&g->out, "\"/>\n");
        }
        free(outline);
        gpd_buf_add(&g->out, body.buf ? body.buf : "", body.len);
        svg_plot_colorbar(&g->out, f.x0 + f.w + 20, f.y0 + 24, fmin(f.h - 30, 300), lo[2],
                          hi[2], 0, 0, "height of the centre z (m)");
        svg_plot_doc_end(&g->out);
        if (body.oom) g->out.oom = 1;
    }
    if (rc == -2) gpd_err_set(err, 500, "out of memory");
    else if (rc) svg_part_error(err, GP_SVG_GRAINS);
    free(body.buf);
    free(gr.r);
    free(ct);
    free(xy);
    mesh_free(&m);
    gp_svg_items_close(it);
    return rc ? -1 : 0;
}
