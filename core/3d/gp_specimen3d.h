/* gp_specimen3d.h -- one call from a validated spheres-3d spec to a stable sphere specimen.
 *
 * The 3D pipeline of Dang & Meguid (2010), see shared/papers (and NOTES.md for the misprints):
 *   sieve curve -> radii (gp_sieve) -> phase 0 deposition under gravity -> phase 1 compaction
 *   with the servo top wall (Eq. 10) to the target porosity -> relaxation to S_c <= 1e-4 (Eq. 7)
 *   (gp_dem3d) -> phase 2 flip tiling to nx x ny x nz (gp_flip) -> measures.
 * The schema/ parser fills gp_spec3d from JSON (converting sieve diameters mm -> m); the service
 * calls gp_specimen3d_build() on a worker thread and serialises the result.
 *
 * Axes: x, y horizontal, z vertical. box[2] is the height; gravity is -9.81 m/s^2 along z. (The
 * paper's y is vertical: its fabric "yy" is our "zz".) The box spans [0, box[i]] on each axis.
 *
 * Invariants: the same spec and seed give the same specimen bit for bit, whatever
 * spec->threads and whichever outputs are asked (the measures do not depend on
 * GP_OUT3_CONTACTS). Ownership: the spec and its sieve are only read; a gp_specimen3d and
 * every array in it are the caller's, freed by gp_specimen3d_destroy; its contacts are the
 * DEM's type (gp_contact3d, gp_dem3d.h). Thread safety: no global state; builds on different
 * threads are independent (each runs spec->threads DEM workers of its own).
 */
#ifndef GP_SPECIMEN3D_H
#define GP_SPECIMEN3D_H

#include <stddef.h>
#include <stdint.h>

#include "gp_dem3d.h" /* gp_contact3d */
#include "gp_error.h"
#include "gp_progress.h"
#include "gp_transfer.h"

/* The protocol's constants that an export reproduces outside grainpack (core/export's
 * lammps-relax writes a LAMMPS relaxation with them): gravity (m/s^2, along -z), the stability
 * threshold of Eq. 7 (0.01 %, NOTES.md), and the least local damping of the relaxation. */
#define GP_SPEC3D_GRAVITY 9.81
#define GP_SPEC3D_STABILITY 1e-4
#define GP_SPEC3D_RELAX_DAMPING 0.7
/* The DEM's time step rule of the protocol (gp_dem3d_params; gp_specimen3d.c says why): the
 * step is GP_SPEC3D_DT_SAFETY sqrt(m / 2 E R) at the relaxation's damping, and follows the
 * damping c as (1 + c)^-GP_SPEC3D_DT_DAMPING_EXP (dt_damping_exp). A triaxial test of the
 * specimen (gp_triax.h) steps by the same rule. */
#define GP_SPEC3D_DT_SAFETY 0.4
#define GP_SPEC3D_DT_DAMPING_EXP 0.45

/* outputs (bit flags); porosity, coordination number, PSD and timings are always reported */
enum {
    GP_OUT3_SPHERES = 1u << 0,  /* the sphere list (of the tiled packing when tiled) */
    GP_OUT3_CONTACTS = 1u << 1, /* the contact list (of the tiled packing when tiled) */
    GP_OUT3_FABRIC = 1u << 2,   /* stats.fabric (Eq. 14) */
    GP_OUT3_STRESS = 1u << 3    /* stats.stress (Eq. 15) */
};

/* One sieve row: diameter in metres, percent passing by weight in [0, 100]. Rows have strictly
 * increasing diameters and non-decreasing percentages; the first row has 0 % (the smallest
 * grain) and the last 100 % (the largest). */
typedef struct gp_sieve_row {
    double diameter;
    double passing;
} gp_sieve_row;

/* Table 1 of the paper. poisson is used as YADE's FrictMat does: the ratio k_s / k_n. */
typedef struct gp_material3d {
    double density;      /* kg/m^3 (2600) */
    double young;        /* Pa (15e6); contact stiffness k_n = 2 E R1 R2 / (R1 + R2) */
    double poisson;      /* k_s / k_n (0.5) */
    double friction_deg; /* sphere-sphere friction angle (18); the box walls are frictionless */
    double damping;      /* local (non-viscous) damping of forces and moments (0.2) */
} gp_material3d;

/* GP_OK, or GP_ERR_INVALID naming the field out of range: density and young > 0 and finite,
 * poisson (k_s / k_n) in [0, 10], friction_deg in [0, 90), damping in [0, 1). */
gp_status gp_material3d_check(const gp_material3d *m, gp_error *err);

/* The spec of kind "spheres-3d" (names as in shared/spec/api.md). The caller owns the sieve
 * array; gp_specimen3d_build() only reads it. */
typedef struct gp_spec3d {
    uint64_t seed;
    double box[3];               /* m: sample size b_x, b_y, b_z (b_z = height) */
    const gp_sieve_row *sieve;   /* diameters in m (the parser converts sieve_units) */
    size_t nsieve;
    double porosity;             /* target, in (0, 1) */
    gp_material3d material;
    int tiling[3];               /* flip tiling n_x, n_y, n_z; {1, 1, 1} = no tiling */
    unsigned outputs;            /* GP_OUT3_* */
    int threads;                 /* DEM worker threads; 0 = 1. Results do not depend on it. */
    long max_steps;              /* cap on DEM steps of phases 0-1 + relaxation; 0 = automatic */
    long tile_relax_steps;       /* optional DEM relaxation of the tiled packing; 0 = none */
} gp_spec3d;

/* Fills a spec with the API defaults: seed 0, box 0.5 m cube, the paper's Table 2 sieve (in m,
 * static storage), porosity 0.38, Table 1 material, tiling {1, 1, 1}, outputs spheres,
 * threads 1, automatic max_steps, no tiled relaxation. */
void gp_spec3d_defaults(gp_spec3d *spec);

/* Grain-size distribution at the sieve diameters, in percent passing. target_weight is the
 * spec; target_number is its conversion for diameters drawn uniformly inside each bin (the law
 * the sampler uses, NOTES.md); target_number_midbin is the paper's mid-bin cube rule (Table 2's
 * printed column); achieved_* are measured on the spheres of the sample. */
typedef struct gp_psd3d {
    size_t n;
    double *diameter;            /* m */
    double *target_weight;
    double *target_number;
    double *target_number_midbin;
    double *achieved_weight;
    double *achieved_number;
} gp_psd3d;

typedef struct gp_stats3d {
    double porosity_target;
    double porosity;             /* achieved, final packing (tiled when tiled): 1 - solid/box,
                                    solid = sphere volume clipped to the box */
    double sample_porosity;      /* achieved, the sample after relaxation */
    double deposition_porosity;  /* after phase 0 (loose packing under the lid) */
    double coordination_number;  /* mean contacts per sphere, wall contacts counted (a wall
                                    contact becomes a sphere contact when flipped) */
    double coordination_spheres; /* the same counting sphere-sphere contacts only */
    double fabric[3][3];         /* Eq. 14 over the spheres' contacts (a pair counted by both
                                    spheres, a wall contact by one: flip-invariant); GP_OUT3_FABRIC */
    double stress[3][3];         /* Eq. 15, Pa, compression positive, V = the box; GP_OUT3_STRESS */
    gp_psd3d psd;
    size_t particles;            /* spheres in the final packing */
    size_t sample_particles;     /* spheres in the sample */
    size_t contacts;             /* sphere-sphere contacts in the final packing */
    size_t wall_contacts;        /* sphere-wall contacts in the final packing */
    const char *stop_reason;     /* static string: "stable", "max_steps", "target_too_dense",
                                    "target_too_loose", "cancelled" */
    double stability;            /* S_c (Eq. 7) of the sample at the end of relaxation */
    double tiled_stability;      /* S_c of the tiled packing (0 unless tile_relax_steps) */
    double compaction_friction_deg; /* friction angle in use when the target height was reached */
    long steps;                  /* DEM steps of the sample, all phases */
    double dt;                   /* DEM time step of the relaxation (its damping's), s */
    /* per DEM phase (0 deposition, 1 compaction, 2 relaxation; zeros for a phase not run):
     * its time step at its end (s; a phase with less damping steps longer, DT_DAMPING_EXP in
     * gp_specimen3d.c and gp_dem3d.h), its steps, and the largest fraction of its own
     * stability limit any of its steps used (the DEM's dt_ratio: < 1 unless the step had to
     * be cut) */
    double phase_dt[3];
    long phase_steps[3];
    double phase_dt_ratio[3];
    long dt_cuts;                /* times the DEM cut its step, all phases and the tiled
                                    relaxation (0 expected) */
    double scaled_radius;        /* the DEM's density scaling radius, m (gp_dem3d_params) */
} gp_stats3d;

typedef struct gp_specimen3d {
    double *spheres;             /* count * 4: x, y, z, r (m); with GP_OUT3_SPHERES, else NULL */
    size_t count;                /* number of spheres in the final packing (even without output) */
    double box[3];               /* the final (tiled) box, m */
    double sample_box[3];        /* the sample box, m */
    double *sample_spheres;      /* stats.sample_particles * 4: x, y, z, r (m) of the sample S0
                                    as its DEM left it, before any tiling (in [0, sample_box]);
                                    always filled, whatever the outputs */
    gp_contact3d *contacts;      /* with GP_OUT3_CONTACTS (the type: gp_dem3d.h) */
    size_t ncontacts;
    gp_stats3d stats;
    /* Did the flip keep the sample's structure (gp_transfer.h)? Only a tiled specimen has
     * them (NULL untiled): the sample (its spheres, sample_box, its own contacts) and the
     * final packing (the tiled spheres and box, its contacts the sample's flipped, or the
     * relaxed tiling's own), measured at the spec's sieves (at most GP_TRANSFER_MAX_SIEVES of
     * them, evenly chosen, when it has more), g(r) in units of the sample's d50 by weight, in
     * bins of 0.05 up to r_max = min(5, 3/4 of the sample box's shortest side), and the diff.
     * The final side's porosity, coordination, fabric and PSD are those of the whole tiling;
     * its g(r) (g, g_err, neighbours, pairs, g_mirror) is that of a block of at most 2 x 2 x 2
     * tiles (the whole tiling when it has at most 2 tiles along every axis, else the block
     * nearest its centre): transfer_block tiles from tile transfer_block_origin on each axis,
     * its transfer_block_spheres spheres (centres in the block) in the block's box. Its cost is
     * at most 8 times the sample's own g(r), whatever the tiling. */
    gp_transfer_side *transfer_sample, *transfer_final;
    gp_transfer_diff transfer_diff;
    int transfer_block[3], transfer_block_origin[3];
    size_t transfer_block_spheres;
    /* timings, seconds (t_transfer: the measures above, not part of t_tiling) */
    double t_deposition, t_compaction, t_relaxation, t_tiling, t_transfer, t_total;
} gp_specimen3d;

/* Builds the specimen. Returns GP_OK, or an error with a message:
 *   GP_ERR_INVALID     bad spec (names the field), e.g. a box smaller than the largest grain;
 *   GP_ERR_INFEASIBLE  the target porosity cannot be reached (denser than the frictionless
 *                      packing, or looser than the deposit); *out holds the partial specimen,
 *                      stats.stop_reason says why;
 *   GP_ERR_NOT_CONVERGED relaxation hit max_steps before S_c <= 1e-4; *out holds the specimen;
 *   GP_ERR_CANCELLED   the progress callback or *cancel asked to stop (*out is NULL).
 * *out is set (and must be freed with gp_specimen3d_destroy) on GP_OK, GP_ERR_INFEASIBLE and
 * GP_ERR_NOT_CONVERGED; it is NULL on every other return. cancel may be NULL. The same spec and
 * seed give the same specimen bit for bit whatever spec->threads is. */
gp_status gp_specimen3d_build(const gp_spec3d *spec, gp_progress_fn progress, void *user,
                              const volatile int *cancel, gp_specimen3d **out, gp_error *err);

void gp_specimen3d_destroy(gp_specimen3d *s);

#endif /* GP_SPECIMEN3D_H */
