/* gp_export_fv3d_dem.c -- the grains of a fv3d pack as rigid bodies for DEM codes: lammps,
 * liggghts, yade. Each grain is its clump of spheres (outputs "clumps") moving as one body, with
 * the grain's own mass (density x the volume of its surface mesh), centre of mass and inertia
 * tensor about it -- not the spheres' sums, which count their overlaps twice (the DEM codes
 * leave that correction to the user: these files make it). Everything SI, %.17g.
 *
 * lammps: a tar (POSIX ustar) of one folder, lammps-grains/, with three files:
 *   grains.in     the input lines that read the other two (LAMMPS 29Sep2021 and later) and print
 *                 the bodies' count and total mass; a user adds the contact law and the run;
 *   grains.data   atom_style hybrid sphere molecular, one atom a clump sphere, atom line
 *                 "id type x y z diameter density molecule", molecule = grain id + 1 (the body
 *                 of fix rigid/small molecule); a grain's spheres get the density rho V / (sum
 *                 of their volumes), so that they weigh its mass (mass(all) = rho sum V);
 *   grains.rigid  fix rigid/small's infile: per body "id mass xcm ycm zcm ixx iyy izz ixy ixz
 *                 iyz" (the inertia tensor's elements about the centre of mass, box axes) and
 *                 zero velocity, angular momentum and image flags; LAMMPS takes these instead of
 *                 summing the atoms.
 *   Why a tar and an infile: LAMMPS reads atoms from a data file only, and a rigid body's mass
 *   and inertia from an infile only. Both members are sized before their tar headers by
 *   formatting every line once: when the pack is made (its fv3d block), else at the first read
 *   (as lammps-relax, whose ustar writer, gp_export_tar.c, this shares); a member that differs
 *   from its header fails the download.
 * liggghts: LIGGGHTS 3.8 input lines: per grain k (type k + 1) a fix particletemplate/multisphere
 *   gpt<k+1> with its spheres relative to its centroid in the specimen's axes (inserted with
 *   "orientation template" a grain keeps its orientation), "mass" = rho V, "inertia_tensor" =
 *   the grain's about its centroid (Ixx Ixy Ixz Iyy Iyz Izz) and "use_density" (LIGGGHTS then
 *   takes the volume as mass / density = V and makes no Monte Carlo estimate: ntry 1000, the
 *   least it allows, is only used for the spheres' CFD volume weights, and it warns that it is
 *   low); then a fix particledistribution/discrete gpdist of all the templates, weighted by mass.
 *   LIGGGHTS cannot read a multisphere body's position (its fix insert styles place bodies at
 *   random): each grain's centroid is in the comment before its template.
 * yade: ymport.textClumps' text, "x y z r clumpId" (clumpId = grain id), each grain's spheres
 *   consecutive and after a "#grain" comment line with its sphere count, volume, mass, centroid
 *   and inertia tensor; textClumps skips those lines and makes each clump's mass and inertia
 *   from its spheres. The "#py " comment lines are a Python function, grainpack_exact, that gives
 *   the clumps textClumps made their grains' exact values (the header says how to run it).
 */
#include "gp_export_internal.h"

#include <math.h>

#define DIR "lammps-grains/"
#define TEMPLATE_SEED 15485863       /* LIGGGHTS asks primes above 10,000 */
#define DIST_SEED 15485867
#define TEMPLATE_NTRY 1000           /* the least fix particletemplate/multisphere takes */

/* ------------------------------------------------------------------ shared */

/* Loads grain e->index into e->x3.grain. */
static int load_grain(gp_export *e)
{
    return gp_xr_grain3(e, e->index, &e->x3.grain);
}

/* Moves to the next grain with a clump sphere after grain e->index (e->sub = 0) and loads it;
 * returns 1 when there is none. */
static int next_grain_with_spheres(gp_export *e, int first)
{
    if (!first) e->index++;
    e->sub = 0;
    for (; e->index < e->info.nitems; e->index++) {
        if (load_grain(e)) return -1;
        if (e->x3.grain.sphere_count) return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ lammps: the files */

static int rigid_head(gp_export *e)
{
    return gp_xw_printf(e,
                        "# grains.rigid -- the infile of fix rigid/small molecule (grains.in): %llu "
                        "grains of a grainpack fourier-voronoi-3d specimen, SI units\n"
                        "# id (molecule = grain id + 1) mass(kg) xcm ycm zcm(m) ixx iyy izz ixy ixz "
                        "iyz(kg m^2, about the centre of mass, box axes) vxcm vycm vzcm lx ly lz "
                        "ixcm iycm izcm\n"
                        "%llu\n",
                        (unsigned long long)e->info.nitems, (unsigned long long)e->info.nitems);
}

/* the body line of grain e->index (loaded) */
static int rigid_body(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    const double *I = g->inertia;
    return gp_xw_printf(e,
                        "%llu %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g 0 0 0 0 0 "
                        "0 0 0 0\n",
                        (unsigned long long)e->index + 1, g->mass, g->centroid[0], g->centroid[1],
                        g->centroid[2], I[0], I[1], I[2], I[3], I[4], I[5]);
}

static int data_head(gp_export *e)
{
    const double *lo = e->info.lo, *hi = e->info.hi;
    return gp_xw_printf(e,
                        "LAMMPS data file from grainpack (fourier-voronoi-3d) for grains.in: %llu "
                        "grains as rigid bodies of %llu spheres, SI units\n"
                        "# atom line: id type x y z diameter(m) density(kg/m^3) molecule (= grain "
                        "id + 1)\n"
                        "# the spheres of a grain weigh its mass, %.17g kg/m^3 x its volume: their "
                        "density is that x the grain's volume / their summed volume\n"
                        "\n"
                        "%llu atoms\n"
                        "1 atom types\n"
                        "\n"
                        "%.17g %.17g xlo xhi\n"
                        "%.17g %.17g ylo yhi\n"
                        "%.17g %.17g zlo zhi\n"
                        "\n"
                        "Atoms # hybrid\n"
                        "\n",
                        (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs,
                        e->info.density, (unsigned long long)e->info.ndiscs, lo[0], hi[0], lo[1],
                        hi[1], lo[2], hi[2]);
}

/* e->x3.rho for grain e->index (loaded): its spheres' density */
static int atom_density(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    double v = 0;
    for (uint64_t k = 0; k < g->sphere_count; k++) {
        double q[4];
        if (gp_xr_clump(e, g->sphere_first + k, q)) return -1;
        v += 4.0 / 3.0 * M_PI * q[3] * q[3] * q[3];
    }
    e->x3.rho = v > 0 ? g->mass / v : e->info.density;
    return 0;
}

/* the atom line of sphere e->sub of grain e->index (loaded, e->x3.rho set) */
static int data_atom(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    uint64_t k = g->sphere_first + e->sub;
    double q[4];
    if (gp_xr_clump(e, k, q)) return -1;
    return gp_xw_printf(e, "%llu 1 %.17g %.17g %.17g %.17g %.17g %llu\n", (unsigned long long)k + 1,
                        q[0], q[1], q[2], 2.0 * q[3], e->x3.rho, (unsigned long long)e->index + 1);
}

/* the staging buffer's length, dropped (counting) */
static uint64_t take(gp_export *e)
{
    uint64_t n = e->len;
    e->len = 0;
    return n;
}

int gp_export_fv3d_count(gp_export *e, uint64_t *data_bytes, uint64_t *rigid_bytes)
{
    uint64_t d = 0, r = 0;
    e->len = e->pos = 0;
    int rc = rigid_head(e);
    r += take(e);
    for (e->index = 0; !rc && e->index < e->info.nitems; e->index++) {
        rc = load_grain(e) || rigid_body(e);
        r += take(e);
    }
    rc = rc || data_head(e);
    d += take(e);
    for (e->index = 0; !rc && e->index < e->info.nitems; e->index++) {
        rc = load_grain(e) || atom_density(e);
        for (e->sub = 0; !rc && e->sub < e->x3.grain.sphere_count; e->sub++) {
            rc = data_atom(e);
            d += take(e);
        }
    }
    e->len = e->pos = 0;
    e->index = e->sub = 0;
    if (rc) return -1;
    *data_bytes = d;
    *rigid_bytes = r;
    return 0;
}

/* ------------------------------------------------------------------ lammps: the script */

static int script(gp_export *e)
{
    return gp_xw_printf(
        e,
        "# grains.in -- a grainpack fourier-voronoi-3d specimen in LAMMPS: %llu grains as rigid\n"
        "# bodies of %llu spheres (their clumps), each body with its grain's own mass, centre of\n"
        "# mass and inertia (from the grain's surface mesh, density %.17g kg/m^3: %.17g kg in all).\n"
        "# In this folder (LAMMPS 29Sep2021 or later):   lmp -in grains.in\n"
        "#   grains.data   the spheres (atom_style hybrid sphere molecular, molecule = grain id + 1);\n"
        "#                 a grain's spheres overlap, and their density makes them weigh its mass\n"
        "#   grains.rigid  fix rigid/small's infile: each body's mass, centre of mass and inertia\n"
        "#                 tensor (LAMMPS would otherwise sum the spheres, their overlaps twice)\n"
        "# The lines below read them and print the bodies' total mass (run 0). Add the contact law,\n"
        "# walls, gravity and the run after them, e.g.\n"
        "#   pair_style      gran/hertz/history <kn> <kt> <gamman> <gammat> <mu> 1\n"
        "#   pair_coeff      * *\n"
        "#   fix             gravity all gravity 9.81 vector 0 0 -1\n"
        "# The box is the container's bounding box, with fixed boundaries.\n"
        "units           si\n"
        "atom_style      hybrid sphere molecular\n"
        "atom_modify     map array\n"
        "boundary        f f f\n"
        "read_data       grains.data\n"
        "# ghost atoms as far as the largest grain reaches\n"
        "comm_modify     vel yes cutoff %.17g\n"
        "neigh_modify    exclude molecule/intra all\n"
        "fix             grains all rigid/small molecule infile grains.rigid\n"
        "compute         bodies all rigid/local grains id mol mass x y z inertiax inertiay inertiaz "
        "quatw quati quatj quatk\n"
        "compute         bodymass all reduce sum c_bodies[3]\n"
        "thermo_style    custom step atoms c_bodymass\n"
        "thermo_modify   format float %%.17g\n"
        "run             0\n",
        (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs, e->info.density,
        e->info.density * e->info.volume, 1.5 * e->info.max_extent);
}

enum { L_SCRIPT = 0, L_RIGID_HEAD, L_RIGID, L_DATA_HEAD, L_ATOMS, L_END };

/* A member written whole: its bytes as its tar header announced them. */
static int member_complete(gp_export *e, const char *name)
{
    if (e->x3.member_written == e->x3.member) return 0;
    return gp_error_set(&e->err, GP_ERR_INVALID,
                        "lammps: %s is %llu bytes, its header says %llu (the pack's count is "
                        "stale)",
                        name, (unsigned long long)e->x3.member_written,
                        (unsigned long long)e->x3.member), -1;
}

/* the folder and grains.in, after the members' sizes are known (counted here when the pack
 * has none) */
static int write_script(gp_export *e)
{
    gp_x3 *x = &e->x3;
    if ((!x->data_bytes || !x->rigid_bytes) && gp_export_fv3d_count(e, &x->data_bytes, &x->rigid_bytes))
        return -1;
    if (x->data_bytes > GP_XW_TAR_MAX_SIZE || x->rigid_bytes > GP_XW_TAR_MAX_SIZE)
        return gp_error_set(&e->err, GP_ERR_INVALID,
                            "lammps: a data file of %llu bytes is over the 8 GiB of a tar member",
                            (unsigned long long)x->data_bytes), -1;
    return gp_xw_tar_header(e, DIR, '5', 0) || gp_xw_tar_file(e, DIR "grains.in", script) ? -1 : 0;
}

/* a member's tar header and its first record (its header lines) */
static int member_head(gp_export *e, const char *name, uint64_t bytes, int (*head)(gp_export *))
{
    if (gp_xw_tar_header(e, name, '0', bytes)) return -1;
    size_t at = e->len;
    if (head(e)) return -1;
    e->x3.member = bytes;
    e->x3.member_written = e->len - at;
    return 0;
}

int gp_export_step_fv3d_lammps(gp_export *e)
{
    gp_x3 *x = &e->x3;
    int rc;
    switch (e->section) {
    case L_SCRIPT:
        e->section = L_RIGID_HEAD;
        return write_script(e) ? -1 : 0;
    case L_RIGID_HEAD:
        e->index = 0;
        e->section = e->info.nitems ? L_RIGID : L_DATA_HEAD;
        return member_head(e, DIR "grains.rigid", x->rigid_bytes, rigid_head) ? -1 : 0;
    case L_RIGID:
        if (load_grain(e) || rigid_body(e)) return -1;
        x->member_written += e->len;
        if (++e->index >= e->info.nitems) e->section = L_DATA_HEAD;
        return 0;
    case L_DATA_HEAD:
        if (member_complete(e, "grains.rigid") || gp_xw_tar_pad(e, x->member)) return -1;
        if (member_head(e, DIR "grains.data", x->data_bytes, data_head)) return -1;
        e->index = 0;
        rc = next_grain_with_spheres(e, 1);
        if (rc < 0 || (rc == 0 && atom_density(e))) return -1;
        e->section = rc ? L_END : L_ATOMS;
        return 0;
    case L_ATOMS: {
        size_t at = e->len;
        if (data_atom(e)) return -1;
        x->member_written += e->len - at;
        if (++e->sub < x->grain.sphere_count) return 0;
        rc = next_grain_with_spheres(e, 0);
        if (rc < 0 || (rc == 0 && atom_density(e))) return -1;
        if (rc) e->section = L_END;
        return 0;
    }
    default: /* the data file's padding, then the end of the archive: two zero blocks */
        return member_complete(e, "grains.data") || gp_xw_tar_pad(e, x->member) || gp_xw_tar_end(e)
                   ? -1
                   : 1;
    }
}

/* ------------------------------------------------------------------ liggghts */

enum { G_HEAD = 0, G_TEMPLATE, G_SPHERES, G_TAIL, G_DIST_HEAD, G_DIST };

static int liggghts_head(gp_export *e)
{
    return gp_xw_printf(
        e,
        "# LIGGGHTS 3.8 input lines from grainpack (fourier-voronoi-3d): %llu grains as multisphere\n"
        "# templates of %llu spheres in all, SI units, density %.17g kg/m^3 (%.17g kg in all).\n"
        "# Template gpt<k> (multisphere type k) is grain k - 1: its clump's spheres about the\n"
        "# grain's centroid in the specimen's axes, its mass (density x the volume of its surface\n"
        "# mesh) and its inertia tensor about the centroid; use_density makes LIGGGHTS take them\n"
        "# as they are (its volume = mass / density). gpdist draws them by mass as the specimen\n"
        "# holds them. Include this file after create_box (atom type 1) and before inserting, e.g.\n"
        "#   fix             ms all multisphere\n"
        "#   include         FILE\n"
        "#   fix             ins all insert/pack seed 32452843 distributiontemplate gpdist &\n"
        "#                   orientation template insert_every once overlapcheck yes &\n"
        "#                   particles_in_region %llu region <region>\n"
        "# (\"orientation template\" keeps each grain's orientation; the comment before a template\n"
        "# has the grain's centroid in the specimen). LIGGGHTS warns that ntry is low: it is only\n"
        "# used for the spheres' CFD volume weights. The types must be the only multisphere ones.\n",
        (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs, e->info.density,
        e->info.density * e->info.volume, (unsigned long long)e->info.nitems);
}

/* the comment and the first line of grain e->index's template (loaded) */
static int template_head(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    unsigned long long k = (unsigned long long)e->index + 1;
    return gp_xw_printf(e,
                        "# grain %llu (cell %llu): centroid %.17g %.17g %.17g, volume %.17g\n"
                        "fix gpt%llu all particletemplate/multisphere %d atom_type 1 density "
                        "constant %.17g nspheres %llu ntry %d spheres &\n",
                        k - 1, (unsigned long long)g->cell, g->centroid[0], g->centroid[1],
                        g->centroid[2], g->volume, k, TEMPLATE_SEED, e->info.density,
                        (unsigned long long)g->sphere_count, TEMPLATE_NTRY);
}

static int template_sphere(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    double q[4];
    if (gp_xr_clump(e, g->sphere_first + e->sub, q)) return -1;
    return gp_xw_printf(e, "    %.17g %.17g %.17g %.17g &\n", q[0] - g->centroid[0],
                        q[1] - g->centroid[1], q[2] - g->centroid[2], q[3]);
}

static int template_tail(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    const double *I = g->inertia; /* xx yy zz xy xz yz -> Ixx Ixy Ixz Iyy Iyz Izz */
    return gp_xw_printf(e,
                        "    type %llu mass %.17g inertia_tensor %.17g %.17g %.17g %.17g %.17g "
                        "%.17g use_density\n",
                        (unsigned long long)e->index + 1, g->mass, I[0], I[3], I[4], I[1], I[5],
                        I[2]);
}

int gp_export_step_fv3d_liggghts(gp_export *e)
{
    double total = e->info.density * e->info.volume;
    switch (e->section) {
    case G_HEAD:
        e->index = 0;
        e->section = e->info.nitems ? G_TEMPLATE : G_DIST_HEAD;
        return liggghts_head(e) ? -1 : 0;
    case G_TEMPLATE:
        e->sub = 0;
        if (load_grain(e) || template_head(e)) return -1;
        e->section = e->x3.grain.sphere_count ? G_SPHERES : G_TAIL;
        return 0;
    case G_SPHERES:
        if (template_sphere(e)) return -1;
        if (++e->sub >= e->x3.grain.sphere_count) e->section = G_TAIL;
        return 0;
    case G_TAIL:
        if (template_tail(e)) return -1;
        e->section = ++e->index < e->info.nitems ? G_TEMPLATE : G_DIST_HEAD;
        return 0;
    case G_DIST_HEAD:
        if (e->info.nitems == 0) return 1;
        e->index = 0;
        e->section = G_DIST;
        return gp_xw_printf(e,
                            "# the templates by mass fraction (each grain's mass / %.17g kg)\n"
                            "fix gpdist all particledistribution/discrete %d %llu &\n",
                            total, DIST_SEED, (unsigned long long)e->info.nitems)
                   ? -1
                   : 0;
    default: {
        if (load_grain(e)) return -1;
        int last = e->index + 1 >= e->info.nitems;
        if (gp_xw_printf(e, "    gpt%llu %.17g%s\n", (unsigned long long)e->index + 1,
                         total > 0 ? e->x3.grain.mass / total : 0.0, last ? "" : " &"))
            return -1;
        e->index++;
        return last;
    }
    }
}

/* ------------------------------------------------------------------ yade */

/* grainpack_exact, in "#py " lines (the file comment says what it does) */
static const char *const yade_py[] = {
    "def grainpack_exact(path, clumps, shift=Vector3.Zero, scale=1.0, orientation=Quaternion.Identity):",
    "    \"\"\"Gives clump k of clumps (what ymport.textClumps(path, ...) returned: (clump id, member",
    "    ids) a grain) the mass, centroid and inertia tensor of grain k (the \"#grain\" lines of path),",
    "    moved by the same shift, scale and orientation. A body carrying them joins the clump while",
    "    its spheres weigh nothing, YADE computes the clump's frame from it (Clump::updateProperties),",
    "    and it leaves (erased: one body id stays vacant). Returns the clump ids.\"\"\"",
    "    from yade.wrapper import Body, Box, FrictMat, State",
    "    grains = [l.split()[1:] for l in open(path) if l.startswith(\"#grain \")]",
    "    if len(grains) != len(clumps):",
    "        raise ValueError(\"%s: %d grains, %d clumps\" % (path, len(grains), len(clumps)))",
    "    zero = O.materials.append(FrictMat(density=0))",
    "    R = orientation.toRotationMatrix()",
    "    slot, out = None, []",
    "    for g, (cid, mids) in zip(grains, clumps):",
    "        if int(g[1]) != len(mids):",
    "            raise ValueError(\"grain %s has %s spheres, its clump %d\" % (g[0], g[1], len(mids)))",
    "        v = [float(t) for t in g[2:]]",
    "        m = v[1] * scale ** 3",
    "        c = shift + scale * (orientation * Vector3(v[2], v[3], v[4]))",
    "        xx, yy, zz, xy, xz, yz = v[5:11]",
    "        I = R * Matrix3(xx, xy, xz, xy, yy, yz, xz, yz, zz) * R.transpose() * scale ** 5",
    "        vecs, vals = I.spectralDecomposition()",
    "        if vecs.determinant() < 0:",
    "            vecs = vecs * -1",
    "        q = Quaternion(vecs)",
    "        q.normalize()",
    "        mats = [O.bodies[i].material for i in mids]",
    "        for i in mids:",
    "            O.bodies[i].material = O.materials[zero]",
    "        # a member's orientation turns its inertia one way or the other (YADE's versions",
    "        # differ): the one whose clump has the grain's tensor is kept",
    "        for ori in (q.conjugate(), q):",
    "            b = Body()",
    "            b.shape = Box(extents=Vector3.Zero)",
    "            b.material = O.materials[zero]",
    "            b.state = State()",
    "            b.state.pos = c",
    "            b.state.ori = ori",
    "            b.state.mass = m",
    "            b.state.inertia = vals",
    "            if slot is None:",
    "                slot = O.bodies.append(b)",
    "            else:",
    "                O.bodies.insertAtId(b, slot)",
    "            O.bodies.addToClump([slot], cid)",
    "            O.bodies.erase(slot)",
    "            s = O.bodies[cid].state",
    "            Rc = s.ori.toRotationMatrix()",
    "            D = Matrix3(s.inertia[0], 0, 0, 0, s.inertia[1], 0, 0, 0, s.inertia[2])",
    "            if (Rc * D * Rc.transpose() - I).maxAbsCoeff() <= 1e-9 * I.maxAbsCoeff():",
    "                break",
    "        else:",
    "            raise RuntimeError(\"grain %s: YADE's clump does not take its inertia\" % g[0])",
    "        for i, mat in zip(mids, mats):",
    "            O.bodies[i].material = mat",
    "        out.append(cid)",
    "    return out",
};

enum { Y_HEAD = 0, Y_GRAIN, Y_SPHERES };

static int yade_head(gp_export *e)
{
    if (gp_xw_printf(
            e,
            "# grainpack fourier-voronoi-3d: %llu grains as clumps of %llu spheres, SI units (m, kg),\n"
            "# density %.17g kg/m^3 (%.17g kg in all). In YADE:\n"
            "#   clumps = ymport.textClumps(FILE, material=...)\n"
            "# makes one clump a grain, its mass and inertia summed from its spheres (their overlaps\n"
            "# counted twice); then\n"
            "#   exec(\"\".join(l[4:] for l in open(FILE) if l.startswith(\"#py \")))\n"
            "#   grainpack_exact(FILE, clumps)\n"
            "# gives each clump its grain's own mass, centroid and inertia, from the grain's surface\n"
            "# mesh (the \"#grain\" lines; give grainpack_exact textClumps' shift, scale and orientation\n"
            "# if you move the specimen).\n"
            "# #grain id nspheres volume(m^3) mass(kg) cx cy cz(m) Ixx Iyy Izz Ixy Ixz Iyz(kg m^2, about\n"
            "# the centroid, world axes; Ixy = -integral of rho x y dV)\n"
            "# x y z r clumpId\n",
            (unsigned long long)e->info.nitems, (unsigned long long)e->info.ndiscs,
            e->info.density, e->info.density * e->info.volume))
        return -1;
    for (size_t k = 0; k < sizeof yade_py / sizeof yade_py[0]; k++)
        if (gp_xw_printf(e, "#py %s\n", yade_py[k])) return -1;
    return 0;
}

static int yade_grain(gp_export *e)
{
    const gp_export_grain3 *g = &e->x3.grain;
    const double *I = g->inertia;
    return gp_xw_printf(e,
                        "#grain %llu %llu %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g "
                        "%.17g %.17g\n",
                        (unsigned long long)e->index, (unsigned long long)g->sphere_count,
                        g->volume, g->mass, g->centroid[0], g->centroid[1], g->centroid[2], I[0],
                        I[1], I[2], I[3], I[4], I[5]);
}

int gp_export_step_fv3d_yade(gp_export *e)
{
    switch (e->section) {
    case Y_HEAD:
        e->index = 0;
        e->section = Y_GRAIN;
        if (yade_head(e)) return -1;
        return e->info.nitems == 0;
    case Y_GRAIN:
        e->sub = 0;
        if (load_grain(e) || yade_grain(e)) return -1;
        if (e->x3.grain.sphere_count) e->section = Y_SPHERES;
        else return ++e->index >= e->info.nitems;
        return 0;
    default: {
        const gp_export_grain3 *g = &e->x3.grain;
        double q[4];
        if (gp_xr_clump(e, g->sphere_first + e->sub, q) ||
            gp_xw_printf(e, "%.17g %.17g %.17g %.17g %llu\n", q[0], q[1], q[2], q[3],
                         (unsigned long long)e->index))
            return -1;
        if (++e->sub < g->sphere_count) return 0;
        e->section = Y_GRAIN;
        return ++e->index >= e->info.nitems;
    }
    }
}
