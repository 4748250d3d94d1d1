/* gp_export_lammps.c -- LAMMPS and LIGGGHTS data files.
 *
 * 3D (lammps, liggghts): atom_style sphere, one atom per sphere, atom line
 *   "id type diameter density x y z" (the order both LAMMPS 2021+ and LIGGGHTS 3.8 read);
 *   LAMMPS computes each mass as density * (4/3) pi r^3, so the file's total mass is exactly
 *   the specimen's. Box bounds are the job's (tiled) box.
 * 2D (lammps): atom_style hybrid sphere molecular, one atom per ODEC disc, atom line
 *   "id type x y z diameter density molecule" with molecule = grain id + 1, so that
 *   `fix rigid/small molecule` makes each grain one rigid body. LAMMPS gives a disc the mass
 *   density * (4/3) pi r^3 even in 2D; the densities written are scaled per disc so that a
 *   grain's discs weigh density * (grain area) * 1 m -- the grain's true mass per metre of
 *   thickness, overlaps between its discs not counted twice. The z bounds straddle 0.
 * The header comment lines carry the input lines that read the file.
 */
#include "gp_export_internal.h"

#include <math.h>

/* The counts, the box and the Atoms line, common to both headers (natoms atoms; z bounds zlo,
 * zhi; the atom style's name). */
static int write_box(gp_export *e, uint64_t natoms, double zlo, double zhi, const char *style)
{
    return gp_xw_printf(e,
                        "\n"
                        "%llu atoms\n"
                        "1 atom types\n"
                        "\n"
                        "%.17g %.17g xlo xhi\n"
                        "%.17g %.17g ylo yhi\n"
                        "%.17g %.17g zlo zhi\n"
                        "\n"
                        "Atoms # %s\n"
                        "\n",
                        (unsigned long long)natoms, e->info.lo[0], e->info.hi[0], e->info.lo[1],
                        e->info.hi[1], zlo, zhi, style);
}

static int header_3d(gp_export *e)
{
    int lig = e->format == GP_EXPORT_LIGGGHTS;
    if (gp_xw_printf(e,
                     "%s data file from grainpack (spheres-3d): %llu spheres, SI units\n"
                     "# read with: units si / atom_style sphere / %sread_data FILE\n"
                     "# atom line: id type diameter(m) density(kg/m^3) x y z (m)\n",
                     lig ? "LIGGGHTS" : "LAMMPS", (unsigned long long)e->info.nitems,
                     lig ? "atom_modify map array sort 0 0 / boundary f f f / " : ""))
        return -1;
    return write_box(e, e->info.nitems, e->info.lo[2], e->info.hi[2], "sphere");
}

static int header_2d(gp_export *e)
{
    double half = 0.5 * fmax(e->info.hi[0] - e->info.lo[0], e->info.hi[1] - e->info.lo[1]);
    if (gp_xw_printf(
            e,
            "LAMMPS data file from grainpack (fourier-voronoi-2d): %llu grains as rigid bodies "
            "of %llu ODEC discs, SI units\n"
            "# atom line: id type x y z diameter(m) density(kg/m^3) molecule (= grain id + 1)\n"
            "# a grain's discs weigh %.17g kg/m^3 * grain area * 1 m (2D, unit thickness)\n"
            "# read with:\n"
            "#   dimension 2\n"
            "#   units si\n"
            "#   atom_style hybrid sphere molecular\n"
            "#   read_data FILE\n"
            "#   pair_style gran/hooke/history <kn> NULL <gamman> NULL <mu> 0 ; pair_coeff * *\n"
            "#   neigh_modify exclude molecule/intra all\n"
            "#   comm_modify vel yes cutoff %.6g\n"
            "#   fix grains all rigid/small molecule\n"
            "#   fix plane all enforce2d\n",
            (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs, e->info.density,
            1.5 * e->info.max_extent))
        return -1;
    return write_box(e, e->info.ndiscs, -half, half, "hybrid");
}

static int lammps_header(gp_export *e)
{
    return e->info.dim == 3 ? header_3d(e) : header_2d(e);
}

/* 3D atom line: id type diameter density x y z */
static int lammps_sphere(gp_export *e, const double q[4])
{
    return gp_xw_printf(e, "%llu 1 %.17g %.17g %.17g %.17g %.17g\n",
                        (unsigned long long)e->index + 1, 2.0 * q[3], e->info.density, q[0], q[1],
                        q[2]);
}

/* Loads grain e->index into e->grain and its disc density scale into e->aux. */
static int load_grain(gp_export *e)
{
    if (gp_xr_grain(e, e->index, &e->grain)) return -1;
    double discs = 0;
    for (uint64_t k = 0; k < e->grain.disc_count; k++) {
        double d[3];
        if (gp_xr_disc(e, e->grain.disc_first + k, d)) return -1;
        discs += M_PI * d[2] * d[2];
    }
    e->aux = discs > 0 ? e->grain.area / discs : 1.0;
    return 0;
}

/* 2D atom line: id type x y z diameter density molecule */
static int lammps_disc(gp_export *e, const double d[3])
{
    /* mass = (4/3) pi r^3 rho' = rho * scale * pi r^2, see the file comment */
    double rho = e->info.density * e->aux * 0.75 / d[2];
    return gp_xw_printf(e, "%llu 1 %.17g %.17g 0 %.17g %.17g %llu\n",
                        (unsigned long long)(e->grain.disc_first + e->sub + 1), d[0], d[1],
                        2.0 * d[2], rho, (unsigned long long)e->index + 1);
}

static const gp_xlines lammps_lines = {lammps_header, lammps_sphere, lammps_disc, load_grain};

int gp_export_step_lammps(gp_export *e)
{
    return gp_xw_lines(e, &lammps_lines);
}
