/* gp_export_lammps_relax.c -- "lammps-relax": the packing and a LAMMPS run that relaxes it.
 *
 * A tar (POSIX ustar) of one folder, lammps-relax/, with two files:
 *   relax.in      a LAMMPS input script: grainpack's own DEM (core/3d/gp_dem3d.h) as closely as
 *                 LAMMPS 29Sep2021 allows, run until S_c <= 1e-4 (Eq. 7) measured as gp_dem3d
 *                 measures it, or a step cap; it writes relax.json (porosity, coordination number
 *                 and S_c before and after, steps, seconds) and final.dump (the final spheres);
 *   spheres.data  the packing, atom_style sphere, one atom type per size class (the contact
 *                 stiffness of a LAMMPS granular pair is per type pair, ours per sphere pair).
 * Why a tar: LAMMPS reads atoms from a data file only; a single script that made them one by one
 * (create_atoms single + set, per atom) is quadratic in LAMMPS and takes hours at 10^5 spheres.
 * One download, `tar xf`, and `mpirun -np 2 lmp -in relax.in` in the folder.
 *
 * What the script does, and where it differs from gp_dem3d, is written in its own header
 * (script_head): a user reads it there. The one approximation is the per-class stiffness
 * (within +-(sqrt(q) - 1) of ours, q the radius ratio of a class: 2.5 % when the sizes allow
 * 32 classes of 5 %, 3.7 % for the paper's 1:10 sieve); moments are not damped (LAMMPS has no
 * per-atom torque fix), and grainpack's free flight of fines is not reproduced.
 *
 * The tar is a stream in O(1) memory like every export: a ustar header carries its file's size,
 * which is counted by formatting each atom line once (a pass over the pack, 0.8 s at 525,000
 * spheres). The pack carries that count, made when the job wrote it (gp_export.h, relax_bytes),
 * so that a download starts at once; a pack without it (made before it was counted) is counted
 * at the first read. The atom lines are counted again as they are written: a data file that
 * would differ from its header fails the download rather than make a corrupt tar. Records:
 * [folder header, script header, script, padding] [data header, data file header] [one atom
 * line per step] [padding, the two zero blocks that end a tar].
 */
#include "gp_export_internal.h"

#include <math.h>
#include <stdio.h>

#define DIR "lammps-relax/"
#define MAX_TYPES 32     /* size classes: pair_coeff lines grow as types^2 / 2 */
#define CLASS_RATIO 1.05 /* narrowest class, as a radius ratio */
#define SKIN 0.2         /* neighbour skin, times the smallest radius */
#define MAX_STEPS 1000000
#define EVERY 100        /* S_c is looked at every this many steps (gp_specimen3d's CHUNK) */

enum { SEC_SCRIPT = 0, SEC_DATA_HEAD, SEC_ATOMS, SEC_END };

/* ------------------------------------------------------------------ size classes */

/* K classes of equal radius ratio q between rmin and rmax, q >= CLASS_RATIO unless K would
 * pass MAX_TYPES. */
static void size_classes(gp_export *e)
{
    double span = e->dem.rmax / e->dem.rmin;
    int k = span > 1 ? (int)ceil(log(span) / log(CLASS_RATIO) - 1e-9) : 1;
    e->ntypes = k < 1 ? 1 : (k > MAX_TYPES ? MAX_TYPES : k);
    e->type_ratio = pow(span, 1.0 / e->ntypes);
}

/* the class (atom type, 1..K) of radius r */
static int size_class(const gp_export *e, double r)
{
    if (e->ntypes == 1) return 1;
    double t = floor(log(r / e->dem.rmin) / log(e->type_ratio));
    return t < 0 ? 1 : (t >= e->ntypes ? e->ntypes : (int)t + 1);
}

/* the radius that stands for class t: the geometric middle of its range */
static double class_radius(const gp_export *e, int t)
{
    return e->dem.rmin * pow(e->type_ratio, t - 0.5);
}

/* ------------------------------------------------------------------ the data file */

static int data_head(gp_export *e)
{
    return gp_xw_printf(e,
                        "LAMMPS data file from grainpack (spheres-3d) for relax.in: %llu spheres, "
                        "SI units\n"
                        "# atom line: id type diameter(m) density(kg/m^3) x y z (m); type = size "
                        "class (relax.in)\n"
                        "\n"
                        "%llu atoms\n"
                        "%d atom types\n"
                        "\n"
                        "%.17g %.17g xlo xhi\n"
                        "%.17g %.17g ylo yhi\n"
                        "%.17g %.17g zlo zhi\n"
                        "\n"
                        "Atoms # sphere\n"
                        "\n",
                        (unsigned long long)e->info.nitems, (unsigned long long)e->info.nitems, e->ntypes,
                        e->info.lo[0], e->info.hi[0], e->info.lo[1], e->info.hi[1], e->info.lo[2],
                        e->info.hi[2]);
}

/* the atom line of sphere i, q = x, y, z, r (the true density: relax.in scales the inertia) */
static int data_atom(gp_export *e, uint64_t i, const double q[4])
{
    return gp_xw_printf(e, "%llu %d %.17g %.17g %.17g %.17g %.17g\n", (unsigned long long)i + 1,
                        size_class(e, q[3]), 2.0 * q[3], e->info.density, q[0], q[1], q[2]);
}

/* The data file's size: its header and every atom line formatted once into the (empty)
 * staging buffer and dropped (size_classes first). */
static int data_size(gp_export *e, uint64_t *bytes)
{
    uint64_t n = 0;
    if (data_head(e)) return -1;
    n += e->len;
    e->len = 0;
    for (uint64_t i = 0; i < e->info.nitems; i++) {
        double q[4];
        if (gp_xr_sphere(e, i, q) || data_atom(e, i, q)) return -1;
        n += e->len;
        e->len = 0;
    }
    *bytes = n;
    return 0;
}

int gp_export_relax_count(gp_export *e, uint64_t *bytes)
{
    size_classes(e);
    e->len = e->pos = 0;
    int rc = data_size(e, bytes);
    e->len = e->pos = 0;
    return rc;
}

/* ------------------------------------------------------------------ the input script */

static int script_head(gp_export *e)
{
    const gp_xdem *d = &e->dem;
    double err = sqrt(e->type_ratio) - 1;
    return gp_xw_printf(
        e,
        "# relax.in -- a LAMMPS relaxation of a grainpack spheres-3d packing to the stability\n"
        "# criterion of Dang & Meguid (2010), Eq. 7: S_c <= %g.\n"
        "# %llu spheres in the box [%.6g, %.6g] x [%.6g, %.6g] x [%.6g, %.6g] m (tiling %d x %d x "
        "%d);\n"
        "# grainpack measured porosity %.6f and coordination number %.4f.\n"
        "#\n"
        "# Run it in this folder:   mpirun -np 2 lmp -in relax.in\n"
        "#   (as root, add --allow-run-as-root; more ranks: -np N). Options: -var maxsteps N\n"
        "#   (default %d), -var timeout HH:MM:SS (stop after this wall time, default off),\n"
        "#   -var every N (S_c is looked at every N steps, default %d), -var ztop Z (the top\n"
        "#   wall's height, default the box's top: above the packing, e.g. twice the box's top,\n"
        "#   the surface settles free under gravity, as a geostatic-3d job settles it).\n"
        "# It writes relax.json (porosity, coordination number and S_c before and after, steps,\n"
        "# seconds), final.dump (id type radius x y z of the final spheres) and log.lammps.\n"
        "#\n"
        "# The model is grainpack's own DEM (core/3d/gp_dem3d.h), as LAMMPS 29Sep2021 can run it:\n"
        "# - normal: a linear spring f_n = k_n delta, k_n = 2 E R_i R_j / (R_i + R_j), E = %.6g "
        "Pa.\n"
        "#   LAMMPS's granular hooke has one k_n per type pair: the spheres are sorted into %d "
        "size\n"
        "#   classes (atom types) of radius ratio %.4f, and k_n uses the middle radius of each\n"
        "#   class: within %.1f %% of grainpack's k_n for every pair.\n"
        "# - tangential: an incremental spring k_s = %.6g k_n kept tangent (linear_history), cut at\n"
        "#   tan(%.6g deg) f_n; no viscous damping at the contacts (gamma = 0).\n"
        "# - walls: the six faces of the box, fixed and frictionless, f = 2 E R (R - d) with d the\n"
        "#   distance from the centre (the force of the sphere's mirror image): exact per sphere.\n"
        "# - gravity %.6g m/s^2 along -z on the true masses.\n"
        "# - local (Cundall) damping %.6g: each force component gets -c |f| sign(v) (grainpack's\n"
        "#   relaxation raises the material's %.6g to this). grainpack damps moments too; LAMMPS\n"
        "#   has no per-sphere torque damping, so moments are undamped here.\n"
        "# - density scaling as grainpack's: a sphere of radius r < r_s = %.6g m moves with the\n"
        "#   mass 4/3 pi rho r_s^2 r (the critical time step of r_s), gravity acts on its true mass;\n"
        "#   time step %.6g s = grainpack's (0.3 of min sqrt(m / 2 E r)). grainpack also lets\n"
        "#   a sphere with no surface near it fall with its true mass and undamped: not here.\n"
        "# - S_c = sum over spheres of |F| (contacts, walls and gravity, before damping) / sum over\n"
        "#   spheres of the |f_n| of their contacts (a pair counted by both spheres, a wall by one).\n"
        "# - porosity = 1 - (sphere volumes clipped to the box) / box volume; coordination number =\n"
        "#   (2 sphere-sphere contacts + wall contacts) / spheres, rattlers included (as grainpack).\n"
        "\n",
        d->stability, (unsigned long long)e->info.nitems, e->info.lo[0], e->info.hi[0], e->info.lo[1],
        e->info.hi[1], e->info.lo[2], e->info.hi[2], d->tiling[0], d->tiling[1], d->tiling[2], d->porosity,
        d->coordination, MAX_STEPS, EVERY, d->young, e->ntypes, e->type_ratio, 100 * err,
        d->poisson, d->friction_deg, d->gravity, d->relax_damping, d->damping, d->scaled_radius,
        d->dt);
}

/* units, the atoms, the contact law per type pair and the neighbour list */
static int script_model(gp_export *e)
{
    const gp_xdem *d = &e->dem;
    if (gp_xw_printf(e,
                     "variable        maxsteps index %d\n"
                     "variable        every index %d\n"
                     "variable        timeout index off\n"
                     "variable        ztop index %.17g\n"
                     "units           si\n"
                     "atom_style      sphere\n"
                     "boundary        f f f\n"
                     "comm_modify     vel yes\n"
                     "read_data       spheres.data\n"
                     "# the box up to the top wall (above the data's box when it is lifted)\n"
                     "change_box      all z final %.17g ${ztop} units box\n"
                     "timestep        %.17g\n"
                     "\n"
                     "# contact law: k_n of the classes' middle radii, k_t = %.6g k_n, mu = "
                     "tan(%.6g deg)\n"
                     "pair_style      granular\n",
                     MAX_STEPS, EVERY, e->info.hi[2], e->info.lo[2], d->dt, d->poisson,
                     d->friction_deg))
        return -1;
    double mu = tan(d->friction_deg * M_PI / 180);
    for (int a = 1; a <= e->ntypes; a++)
        for (int b = a; b <= e->ntypes; b++) {
            double ra = class_radius(e, a), rb = class_radius(e, b);
            double kn = 2 * d->young * ra * rb / (ra + rb);
            if (gp_xw_printf(e,
                             "pair_coeff      %d %d hooke %.17g 0 tangential linear_history %.17g "
                             "0 %.17g damping velocity\n",
                             a, b, kn, d->poisson * kn, mu))
                return -1;
        }
    return gp_xw_printf(e,
                        "neighbor        %.17g bin\n"
                        "neigh_modify    delay 0 every 1 check yes\n"
                        "\n",
                        SKIN * d->rmin);
}

/* The inertia of density scaling (after a run 0, so that the radii compute is current: `set`
 * reads an atom-style variable of it), then the walls, the weight and the damping as fixes in
 * the order their forces must add up: store/force keeps the resultant before damping. */
static int script_forces(gp_export *e)
{
    const gp_xdem *d = &e->dem;
    double rho43 = 4.0 / 3.0 * M_PI * e->info.density, rs = d->scaled_radius;
    const double *L = e->info.hi;
    if (gp_xw_printf(e,
                     "# radii, and the inertia of density scaling (r_s = %.17g m)\n"
                     "compute         r all property/atom radius\n"
                     "compute         rmax all reduce max c_r\n"
                     "thermo_style    custom step atoms c_rmax\n"
                     "run             0 post no\n"
                     "variable        inertia atom %.17g*c_r*c_r*c_r*((c_r<%.17g)*(%.17g/c_r)^2"
                     "+(c_r>=%.17g))\n"
                     "set             group all mass v_inertia\n"
                     "\n"
                     "# walls: h = the overlap with each face, f = 2 E r h\n",
                     rs, rho43, rs, rs, rs))
        return -1;
    const char ax[3] = {'x', 'y', 'z'};
    for (int a = 0; a < 3; a++) {
        /* the top wall at ${ztop} (the box's top unless the run lifts it) */
        char hi[32];
        if (a == 2) snprintf(hi, sizeof hi, "${ztop}");
        else snprintf(hi, sizeof hi, "%.17g", L[a]);
        if (gp_xw_printf(e,
                         "variable        h%cl atom 0.5*(c_r-(%c-%.17g)+abs(c_r-(%c-%.17g)))\n"
                         "variable        h%ch atom 0.5*(c_r-(%s-%c)+abs(c_r-(%s-%c)))\n"
                         "variable        fw%c atom %.17g*c_r*(v_h%cl-v_h%ch)\n",
                         ax[a], ax[a], e->info.lo[a], ax[a], e->info.lo[a], ax[a], hi, ax[a], hi,
                         ax[a], ax[a], 2 * d->young, ax[a], ax[a]))
            return -1;
    }
    /* only the spheres within rmax of a face can touch one: the others skip the variables */
    double rm = d->rmax;
    int thin = 0;
    for (int a = 0; a < 3; a++) thin |= L[a] - e->info.lo[a] < 4 * rm;
    if (thin ? gp_xw_printf(e, "group           nearwall union all\n")
             : gp_xw_printf(e,
                            "region          core block %.17g %.17g %.17g %.17g %.17g %.17g side "
                            "out units box\n"
                            "group           nearwall dynamic all region core every 1\n",
                            e->info.lo[0] + rm, L[0] - rm, e->info.lo[1] + rm, L[1] - rm,
                            e->info.lo[2] + rm, L[2] - rm))
        return -1;
    double c = d->relax_damping;
    return gp_xw_printf(
        e,
        "fix             walls nearwall addforce v_fwx v_fwy v_fwz\n"
        "# weight on the true mass\n"
        "variable        weight atom -%.17g*c_r*c_r*c_r\n"
        "fix             weight all addforce 0 0 v_weight\n"
        "# the resultant before damping (S_c), then local damping -c |f| sign(v)\n"
        "fix             resultant all store/force\n"
        "variable        dx atom -%.17g*abs(fx)*((vx>0)-(vx<0))\n"
        "variable        dy atom -%.17g*abs(fy)*((vy>0)-(vy<0))\n"
        "variable        dz atom -%.17g*abs(fz)*((vz>0)-(vz<0))\n"
        "fix             damping all addforce v_dx v_dy v_dz\n"
        "fix             integrate all nve/sphere\n"
        "\n",
        rho43 * d->gravity, c, c, c);
}

/* S_c, the coordination number and the porosity, each measured as grainpack measures it */
static int script_measures(gp_export *e)
{
    const double *lo = e->info.lo, *hi = e->info.hi;
    double V = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    return gp_xw_printf(
        e,
        "# S_c (Eq. 7): sum |F| / (2 sum of pair f_n + sum of wall f_n)\n"
        "variable        fres atom sqrt(f_resultant[1]^2+f_resultant[2]^2+f_resultant[3]^2)\n"
        "compute         sumf all reduce sum v_fres\n"
        "compute         pairs all pair/local force cutoff radius\n"
        "compute         sumfn all reduce sum c_pairs\n"
        "variable        fnw atom %.17g*c_r*(v_hxl+v_hxh+v_hyl+v_hyh+v_hzl+v_hzh)\n"
        "compute         sumfw all reduce sum v_fnw\n"
        "variable        fnsum equal 2*c_sumfn+c_sumfw\n"
        "variable        Sc equal c_sumf/(v_fnsum+(v_fnsum==0))\n"
        "# coordination number: sphere contacts (both ends) and wall contacts, per sphere\n"
        "compute         contacts all contact/atom\n"
        "variable        nwall atom (v_hxl>0)+(v_hxh>0)+(v_hyl>0)+(v_hyh>0)+(v_hzl>0)+(v_hzh>0)\n"
        "compute         ncont all reduce sum c_contacts v_nwall\n"
        "variable        Z equal (c_ncont[1]+c_ncont[2])/atoms\n"
        "# porosity: sphere volumes less the caps beyond the faces\n"
        "variable        solid atom 4/3*PI*c_r^3-PI/3*(v_hxl^2*(3*c_r-v_hxl)+v_hxh^2*(3*c_r-v_hxh)"
        "+v_hyl^2*(3*c_r-v_hyl)+v_hyh^2*(3*c_r-v_hyh)+v_hzl^2*(3*c_r-v_hzl)+v_hzh^2*(3*c_r-v_hzh))\n"
        "compute         solid all reduce sum v_solid\n"
        "variable        porosity equal 1-c_solid/%.17g\n"
        "\n",
        2 * e->dem.young, V);
}

/* the state before, the run to S_c <= threshold or maxsteps, the state after */
static int script_run(gp_export *e)
{
    const gp_xdem *d = &e->dem;
    return gp_xw_printf(
        e,
        "variable        cpu equal cpu\n"
        "thermo_style    custom step time v_Sc v_porosity v_Z ke cpu\n"
        "thermo_modify   format float %%.6g flush yes\n"
        "thermo          ${every}\n"
        "run             0\n"
        "variable        por0 equal $(v_porosity:%%.17g)\n"
        "variable        Z0 equal $(v_Z:%%.17g)\n"
        "variable        Sc0 equal $(v_Sc:%%.17g)\n"
        "\n"
        "# relax: stop when S_c <= %g (looked at every ${every} steps), after maxsteps (rounded\n"
        "# up to a multiple of every, so that the timer below is current at the end) or timeout\n"
        "variable        nrun equal ${every}*ceil(${maxsteps}/${every})\n"
        "fix             halt all halt ${every} v_Sc <= %.17g error continue\n"
        "fix             timer all ave/time ${every} 1 ${every} v_cpu\n"
        "timer           timeout ${timeout} every ${every}\n"
        "run             ${nrun}\n"
        "# (print fills no ${...} inside quotes: the flag is a bare JSON word)\n"
        "if \"$(v_Sc) <= %.17g\" then \"variable stable string true\" else \"variable stable "
        "string false\"\n"
        "\n"
        "print \"\"\"{\"spheres\": $(atoms), \"steps\": $(step), \"stable\": ${stable}, "
        "\"threshold\": %.17g, \"dt\": %.17g, \"seconds\": $(f_timer:%%.6g),\n"
        " \"before\": {\"porosity\": ${por0}, \"coordination_number\": ${Z0}, \"stability\": "
        "${Sc0}},\n"
        " \"after\": {\"porosity\": $(v_porosity:%%.17g), \"coordination_number\": "
        "$(v_Z:%%.17g), \"stability\": $(v_Sc:%%.17g)},\n"
        " \"grainpack\": {\"porosity\": %.17g, \"coordination_number\": %.17g}}\"\"\" file "
        "relax.json screen no\n"
        "write_dump      all custom final.dump id type radius x y z modify format float %%.17g\n"
        "print           \"relaxation: stable ${stable} after $(step) steps, S_c $(v_Sc:%%.3g), porosity "
        "${por0} -> $(v_porosity:%%.6f), coordination ${Z0} -> $(v_Z:%%.4f)\"\n",
        d->stability, d->stability, d->stability, d->stability, d->dt, d->porosity,
        d->coordination);
}

/* ------------------------------------------------------------------ the stream */

/* relax.in, all of it */
static int script(gp_export *e)
{
    return script_head(e) || script_model(e) || script_forces(e) || script_measures(e) ||
                   script_run(e)
               ? -1
               : 0;
}

/* section SEC_SCRIPT: the folder, and relax.in with its header (written in front of it once
 * its size is known); the data file is sized first, while the staging buffer is empty */
static int write_script(gp_export *e)
{
    size_classes(e);
    uint64_t bytes = e->relax_bytes;
    if (!bytes && data_size(e, &bytes)) return -1;
    if (bytes > GP_XW_TAR_MAX_SIZE)
        return gp_error_set(&e->err, GP_ERR_INVALID,
                            "lammps-relax: a data file of %llu bytes is over the 8 GiB of a tar "
                            "member", (unsigned long long)bytes), -1;
    e->file_bytes = bytes;
    return gp_xw_tar_header(e, DIR, '5', 0) || gp_xw_tar_file(e, DIR "relax.in", script) ? -1 : 0;
}

static int write_data_head(gp_export *e)
{
    if (gp_xw_tar_header(e, DIR "spheres.data", '0', e->file_bytes)) return -1;
    size_t at = e->len;
    if (data_head(e)) return -1;
    e->written = e->len - at;
    return 0;
}

/* The data file written whole: its bytes as its tar header announced them. */
static int data_complete(gp_export *e)
{
    if (e->written == e->file_bytes) return 0;
    return gp_error_set(&e->err, GP_ERR_INVALID,
                        "lammps-relax: the data file is %llu bytes, its header says %llu (the "
                        "pack's count is stale)",
                        (unsigned long long)e->written, (unsigned long long)e->file_bytes), -1;
}

int gp_export_step_lammps_relax(gp_export *e)
{
    switch (e->section) {
    case SEC_SCRIPT:
        e->section = SEC_DATA_HEAD;
        return write_script(e) ? -1 : 0;
    case SEC_DATA_HEAD:
        e->section = e->info.nitems ? SEC_ATOMS : SEC_END;
        e->index = 0;
        return write_data_head(e) ? -1 : 0;
    case SEC_ATOMS: {
        double q[4];
        if (gp_xr_sphere(e, e->index, q) || data_atom(e, e->index, q)) return -1;
        e->written += e->len;
        if (++e->index >= e->info.nitems) e->section = SEC_END;
        return 0;
    }
    default: /* the data file's padding, then the end of the archive: two zero blocks */
        return data_complete(e) || gp_xw_tar_pad(e, e->file_bytes) || gp_xw_tar_end(e) ? -1 : 1;
    }
}
