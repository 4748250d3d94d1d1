/* gp_grain3d.c -- 3D Fourier grains. See gp_grain3d.h.
 *
 * Layout: harmonics and the basis, random draws, the field and the stretch, the star-shape
 * check, radii, descriptors, projections.
 */
#include "gp_grain3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_sf_legendre.h>

#define G3_PI 3.14159265358979323846
#define G3_SQRT2 1.41421356237309504880
#define LEG_BUF 640            /* >= gsl_sf_legendre_array_n(GP_GRAIN3D_DEGREE_MAX) = 558 */
#define TABLE_MAX (1u << 27)   /* doubles in a basis' table (1 GB) */
#define STAR_REL 1e-9          /* the star test's thresholds, widened against rounding */
#define STAR_ABS 1e-12
#define PROJ_ANGLE_EPS 1e-9    /* an edge's angular span, widened (in bins) */
#define PROJ_COLLINEAR 1e-12   /* an edge in line with the centre (|Pi x Pj| / |Pi||Pj|) */

struct gp_grain3d_basis {
    unsigned level, degree;
    size_t nv, nt, ne, ncoef;
    double elongation, flatness; /* the stretch S = diag(1, e, e f) the table is for */
    double kappa;    /* the level's volume factor: (4 pi / 3 / V_icosphere)^(1/3) */
    gp_mesh3d *mesh; /* the directions d_i = S u_i / |S u_i| and the icosphere's triangles */
    double *u;       /* 3 per vertex: the icosphere's directions u_i, where the field is summed */
    double *k;       /* per vertex: kappa |S u_i|, the radius along d_i over the field's */
    double *Y;       /* ncoef rows of nv: Y[k nv + i] = Y_k(u_i) */
    double *rho2;    /* per triangle of the u_i: its squared spherical circumradius */
    uint32_t *edges; /* ne pairs (i, j), i < j */
};

/* ------------------------------------------------------------------------------------------ */
/* harmonics and the basis                                                                     */

void gp_grain3d_harmonics(unsigned degree, const double u[3], double *Y)
{
    if (degree > GP_GRAIN3D_DEGREE_MAX) degree = GP_GRAIN3D_DEGREE_MAX;
    size_t nc = GP_GRAIN3D_NCOEF(degree);
    double r = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(r > 0) || !isfinite(r)) {
        for (size_t k = 0; k < nc; k++) Y[k] = NAN;
        return;
    }
    double x = fmin(1.0, fmax(-1.0, u[2] / r)), rho = hypot(u[0], u[1]);
    double cp = rho > 0 ? u[0] / rho : 1.0, sp = rho > 0 ? u[1] / rho : 0.0;
    double P[LEG_BUF];
    gsl_sf_legendre_array(GSL_SF_LEGENDRE_SPHARM, degree, x, P);
    for (unsigned n = 0; n <= degree; n++) Y[GP_GRAIN3D_INDEX(n, 0)] = P[n * (n + 1) / 2];
    double cm = 1.0, sm = 0.0;
    for (unsigned m = 1; m <= degree; m++) {
        double c2 = cm * cp - sm * sp;
        sm = sm * cp + cm * sp;
        cm = c2;
        for (unsigned n = m; n <= degree; n++) {
            double p = G3_SQRT2 * P[n * (n + 1) / 2 + m];
            Y[GP_GRAIN3D_INDEX(n, (int)m)] = p * cm;
            Y[GP_GRAIN3D_INDEX(n, 0) - m] = p * sm;
        }
    }
}

double gp_grain3d_section_weight(unsigned n, unsigned k)
{
    if (k > n || (n - k) % 2 || n > 1000) return 0.0;
    double p = gsl_sf_legendre_sphPlm((int)n, (int)k, 0.0);
    return 4.0 * G3_PI / (2.0 * n + 1.0) * (k ? 2.0 : 1.0) * p * p;
}

static void sub3(const double *a, const double *b, double *c)
{
    c[0] = a[0] - b[0];
    c[1] = a[1] - b[1];
    c[2] = a[2] - b[2];
}

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/* The squared angular radius of the circle through the unit vectors a, b, c (counter-clockwise
 * seen from outside): the angle between a and the pole of the plane through them. */
static double circumradius2(const double *a, const double *b, const double *c)
{
    double u[3], w[3], n[3], s[3];
    sub3(b, a, u);
    sub3(c, a, w);
    cross3(u, w, n);
    double len = norm3(n);
    if (!(len > 0)) return INFINITY;
    for (int k = 0; k < 3; k++) n[k] /= len;
    cross3(n, a, s);
    double rho = atan2(norm3(s), n[0] * a[0] + n[1] * a[1] + n[2] * a[2]);
    return rho * rho;
}

void gp_grain3d_basis_destroy(gp_grain3d_basis *b)
{
    if (!b) return;
    gp_mesh3d_destroy(b->mesh);
    free(b->u);
    free(b->k);
    free(b->Y);
    free(b->rho2);
    free(b->edges);
    free(b);
}

/* The level's volume factor: the unit icosphere's vertices lie on the sphere and its flat
 * triangles inside it; kappa^3 times its volume is the sphere's. */
static gp_status basis_kappa(gp_grain3d_basis *b, gp_error *err)
{
    gp_mesh3d_mass ms;
    gp_status st = gp_mesh3d_mass_properties(gp_mesh3d_vertices(b->mesh), b->nv, gp_mesh3d_triangles(b->mesh),
                                             b->nt, &ms, err);
    if (st) return st;
    b->kappa = cbrt(4.0 * G3_PI / 3.0 / ms.volume);
    return GP_OK;
}

/* The field's directions u_i (the icosphere), the stretched body's d_i = S u_i / |S u_i| and the
 * factors k_i = kappa |S u_i|: the stretch maps the icosphere's mesh affinely, so a stretched
 * sphere's mesh is the ellipsoid's with the sphere's own (volume-exact) accuracy. */
static gp_status basis_stretch(gp_grain3d_basis *b, gp_error *err)
{
    const double *u = gp_mesh3d_vertices(b->mesh);
    memcpy(b->u, u, 3 * b->nv * sizeof(double));
    if (b->elongation == 1.0 && b->flatness == 1.0) { /* the directions themselves, bit for bit */
        for (size_t i = 0; i < b->nv; i++) b->k[i] = b->kappa;
        return GP_OK;
    }
    double sy = b->elongation, sz = b->elongation * b->flatness;
    double *d = malloc(3 * b->nv * sizeof *d);
    if (!d) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < b->nv; i++) {
        double q[3] = {u[3 * i], u[3 * i + 1] * sy, u[3 * i + 2] * sz}, l = norm3(q);
        b->k[i] = b->kappa * l;
        for (int j = 0; j < 3; j++) d[3 * i + j] = q[j] / l;
    }
    gp_mesh3d *m = gp_mesh3d_create(d, b->nv, gp_mesh3d_triangles(b->mesh), b->nt, err);
    free(d);
    if (!m) return err ? err->code : GP_ERR_NOMEM;
    gp_mesh3d_destroy(b->mesh);
    b->mesh = m;
    return GP_OK;
}

static gp_status basis_fill(gp_grain3d_basis *b, gp_error *err)
{
    gp_status st = basis_kappa(b, err);
    if (st || (st = basis_stretch(b, err))) return st;
    const double *d = b->u;
    const uint32_t *t = gp_mesh3d_triangles(b->mesh);
    double row[GP_GRAIN3D_NCOEF(GP_GRAIN3D_DEGREE_MAX)];
    for (size_t i = 0; i < b->nv; i++) {
        gp_grain3d_harmonics(b->degree, d + 3 * i, row);
        for (size_t k = 0; k < b->ncoef; k++) b->Y[k * b->nv + i] = row[k];
    }
    b->ne = 0;
    for (size_t f = 0; f < b->nt; f++) {
        const uint32_t *v = t + 3 * f;
        b->rho2[f] = circumradius2(d + 3 * (size_t)v[0], d + 3 * (size_t)v[1], d + 3 * (size_t)v[2]);
        for (int k = 0; k < 3; k++) /* each edge once: from the triangle that has it as i -> j, i < j */
            if (v[k] < v[(k + 1) % 3]) {
                b->edges[2 * b->ne] = v[k];
                b->edges[2 * b->ne++ + 1] = v[(k + 1) % 3];
            }
    }
    return GP_OK;
}

gp_grain3d_basis *gp_grain3d_basis_create(unsigned level, unsigned degree, gp_error *err)
{
    return gp_grain3d_basis_create_ex(level, degree, 1.0, 1.0, err);
}

gp_grain3d_basis *gp_grain3d_basis_create_ex(unsigned level, unsigned degree, double elongation,
                                             double flatness, gp_error *err)
{
    if (degree > GP_GRAIN3D_DEGREE_MAX) {
        gp_error_set(err, GP_ERR_INVALID, "grain3d: degree %u > %d", degree, GP_GRAIN3D_DEGREE_MAX);
        return NULL;
    }
    if (!(elongation > 0 && elongation <= 1) || !(flatness > 0 && flatness <= 1)) {
        gp_error_set(err, GP_ERR_INVALID, "grain3d: elongation %g and flatness %g must be in (0, 1]", elongation, flatness);
        return NULL;
    }
    gp_mesh3d *m = gp_mesh3d_icosphere(level, err);
    if (!m) return NULL;
    size_t nv = gp_mesh3d_vertex_count(m), nt = gp_mesh3d_triangle_count(m), nc = GP_GRAIN3D_NCOEF(degree);
    if (nc * nv > TABLE_MAX) {
        gp_mesh3d_destroy(m);
        gp_error_set(err, GP_ERR_INVALID, "grain3d: a table of %zu x %zu harmonics is too large (level %u, degree %u)",
                     nv, nc, level, degree);
        return NULL;
    }
    gp_grain3d_basis *b = calloc(1, sizeof *b);
    if (b) {
        *b = (gp_grain3d_basis){level, degree, nv, nt, 0, nc, elongation, flatness, 1.0, m, NULL, NULL, NULL, NULL, NULL};
        b->u = malloc(3 * nv * sizeof(double));
        b->k = malloc(nv * sizeof(double));
        b->Y = malloc(nc * nv * sizeof(double));
        b->rho2 = malloc(nt * sizeof(double));
        b->edges = malloc(3 * nt * sizeof(uint32_t));
    }
    if (!b || !b->u || !b->k || !b->Y || !b->rho2 || !b->edges) {
        if (b) gp_grain3d_basis_destroy(b);
        else gp_mesh3d_destroy(m);
        gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        return NULL;
    }
    if (basis_fill(b, err) != GP_OK) {
        gp_grain3d_basis_destroy(b);
        return NULL;
    }
    return b;
}

unsigned gp_grain3d_basis_level(const gp_grain3d_basis *b) { return b ? b->level : 0; }
double gp_grain3d_basis_kappa(const gp_grain3d_basis *b) { return b ? b->kappa : 0; }
unsigned gp_grain3d_basis_degree(const gp_grain3d_basis *b) { return b ? b->degree : 0; }
double gp_grain3d_basis_elongation(const gp_grain3d_basis *b) { return b ? b->elongation : 0; }
double gp_grain3d_basis_flatness(const gp_grain3d_basis *b) { return b ? b->flatness : 0; }
const gp_mesh3d *gp_grain3d_basis_mesh(const gp_grain3d_basis *b) { return b ? b->mesh : NULL; }
size_t gp_grain3d_basis_count(const gp_grain3d_basis *b) { return b ? b->nv : 0; }

/* ------------------------------------------------------------------------------------------ */
/* random draws                                                                                */

typedef struct gauss {
    gp_fourier_u01_fn u01;
    void *state;
    double spare;
    int has, bad;
} gauss;

static double gauss_next(gauss *g)
{
    if (g->has) {
        g->has = 0;
        return g->spare;
    }
    double a = g->u01(g->state), c = g->u01(g->state);
    if (!(a >= 0 && a <= 1) || !(c >= 0 && c <= 1)) {
        g->bad = 1;
        a = c = 0.5;
    }
    double q = fmax(1.0 - a, 0x1p-53), r = sqrt(-2.0 * log(q)), t = 2.0 * G3_PI * c;
    g->spare = r * sin(t);
    g->has = 1;
    return r * cos(t);
}

static gp_status law_check(const gp_grain3d_law *law, gp_fourier_u01_fn u01, gp_error *err)
{
    if (!law || !u01) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no law or no u01 stream");
    gp_status st = gp_fourier_spectrum_check(law->D, law->nmodes, err);
    if (st) return st;
    for (size_t n = 1; law->cov && n < law->nmodes; n++)
        if (!isfinite(law->cov[n]) || law->cov[n] < 0)
            return gp_error_set(err, GP_ERR_INVALID, "grain3d: cov_%zu = %g must be finite and >= 0", n, law->cov[n]);
    if (law->degree > GP_GRAIN3D_DEGREE_MAX)
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: degree %u > %d", law->degree, GP_GRAIN3D_DEGREE_MAX);
    if (!(law->elongation > 0 && law->elongation <= 1) || !(law->flatness > 0 && law->flatness <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: elongation %g and flatness %g must be in (0, 1]",
                            law->elongation, law->flatness);
    return GP_OK;
}

gp_status gp_grain3d_draw(const gp_grain3d_law *law, gp_fourier_u01_fn u01, void *state,
                          gp_grain3d_shape *out, gp_error *err)
{
    gp_status st = law_check(law, u01, err);
    if (st) return st;
    if (!out) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no output shape");
    unsigned N = law->nmodes - 1 < law->degree ? (unsigned)(law->nmodes - 1) : law->degree;
    gauss g = {u01, state, 0, 0, 0};
    double norm[GP_GRAIN3D_DEGREE_MAX + 1] = {0};
    memset(out, 0, sizeof *out);
    out->degree = N;
    out->elongation = law->elongation;
    out->flatness = law->flatness;
    for (unsigned n = 1; n <= N; n++) { /* directions: c_n,-n .. c_n,n, stored in place */
        double s = 0;
        for (size_t k = (size_t)n * n; k <= (size_t)n * n + 2 * n; k++) {
            out->c[k] = gauss_next(&g);
            s += out->c[k] * out->c[k];
        }
        norm[n] = sqrt(s);
    }
    for (unsigned n = 1; n <= N; n++) {
        double Dn = law->D[n];
        if (law->cov) { /* the lognormal of mean D_n and COV cov_n */
            double s2 = log1p(law->cov[n] * law->cov[n]);
            Dn *= exp(sqrt(s2) * gauss_next(&g) - 0.5 * s2);
        }
        double amp = Dn * sqrt(2.0 * G3_PI);
        for (size_t k = (size_t)n * n; k <= (size_t)n * n + 2 * n; k++)
            out->c[k] = norm[n] > 0 ? out->c[k] * (amp / norm[n]) : (k == GP_GRAIN3D_INDEX(n, 0) ? amp : 0.0);
    }
    if (g.bad) return gp_error_set(err, GP_ERR_INVALID, "grain3d: a u01 draw is not in [0, 1]");
    return GP_OK;
}

void gp_grain3d_power(const gp_grain3d_shape *s, double *power)
{
    for (unsigned n = 0; n <= s->degree && n <= GP_GRAIN3D_DEGREE_MAX; n++) {
        double p = 0;
        for (size_t k = (size_t)n * n; k <= (size_t)n * n + 2 * n; k++) p += s->c[k] * s->c[k];
        power[n] = p;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* the field and the stretch                                                                   */

static unsigned shape_degree(const gp_grain3d_shape *s)
{
    return s->degree < GP_GRAIN3D_DEGREE_MAX ? s->degree : GP_GRAIN3D_DEGREE_MAX;
}

double gp_grain3d_field(const gp_grain3d_shape *s, const double u[3])
{
    unsigned N = shape_degree(s);
    double Y[GP_GRAIN3D_NCOEF(GP_GRAIN3D_DEGREE_MAX)], r = 1.0;
    gp_grain3d_harmonics(N, u, Y);
    for (size_t k = 1; k < GP_GRAIN3D_NCOEF(N); k++) /* the table's order (table_product) */
        if (s->c[k] != 0.0) r += s->c[k] * Y[k];
    return r;
}

double gp_grain3d_radius(const gp_grain3d_shape *s, const double d[3])
{
    double q[3] = {d[0], d[1] / s->elongation, d[2] / (s->elongation * s->flatness)};
    return gp_grain3d_field(s, q) * norm3(d) / norm3(q);
}

/* F_i = 1 + f(u_i) at every basis vertex: row by row of the table (vectorisable, and in the
 * order gp_grain3d_field sums). */
static void table_product(const gp_grain3d_basis *b, const gp_grain3d_shape *s, double *F)
{
    size_t nv = b->nv, nc = GP_GRAIN3D_NCOEF(shape_degree(s));
    for (size_t i = 0; i < nv; i++) F[i] = 1.0;
    for (size_t k = 1; k < nc; k++) {
        double ck = s->c[k];
        if (ck == 0.0) continue;
        const double *Yk = b->Y + k * nv;
        for (size_t i = 0; i < nv; i++) F[i] += ck * Yk[i];
    }
}

static gp_status shape_check(const gp_grain3d_basis *b, const gp_grain3d_shape *s, gp_error *err)
{
    if (!b || !s) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no basis or no shape");
    if (s->degree > b->degree)
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: the shape's degree %u is above the basis' %u", s->degree, b->degree);
    for (size_t k = 0; k < GP_GRAIN3D_NCOEF(s->degree); k++)
        if (!isfinite(s->c[k])) return gp_error_set(err, GP_ERR_INVALID, "grain3d: coefficient %zu is not finite", k);
    if (!(s->elongation > 0 && s->elongation <= 1) || !(s->flatness > 0 && s->flatness <= 1))
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: elongation %g and flatness %g must be in (0, 1]",
                            s->elongation, s->flatness);
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the star-shape check                                                                        */

typedef struct star_tri {
    double u[3][3]; /* unit vertices, counter-clockwise */
    double f[3];    /* 1 + f there */
    int depth;
} star_tri;

static double star_threshold(double H, double rho2)
{
    return 0.5 * H * rho2 * (1.0 + STAR_REL) + STAR_ABS;
}

static gp_status not_star_at(const double *u, double f, gp_error *err)
{
    return gp_error_set(err, GP_ERR_NOT_STAR, "grain3d: r = %.3g r0 <= 0 along (%.4f, %.4f, %.4f): not star-shaped",
                        f, u[0], u[1], u[2]);
}

static void midpoint(const double *a, const double *b, double *m)
{
    double s[3] = {a[0] + b[0], a[1] + b[1], a[2] + b[2]}, l = norm3(s);
    for (int k = 0; k < 3; k++) m[k] = s[k] / l;
}

/* Subdivides T's suspect descendants until each is cleared (see the header). */
static gp_status refine(const gp_grain3d_shape *s, double H, const star_tri *T, long *budget,
                        gp_error *err)
{
    static const int child[4][3] = {{0, 3, 5}, {1, 4, 3}, {2, 5, 4}, {3, 4, 5}};
    star_tri stack[4 * GP_GRAIN3D_STAR_DEPTH + 4];
    int top = 0;
    stack[top++] = *T;
    while (top) {
        star_tri t = stack[--top];
        if (t.depth >= GP_GRAIN3D_STAR_DEPTH || *budget < 3)
            return gp_error_set(err, GP_ERR_NOT_STAR,
                                "grain3d: r comes within %.2g r0 of the centre near (%.4f, %.4f, %.4f): refused (conservative)",
                                fmin(t.f[0], fmin(t.f[1], t.f[2])), t.u[0][0], t.u[0][1], t.u[0][2]);
        double p[6][3], f[6];
        for (int k = 0; k < 3; k++) {
            memcpy(p[k], t.u[k], sizeof p[k]);
            f[k] = t.f[k];
            midpoint(t.u[k], t.u[(k + 1) % 3], p[3 + k]); /* 3: ab, 4: bc, 5: ca */
            f[3 + k] = gp_grain3d_field(s, p[3 + k]);
            if (!(f[3 + k] > 0)) return not_star_at(p[3 + k], f[3 + k], err);
        }
        *budget -= 3;
        for (int c = 0; c < 4; c++) {
            star_tri ch = {.depth = t.depth + 1};
            for (int k = 0; k < 3; k++) {
                memcpy(ch.u[k], p[child[c][k]], sizeof ch.u[k]);
                ch.f[k] = f[child[c][k]];
            }
            double lo = fmin(ch.f[0], fmin(ch.f[1], ch.f[2]));
            if (lo <= star_threshold(H, circumradius2(ch.u[0], ch.u[1], ch.u[2]))) stack[top++] = ch;
        }
    }
    return GP_OK;
}

/* The vertex test and the triangle-by-triangle proof on field F (at the u_i). */
static gp_status star_mesh(const gp_grain3d_basis *b, const gp_grain3d_shape *s, const double *F,
                           double H, gp_error *err)
{
    const double *d = b->u;
    const uint32_t *t = gp_mesh3d_triangles(b->mesh);
    for (size_t i = 0; i < b->nv; i++)
        if (!(F[i] > 0)) return not_star_at(d + 3 * i, F[i], err);
    long budget = GP_GRAIN3D_STAR_EVALS;
    for (size_t f = 0; f < b->nt; f++) {
        const uint32_t *v = t + 3 * f;
        double lo = fmin(F[v[0]], fmin(F[v[1]], F[v[2]]));
        if (lo > star_threshold(H, b->rho2[f])) continue;
        star_tri T = {.depth = 0};
        for (int k = 0; k < 3; k++) {
            memcpy(T.u[k], d + 3 * (size_t)v[k], sizeof T.u[k]);
            T.f[k] = F[v[k]];
        }
        gp_status st = refine(s, H, &T, &budget, err);
        if (st) return st;
    }
    return GP_OK;
}

gp_status gp_grain3d_star_check(const gp_grain3d_basis *b, const gp_grain3d_shape *s,
                                const double *field, gp_error *err)
{
    gp_status st = shape_check(b, s, err);
    if (st) return st;
    double B = 0, H = 0;
    for (unsigned n = 1; n <= s->degree; n++) {
        double p = 0;
        for (size_t k = (size_t)n * n; k <= (size_t)n * n + 2 * n; k++) p += s->c[k] * s->c[k];
        double a = sqrt(p * (2.0 * n + 1.0) / (4.0 * G3_PI));
        B += a;
        H += (double)n * n * a;
    }
    if (B < 1.0) return GP_OK; /* |f| <= B < 1 everywhere */
    double *own = NULL;
    if (!field) {
        if (!(own = malloc(b->nv * sizeof *own))) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
        table_product(b, s, own);
        field = own;
    }
    st = star_mesh(b, s, field, H, err);
    free(own);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* radii                                                                                       */

gp_status gp_grain3d_radii(const gp_grain3d_basis *b, const gp_grain3d_shape *s, double *radii,
                           gp_error *err)
{
    gp_status st = shape_check(b, s, err);
    if (st) return st;
    if (!radii) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no radii array");
    table_product(b, s, radii);
    if ((st = gp_grain3d_star_check(b, s, radii, err))) return st;
    if (s->elongation == b->elongation && s->flatness == b->flatness) {
        for (size_t i = 0; i < b->nv; i++) radii[i] *= b->k[i];
    } else { /* another stretch than the table's: summed direction by direction */
        const double *d = gp_mesh3d_vertices(b->mesh);
        for (size_t i = 0; i < b->nv; i++) radii[i] = b->kappa * gp_grain3d_radius(s, d + 3 * i);
    }
    return GP_OK;
}

void gp_grain3d_vertices(const gp_grain3d_basis *b, const double *radii, double *xyz)
{
    const double *d = gp_mesh3d_vertices(b->mesh);
    for (size_t i = 0; i < 3 * b->nv; i++) xyz[i] = radii[i / 3] * d[i];
}

/* ------------------------------------------------------------------------------------------ */
/* descriptors                                                                                 */

static gp_status radii_check(const gp_grain3d_basis *b, const double *radii, gp_error *err)
{
    if (!b || !radii) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no basis or no radii");
    for (size_t i = 0; i < b->nv; i++)
        if (!(radii[i] > 0) || !isfinite(radii[i]))
            return gp_error_set(err, GP_ERR_INVALID, "grain3d: radius %zu = %g must be finite and > 0", i, radii[i]);
    return GP_OK;
}

gp_status gp_grain3d_describe(const gp_grain3d_basis *b, const double *radii,
                              gp_grain3d_descriptors *out, gp_error *err)
{
    gp_status st = radii_check(b, radii, err);
    if (st) return st;
    double *xyz = malloc(3 * b->nv * sizeof *xyz);
    if (!xyz) return gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    gp_grain3d_vertices(b, radii, xyz);
    st = gp_mesh3d_mass_properties(xyz, b->nv, gp_mesh3d_triangles(b->mesh), b->nt, &out->mass, err);
    if (!st) st = gp_mesh3d_principal_axes(xyz, b->nv, &out->mass, &out->axes, err);
    if (!st) st = gp_mesh3d_hull_volume(xyz, b->nv, &out->hull_volume, err);
    free(xyz);
    if (st) return st;
    const double *e = out->axes.extent;
    double V = out->mass.volume;
    out->elongation = e[1] / e[0];
    out->flatness = e[2] / e[1];
    out->sphericity = cbrt(G3_PI) * pow(6.0 * V, 2.0 / 3.0) / out->mass.area;
    out->convexity = V / out->hull_volume;
    return GP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* projections                                                                                 */

/* The crossing of ray j (direction cs[j]) with segment p -> q, p to q counter-clockwise about
 * the origin, for every ray in the segment's angular span [a0, a1] (in units of the rays'
 * spacing, a1 >= a0, widened by PROJ_ANGLE_EPS): r[j] is raised to it. A crossing is at most
 * the farther endpoint's distance (the segment lies in that disc), which also bounds the
 * widened rays that meet only the segment's line, near a nearly radial segment. */
static void edge_rays(const double *p, const double *q, double a0, double a1, size_t n,
                      const double *cs, double *r)
{
    double e[2] = {q[0] - p[0], q[1] - p[1]}, pe = p[0] * e[1] - p[1] * e[0];
    double tmax = fmax(hypot(p[0], p[1]), hypot(q[0], q[1]));
    long k0 = (long)ceil(a0 - PROJ_ANGLE_EPS), k1 = (long)floor(a1 + PROJ_ANGLE_EPS);
    for (long k = k0; k <= k1; k++) {
        size_t j = (size_t)(((k % (long)n) + (long)n) % (long)n);
        double den = cs[2 * j] * e[1] - cs[2 * j + 1] * e[0];
        if (den == 0.0) continue;
        double t = fmin(pe / den, tmax);
        if (t > r[j]) r[j] = t;
    }
}

static gp_status projection_args(const gp_grain3d_basis *b, const double *radii, const double *eu,
                                 const double *ev, size_t n, const gp_vec2 *contour, gp_error *err)
{
    gp_status st = radii_check(b, radii, err);
    if (st) return st;
    if (!eu || !ev || !contour || n < 8 || n > (1u << 24))
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: projection needs two axes and 8 .. 2^24 angles");
    double uu = eu[0] * eu[0] + eu[1] * eu[1] + eu[2] * eu[2], vv = ev[0] * ev[0] + ev[1] * ev[1] + ev[2] * ev[2];
    double uv = eu[0] * ev[0] + eu[1] * ev[1] + eu[2] * ev[2];
    if (!(fabs(uu - 1) < 1e-9 && fabs(vv - 1) < 1e-9 && fabs(uv) < 1e-9))
        return gp_error_set(err, GP_ERR_INVALID, "grain3d: the projection's axes must be orthonormal");
    return GP_OK;
}

/* The vertices projected on (eu, ev), P (2 each), and their angles in units of 2 pi / n. */
static void project_vertices(const gp_grain3d_basis *b, const double *radii, const double *eu,
                             const double *ev, size_t n, double *P, double *ang)
{
    const double *d = gp_mesh3d_vertices(b->mesh), unit = (double)n / (2.0 * G3_PI);
    for (size_t i = 0; i < b->nv; i++) {
        const double *u = d + 3 * i;
        P[2 * i] = radii[i] * (u[0] * eu[0] + u[1] * eu[1] + u[2] * eu[2]);
        P[2 * i + 1] = radii[i] * (u[0] * ev[0] + u[1] * ev[1] + u[2] * ev[2]);
        ang[i] = atan2(P[2 * i + 1], P[2 * i]) * unit;
    }
}

/* Every edge's crossings with the rays it spans (edges in line with the centre are skipped:
 * their endpoints' other edges cover them). */
static void outline(const gp_grain3d_basis *b, const double *P, const double *ang, size_t n,
                    const double *cs, double *r)
{
    for (size_t e = 0; e < b->ne; e++) {
        uint32_t i = b->edges[2 * e], k = b->edges[2 * e + 1];
        const double *p = P + 2 * (size_t)i, *q = P + 2 * (size_t)k;
        double cr = p[0] * q[1] - p[1] * q[0];
        if (fabs(cr) <= PROJ_COLLINEAR * hypot(p[0], p[1]) * hypot(q[0], q[1])) continue;
        if (cr < 0) { /* counter-clockwise from p to q */
            const double *t = p;
            p = q;
            q = t;
            uint32_t s = i;
            i = k;
            k = s;
        }
        double a0 = ang[i], a1 = ang[k];
        if (a1 < a0) /* across the angle -pi / pi, or rounding against the sign of cr: no span */
            a1 = a0 - a1 > 0.5 * (double)n ? a1 + (double)n : a0;
        edge_rays(p, q, a0, a1, n, cs, r);
    }
}

gp_status gp_grain3d_projection(const gp_grain3d_basis *b, const double *radii, const double eu[3],
                                const double ev[3], size_t n, gp_vec2 *contour, gp_error *err)
{
    gp_status st = projection_args(b, radii, eu, ev, n, contour, err);
    if (st) return st;
    double *P = malloc(2 * b->nv * sizeof *P), *ang = malloc(b->nv * sizeof *ang);
    double *cs = malloc(2 * n * sizeof *cs), *r = calloc(n, sizeof *r);
    if (!P || !ang || !cs || !r) st = gp_error_set(err, GP_ERR_NOMEM, "out of memory");
    for (size_t j = 0; !st && j < n; j++) {
        cs[2 * j] = cos(2.0 * G3_PI * (double)j / (double)n);
        cs[2 * j + 1] = sin(2.0 * G3_PI * (double)j / (double)n);
    }
    if (!st) {
        project_vertices(b, radii, eu, ev, n, P, ang);
        outline(b, P, ang, n, cs, r);
    }
    for (size_t j = 0; j < n && !st; j++) {
        if (!(r[j] > 0)) st = gp_error_set(err, GP_ERR_INTERNAL, "grain3d: projection ray %zu met no edge", j);
        contour[j] = (gp_vec2){r[j] * cs[2 * j], r[j] * cs[2 * j + 1]};
    }
    free(P);
    free(ang);
    free(cs);
    free(r);
    return st;
}

gp_status gp_grain3d_describe_projections(const gp_grain3d_basis *b, const double *radii,
                                          const gp_mesh3d_axes *axes, const gp_odec_params *odec,
                                          gp_shape_result out[3], gp_error *err)
{
    static const int plane[3][2] = {{1, 2}, {0, 2}, {0, 1}};
    if (!axes || !out) return gp_error_set(err, GP_ERR_INVALID, "grain3d: no axes or no output");
    gp_vec2 contour[GP_GRAIN3D_PROJ_ANGLES];
    for (int k = 0; k < 3; k++) {
        gp_status st = gp_grain3d_projection(b, radii, axes->axis[plane[k][0]], axes->axis[plane[k][1]],
                                             GP_GRAIN3D_PROJ_ANGLES, contour, err);
        if (!st) st = gp_shape_describe(contour, GP_GRAIN3D_PROJ_ANGLES, odec, &out[k], err);
        if (st) return st;
    }
    return GP_OK;
}
