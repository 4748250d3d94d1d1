/* gp_grain3d.h -- 3D Fourier grains (Mollon & Zhao 2012 Sec. 7, 2014): star-shaped bodies whose
 * radius is a random spherical-harmonic field, sampled on a shared icosphere, and their 3D
 * and projected 2D shape descriptors.
 *
 * Field. A grain of mean radius r0 is, about its centre, the star-shaped body
 *
 *     r(u) = r0 (1 + f(u)),   f(u) = sum_{n=1..N} sum_{m=-n..n} c_nm Y_nm(u),   |u| = 1,
 *
 * with the real orthonormal spherical harmonics (integral of Y_nm Y_n'm' over the sphere =
 * delta), without the Condon-Shortley phase: for u = (sin t cos p, sin t sin p, cos t),
 * Y_n0 = P_n^0(cos t), Y_nm = sqrt(2) P_n^m(cos t) cos(m p) and Y_n,-m = sqrt(2) P_n^m(cos t)
 * sin(m p) (m > 0), P_n^m normalised as GSL_SF_LEGENDRE_SPHARM (gsl_sf_legendre_array). The
 * coefficients are stored at c[n^2 + n + m] (GP_GRAIN3D_INDEX), c[0] = 0: r0 is the mean of r
 * over the sphere (solid-angle mean). Degrees 1 .. GP_GRAIN3D_DEGREE_MAX = 30: GSL's
 * recurrences are accurate far beyond, but the 2,562 directions of a level-4 icosphere resolve
 * degrees up to about 40 (so higher degrees would alias), and the table below grows as
 * (N + 1)^2.
 *
 * Spectrum convention (what D_n means in 3D). The same amplitude list D_0 = 1, D_1, D_2, ...
 * as the 2D grains (gp_fourier.h: gp_fourier_spectrum() from D2, D3, D8, alpha, beta, or a
 * user list) sets the power of each degree: the degree-n part f_n has the mean square of the 2D
 * mode D_n cos(n theta - delta_n) over its circle,
 *
 *     (1 / 4 pi) integral f_n^2 = D_n^2 / 2,   i.e.   sum_m c_nm^2 = 4 pi D_n^2 / 2 = 2 pi D_n^2,
 *
 * and (c_n,-n .. c_n,n) is a uniformly random direction on the (2n+1)-sphere scaled to that
 * norm (isotropic: a rotated grain is as likely as the grain). The field's covariance is
 * E[f(u) f(v)] = sum_n (D_n^2 / 2) P_n(u . v): the Legendre polynomials that the kernels
 * cos(K alpha) of Mollon & Zhao's geodesic construction reduce to (shared/papers/NOTES.md),
 * with the 2D mode's variance in each degree.
 * What a section or projection sees: the restriction of f_n to a great circle is a
 * trigonometric polynomial of degree n with only the modes n, n - 2, n - 4, ...; averaged over
 * orientations the share of f_n's mean square at 2D mode k is
 * w_nk = (4 pi / (2n + 1)) (2 - delta_k0) P_n^k(0)^2 (gp_grain3d_section_weight; n = 2: 3/4
 * at mode 2, 1/4 at mode 0). So a planar section through the centre of a grain with spectrum
 * D does not have the 2D spectrum D: its mode-k amplitude has the mean square
 * E[D_k'^2] = sum_n w_nk D_n^2. To match a 2D spectrum measured on sections, correct the
 * weights first; likewise a projection's outline does not show D.
 *
 * Aspect ratios. elongation e = I / L and flatness f = S / I stretch the rough body affinely by
 * S = diag(1, e, e f) (x the long axis, z the short one; the volume changes by e^2 f, the
 * caller's scale sets the size). The stretch maps the mesh too: the field is summed at the
 * icosphere's directions u_i and the grain is stored as radii along d_i = S u_i / |S u_i|, the
 * radius there being r(u_i) |S u_i|. So a stretched sphere's mesh is the affine image of the
 * sphere's, with its vertices denser at the sharper ends, and has the sphere's relative error
 * in volume, centroid and inertia (a radial resampling on the unstretched directions would give
 * the ends fewer vertices: 3.7e-3 of an ellipsoid (1, 0.5, 0.3)'s volume missing at level 4).
 *
 * The mesh's volume. Vertices on the smooth surface make an inscribed mesh: each flat triangle
 * lies inside the body, and a level-4 sphere misses 2.2e-3 of its volume (3.6e-3 of its inertia;
 * the deficit falls 4x a level). The mesh is the grain (its mass, inertia, filling, exports), so
 * its vertices are placed at kappa_L times the smooth radius, kappa_L = (4 pi / 3 / V_L)^(1/3)
 * with V_L the unit icosphere's volume (level 4: 1 + 7.2e-4): the facets then cross the
 * surface, halving the largest gap to it, and the mesh of a sphere or an ellipsoid has its
 * volume to rounding and its inertia to 2e-7 at level 4 (16x less a level); a rough body's
 * volume error falls from 2.9e-3 to 7.2e-4 (r = 1 + 0.6 Y_20, level 4; 4x a level).
 *
 * Random draws (gp_grain3d_draw). Standard normal variates come in pairs from two u01 draws
 * (a, b) by Box-Muller: sqrt(-2 ln(1 - a)) cos(2 pi b) and sqrt(-2 ln(1 - a)) sin(2 pi b)
 * (1 - a floored at 2^-53). For N' = min(nmodes - 1, degree) degrees: first the (2n + 1)
 * direction variates of n = 1 .. N' (m = -n .. n), then, with a spread, one variate z_n per
 * degree n = 1 .. N'; exactly 2 ceil(K / 2) u01 draws for K variates, so a grain is a function
 * of its stream. Spread (the 2D gp_grainshape law): D_n becomes D_n exp(s_n z_n - s_n^2 / 2),
 * s_n^2 = ln(1 + cov_n^2), the lognormal of mean D_n and coefficient of variation cov_n.
 *
 * Star shape. A grain is accepted only if r > 0 on the whole sphere, not only at the vertices.
 * With a_n = |c_n| sqrt((2n + 1) / 4 pi) (|f_n| <= a_n everywhere, by Cauchy-Schwarz and the
 * addition theorem sum_m Y_nm^2 = (2n + 1) / 4 pi): if sum a_n < 1, r > 0 everywhere. Else the
 * field is checked on the basis' vertices (any value <= 0: refused), then triangle by
 * triangle: if the minimum of 1 + f were <= 0 at u*, the triangle T containing u* has a vertex
 * within its spherical circumradius rho_T of u*, where 1 + f <= H rho_T^2 / 2, H = sum n^2 a_n
 * (along the great circle from u*, a critical point, f is a trigonometric polynomial of degree
 * N whose second derivative Bernstein's inequality bounds by H). Triangles with no such vertex
 * are cleared; the others are subdivided (midpoints evaluated directly) down to
 * GP_GRAIN3D_STAR_DEPTH levels below the basis, within GP_GRAIN3D_STAR_EVALS evaluations. A
 * point with 1 + f <= 0 refuses the grain (GP_ERR_NOT_STAR); so does a triangle still
 * undecided at the last level or the budget's end. That is conservative only for grains that
 * nearly touch their centre: in the worst case, a zonal degree-2 field whose minimum lies along
 * a whole great circle, min r = 1e-4 r0 is accepted (in 6 ms) and 1e-5 r0 refused. The
 * stretch does not change the sign of r, so the check is on the field itself (on the basis'
 * directions u_i, below).
 *
 * Basis (gp_grain3d_basis). The icosphere of a level (gp_mesh3d.h) and the table of Y_nm for
 * degrees <= N at its directions u_i (stored degree by degree, (N + 1)^2 rows of nv values:
 * 5.2 MB at level 4, N = 15; 19.7 MB at N = 30), with the triangles' circumradii and the mesh's
 * edges: built once, then read only (any number of threads may share it). A basis is made for
 * one stretch (e, f) (1, 1 by default): its mesh (gp_grain3d_basis_mesh) has the stretched
 * directions d_i and the icosphere's triangles, and it keeps k_i = kappa_L |S u_i|, so the
 * radii of a grain with that stretch are one matrix-vector product. A grain with another
 * stretch than its basis' has its radii along the basis' d_i summed direction by direction
 * (gp_grain3d_radius; ten times slower, and the mesh not affine to the sphere's).
 *
 * Descriptors (gp_grain3d_describe), on the mesh of the grain (vertex i = radii[i] d_i; all of
 * them are scale and rotation invariant): volume, centroid, inertia, area (gp_mesh3d), principal
 * axes and extents L >= I >= S of the vertices along them (gp_mesh3d_principal_axes), the
 * convex hull's volume, and elongation I / L, flatness S / I, sphericity (Wadell)
 * pi^(1/3) (6 V)^(2/3) / A, convexity V / V_hull.
 * Projections (gp_grain3d_describe_projections): the body projected along each principal axis
 * onto the plane of the other two. The projection of a body star-shaped about c is star-shaped
 * about c's projection, and its outline along a ray from there is the farthest crossing of the
 * ray with the projected triangles, i.e. with the projected mesh edges: each edge is binned by
 * the angles it spans, so the outline at n angles costs O(edges + n). The outline at
 * GP_GRAIN3D_PROJ_ANGLES = 128 angles theta_j = 2 pi j / n (counter-clockwise from the plane's
 * first axis) goes to gp_shape_describe (the four 2D descriptors, gp_shape.h, with the given
 * ODEC parameters; its regularity is that of the 128-gon).
 *
 * Thread safety: a basis is immutable after creation and may be shared; every other function
 * is pure (its scratch on the stack or malloc'ed per call). GSL is called only with arguments in
 * its domain, so its error handler is never invoked. No printing, no global state.
 */
#ifndef GP_GRAIN3D_H
#define GP_GRAIN3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_fourier.h" /* gp_fourier_u01_fn */
#include "gp_mesh3d.h"
#include "gp_shape.h"

#define GP_GRAIN3D_DEGREE_MAX 30
#define GP_GRAIN3D_NCOEF(n) (((size_t)(n) + 1) * ((size_t)(n) + 1))
#define GP_GRAIN3D_INDEX(n, m) ((size_t)(n) * (n) + (n) + (m))
#define GP_GRAIN3D_LEVEL_DEFAULT 4
#define GP_GRAIN3D_STAR_DEPTH 10
#define GP_GRAIN3D_STAR_EVALS 20000
#define GP_GRAIN3D_PROJ_ANGLES 128

typedef struct gp_grain3d_basis gp_grain3d_basis;

/* One grain's shape, before scale and rotation. */
typedef struct gp_grain3d_shape {
    unsigned degree;   /* N: the harmonics of degrees 1 .. N */
    double elongation; /* e = I / L of the stretch, in (0, 1]; 1: none */
    double flatness;   /* f = S / I of the stretch, in (0, 1]; 1: none */
    double c[GP_GRAIN3D_NCOEF(GP_GRAIN3D_DEGREE_MAX)]; /* c[n^2 + n + m], c[0] = 0; the rest unused */
} gp_grain3d_shape;

/* The law grains are drawn from. */
typedef struct gp_grain3d_law {
    const double *D;     /* D_0 .. D_{nmodes-1}, D_0 = 1, the others finite >= 0 */
    const double *cov;   /* NULL, or cov[n] >= 0 for each mode (spread; cov[0] unused) */
    size_t nmodes;
    unsigned degree;     /* N <= GP_GRAIN3D_DEGREE_MAX: modes above it are not drawn */
    double elongation;   /* (0, 1]; 1: no stretch */
    double flatness;     /* (0, 1] */
} gp_grain3d_law;

typedef struct gp_grain3d_descriptors {
    gp_mesh3d_mass mass;  /* volume, centroid, inertia about it, area */
    gp_mesh3d_axes axes;  /* principal axes (long, intermediate, short) and extents L, I, S */
    double hull_volume;
    double elongation;    /* I / L */
    double flatness;      /* S / I */
    double sphericity;    /* pi^(1/3) (6 V)^(2/3) / A: 1 for a sphere */
    double convexity;     /* V / V_hull */
} gp_grain3d_descriptors;

/* The basis of an icosphere level (<= GP_MESH3D_ICOSPHERE_LEVEL_MAX) for degrees <= degree
 * (<= GP_GRAIN3D_DEGREE_MAX), without a stretch. NULL on error (GP_ERR_INVALID, for a table
 * beyond 2^27 values too; GP_ERR_NOMEM). */
gp_grain3d_basis *gp_grain3d_basis_create(unsigned level, unsigned degree, gp_error *err);
/* The same for grains of elongation e and flatness f (in (0, 1]). */
gp_grain3d_basis *gp_grain3d_basis_create_ex(unsigned level, unsigned degree, double elongation,
                                             double flatness, gp_error *err);
void gp_grain3d_basis_destroy(gp_grain3d_basis *b); /* NULL is fine */
unsigned gp_grain3d_basis_level(const gp_grain3d_basis *b);
unsigned gp_grain3d_basis_degree(const gp_grain3d_basis *b);
double gp_grain3d_basis_elongation(const gp_grain3d_basis *b);
double gp_grain3d_basis_flatness(const gp_grain3d_basis *b);
/* The grains' shared directions d_i (its vertices: the icosphere's, stretched as the basis' grains
 * are) and the icosphere's triangles. */
const gp_mesh3d *gp_grain3d_basis_mesh(const gp_grain3d_basis *b);
/* kappa_L of the level (see "The mesh's volume"). */
double gp_grain3d_basis_kappa(const gp_grain3d_basis *b);
size_t gp_grain3d_basis_count(const gp_grain3d_basis *b); /* its vertices */

/* The real harmonics Y_nm(u) of degrees 0 .. degree (<= GP_GRAIN3D_DEGREE_MAX) at the direction
 * of u (any non-zero vector) into Y[GP_GRAIN3D_INDEX(n, m)] ((degree + 1)^2 values). */
void gp_grain3d_harmonics(unsigned degree, const double u[3], double *Y);

/* w_nk: the expected share of a degree-n field's mean square that a great circle shows at 2D
 * mode k (see "Spectrum convention"); 0 unless k <= n and n - k is even. Sum over k is 1. */
double gp_grain3d_section_weight(unsigned n, unsigned k);

/* Draws a grain from law with the u01 stream (see "Random draws"): out->degree = N'. Its
 * star shape is not checked here (gp_grain3d_radii does). GP_ERR_INVALID for a bad law or a
 * draw outside [0, 1]. */
gp_status gp_grain3d_draw(const gp_grain3d_law *law, gp_fourier_u01_fn u01, void *state,
                          gp_grain3d_shape *out, gp_error *err);

/* power[n] = sum_m c_nm^2 for n = 0 .. s->degree (2 pi D_n^2 for a drawn grain without spread). */
void gp_grain3d_power(const gp_grain3d_shape *s, double *power);

/* 1 + f(u): the unstretched radius over r0 along the direction of u (non-zero). */
double gp_grain3d_field(const gp_grain3d_shape *s, const double u[3]);
/* r_s(d) / r0: the stretched grain's radius along the direction of d (non-zero). */
double gp_grain3d_radius(const gp_grain3d_shape *s, const double d[3]);

/* The star-shape test above. field: 1 + f at the basis' directions u_i (as gp_grain3d_radii
 * computes it first), or NULL to compute it. GP_OK, or GP_ERR_NOT_STAR saying where; GP_ERR_INVALID for
 * s->degree above the basis' or non-finite coefficients; GP_ERR_NOMEM. */
gp_status gp_grain3d_star_check(const gp_grain3d_basis *b, const gp_grain3d_shape *s,
                                const double *field, gp_error *err);

/* The grain's mesh radii over r0 along the basis' directions d_i (gp_grain3d_basis_count
 * values; kappa_L r_s(d_i) / r0, see "The mesh's volume"): vertex i = center + scale R radii[i] d_i
 * with scale = r0. Star shape checked as
 * above (GP_ERR_NOT_STAR); elongation and flatness in (0, 1] (GP_ERR_INVALID); fast when they
 * are the basis' (see "Basis"). On error radii holds no grain. */
gp_status gp_grain3d_radii(const gp_grain3d_basis *b, const gp_grain3d_shape *s, double *radii,
                           gp_error *err);

/* xyz[3 i + k] = radii[i] d_i[k]: the grain's mesh vertices about its centre (the basis'
 * triangles). */
void gp_grain3d_vertices(const gp_grain3d_basis *b, const double *radii, double *xyz);

/* The 3D descriptors of the grain with these radii (see "Descriptors"). GP_ERR_INVALID for
 * radii not finite and > 0; GP_ERR_NOMEM. */
gp_status gp_grain3d_describe(const gp_grain3d_basis *b, const double *radii,
                              gp_grain3d_descriptors *out, gp_error *err);

/* The outline of the grain projected onto the plane spanned by the orthonormal eu, ev,
 * seen from the centre's projection: contour[j] = r_j (cos theta_j, sin theta_j) in (eu, ev)
 * coordinates, theta_j = 2 pi j / n, n >= 8 (see "Projections"). GP_ERR_INVALID for bad
 * arguments, GP_ERR_INTERNAL if some ray found no edge. */
gp_status gp_grain3d_projection(const gp_grain3d_basis *b, const double *radii, const double eu[3],
                                const double ev[3], size_t n, gp_vec2 *contour, gp_error *err);

/* The four 2D descriptors of the projections along each principal axis: out[k] along
 * axes->axis[k] (0 long, 1 intermediate, 2 short) onto the plane of the other two, in their
 * order (so out[2]'s 2D elongation is about I / L, out[1]'s S / L, out[0]'s S / I), each at
 * GP_GRAIN3D_PROJ_ANGLES angles. odec: NULL for gp_odec_params_defaults. */
gp_status gp_grain3d_describe_projections(const gp_grain3d_basis *b, const double *radii,
                                          const gp_mesh3d_axes *axes, const gp_odec_params *odec,
                                          gp_shape_result out[3], gp_error *err);

#endif /* GP_GRAIN3D_H */
