/* gp_dem3d.h -- a small sphere DEM for building specimens (Dang & Meguid 2010, Eqs 1-3, 7, 10).
 *
 * Models only what a packing needs:
 *   - normal force f_n = k_n * delta, delta = R_i + R_j - |O_i O_j| (full overlap),
 *     k_n = 2 E R_i R_j / (R_i + R_j) (YADE's FrictPhys; E R for equal spheres);
 *   - incremental shear spring dF_s = -k_s du_t (Eq. 2), k_s = ks_kn * k_n, kept tangent to the
 *     contact as it rotates, truncated at tan(phi) f_n (Eq. 3); spheres rotate (the shear force
 *     needs the contact-point velocity, omega x r) but carry no orientation;
 *   - six rigid, frictionless box walls (Table 1: box friction 0). A wall acts as the mirror
 *     image of the sphere: f = E R * 2 (R - d), d = distance from the centre to the wall. This is
 *     exactly the force the sphere gets from its flipped copy (Eq. 13), so flipping keeps the
 *     wall forces; any wall may be a servo wall (Eq. 10);
 *   - gravity and local (non-viscous, Cundall) damping of forces and moments;
 *   - density scaling for quasi-static runs (YADE's NewtonIntegrator.densityScaling idea): the
 *     inertia of a sphere smaller than scaled_radius is raised to that of a sphere whose critical
 *     time step is the one of scaled_radius. Gravity uses the true mass, so the static state
 *     (what a specimen is) does not change; only how fast it is reached. A sphere with no
 *     surface within 0.05 x the smallest radius flies with its true mass and no damping
 *     (free flight: fines fall at g, not at g scaled down; see gp_dem3d.c);
 *   - time step dt = dt_safety * min_i sqrt(m_i / (2 E R_i)) (m_i the inertial mass: density
 *     scaled; with params.dt_damping_exp e divided by (1 + c)^e, c the damping in force, so
 *     that a phase with less damping steps longer, below), checked after every
 *     step against a proven bound on the fastest vibration of the contacts of that step,
 *     shear and rotation included (below); dt is cut when it fails;
 *   - contact detection: a Verlet list of candidate pairs i < j (a half list: each pair once),
 *     those with a gap below skin + the free-flight gap, sorted by (i, j); rebuilt only when
 *     some sphere has moved (or grown) more than skin / 2 since the last rebuild, from
 *     linked-cell grids, one per size level, in which each pair is looked at once (within a
 *     level from the first of its two cells in a fixed forward order, across levels from the
 *     smaller sphere). Shear springs persist across rebuilds by (i, j). Results do not depend
 *     on the skin, bit for bit (a sphere sums its pairs in (i, j) order, and a pair enters the
 *     list before it can come within the free-flight gap);
 *   - a step: the pair kernel, then the spheres. The kernel sifts the candidates (which
 *     touch; a pair that does not gets its f_n mark and loses its spring) and computes the
 *     touching ones, four pairs to a vector, branch-free. One thread then goes through the
 *     spheres in order, adding each contact's force to both spheres' sums in pair order and
 *     moving a sphere (walls, damping, leapfrog) as soon as its sums are complete; with
 *     threads, the kernel runs on ranges of pairs and each block of spheres gathers its own
 *     contacts in pair order, then moves. Both sum a sphere's pairs in (i, j) order and
 *     every reduction runs over fixed blocks of spheres, so results are bit for bit the same
 *     for any thread count, and for any vector width (each lane does the scalar operations
 *     in the scalar order; no FMA). Layout: the pair list is a structure of arrays (i, j,
 *     f_n, and one array per component of the spring, the force on i and n x f_s).
 * Units SI. Walls 0..5: x-, x+, y-, y+, z-, z+.
 *
 * Stability of the time step. Linearised about a state, the spheres' translations u_i and
 * rotations theta_i obey M q'' = -K q, M = diag(m_i I, I_i I) (the integrator's masses:
 * m_i, I_i = 0.4 m_i R_i^2 density-scaled, R_i the full radius), K = sum over contacts of
 * PSD terms: a pair (n from i to j) adds k_n (n.(u_i - u_j))^2 + k_s |P D|^2 to 2 x energy,
 * D = u_i - u_j + r_i theta_i x n + r_j theta_j x n the contact-point displacement, P = I - n n^T
 * (the shear spring is incremental: after a step it holds -k_s P D of the step's motion); a
 * wall adds 2 E R_i (e.u_i)^2. Left out, and why no harm: the geometric stiffness of the normal
 * force (-f_n / |O_i O_j| P on the relative translation: negative semi-definite, it can only
 * lower omega_max, Weyl), the turn of the spring with the contact (order |f_s| / |O_i O_j| <=
 * tan(phi) k_n delta / |O_i O_j|: below 1e-3 k_n at a packing's overlaps), Coulomb slip (a
 * projection onto the friction cone: never stiffer).
 * The bound: in mass-scaled coordinates a contact's block on sphere i has the eigenvalues
 * k_n / m_i (normal) and k_s (1 / m_i + r_i^2 / I_i) = 3.5 k_s / m_i (twice: a tangential slide
 * of the contact point, shared by u and theta), so its norm is lam_ci = beta k_n / m_i, beta =
 * max(1, 3.5 k_s / k_n) (1.75 for k_s = k_n / 2: shear with rotation is sqrt(1.75) = 1.32 times
 * faster than the normal mode); the pair's off-diagonal block has norm sqrt(lam_ci lam_cj)
 * (exactly: normal and shear parts act on orthogonal subspaces). Block Gershgorin with unit
 * weights: omega_max^2 = lam_max(M^-1/2 K M^-1/2) <= max_i [sum_c beta k_n (1/m_i +
 * 1/sqrt(m_i m_j)) + 2 E R_i n_w / m_i], n_w the most walls touched on one axis (the walls'
 * block is diagonal). k_n is taken at the full radii (never smaller than at the current ones).
 * On packings of this DEM the bound is 1.5-1.6 x the true omega_max (test_dem3d checks it
 * against the eigenvalues; docs/design/dem3d.md), close enough that a tighter, direction-aware
 * bound would not pay.
 * The integrator: leapfrog (v += a dt, then x += v dt; the spring sees the motion of the step)
 * is stable for omega dt < 2. Local damping multiplies a force component by 1 + c where it
 * brakes (f v < 0); in leapfrog's fastest mode (the sign flips every step) every component
 * brakes on every step, so it acts as a stiffness raised by 1 + c and the limit becomes
 * omega dt < 2 / sqrt(1 + c) (0.77 x at the relaxation's c = 0.7; test_dem3d shows both sides).
 * So after each step the largest per-sphere bound lam (a max over spheres: the same bits for
 * any thread count) is checked: omega dt sqrt(1 + c) / 2 = sqrt(lam (1 + c)) dt / 2 < 1; when
 * it is not, dt is cut to 0.9 of the limit for the steps that follow (the step that found it
 * cannot blow up alone; params.dt_unguarded turns the cut off, for the tests). Every contact
 * is covered on the step it acts (the shares are summed over the pairs that touch), so the
 * check does not depend on the skin either.
 * The fraction of the limit used, sqrt(lam) dt sqrt(1 + c) / 2, depends on c only through
 * dt sqrt(1 + c). With params.dt_damping_exp e, dt (1 + c)^e is held fixed (dt_und; a cut sets
 * it too) and dt = dt_und / (1 + c)^e at every change of c: e = 0.5 gives every damping the
 * same fraction of its own limit for the same contacts (a phase at 0.2 steps sqrt(1.7 / 1.2)
 * = 1.19 x longer than one at 0.7); e < 0.5 keeps the less damped phase below the more
 * damped one's fraction, by the factor ((1 + c_lo) / (1 + c_hi))^(0.5 - e).
 *
 * Ownership: gp_dem3d_create copies the spheres; the gp_dem3d owns its state and its worker
 * threads until gp_dem3d_destroy. Lists handed out (gp_dem3d_contacts, gp_dem3d_find_pairs)
 * are malloc'ed and the caller's to free. Thread safety: one caller thread per gp_dem3d (it
 * runs its own workers inside gp_dem3d_run); the measures on a static list
 * (gp_dem3d_measure.c) only read their arguments and may run concurrently.
 */
#ifndef GP_DEM3D_H
#define GP_DEM3D_H

#include <stddef.h>

#include "gp_error.h"

typedef struct gp_dem3d gp_dem3d;

typedef struct gp_dem3d_params {
    double density;      /* kg/m^3 */
    double young;        /* Pa, for k_n */
    double ks_kn;        /* k_s / k_n */
    double friction_deg; /* sphere-sphere friction */
    double damping;      /* local damping coefficient in [0, 1) */
    double gravity[3];   /* m/s^2 */
    double dt_safety;    /* dt = dt_safety min_i sqrt(m_i / (2 E R_i)) (see the time step
                            above; the check may cut it); 0 = 0.2 */
    double scaled_radius;/* density scaling radius (m); 0 = none */
    double skin;         /* Verlet skin (m); 0 = 0.2 * smallest radius */
    int dt_unguarded;    /* nonzero: never cut dt (tests of the stability bound) */
    double dt_damping_exp; /* e > 0: the step follows the damping c in force (this one, then
                            each gp_dem3d_set_damping): dt = dt_safety min_i sqrt(m_i / (2 E
                            R_i)) / (1 + c)^e (see "Stability" above; 0.5: the same fraction
                            of the damped limit for any c); 0: dt does not depend on c */
    int threads;         /* 0 = 1 */
} gp_dem3d_params;

/* Sensible defaults: Table 1 material, gravity -9.81 along z, safety 0.2, no scaling. */
void gp_dem3d_params_defaults(gp_dem3d_params *p);

/* n spheres xyzr[4n] (radii are the full radii; see set_radius_scale) in the box [lo, hi]. */
gp_status gp_dem3d_create(const gp_dem3d_params *p, const double *xyzr, size_t n,
                          const double lo[3], const double hi[3], gp_dem3d **out, gp_error *err);
void gp_dem3d_destroy(gp_dem3d *d);

double gp_dem3d_dt(const gp_dem3d *d);
void gp_dem3d_set_friction(gp_dem3d *d, double friction_deg);
/* With params.dt_damping_exp e this also sets dt = dt_und / (1 + damping)^e, dt_und =
 * dt (1 + c)^e before the change (a cut's share is kept); otherwise dt stays. */
void gp_dem3d_set_damping(gp_dem3d *d, double damping);
/* Current radii are the full radii times s (in (0, 1]); masses stay those of the full radii. */
void gp_dem3d_set_radius_scale(gp_dem3d *d, double s);
double gp_dem3d_wall(const gp_dem3d *d, int w);
/* Servo wall (Eq. 10): each step the wall moves inward by gain * (F - F_c) / k_wall (gain: see
 * gp_dem3d_set_servo_dt), F_c and k_wall the sum of the forces and normal stiffnesses of its
 * contacts, at most vmax * dt (and by vmax * dt when it has no contact). force <= 0 turns the servo off (the wall stays).
 * Replaces a stress servo or a velocity on w. */
void gp_dem3d_set_servo(gp_dem3d *d, int w, double force, double vmax);
/* The servo as a rate in time: a step of dt moves a wall by gain = SERVO_GAIN dt / dt_ref of
 * Eq. 10's displacement (SERVO_GAIN = 0.25), the same wall motion per unit time whatever the
 * step; dt_ref <= 0 (the default): SERVO_GAIN per step. */
void gp_dem3d_set_servo_dt(gp_dem3d *d, double dt_ref);
/* The servo never moves wall w inward past position (NAN = no limit). */
void gp_dem3d_set_servo_limit(gp_dem3d *d, int w, double position);
/* A servo wall aiming at a stress (Pa): each step its target force is stress times the
 * current area of its face (the spans of the other two axes, as the walls stood when the
 * step began), the rest as gp_dem3d_set_servo (Eq. 10, gain, vmax, limit); stress <= 0 turns
 * the servo off (the wall stays). Replaces a force servo or a velocity on w. */
void gp_dem3d_set_servo_stress(gp_dem3d *d, int w, double stress, double vmax);
/* Wall w moves at v (m/s, along +axis: v < 0 moves wall 5 down) on every step: position +=
 * v dt after the step. Replaces a servo on w; gp_dem3d_set_servo and _servo_stress turn the
 * velocity off again (v = 0: the wall stays). */
void gp_dem3d_set_wall_velocity(gp_dem3d *d, int w, double v);
/* The current area of wall w's face (m^2): the spans of the other two axes. */
double gp_dem3d_face_area(const gp_dem3d *d, int w);

/* Advances nsteps. Fails (GP_ERR_DEGENERATE) if a sphere leaves the box or a value is not
 * finite, and with GP_ERR_CANCELLED before a step when the cancel flag is up. */
gp_status gp_dem3d_run(gp_dem3d *d, long nsteps, gp_error *err);
/* A flag another thread may raise (with an atomic store) to stop gp_dem3d_run before its next
 * step; NULL (the default) = none. Not owned; it must outlive the runs. */
void gp_dem3d_set_cancel(gp_dem3d *d, const volatile int *cancel);

typedef struct gp_dem3d_state {
    long steps;
    double time;
    double stability;        /* S_c (Eq. 7) of the last step: sum |resultant| over spheres (gravity
                                included) / sum over spheres of sum |f_n| of their contacts */
    double kinetic;          /* translational kinetic energy, true masses, J */
    double vmax;             /* largest sphere speed, m/s */
    double wall_force[6];    /* normal force on each wall, N */
    size_t contacts;         /* sphere-sphere contacts */
    size_t wall_contacts;
    long rebuilds;
    double omega_bound;      /* the bound on omega_max at the last step (rad/s; see the header) */
    double dt_ratio;         /* the largest omega_bound dt sqrt(1 + c) / 2 of any step (< 1: all
                                steps within the proven limit) */
    long dt_cuts;            /* how often dt was cut (gp_dem3d_dt is the current step) */
} gp_dem3d_state;

void gp_dem3d_get_state(const gp_dem3d *d, gp_dem3d_state *s);
/* Starts state.dt_ratio afresh (0): the largest fraction of the limit from the next step on,
 * e.g. one phase's own. */
void gp_dem3d_reset_dt_ratio(gp_dem3d *d);
/* Current x, y, z, r (current radii) into xyzr[4n]. */
void gp_dem3d_spheres(const gp_dem3d *d, double *xyzr);

/* A contact, the one contact type of the 3D code: the DEM makes it (gp_dem3d_contacts), the
 * flip maps it to a tiling (gp_flip.h), the measures below read it, and a specimen hands it
 * out (gp_specimen3d.contacts). j >= 0: sphere j (i < j); j < 0: wall -1 - j, walls 0..5 =
 * x-, x+, y-, y+, z-, z+ of the box (the tiled box in a tiled packing). normal: the unit
 * vector from sphere i to j (or to the wall). overlap: the full overlap R_i + R_j - |O_i O_j|
 * (for a wall: R_i - |O_i W|, Eq. 12; Eq. 11's penetration is half the sphere-sphere
 * overlap). force: the force on sphere i (normal + shear), N. */
typedef struct gp_contact3d {
    size_t i;
    long j;
    double normal[3];
    double overlap;
    double force[3];
} gp_contact3d;

/* The current contacts (sphere pairs in (i, j) order, then wall contacts by sphere), malloc'ed. */
gp_status gp_dem3d_contacts(const gp_dem3d *d, gp_contact3d **c, size_t *nc, gp_error *err);

/* --- measures on a static list (gp_dem3d_measure.c) --- */

/* All pairs i < j with |O_i O_j| < R_i + R_j + gap, by linked cells, sorted by (i, j):
 * pairs[2k], pairs[2k+1]. O(n) for bounded size ratios. */
gp_status gp_dem3d_find_pairs(const double *xyzr, size_t n, double gap, size_t **pairs,
                              size_t *npairs, gp_error *err);

/* Eq. 14: F = (1/N_c) sum n n^T, summed over the spheres' contacts: a sphere pair is seen by
 * both spheres (weight 2), a wall contact by one (weight 1; the flip turns it into half of a
 * pair with the sphere's image). With no wall contacts this is Eq. 14 exactly; with them it is
 * invariant under flip tiling. */
void gp_dem3d_fabric(const gp_contact3d *c, size_t nc, double F[3][3]);

/* Eq. 15 with compression positive: sigma = -(1/V) sum_c l_c (x) f_c, summed over both spheres of
 * a pair (the branch vector O_i O_j times the force on i) and over the sphere of a wall contact
 * (centre to contact point). xyzr: the spheres the contacts refer to. */
void gp_dem3d_stress(const gp_contact3d *c, size_t nc, const double *xyzr, double volume,
                     double S[3][3]);

/* The same measures as accumulators, for contacts that come in chunks (gp_flip_contacts_each
 * streams the contacts of a tiled packing without building their array): _init, _add for
 * each chunk in order, _finish. The sums run over the contacts in the order they are added,
 * one by one, exactly as the array functions run over their array (which are built on
 * these): any chunking of the same sequence gives the same bits as the array function on it.
 * Plain structs owned by the caller, no allocation; one per thread. */
typedef struct gp_dem3d_fabric_acc {
    double sum[3][3]; /* sum of w n n^T */
    double wsum;      /* sum of the weights w (2 per pair, 1 per wall contact) */
} gp_dem3d_fabric_acc;

typedef struct gp_dem3d_stress_acc {
    const double *xyzr; /* the spheres the contacts refer to (not owned) */
    double sum[3][3];   /* sum of l (x) f */
} gp_dem3d_stress_acc;

void gp_dem3d_fabric_acc_init(gp_dem3d_fabric_acc *a);
void gp_dem3d_fabric_acc_add(gp_dem3d_fabric_acc *a, const gp_contact3d *c, size_t nc);
/* F = sum / wsum (zero without contacts) */
void gp_dem3d_fabric_acc_finish(const gp_dem3d_fabric_acc *a, double F[3][3]);
void gp_dem3d_stress_acc_init(gp_dem3d_stress_acc *a, const double *xyzr);
void gp_dem3d_stress_acc_add(gp_dem3d_stress_acc *a, const gp_contact3d *c, size_t nc);
/* S = -sum / volume (volume <= 0: -sum) */
void gp_dem3d_stress_acc_finish(const gp_dem3d_stress_acc *a, double volume, double S[3][3]);

/* Solid volume of the spheres inside the box [lo, hi] (each sphere clipped by the six planes;
 * caps of one sphere at two walls are assumed disjoint). */
double gp_dem3d_solid_volume(const double *xyzr, size_t n, const double lo[3], const double hi[3]);

#endif /* GP_DEM3D_H */
