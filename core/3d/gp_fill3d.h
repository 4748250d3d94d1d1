/* gp_fill3d.h -- place one 3D grain in one convex Voronoi cell at a target solid fraction
 * (the 3D form of Mollon & Zhao 2012, Sect. 4.1, Eq. 19; gp_fill.h is the 2D one).
 *
 * The grain is a point set P (its surface mesh's vertices, in its own frame, about its centre)
 * placed as x = c + s R p: a centre c, a scale s > 0 and a rotation R. The cell is convex (every
 * cell of a convex container is), the intersection of its face half-spaces n_f . x <= d_f, so the
 * mesh is inside iff every vertex is (its triangles are convex combinations of them), i.e. iff
 *
 *     n_f . c + s h_f(R) <= d_f   for every face f,   h_f(R) = max_i (R^T n_f) . p_i,
 *
 * h_f the grain's support along n_f. For a fixed R that is linear in (c, s): the largest scale
 * and its centre are a 4-variable LP (a dense primal simplex with free variables, Bland's rule;
 * a few dozen faces), solved exactly, no penalty to tune. The target scale is the one of
 * volume F_S V_cell: s_t = (F_S V_cell / V_grain)^(1/3), V_grain the grain's volume at s = 1.
 *
 * Rotation. R first maps the grain's principal axes onto the cell's, longest on longest (least
 * moment of inertia), shortest on shortest, so that a grain takes its cell's orientation as the
 * 2D grain takes its cell's minimum-caliper axis (or starts from the caller's R). When s_t is out of reach there, a hill climb
 * turns R by random small rotations (axis uniform on the sphere, angle up to `turn`, halved
 * after a run of failures) and keeps those that raise the largest scale, for `rotations` tries
 * or until s_t is reached.
 *
 * Placement. s = s_t when reachable (target_met), else the largest found; the centre is then the
 * one with the most clearance: the LP max t s.t. n_f . c + s h_f + t <= d_f (unit normals), so a
 * grain smaller than the largest sits in the middle of its cell, not against a face. The final
 * pose is checked vertex by vertex against every face (with the cell's relative tolerance
 * `margin` as clearance) and shrunk about c until it holds, so no vertex is ever outside.
 *
 * Numbers: coordinates are taken relative to the cell's interior point and divided by its size,
 * so the LP works on O(1) numbers whatever the container's units or offset.
 * Work: O(F V) a support evaluation (F faces, V points), 1 + rotations of them.
 * Threads: no state; one call per cell, any number at once. Ownership: nothing is kept.
 */
#ifndef GP_FILL3D_H
#define GP_FILL3D_H

#include <stddef.h>

#include "gp_error.h"

/* A convex cell: planes[4 f .. 4 f + 3] = (nx, ny, nz, d), n . x <= d inside (any |n| > 0);
 * interior a point strictly inside (its seed or centroid); its volume and its inertia tensor
 * (row-major, about any point: only its eigenvectors are used). */
typedef struct gp_fill3d_cell {
    const double *planes;
    size_t nplanes;
    double interior[3];
    double volume;
    double inertia[9];
} gp_fill3d_cell;

/* A grain at scale 1 in its own frame: points[3 i ..] the n surface vertices, volume the
 * volume they enclose, inertia its tensor (row-major, about its centroid or origin). The
 * origin must be strictly inside the grain's hull (its centre). */
typedef struct gp_fill3d_grain {
    const double *points;
    size_t n;
    double volume;
    double inertia[9];
} gp_fill3d_grain;

typedef struct gp_fill3d_params {
    double solid_fraction; /* F_S in (0, 1] */
    int rotations;         /* hill-climb tries when F_S is out of reach aligned (default 24) */
    double turn;           /* largest turn of a try, radians (default 0.35) */
    double margin;         /* clearance from every face, relative to the cell's size (1e-9) */
    const double *rotation; /* NULL: principal axes aligned; else R to start from (row-major,
                            * proper), e.g. a grain already shaped in its cell's frame */
} gp_fill3d_params;

void gp_fill3d_params_defaults(gp_fill3d_params *p);

typedef struct gp_fill3d_result {
    double R[9];      /* row-major: x = c + s R p */
    double centre[3];
    double scale;     /* s */
    double scale_max; /* the largest scale found for the final R */
    double fraction;  /* s^3 V_grain / V_cell */
    int target_met;   /* fraction = F_S (to rounding) */
    int tries;        /* support evaluations made */
} gp_fill3d_result;

/* Uniform [0, 1) draws for the rotation search (e.g. gp_rng_uniform with a gp_rng*). */
typedef double (*gp_fill3d_u01_fn)(void *state);

/* Places the grain in the cell. GP_ERR_INVALID for bad params (naming the field), a cell
 * without faces or volume, a grain without points or volume; GP_ERR_DEGENERATE when the
 * interior point is not strictly inside or the grain's origin is not inside its hull (a
 * support h_f <= 0). u01 may be NULL when params->rotations is 0. */
gp_status gp_fill3d_place(const gp_fill3d_cell *cell, const gp_fill3d_grain *grain,
                          const gp_fill3d_params *params, gp_fill3d_u01_fn u01, void *state,
                          gp_fill3d_result *out, gp_error *err);

/* The cell's principal frame: the columns of E are the unit eigenvectors of the symmetric
 * inertia I, least moment (longest axis) first, right-handed; 0 when I is not finite. */
int gp_fill3d_frame(const double I[9], double E[9]);

/* The LP itself, exposed for tests and other placements: maximises x[3] over x in R^4 subject
 * to a[4 k] x[0] + a[4 k + 1] x[1] + a[4 k + 2] x[2] + a[4 k + 3] x[3] <= b[k], k < m, given
 * that x = 0 is feasible (every b[k] >= 0). Returns 0 with x, 1 when unbounded, -1 when out of
 * memory or the pivot budget (m + 64 pivots) runs out. */
int gp_fill3d_lp(const double *a, const double *b, size_t m, double x[4]);

#endif /* GP_FILL3D_H */
