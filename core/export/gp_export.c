/* gp_export.c -- format registry, packs, the cached pack reader and the pull-stream driver.
 * The formats themselves are in gp_export_{lammps,lammps_relax,yade,vtk,csv}.c, and those of a
 * fv3d pack in gp_export_fv3d_{dem,mesh}.c (its records: gp_export_fv3d.c). */
#include "gp_export_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CACHE_BYTES (64u * 1024u)

/* ------------------------------------------------------------------ registry */

#define DIMS_2 (1u << 2)
#define DIMS_3 (1u << 3)
#define DIMS_FV3D (1u << GP_EXPORT_FV3D)

static const struct {
    const char *name, *ext, *mime;
    unsigned dims; /* bit 2: 2D, bit 3: 3D, bit GP_EXPORT_FV3D: fv3d */
} formats[GP_EXPORT_NFORMATS] = {
    [GP_EXPORT_LAMMPS] = {"lammps", "data", "text/plain; charset=utf-8", DIMS_2 | DIMS_3 | DIMS_FV3D},
    [GP_EXPORT_LIGGGHTS] = {"liggghts", "data", "text/plain; charset=utf-8", DIMS_3 | DIMS_FV3D},
    [GP_EXPORT_YADE] = {"yade", "txt", "text/plain; charset=utf-8", DIMS_2 | DIMS_3 | DIMS_FV3D},
    [GP_EXPORT_VTK] = {"vtk", "vtk", "application/octet-stream", DIMS_2 | DIMS_3 | DIMS_FV3D},
    [GP_EXPORT_CSV] = {"csv", "csv", "text/csv; charset=utf-8", DIMS_2 | DIMS_3},
    [GP_EXPORT_LAMMPS_RELAX] = {"lammps-relax", "tar", "application/x-tar", DIMS_3},
    [GP_EXPORT_STL] = {"stl", "stl", "model/stl", DIMS_FV3D},
};

/* a pack's dimension that the registry knows */
static int known_dim(int dim)
{
    return dim == 2 || dim == 3 || dim == GP_EXPORT_FV3D;
}

/* its name in messages */
static const char *dim_name(int dim)
{
    return dim == 2 ? "2D" : dim == 3 ? "3D" : dim == GP_EXPORT_FV3D ? "fv3d" : "unknown";
}

int gp_export_format_parse(const char *name)
{
    if (!name) return -1;
    for (int f = 0; f < GP_EXPORT_NFORMATS; f++)
        if (!strcmp(name, formats[f].name)) return f;
    return -1;
}

const char *gp_export_format_name(gp_export_format f)
{
    return (unsigned)f < GP_EXPORT_NFORMATS ? formats[f].name : "?";
}

int gp_export_format_supports(gp_export_format f, int dim)
{
    return (unsigned)f < GP_EXPORT_NFORMATS && known_dim(dim) && (formats[f].dims >> dim & 1u);
}

const char *gp_export_format_list(int dim)
{
    switch (dim) {
    case 2: return "lammps, yade, vtk, csv";
    case 3: return "lammps, liggghts, yade, vtk, csv, lammps-relax";
    case GP_EXPORT_FV3D: return "lammps, liggghts, yade, vtk, stl";
    default: return "";
    }
}

const char *gp_export_format_extension(gp_export_format f)
{
    return (unsigned)f < GP_EXPORT_NFORMATS ? formats[f].ext : "bin";
}

const char *gp_export_format_mime(gp_export_format f)
{
    return (unsigned)f < GP_EXPORT_NFORMATS ? formats[f].mime : "application/octet-stream";
}

const char *gp_export_format_extension_in(gp_export_format f, int dim)
{
    if (dim == GP_EXPORT_FV3D && f == GP_EXPORT_LAMMPS) return "tar";
    if (dim == GP_EXPORT_FV3D && f == GP_EXPORT_LIGGGHTS) return "in";
    return gp_export_format_extension(f);
}

int gp_export_format_needs_clumps(gp_export_format f, int dim)
{
    return dim == GP_EXPORT_FV3D &&
           (f == GP_EXPORT_LAMMPS || f == GP_EXPORT_LIGGGHTS || f == GP_EXPORT_YADE);
}

const char *gp_export_format_mime_in(gp_export_format f, int dim)
{
    if (dim == GP_EXPORT_FV3D && f == GP_EXPORT_LAMMPS) return "application/x-tar";
    if (dim == GP_EXPORT_FV3D && f == GP_EXPORT_LIGGGHTS) return "text/plain; charset=utf-8";
    return gp_export_format_mime(f);
}

/* ------------------------------------------------------------------ packs */

typedef struct pack_header {
    char magic[8];
    uint32_t bom, version, dim, flags;
    uint64_t nitems, npoints, ndiscs;
    double density;
    double lo[3], hi[3];
    double max_extent; /* 2D: the largest grain's bounding-box diagonal */
    uint64_t relax_bytes;  /* 3D with a DEM block: lammps-relax's data file size (0: unknown) */
    uint32_t relax_layout; /* the data file layout relax_bytes was counted for */
} pack_header;

_Static_assert(sizeof(pack_header) <= GP_PACK_HEADER, "pack header fits its 128 bytes");

static void header_init(pack_header *h, int dim, double density)
{
    memset(h, 0, sizeof *h);
    memcpy(h->magic, GP_PACK_MAGIC, 8);
    h->bom = GP_PACK_BOM;
    h->version = GP_PACK_VERSION;
    h->dim = (uint32_t)dim;
    h->density = density;
}

static gp_status check_density(double density, gp_error *err)
{
    if (!(density > 0) || !isfinite(density))
        return gp_error_set(err, GP_ERR_INVALID, "density must be a finite number > 0");
    return GP_OK;
}

static void put_f64(unsigned char **w, double v);

/* The DEM block (gp_export.h) of s built from spec, at w (GP_PACK_DEM zeroed bytes). */
static void put_dem_block(unsigned char *w, const gp_specimen3d *s, const gp_spec3d *spec)
{
    double rmin = 0, rmax = 0;
    for (size_t i = 0; i < s->count; i++) {
        double r = s->spheres[4 * i + 3];
        if (i == 0 || r < rmin) rmin = r;
        if (i == 0 || r > rmax) rmax = r;
    }
    const gp_material3d *m = &spec->material;
    memcpy(w, GP_PACK_DEM_MAGIC, 8);
    w += 8;
    const double v[13] = {m->young, m->poisson, m->friction_deg, m->damping,
                          fmax(m->damping, GP_SPEC3D_RELAX_DAMPING), GP_SPEC3D_GRAVITY,
                          s->stats.dt, s->stats.scaled_radius, GP_SPEC3D_STABILITY, rmin, rmax,
                          s->stats.porosity, s->stats.coordination_number};
    for (int k = 0; k < 13; k++) put_f64(&w, v[k]);
    for (int a = 0; a < 3; a++) {
        int32_t t = spec->tiling[a];
        memcpy(w + 4 * a, &t, 4);
    }
}

/* The size of lammps-relax's data file counted into the header of pack (len bytes, with a DEM
 * block): its tar header needs it before the first atom, and counting means formatting every
 * atom line (0.8 s at 525,000 spheres), done here once on the worker rather than by every
 * download on an HTTP thread. Left 0 (counted at the download) when the pack cannot be read
 * back for lammps-relax. */
static void put_relax_size(unsigned char *pack, size_t len)
{
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *e = NULL;
    gp_error err;
    uint64_t bytes = 0;
    if (gp_export_open(GP_EXPORT_LAMMPS_RELAX, &src, &e, &err) != GP_OK) return;
    if (gp_export_relax_count(e, &bytes) == 0) {
        pack_header h;
        memcpy(&h, pack, sizeof h);
        h.relax_bytes = bytes;
        h.relax_layout = GP_EXPORT_RELAX_LAYOUT;
        memcpy(pack, &h, sizeof h);
    }
    gp_export_destroy(e);
}

/* gp_export_pack_3d, with the DEM block when spec is given */
static gp_status pack_3d(const gp_specimen3d *s, double density, const gp_spec3d *spec,
                         void **pack, size_t *len, gp_error *err)
{
    *pack = NULL;
    *len = 0;
    if (!s) return gp_error_set(err, GP_ERR_INVALID, "no specimen");
    if (!s->spheres && s->count > 0)
        return gp_error_set(err, GP_ERR_INVALID,
                            "the specimen has no sphere list (outputs must include \"spheres\")");
    gp_status st = check_density(density, err);
    if (st) return st;
    size_t dem = spec ? GP_PACK_DEM : 0;
    if (s->count > (SIZE_MAX - GP_PACK_HEADER - dem) / 32)
        return gp_error_set(err, GP_ERR_NOMEM, "too many spheres to pack");
    size_t n = GP_PACK_HEADER + 32 * s->count + dem;
    unsigned char *p = calloc(1, n);
    if (!p) return gp_error_set(err, GP_ERR_NOMEM, "out of memory packing %zu spheres", s->count);
    pack_header h;
    header_init(&h, 3, density);
    h.nitems = s->count;
    h.flags = spec ? GP_EXPORT_HAS_DEM : 0;
    for (int k = 0; k < 3; k++) {
        h.lo[k] = 0.0;
        h.hi[k] = s->box[k];
    }
    memcpy(p, &h, sizeof h);
    if (s->count) memcpy(p + GP_PACK_HEADER, s->spheres, 32 * s->count);
    if (spec) put_dem_block(p + GP_PACK_HEADER + 32 * s->count, s, spec);
    if (spec) put_relax_size(p, n);
    *pack = p;
    *len = n;
    return GP_OK;
}

gp_status gp_export_pack_3d(const gp_specimen3d *s, double density, void **pack, size_t *len,
                            gp_error *err)
{
    return pack_3d(s, density, NULL, pack, len, err);
}

gp_status gp_export_pack_3d_dem(const gp_specimen3d *s, const gp_spec3d *spec, void **pack,
                                size_t *len, gp_error *err)
{
    if (!spec) {
        *pack = NULL;
        *len = 0;
        return gp_error_set(err, GP_ERR_INVALID, "no spec");
    }
    return pack_3d(s, spec->material.density, spec, pack, len, err);
}

static void put_u64(unsigned char **w, uint64_t v)
{
    memcpy(*w, &v, 8);
    *w += 8;
}

static void put_f64(unsigned char **w, double v)
{
    memcpy(*w, &v, 8);
    *w += 8;
}

/* A 2D pack: with its grains' ODEC discs (an export pack), or without (view: a view pack) */
static gp_status pack_2d(const gp_specimen2d *s, const gp_spec2d *spec, double density, int view,
                         void **pack, size_t *len, gp_error *err)
{
    *pack = NULL;
    *len = 0;
    if (!s || !spec) return gp_error_set(err, GP_ERR_INVALID, "no specimen");
    gp_status st = check_density(density, err);
    if (st) return st;
    uint64_t npts = 0, ndisc = 0;
    for (size_t g = 0; g < s->ngrains; g++) {
        const gp_grain2d *gr = &s->grains[g];
        if (!view && (!gr->discs || gr->ndiscs == 0))
            return gp_error_set(err, GP_ERR_INVALID,
                                "grain %zu has no ODEC discs (outputs must include \"odec\")", g);
        npts += gr->ncontour;
        ndisc += view ? 0 : gr->ndiscs;
    }
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    if (spec->container == GP_CONTAINER_CIRCLE) {
        lo[0] = spec->circle_center.x - spec->circle_radius;
        hi[0] = spec->circle_center.x + spec->circle_radius;
        lo[1] = spec->circle_center.y - spec->circle_radius;
        hi[1] = spec->circle_center.y + spec->circle_radius;
    } else {
        for (size_t i = 0; i < spec->outer.n; i++) {
            lo[0] = fmin(lo[0], spec->outer.pts[i].x);
            hi[0] = fmax(hi[0], spec->outer.pts[i].x);
            lo[1] = fmin(lo[1], spec->outer.pts[i].y);
            hi[1] = fmax(hi[1], spec->outer.pts[i].y);
        }
    }
    if (!(lo[0] < hi[0]) || !(lo[1] < hi[1]))
        return gp_error_set(err, GP_ERR_INVALID, "the container has no extent");
    uint64_t bytes = GP_PACK_HEADER + (uint64_t)GP_PACK_GRAIN * s->ngrains + 16 * npts + 24 * ndisc;
    if (bytes > SIZE_MAX) return gp_error_set(err, GP_ERR_NOMEM, "specimen too large to pack");
    unsigned char *p = calloc(1, (size_t)bytes);
    if (!p) return gp_error_set(err, GP_ERR_NOMEM, "out of memory packing %zu grains", s->ngrains);
    pack_header h;
    header_init(&h, 2, density);
    int with_desc = (spec->outputs & GP_OUT2_DESCRIPTORS) != 0;
    h.flags = (with_desc ? GP_EXPORT_HAS_DESCRIPTORS : 0) | (view ? GP_EXPORT_VIEW_ONLY : 0);
    h.nitems = s->ngrains;
    h.npoints = npts;
    h.ndiscs = ndisc;
    h.lo[0] = lo[0];
    h.lo[1] = lo[1];
    h.hi[0] = hi[0];
    h.hi[1] = hi[1];
    double ext = 0;
    for (size_t g = 0; g < s->ngrains; g++) {
        const gp_grain2d *gr = &s->grains[g];
        double a[2] = {INFINITY, INFINITY}, b[2] = {-INFINITY, -INFINITY};
        for (size_t k = 0; k < gr->ncontour; k++) {
            a[0] = fmin(a[0], gr->contour[k].x);
            b[0] = fmax(b[0], gr->contour[k].x);
            a[1] = fmin(a[1], gr->contour[k].y);
            b[1] = fmax(b[1], gr->contour[k].y);
        }
        if (gr->ncontour) ext = fmax(ext, hypot(b[0] - a[0], b[1] - a[1]));
    }
    h.max_extent = ext;
    memcpy(p, &h, sizeof h);
    unsigned char *w = p + GP_PACK_HEADER;
    unsigned char *wp = p + GP_PACK_HEADER + (size_t)GP_PACK_GRAIN * s->ngrains;
    unsigned char *wd = wp + 16 * npts;
    uint64_t pf = 0, df = 0;
    for (size_t g = 0; g < s->ngrains; g++) {
        const gp_grain2d *gr = &s->grains[g];
        put_u64(&w, pf);
        put_u64(&w, gr->ncontour);
        size_t nd = view ? 0 : gr->ndiscs;
        put_u64(&w, df);
        put_u64(&w, nd);
        put_f64(&w, gr->area);
        put_f64(&w, gr->orientation_deg);
        const gp_descriptors *d = &gr->descriptors;
        put_f64(&w, with_desc ? d->elongation : NAN);
        put_f64(&w, with_desc ? d->roundness : NAN);
        put_f64(&w, with_desc ? d->circularity : NAN);
        put_f64(&w, with_desc ? d->regularity : NAN);
        for (size_t k = 0; k < gr->ncontour; k++) {
            put_f64(&wp, gr->contour[k].x);
            put_f64(&wp, gr->contour[k].y);
        }
        if (nd) memcpy(wd, gr->discs, 24 * nd);
        wd += 24 * nd;
        pf += gr->ncontour;
        df += nd;
    }
    *pack = p;
    *len = (size_t)bytes;
    return GP_OK;
}

gp_status gp_export_pack_2d(const gp_specimen2d *s, const gp_spec2d *spec, double density,
                            void **pack, size_t *len, gp_error *err)
{
    return pack_2d(s, spec, density, 0, pack, len, err);
}

gp_status gp_export_pack_2d_view(const gp_specimen2d *s, const gp_spec2d *spec, void **pack,
                                 size_t *len, gp_error *err)
{
    return pack_2d(s, spec, GP_EXPORT_DEFAULT_DENSITY, 1, pack, len, err);
}

/* ------------------------------------------------------------------ the fv3d pack */

/* lammps' member sizes counted into the fv3d block of pack (len bytes, with clumps): made here
 * once on the worker rather than by every download (as put_relax_size). Left 0 (counted at the
 * download) when the pack cannot be read back. */
static void put_fv3d_sizes(unsigned char *pack, size_t len)
{
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *e = NULL;
    gp_error err;
    uint64_t data = 0, rigid = 0;
    if (gp_export_open(GP_EXPORT_LAMMPS, &src, &e, &err) != GP_OK) return;
    if (gp_export_fv3d_count(e, &data, &rigid) == 0) {
        uint32_t layout = GP_EXPORT_FV3D_LAYOUT;
        memcpy(pack + GP_PACK_HEADER + 16, &data, 8);
        memcpy(pack + GP_PACK_HEADER + 24, &rigid, 8);
        memcpy(pack + GP_PACK_HEADER + 32, &layout, 4);
    }
    gp_export_destroy(e);
}

/* The box of a fv3d specimen: its cells' vertices' extent (the container's bounding box), with
 * the grains' vertices and clump spheres, which lie inside (a guard); max_extent the largest
 * grain's bounding-box diagonal. xyz holds 3 x ndirs doubles. */
static gp_status fv3d_box(const gp_fv3d *s, size_t ndirs, double *xyz, pack_header *h,
                          gp_error *err)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    const gp_voronoi3d *v = gp_fv3d_cells(s);
    size_t n = gp_fv3d_count(s), cap = 0;
    double *cv = NULL;
    for (size_t i = 0; v && i < gp_voronoi3d_count(v); i++) {
        size_t nv = gp_voronoi3d_cell_vertices(v, i, NULL, 0);
        if (nv > cap) {
            double *nb = realloc(cv, 3 * nv * sizeof *nb);
            if (!nb) {
                free(cv);
                return gp_error_set(err, GP_ERR_NOMEM, "out of memory packing the cells");
            }
            cv = nb;
            cap = nv;
        }
        nv = gp_voronoi3d_cell_vertices(v, i, cv, cap);
        for (size_t k = 0; k < nv; k++)
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], cv[3 * k + a]);
                hi[a] = fmax(hi[a], cv[3 * k + a]);
            }
    }
    free(cv);
    double ext = 0;
    for (size_t g = 0; g < n; g++) {
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        double a[3] = {INFINITY, INFINITY, INFINITY}, b[3] = {-INFINITY, -INFINITY, -INFINITY};
        gp_fv3d_grain_vertices(s, g, xyz);
        for (size_t k = 0; k < ndirs; k++)
            for (int c = 0; c < 3; c++) {
                a[c] = fmin(a[c], xyz[3 * k + c]);
                b[c] = fmax(b[c], xyz[3 * k + c]);
            }
        for (size_t k = 0; k < gr->nspheres; k++)
            for (int c = 0; c < 3; c++) {
                a[c] = fmin(a[c], gr->spheres[4 * k + c] - gr->spheres[4 * k + 3]);
                b[c] = fmax(b[c], gr->spheres[4 * k + c] + gr->spheres[4 * k + 3]);
            }
        if (ndirs) ext = fmax(ext, sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                                        (b[2] - a[2]) * (b[2] - a[2])));
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], a[c]);
            hi[c] = fmax(hi[c], b[c]);
        }
    }
    for (int c = 0; c < 3; c++)
        if (!(lo[c] <= hi[c]) || !isfinite(lo[c]) || !isfinite(hi[c]))
            return gp_error_set(err, GP_ERR_INVALID, "the specimen has no finite extent");
    memcpy(h->lo, lo, sizeof lo);
    memcpy(h->hi, hi, sizeof hi);
    h->max_extent = ext;
    return GP_OK;
}

gp_status gp_export_pack_fv3d(const gp_fv3d *s, double density, void **pack, size_t *len,
                              gp_error *err)
{
    *pack = NULL;
    *len = 0;
    if (!s) return gp_error_set(err, GP_ERR_INVALID, "no specimen");
    gp_status st = check_density(density, err);
    if (st) return st;
    const double *dirs;
    const uint32_t *tris;
    size_t n = gp_fv3d_count(s), nd = gp_fv3d_directions(s, &dirs), nt = gp_fv3d_triangles(s, &tris);
    if ((nd && !dirs) || (nt && !tris))
        return gp_error_set(err, GP_ERR_INVALID, "the specimen has no icosphere");
    uint64_t nsph = 0;
    size_t with = 0;
    double rmin = 0, rmax = 0, volume = 0;
    for (size_t g = 0; g < n; g++) {
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        if (!gr->radii && nd) return gp_error_set(err, GP_ERR_INVALID, "grain %zu has no radii", g);
        if (gr->nspheres && !gr->spheres)
            return gp_error_set(err, GP_ERR_INVALID, "grain %zu has no sphere list", g);
        with += gr->nspheres > 0;
        for (size_t k = 0; k < gr->nspheres; k++) {
            double r = gr->spheres[4 * k + 3];
            rmin = nsph + k == 0 ? r : fmin(rmin, r);
            rmax = nsph + k == 0 ? r : fmax(rmax, r);
        }
        nsph += gr->nspheres;
        volume += gr->volume;
    }
    if (with && with < n)
        return gp_error_set(err, GP_ERR_INVALID,
                            "%zu of %zu grains have a clump of spheres: all or none must", with, n);
    double need = GP_PACK_HEADER + (double)GP_PACK_FV3D + (double)GP_PACK_GRAIN3 * (double)n +
                  32.0 * (double)nsph + 8.0 * (double)n * (double)nd + 24.0 * (double)nd +
                  12.0 * (double)nt;
    if (need > (double)(SIZE_MAX / 2)) return gp_error_set(err, GP_ERR_NOMEM, "specimen too large to pack");
    size_t bytes = (size_t)need;
    double *xyz = malloc((nd ? 3 * nd : 1) * sizeof *xyz);
    unsigned char *p = calloc(1, bytes);
    if (!p || !xyz) {
        free(p);
        free(xyz);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory packing %zu grains", n);
    }
    pack_header h;
    header_init(&h, GP_EXPORT_FV3D, density);
    h.flags = with ? GP_EXPORT_HAS_CLUMPS : 0;
    h.nitems = n;
    h.npoints = nd;
    h.ndiscs = nsph;
    st = fv3d_box(s, nd, xyz, &h, err);
    free(xyz);
    if (st) {
        free(p);
        return st;
    }
    memcpy(p, &h, sizeof h);
    /* the fv3d block */
    unsigned char *w = p + GP_PACK_HEADER;
    memcpy(w, GP_PACK_FV3D_MAGIC, 8);
    w += 8;
    put_u64(&w, nt);
    w += 8 + 8 + 8; /* the counted sizes (below) and the layout */
    put_f64(&w, volume);
    put_f64(&w, rmin);
    put_f64(&w, rmax);
    /* the grains, their spheres, their radii, the icosphere */
    w = p + GP_PACK_HEADER + GP_PACK_FV3D;
    unsigned char *ws = w + (size_t)GP_PACK_GRAIN3 * n;
    unsigned char *wr = ws + 32 * nsph;
    uint64_t first = 0;
    for (size_t g = 0; g < n; g++) {
        const gp_fv3d_grain *gr = gp_fv3d_grain_at(s, g);
        put_u64(&w, gr->cell);
        put_u64(&w, first);
        put_u64(&w, gr->nspheres);
        for (int k = 0; k < 3; k++) put_f64(&w, gr->centre[k]);
        for (int k = 0; k < 4; k++) put_f64(&w, gr->rotation[k]);
        put_f64(&w, gr->scale);
        put_f64(&w, gr->volume);
        put_f64(&w, density * gr->volume);
        for (int k = 0; k < 3; k++) put_f64(&w, gr->centroid[k]);
        static const int upper[6] = {0, 4, 8, 1, 2, 5}; /* xx yy zz xy xz yz */
        for (int k = 0; k < 6; k++) put_f64(&w, density * gr->inertia[upper[k]]);
        if (gr->nspheres) memcpy(ws, gr->spheres, 32 * gr->nspheres);
        ws += 32 * gr->nspheres;
        first += gr->nspheres;
        if (nd) memcpy(wr, gr->radii, 8 * nd);
        wr += 8 * nd;
    }
    if (nd) memcpy(wr, dirs, 24 * nd);
    wr += 24 * nd;
    if (nt) memcpy(wr, tris, 12 * nt);
    if (with) put_fv3d_sizes(p, bytes);
    *pack = p;
    *len = bytes;
    return GP_OK;
}

/* ------------------------------------------------------------------ sources */

/* The pack in memory. Bounds are checked by cache_get() against the source's size before any
 * read, so the reader itself only copies. */
static int mem_read(void *user, uint64_t off, void *dst, size_t n)
{
    memcpy(dst, (const unsigned char *)user + off, n);
    return 0;
}

gp_export_source gp_export_memory_source(const void *pack, size_t len)
{
    gp_export_source s = {mem_read, (void *)pack, len};
    return s;
}

/* Makes [off, off + n) available in the cache; returns a pointer into it or NULL. */
static const unsigned char *cache_get(gp_export *e, uint64_t off, size_t n)
{
    if (off >= e->cache_off && off + n <= e->cache_off + e->cache_len)
        return e->cache + (off - e->cache_off);
    if (off > e->src.size || n > e->src.size - off || n > CACHE_BYTES) {
        gp_error_set(&e->err, GP_ERR_INVALID, "pack truncated: %zu bytes at offset %llu of %llu",
                     n, (unsigned long long)off, (unsigned long long)e->src.size);
        return NULL;
    }
    uint64_t want = e->src.size - off;
    size_t len = want < CACHE_BYTES ? (size_t)want : CACHE_BYTES;
    if (e->src.read(e->src.user, off, e->cache, len)) {
        e->cache_len = 0;
        gp_error_set(&e->err, GP_ERR_INVALID, "reading the pack failed at offset %llu",
                     (unsigned long long)off);
        return NULL;
    }
    e->cache_off = off;
    e->cache_len = len;
    return e->cache;
}

const unsigned char *gp_xr_window(gp_export *e, uint64_t off, size_t n)
{
    return cache_get(e, off, n);
}

const unsigned char *gp_xr_window2(gp_export *e, uint64_t off, size_t n)
{
    gp_x3 *x = &e->x3;
    if (x->cache && off >= x->cache_off && off + n <= x->cache_off + x->cache_len)
        return x->cache + (off - x->cache_off);
    if (off > e->src.size || n > e->src.size - off || n > CACHE_BYTES) {
        gp_error_set(&e->err, GP_ERR_INVALID, "pack truncated: %zu bytes at offset %llu of %llu",
                     n, (unsigned long long)off, (unsigned long long)e->src.size);
        return NULL;
    }
    if (!x->cache && !(x->cache = malloc(CACHE_BYTES))) {
        gp_error_set(&e->err, GP_ERR_NOMEM, "out of memory");
        return NULL;
    }
    uint64_t want = e->src.size - off;
    size_t len = want < CACHE_BYTES ? (size_t)want : CACHE_BYTES;
    if (e->src.read(e->src.user, off, x->cache, len)) {
        x->cache_len = 0;
        gp_error_set(&e->err, GP_ERR_INVALID, "reading the pack failed at offset %llu",
                     (unsigned long long)off);
        return NULL;
    }
    x->cache_off = off;
    x->cache_len = len;
    return x->cache;
}

static int read_f64s(gp_export *e, uint64_t off, double *out, int n)
{
    const unsigned char *p = cache_get(e, off, 8 * (size_t)n);
    if (!p) return -1;
    memcpy(out, p, 8 * (size_t)n);
    return 0;
}

int gp_xr_sphere(gp_export *e, uint64_t i, double q[4])
{
    if (i >= e->info.nitems) return gp_error_set(&e->err, GP_ERR_INTERNAL, "sphere %llu", (unsigned long long)i), -1;
    return read_f64s(e, e->off_items + 32 * i, q, 4);
}

int gp_xr_grain(gp_export *e, uint64_t g, gp_export_grain *out)
{
    if (g >= e->info.nitems) return gp_error_set(&e->err, GP_ERR_INTERNAL, "grain %llu", (unsigned long long)g), -1;
    const unsigned char *p = cache_get(e, e->off_items + (uint64_t)GP_PACK_GRAIN * g, GP_PACK_GRAIN);
    if (!p) return -1;
    memcpy(&out->point_first, p, 8);
    memcpy(&out->point_count, p + 8, 8);
    memcpy(&out->disc_first, p + 16, 8);
    memcpy(&out->disc_count, p + 24, 8);
    memcpy(&out->area, p + 32, 8);
    memcpy(&out->orientation_deg, p + 40, 8);
    memcpy(&out->elongation, p + 48, 8);
    memcpy(&out->roundness, p + 56, 8);
    memcpy(&out->circularity, p + 64, 8);
    memcpy(&out->regularity, p + 72, 8);
    /* a corrupt record must not send the readers past their arrays */
    const gp_export_info *h = &e->info;
    if (out->point_first > h->npoints || out->point_count > h->npoints - out->point_first ||
        out->disc_first > h->ndiscs || out->disc_count > h->ndiscs - out->disc_first) {
        gp_error_set(&e->err, GP_ERR_INVALID, "pack grain %llu points outside its arrays",
                     (unsigned long long)g);
        return -1;
    }
    return 0;
}

int gp_xr_point(gp_export *e, uint64_t k, double p[2])
{
    if (k >= e->info.npoints) return gp_error_set(&e->err, GP_ERR_INTERNAL, "point %llu", (unsigned long long)k), -1;
    return read_f64s(e, e->off_points + 16 * k, p, 2);
}

int gp_xr_disc(gp_export *e, uint64_t k, double d[3])
{
    if (k >= e->info.ndiscs) return gp_error_set(&e->err, GP_ERR_INTERNAL, "disc %llu", (unsigned long long)k), -1;
    return read_f64s(e, e->off_discs + 24 * k, d, 3);
}

/* ------------------------------------------------------------------ writer */

int gp_xw_bytes(gp_export *e, const void *p, size_t n)
{
    if (n > e->cap - e->len) {
        size_t ncap = e->cap * 2 > e->len + n ? e->cap * 2 : e->len + n;
        char *nb = realloc(e->buf, ncap);
        if (!nb) {
            gp_error_set(&e->err, GP_ERR_NOMEM, "out of memory writing a record");
            return -1;
        }
        e->buf = nb;
        e->cap = ncap;
    }
    if (p) memcpy(e->buf + e->len, p, n);
    else memset(e->buf + e->len, 0, n);
    e->len += n;
    return 0;
}

int gp_xw_printf(gp_export *e, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = e->cap - e->len;
        int k = vsnprintf(e->buf + e->len, room, fmt, ap);
        va_end(ap);
        if (k < 0) {
            gp_error_set(&e->err, GP_ERR_INTERNAL, "formatting failed");
            return -1;
        }
        if ((size_t)k < room) {
            e->len += (size_t)k;
            return 0;
        }
        size_t ncap = e->cap * 2 > e->len + (size_t)k + 1 ? e->cap * 2 : e->len + (size_t)k + 1;
        char *nb = realloc(e->buf, ncap);
        if (!nb) {
            gp_error_set(&e->err, GP_ERR_NOMEM, "out of memory formatting a record");
            return -1;
        }
        e->buf = nb;
        e->cap = ncap;
    }
}

/* the line-per-item formats (gp_export_internal.h) */
static int next_grain(gp_export *e, const gp_xlines *f)
{
    return f->grain ? f->grain(e) : gp_xr_grain(e, e->index, &e->grain);
}

int gp_xw_lines(gp_export *e, const gp_xlines *f)
{
    if (e->section == 0) {
        e->section = 1;
        e->index = e->sub = 0;
        if (f->header(e)) return -1;
        if (e->info.nitems == 0) return 1;
        return e->info.dim == 2 ? next_grain(e, f) : 0;
    }
    if (e->info.dim == 3) {
        double q[4];
        if (gp_xr_sphere(e, e->index, q) || f->sphere(e, q)) return -1;
        return ++e->index >= e->info.nitems;
    }
    double d[3];
    if (gp_xr_disc(e, e->grain.disc_first + e->sub, d) || f->disc(e, d)) return -1;
    if (++e->sub < e->grain.disc_count) return 0;
    e->sub = 0;
    if (++e->index >= e->info.nitems) return 1;
    return next_grain(e, f);
}

/* ------------------------------------------------------------------ stream */

/* The DEM block after the spheres into e->dem; -1 when its magic is not there. */
static int read_dem(gp_export *e)
{
    const unsigned char *p = cache_get(e, GP_PACK_HEADER + 32 * e->info.nitems, GP_PACK_DEM);
    if (!p || memcmp(p, GP_PACK_DEM_MAGIC, 8)) return -1;
    double v[13];
    memcpy(v, p + 8, sizeof v);
    gp_xdem *d = &e->dem;
    d->young = v[0]; d->poisson = v[1]; d->friction_deg = v[2]; d->damping = v[3];
    d->relax_damping = v[4]; d->gravity = v[5]; d->dt = v[6]; d->scaled_radius = v[7];
    d->stability = v[8]; d->rmin = v[9]; d->rmax = v[10]; d->porosity = v[11];
    d->coordination = v[12];
    memcpy(d->tiling, p + 8 + sizeof v, sizeof d->tiling);
    d->present = 1;
    return 0;
}

/* Whether a DEM block can drive a relaxation (the writer divides by and takes logs of these). */
static int dem_usable(const gp_xdem *d)
{
    return d->present && d->young > 0 && d->young < INFINITY && d->poisson >= 0 &&
           d->poisson < INFINITY && d->friction_deg >= 0 && d->friction_deg < 90 &&
           d->relax_damping >= 0 && d->relax_damping < 1 && isfinite(d->gravity) && d->dt > 0 &&
           d->dt < INFINITY && d->scaled_radius >= 0 && d->scaled_radius < INFINITY &&
           d->stability > 0 && d->stability < 1 && d->rmin > 0 && d->rmax >= d->rmin &&
           d->rmax < INFINITY && d->tiling[0] >= 1 && d->tiling[1] >= 1 && d->tiling[2] >= 1;
}

/* Opens the pack behind src and checks its header, sizes and DEM block: the part of an export
 * that every format and the record reader share. */
static gp_status pack_open(const gp_export_source *src, gp_export **out, gp_error *err)
{
    *out = NULL;
    if (!src || !src->read) return gp_error_set(err, GP_ERR_INVALID, "no source");
    if (src->size < GP_PACK_HEADER)
        return gp_error_set(err, GP_ERR_INVALID, "not an export pack (%llu bytes)",
                            (unsigned long long)src->size);
    gp_export *e = calloc(1, sizeof *e);
    if (!e) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    e->src = *src;
    e->cache = malloc(CACHE_BYTES);
    if (!e->cache) {
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    pack_header h;
    const unsigned char *p = cache_get(e, 0, GP_PACK_HEADER);
    if (!p) {
        gp_status st = gp_error_set(err, e->err.code, "%s", e->err.message);
        gp_export_destroy(e);
        return st;
    }
    memcpy(&h, p, sizeof h);
    const char *why = NULL;
    if (memcmp(h.magic, GP_PACK_MAGIC, 8)) why = "bad magic";
    else if (h.bom != GP_PACK_BOM) why = "written with another byte order";
    else if (h.version != GP_PACK_VERSION) why = "unknown version";
    else if (!known_dim((int)h.dim)) why = "bad dimension";
    if (!why) {
        e->info.dim = (int)h.dim;
        e->info.flags = h.flags;
        e->info.nitems = h.nitems;
        e->info.npoints = h.npoints;
        e->info.ndiscs = h.ndiscs;
        e->info.density = h.density;
        memcpy(e->info.lo, h.lo, sizeof e->info.lo);
        memcpy(e->info.hi, h.hi, sizeof e->info.hi);
        e->info.max_extent = h.max_extent;
        e->relax_bytes = h.relax_layout == GP_EXPORT_RELAX_LAYOUT ? h.relax_bytes : 0;
        e->off_items = GP_PACK_HEADER;
        /* sizes are checked in floating point first so that a corrupt count cannot wrap */
        double need;
        if (e->info.dim == GP_EXPORT_FV3D) {
            need = gp_x3_read_block(e) ? -1.0 : gp_x3_pack_size(&e->info);
            if (need < 0) why = "bad fv3d block";
        } else if (e->info.dim == 3) {
            need = GP_PACK_HEADER + 32.0 * (double)e->info.nitems;
            if (e->info.flags & GP_EXPORT_HAS_DEM) need += GP_PACK_DEM;
        } else {
            need = GP_PACK_HEADER + (double)GP_PACK_GRAIN * (double)e->info.nitems +
                   16.0 * (double)e->info.npoints + 24.0 * (double)e->info.ndiscs;
            e->off_points = GP_PACK_HEADER + (uint64_t)GP_PACK_GRAIN * e->info.nitems;
            e->off_discs = e->off_points + 16 * e->info.npoints;
        }
        if (!why && need != (double)src->size) why = "its size does not match its counts";
    }
    if (!why && e->info.dim == 3 && (e->info.flags & GP_EXPORT_HAS_DEM) && read_dem(e))
        why = "bad DEM block";
    if (why) {
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_INVALID, "not an export pack: %s", why);
    }
    *out = e;
    return GP_OK;
}

gp_status gp_export_open(gp_export_format f, const gp_export_source *src, gp_export **out,
                         gp_error *err)
{
    *out = NULL;
    if ((unsigned)f >= GP_EXPORT_NFORMATS)
        return gp_error_set(err, GP_ERR_INVALID, "unknown export format %d", (int)f);
    gp_export *e;
    gp_status st = pack_open(src, &e, err);
    if (st) return st;
    if (e->info.flags & GP_EXPORT_VIEW_ONLY) {
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_INVALID,
                            "a view pack has no ODEC discs to export (outputs must include \"odec\")");
    }
    e->format = f;
    e->cap = 4096;
    e->buf = malloc(e->cap);
    if (!e->buf) {
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    }
    if (!gp_export_format_supports(f, e->info.dim)) {
        int dim = e->info.dim;
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_INVALID, "format %s does not exist in %s (valid: %s)",
                            gp_export_format_name(f), dim_name(dim), gp_export_format_list(dim));
    }
    if (e->info.dim == GP_EXPORT_FV3D) {
        switch (f) {
        case GP_EXPORT_LAMMPS: e->step = gp_export_step_fv3d_lammps; break;
        case GP_EXPORT_LIGGGHTS: e->step = gp_export_step_fv3d_liggghts; break;
        case GP_EXPORT_YADE: e->step = gp_export_step_fv3d_yade; break;
        case GP_EXPORT_VTK: e->step = gp_export_step_fv3d_vtk; break;
        default: e->step = gp_export_step_fv3d_stl; break;
        }
        if (gp_export_format_needs_clumps(f, e->info.dim) &&
            !(e->info.flags & GP_EXPORT_HAS_CLUMPS) && e->info.nitems > 0) {
            gp_export_destroy(e);
            return gp_error_set(err, GP_ERR_INVALID,
                                "%s needs the clumps output (outputs must include \"clumps\"): "
                                "its rigid bodies are the grains' clumps of spheres",
                                gp_export_format_name(f));
        }
        *out = e;
        return GP_OK;
    }
    switch (f) {
    case GP_EXPORT_LAMMPS:
    case GP_EXPORT_LIGGGHTS: e->step = gp_export_step_lammps; break;
    case GP_EXPORT_YADE: e->step = gp_export_step_yade; break;
    case GP_EXPORT_VTK:
        e->step = e->info.dim == 3 ? gp_export_step_vtk3d : gp_export_step_vtk2d;
        break;
    case GP_EXPORT_LAMMPS_RELAX: e->step = gp_export_step_lammps_relax; break;
    default: e->step = gp_export_step_csv; break;
    }
    if (f == GP_EXPORT_LAMMPS_RELAX && !dem_usable(&e->dem)) {
        int old = !e->dem.present;
        gp_export_destroy(e);
        return gp_error_set(err, GP_ERR_INVALID,
                            old ? "lammps-relax needs the job's material and DEM settings, which "
                                  "its export pack (made before lammps-relax existed) lacks: "
                                  "submit the job again"
                                : "lammps-relax: the pack's DEM settings are out of range");
    }
    *out = e;
    return GP_OK;
}

gp_status gp_export_read(gp_export *e, char *buf, size_t cap, size_t *n, gp_error *err)
{
    *n = 0;
    if (e->failed) return gp_error_set(err, e->err.code, "%s", e->err.message);
    if (!buf || cap == 0) /* n = 0 would read as the end */
        return gp_error_set(err, GP_ERR_INVALID, "gp_export_read needs a buffer of cap > 0");
    size_t got = 0;
    while (got < cap) {
        if (e->pos < e->len) {
            size_t k = e->len - e->pos;
            if (k > cap - got) k = cap - got;
            memcpy(buf + got, e->buf + e->pos, k);
            e->pos += k;
            got += k;
            continue;
        }
        if (e->done) break;
        e->len = e->pos = 0;
        int r = e->step(e);
        if (r < 0) {
            e->failed = 1;
            if (e->err.code == GP_OK) gp_error_set(&e->err, GP_ERR_INTERNAL, "export failed");
            return gp_error_set(err, e->err.code, "%s", e->err.message);
        }
        if (r > 0) e->done = 1;
    }
    *n = got;
    return GP_OK;
}

void gp_export_destroy(gp_export *e)
{
    if (!e) return;
    free(e->cache);
    free(e->buf);
    free(e->x3.cache);
    free(e->x3.verts);
    free(e->x3.dirs);
    free(e->x3.tris);
    free(e);
}

/* ------------------------------------------------------------------ record reader */

struct gp_export_reader {
    gp_export *e; /* opened by pack_open: the header and the read cache, no format */
};

gp_status gp_export_pack_info(const gp_export_source *src, gp_export_info *info, gp_error *err)
{
    gp_export *e;
    gp_status st = pack_open(src, &e, err);
    if (st) return st;
    *info = e->info;
    gp_export_destroy(e);
    return GP_OK;
}

gp_status gp_export_reader_open(const gp_export_source *src, gp_export_reader **out,
                                gp_error *err)
{
    *out = NULL;
    gp_export_reader *r = calloc(1, sizeof *r);
    if (!r) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    gp_status st = pack_open(src, &r->e, err);
    if (st) {
        free(r);
        return st;
    }
    *out = r;
    return GP_OK;
}

const gp_export_info *gp_export_reader_info(const gp_export_reader *r) { return &r->e->info; }

/* The index check of a public read: a record of the pack's kind (dim), index below count. */
static gp_status reader_check(const gp_export_reader *r, int dim, const char *what, uint64_t k,
                              uint64_t count, gp_error *err)
{
    if (r->e->info.dim != dim)
        return gp_error_set(err, GP_ERR_INVALID, "a %s pack has no %s records",
                            dim_name(r->e->info.dim), what);
    if (k >= count)
        return gp_error_set(err, GP_ERR_INVALID, "%s %llu of %llu", what, (unsigned long long)k,
                            (unsigned long long)count);
    return GP_OK;
}

/* The outcome of a record read: the reader's error, passed to the caller's. */
static gp_status reader_result(const gp_export_reader *r, int failed, gp_error *err)
{
    return failed ? gp_error_set(err, r->e->err.code, "%s", r->e->err.message) : GP_OK;
}

gp_status gp_export_reader_sphere(gp_export_reader *r, uint64_t i, double q[4], gp_error *err)
{
    gp_status st = reader_check(r, 3, "sphere", i, r->e->info.nitems, err);
    return st ? st : reader_result(r, gp_xr_sphere(r->e, i, q), err);
}

gp_status gp_export_reader_grain(gp_export_reader *r, uint64_t g, gp_export_grain *out,
                                 gp_error *err)
{
    gp_status st = reader_check(r, 2, "grain", g, r->e->info.nitems, err);
    return st ? st : reader_result(r, gp_xr_grain(r->e, g, out), err);
}

gp_status gp_export_reader_point(gp_export_reader *r, uint64_t k, double p[2], gp_error *err)
{
    gp_status st = reader_check(r, 2, "point", k, r->e->info.npoints, err);
    return st ? st : reader_result(r, gp_xr_point(r->e, k, p), err);
}

gp_status gp_export_reader_disc(gp_export_reader *r, uint64_t k, double d[3], gp_error *err)
{
    gp_status st = reader_check(r, 2, "disc", k, r->e->info.ndiscs, err);
    return st ? st : reader_result(r, gp_xr_disc(r->e, k, d), err);
}

gp_status gp_export_reader_grain3(gp_export_reader *r, uint64_t g, gp_export_grain3 *out,
                                  gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "grain", g, r->e->info.nitems, err);
    return st ? st : reader_result(r, gp_xr_grain3(r->e, g, out), err);
}

gp_status gp_export_reader_clump_sphere(gp_export_reader *r, uint64_t k, double q[4],
                                        gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "clump sphere", k, r->e->info.ndiscs, err);
    return st ? st : reader_result(r, gp_xr_clump(r->e, k, q), err);
}

gp_status gp_export_reader_direction(gp_export_reader *r, uint64_t k, double d[3], gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "direction", k, r->e->info.npoints, err);
    return st ? st : reader_result(r, gp_xr_direction(r->e, k, d), err);
}

gp_status gp_export_reader_triangle(gp_export_reader *r, uint64_t t, uint32_t tri[3],
                                    gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "triangle", t, r->e->info.ntriangles, err);
    return st ? st : reader_result(r, gp_xr_triangle(r->e, t, tri), err);
}

gp_status gp_export_reader_vertices(gp_export_reader *r, uint64_t g, double *xyz, gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "grain", g, r->e->info.nitems, err);
    if (st) return st;
    gp_export_grain3 gr;
    return reader_result(r, gp_xr_grain3(r->e, g, &gr) || gp_x3_vertices(r->e, g, &gr, xyz), err);
}

/* grain g's radii (g below nitems) in pieces of the read cache's size, as gp_x3_vertices reads
 * them */
static int read_radii(gp_export *e, uint64_t g, double *radii)
{
    const uint64_t nd = e->info.npoints, piece = 4096;
    for (uint64_t k0 = 0; k0 < nd; k0 += piece) {
        uint64_t m = nd - k0 < piece ? nd - k0 : piece;
        const unsigned char *p = gp_xr_window(e, e->x3.off_radii + 8 * (g * nd + k0), 8 * (size_t)m);
        if (!p) return -1;
        memcpy(radii + k0, p, 8 * (size_t)m);
    }
    return 0;
}

gp_status gp_export_reader_radii(gp_export_reader *r, uint64_t g, double *radii, gp_error *err)
{
    gp_status st = reader_check(r, GP_EXPORT_FV3D, "grain", g, r->e->info.nitems, err);
    return st ? st : reader_result(r, read_radii(r->e, g, radii), err);
}

void gp_export_reader_destroy(gp_export_reader *r)
{
    if (!r) return;
    gp_export_destroy(r->e);
    free(r);
}
