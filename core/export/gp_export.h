/* gp_export.h -- a finished specimen as the files DEM codes read (LAMMPS, LIGGGHTS, YADE,
 * VTK/ParaView, CSV, STL), produced as a pull stream so that a 230,000-sphere packing or a
 * 10,000-grain ODEC file never has to exist in memory as text.
 *
 * Two steps, because the service writes a job's result once and serves it many times:
 *
 *  1. gp_export_pack_3d() / gp_export_pack_2d() / gp_export_pack_fv3d() turn a specimen into a
 *     compact binary "pack" (layout below), built when the job finishes and stored next to its
 *     JSON result.
 *  2. gp_export_open() reads a pack through a byte-range reader (a memory buffer, an SQLite
 *     incremental blob, a file...) and gp_export_read() hands the file out in pieces of any
 *     size. Working memory is O(1) in the specimen size: one staging buffer of one record (a
 *     line) and a 64 KiB read cache; a fv3d pack's formats add a second 64 KiB window (for the
 *     grain records beside the arrays they walk) and, for vtk and stl, the shared icosphere and
 *     one grain's vertices: 72 bytes a direction (184 KB at mesh level 4), whatever the number
 *     of grains. A gp_export_reader (below) reads the pack's records themselves, for a caller
 *     that draws or measures the specimen rather than writing a file.
 *
 * The format families live in gp_export_lammps.c (lammps, liggghts), gp_export_lammps_relax.c
 * (lammps-relax), gp_export_yade.c, gp_export_vtk.c, gp_export_csv.c and, for the grains of a 3D
 * Fourier-Voronoi specimen, gp_export_fv3d.c (the pack's records), gp_export_fv3d_dem.c
 * (lammps, liggghts, yade) and gp_export_fv3d_mesh.c (vtk, stl), behind one small
 * record-writer interface (gp_export_internal.h). Everything is SI, as in the JSON result;
 * reals are written with %.17g, which reads back bit for bit.
 *
 * Ownership: a pack is malloc'ed by gp_export_pack_*() and is the caller's to free; an export
 * neither copies nor owns its source, which must outlive it (gp_export_destroy frees the
 * export's own buffers). Thread safety: no global state; one thread at a time per gp_export,
 * and any number of exports (of the same pack too) may run concurrently.
 *
 * Pack layout (native byte order and IEEE doubles, as the daemon reads what it wrote on the
 * same machine; the header carries a byte-order mark and a version, checked on open):
 *
 *   header, 128 bytes:
 *     char     magic[8]   "GPEXPACK"
 *     uint32   bom        0x01020304
 *     uint32   version    1
 *     uint32   dim        2, 3 or GP_EXPORT_FV3D (4: the grains of a 3D Fourier-Voronoi
 *                         specimen; the value only tells the packs apart)
 *     uint32   flags      GP_EXPORT_HAS_DESCRIPTORS, GP_EXPORT_VIEW_ONLY (2D);
 *                         GP_EXPORT_HAS_DEM (3D); GP_EXPORT_HAS_CLUMPS (fv3d)
 *     uint64   nitems     3D: spheres; 2D and fv3d: grains
 *     uint64   npoints    2D: contour points of all grains; fv3d: directions of the icosphere
 *     uint64   ndiscs     2D: ODEC discs of all grains; fv3d: clump spheres of all grains
 *     double   density    kg/m^3
 *     double   lo[3], hi[3]  the box (3D: [0, box]; 2D: the container's bounding box, z 0;
 *                         fv3d: the container's bounding box, its cells' vertices' extent)
 *     double   max_extent 2D: the largest grain's bounding-box diagonal (for LAMMPS' cutoff);
 *                         fv3d: the same of the placed meshes
 *     uint64   relax_bytes   3D with the DEM block: the size of lammps-relax's data file,
 *                            counted when the pack is made (0: not counted, as in packs made
 *                            before it was; a download counts it then)
 *     uint32   relax_layout  the data file layout it was counted for
 *     (zero padding to 128)
 *   3D: nitems records of 4 doubles x, y, z, r; then, with flag GP_EXPORT_HAS_DEM
 *       (gp_export_pack_3d_dem), the DEM block of 128 bytes that lammps-relax needs:
 *         char     magic[8]  "GPEXDEM3"
 *         double   young, poisson (k_s / k_n), friction_deg, damping   the spec's material
 *         double   relax_damping   local damping of the relaxation (gp_specimen3d.c's rule)
 *         double   gravity         m/s^2, along -z
 *         double   dt, scaled_radius  the DEM's time step and density scaling radius (stats)
 *         double   stability       the threshold of Eq. 7 (S_c)
 *         double   rmin, rmax      the smallest and largest radius of the spheres
 *         double   porosity, coordination_number   the result's (stats)
 *         int32    tiling[3]       (zero padding to 128)
 *   2D: nitems grain records of 10 x 8 bytes:
 *         uint64 point_first, point_count, disc_first, disc_count;
 *         double area, orientation_deg, elongation, roundness, circularity, regularity
 *       then npoints x (x, y) doubles, then ndiscs x (x, y, r) doubles.
 *   fv3d (gp_export_pack_fv3d): the fv3d block of 128 bytes:
 *         char     magic[8]  "GPEXFV3D"
 *         uint64   ntriangles   triangles of the shared icosphere
 *         uint64   data_bytes, rigid_bytes   lammps: the sizes of the tar's grains.data and
 *                            grains.rigid, counted when the pack is made (as relax_bytes)
 *         uint32   count_layout  the file layout they were counted for (another: counted
 *                            again at the download)
 *         uint32   (zero)
 *         double   volume       the sum of the grain volumes (m^3)
 *         double   rmin, rmax   the smallest and largest clump sphere (0 without clumps)
 *         (zero padding to 128)
 *       then nitems grain records of 176 bytes (gp_export_grain3, in this order):
 *         uint64 cell, sphere_first, sphere_count;
 *         double centre[3], rotation[4] (unit quaternion w, x, y, z), scale,
 *                volume (m^3), mass (kg, = density x volume), centroid[3],
 *                inertia[6] (kg m^2, = density x the mesh's, about the centroid, in the
 *                world's axes: xx, yy, zz, xy, xz, yz, the tensor's elements, xy = -integral
 *                of rho x y dV);
 *       then ndiscs clump spheres of 4 doubles x, y, z, r (world coordinates, grain by grain:
 *       grain g's are sphere_first .. sphere_first + sphere_count - 1); then nitems x npoints
 *       radii (doubles, grain by grain: the result's "radii"); then npoints directions of 3
 *       doubles; then ntriangles triangles of 3 uint32 (indices of directions, counter-clockwise
 *       seen from outside). Vertex k of grain g is centre + scale R(rotation) (radius_k
 *       direction_k), as gp_fv3d_grain_vertices places it, bit for bit.
 */
#ifndef GP_EXPORT_H
#define GP_EXPORT_H

#include <stddef.h>
#include <stdint.h>

#include "gp_error.h"
#include "gp_fv3d.h"
#include "gp_specimen2d.h"
#include "gp_specimen3d.h"

typedef enum gp_export_format {
    GP_EXPORT_LAMMPS = 0, /* LAMMPS data file (3D atom_style sphere; 2D hybrid sphere molecular) */
    GP_EXPORT_LIGGGHTS,   /* LIGGGHTS 3.8 data file, atom_style sphere (3D only) */
    GP_EXPORT_YADE,       /* ymport.text (3D: x y z r) / ymport.textClumps (2D: x y z r clump) */
    GP_EXPORT_VTK,        /* legacy VTK polydata, ASCII (ParaView, VTK readers) */
    GP_EXPORT_CSV,        /* 3D: x,y,z,r; 2D: grain,x,y,r (one disc per line) */
    GP_EXPORT_LAMMPS_RELAX, /* 3D: a tar of a LAMMPS data file and an input script that relaxes
                               the packing to S_c <= 1e-4 (needs a pack with GP_EXPORT_HAS_DEM) */
    GP_EXPORT_STL,        /* fv3d: ASCII STL, one solid a grain (its placed mesh) */
    GP_EXPORT_NFORMATS
} gp_export_format;

/* The formats of a fv3d pack (gp_export_pack_fv3d), in gp_export_fv3d_dem.c and
 * gp_export_fv3d_mesh.c (their file comments have the details):
 *   lammps    a tar of lammps-grains/: grains.data (atom_style hybrid sphere molecular, one
 *             atom a clump sphere, molecule = grain id + 1), grains.rigid (the infile of fix
 *             rigid/small: each body's mass, centre of mass and inertia tensor, the grain's own)
 *             and grains.in, the input lines that read them (LAMMPS 29Sep2021 and later);
 *   liggghts  LIGGGHTS 3.8 input lines: one fix particletemplate/multisphere a grain (its
 *             spheres about its centroid, its mass and inertia tensor, use_density) and a fix
 *             particledistribution/discrete of all of them by mass;
 *   yade      ymport.textClumps' text "x y z r clumpId", a "#grain" comment line before each
 *             grain's spheres with its exact mass, centroid and inertia, and in "#py " comment
 *             lines the Python function that gives each clump of textClumps those values;
 *   vtk       legacy ASCII polydata: every grain's surface as triangles, cell data grain_id,
 *             cell_id and volume;
 *   stl       ASCII STL, one solid "grain_<id>" a grain, %.17g vertices.
 * lammps, liggghts and yade need the clumps (GP_EXPORT_HAS_CLUMPS: outputs "clumps"); vtk and
 * stl need only the grains. */

#define GP_EXPORT_HAS_DESCRIPTORS 1u
#define GP_EXPORT_HAS_DEM 2u /* 3D: the pack ends with the DEM block (layout above) */
/* 2D: a view pack (gp_export_pack_2d_view): the grains' records and contours without ODEC
 * discs, for drawing them; no file is written from it (gp_export_open refuses it) */
#define GP_EXPORT_VIEW_ONLY 4u
/* fv3d: every grain has its clump of spheres (outputs "clumps") */
#define GP_EXPORT_HAS_CLUMPS 8u

/* The "dim" of a fv3d pack (its header, gp_export_info, gp_export_format_supports and
 * gp_export_format_list): the grains of a 3D Fourier-Voronoi specimen, meshes and clumps. */
#define GP_EXPORT_FV3D 4

/* The 2D default density (kg/m^3) when a spec has no material: quartz, 2650. */
#define GP_EXPORT_DEFAULT_DENSITY 2650.0

/* Parses a format name ("lammps", ...); -1 when unknown. */
int gp_export_format_parse(const char *name);
const char *gp_export_format_name(gp_export_format f);
/* Whether the format exists for packs of dimension dim (2, 3 or GP_EXPORT_FV3D). */
int gp_export_format_supports(gp_export_format f, int dim);
/* "lammps, liggghts, yade, vtk, csv, lammps-relax" for dim 3, "lammps, yade, vtk, csv" for
 * dim 2, "lammps, liggghts, yade, vtk, stl" for GP_EXPORT_FV3D ("" for any other). */
const char *gp_export_format_list(int dim);
/* File name extension (without dot) and MIME type of a format, as written from 2D and 3D
 * packs (stl: "stl", model/stl). */
const char *gp_export_format_extension(gp_export_format f);
const char *gp_export_format_mime(gp_export_format f);
/* The same for packs of dimension dim: a fv3d pack's lammps is a tar ("tar",
 * application/x-tar) and its liggghts input lines ("in", text/plain); every other pair is
 * gp_export_format_extension / _mime's. */
const char *gp_export_format_extension_in(gp_export_format f, int dim);
const char *gp_export_format_mime_in(gp_export_format f, int dim);
/* Whether format f of a pack of dimension dim needs the clumps (GP_EXPORT_HAS_CLUMPS): a fv3d
 * pack's lammps, liggghts and yade. gp_export_open refuses those without them (GP_ERR_INVALID);
 * a caller that answers a missing output apart from a failure checks this against
 * gp_export_pack_info's flags first. */
int gp_export_format_needs_clumps(gp_export_format f, int dim);

/* ---- packs ---- */

/* Packs a 3D specimen (which must carry its spheres) with the given density. *pack is
 * malloc'ed; free() it. */
gp_status gp_export_pack_3d(const gp_specimen3d *s, double density, void **pack, size_t *len,
                            gp_error *err);

/* The same, with the DEM block (GP_EXPORT_HAS_DEM) that lammps-relax needs: spec's material
 * (its density too), and s's DEM settings (stats.dt, stats.scaled_radius) and measures. */
gp_status gp_export_pack_3d_dem(const gp_specimen3d *s, const gp_spec3d *spec, void **pack,
                                size_t *len, gp_error *err);

/* Packs a 2D specimen, which must carry its ODEC discs (outputs "odec"). The box is the
 * bounding box of spec's container; descriptors are packed when spec->outputs asks for them. */
gp_status gp_export_pack_2d(const gp_specimen2d *s, const gp_spec2d *spec, double density,
                            void **pack, size_t *len, gp_error *err);

/* A view pack of a 2D specimen whose grains may lack ODEC discs (outputs without "odec"):
 * the layout of gp_export_pack_2d with no discs (ndiscs 0) and flag GP_EXPORT_VIEW_ONLY. Its
 * records are what the record reader (below) hands out, at 80 bytes a grain and 16 a contour
 * point: the service stores one with every 2D result that has grains, so that its pictures
 * need not parse the result's text; its exports still need the ODEC discs. */
gp_status gp_export_pack_2d_view(const gp_specimen2d *s, const gp_spec2d *spec, void **pack,
                                 size_t *len, gp_error *err);

/* Packs the grains of a 3D Fourier-Voronoi specimen with the given density (kg/m^3): their
 * poses, volumes, masses (density x volume), centroids and inertia tensors (density x the
 * mesh's), their clump spheres when every grain has one (flag GP_EXPORT_HAS_CLUMPS; a specimen
 * built without outputs "clumps" packs without, for vtk and stl), the shared icosphere and every
 * grain's radii (layout above). GP_ERR_INVALID: no specimen, a bad density, a grain without
 * radii, some grains with clumps and others without; GP_ERR_NOMEM. *pack is malloc'ed; free()
 * it. It takes O(N V) time (the grains' extents from their meshes, and lammps' file sizes
 * counted once as lammps-relax's are) and the pack's memory plus O(V), V the directions. */
gp_status gp_export_pack_fv3d(const gp_fv3d *s, double density, void **pack, size_t *len,
                              gp_error *err);

/* ---- streaming ---- */

/* Reads n bytes at offset off of the pack into dst; returns 0 on success. */
typedef int (*gp_export_read_fn)(void *user, uint64_t off, void *dst, size_t n);

typedef struct gp_export_source {
    gp_export_read_fn read;
    void *user;
    uint64_t size; /* bytes in the pack */
} gp_export_source;

/* A source over a pack in memory (the pack must outlive the source's use). */
gp_export_source gp_export_memory_source(const void *pack, size_t len);

typedef struct gp_export gp_export;

/* Opens an export of the pack behind src in format f. GP_ERR_INVALID when the pack is not one
 * (magic, byte order, version, sizes), is a view pack (GP_EXPORT_VIEW_ONLY: a caller tells
 * those apart first with gp_export_pack_info), the format does not exist for its dimension,
 * or the format is lammps, liggghts or yade and a fv3d pack has no clumps ("... needs the
 * clumps output (outputs must include \"clumps\")"). The source must stay valid until
 * gp_export_destroy. */
gp_status gp_export_open(gp_export_format f, const gp_export_source *src, gp_export **out,
                         gp_error *err);

/* Copies up to cap (> 0) bytes of the file into buf; *n = 0 means the end. GP_ERR_INVALID when the
 * source failed or the pack is inconsistent (the file is then incomplete: drop it). */
gp_status gp_export_read(gp_export *e, char *buf, size_t cap, size_t *n, gp_error *err);

void gp_export_destroy(gp_export *e);

/* ---- reading a pack's records ----
 *
 * For a caller that wants the specimen rather than a file (the service draws its SVG views from
 * the pack): a reader opens a pack with the checks of gp_export_open (magic, byte order,
 * version, sizes, DEM block) and hands out its records by index, in any order, through the same
 * 64 KiB read cache. Reads near the previous one come from the cache, so a caller that walks two
 * arrays together (each grain's record and its contour points) keeps a reader for each.
 * A read returns GP_OK, or GP_ERR_INVALID for a record the pack does not have (a sphere of a 2D
 * pack, an index past its count), a failed source read, or a grain record whose points or discs
 * lie outside their arrays; the reader stays usable. Ownership and threads as for a gp_export:
 * the source must outlive the reader; one thread at a time per reader, any number of readers
 * (of the same pack too) at once. */

typedef struct gp_export_reader gp_export_reader;

/* A pack's header (layout above). */
typedef struct gp_export_info {
    int dim;            /* 2, 3 or GP_EXPORT_FV3D */
    unsigned flags;     /* GP_EXPORT_HAS_DESCRIPTORS, GP_EXPORT_HAS_DEM, GP_EXPORT_HAS_CLUMPS */
    uint64_t nitems;    /* 3D: spheres; 2D and fv3d: grains */
    uint64_t npoints;   /* 2D: contour points of all grains; fv3d: directions */
    uint64_t ndiscs;    /* 2D: ODEC discs of all grains; fv3d: clump spheres of all grains */
    double density;     /* kg/m^3 */
    double lo[3], hi[3];/* the box (2D: the container's bounding box, z 0) */
    double max_extent;  /* 2D, fv3d: the largest grain's bounding-box diagonal */
    uint64_t ntriangles;/* fv3d: triangles of the shared icosphere */
    double volume;      /* fv3d: the sum of the grain volumes (m^3) */
} gp_export_info;

/* One fv3d grain record (layout above): its clump spheres are sphere_first .. sphere_first +
 * sphere_count - 1 (none without GP_EXPORT_HAS_CLUMPS), inside the pack's array. SI units;
 * mass = density x volume, inertia about the centroid in the world's axes (xx, yy, zz, xy,
 * xz, yz: the tensor's elements). */
typedef struct gp_export_grain3 {
    uint64_t cell, sphere_first, sphere_count;
    double centre[3], rotation[4], scale, volume, mass, centroid[3], inertia[6];
} gp_export_grain3;

/* One 2D grain record. Its contour (the result's, point for point) is points point_first ..
 * point_first + point_count - 1, its ODEC discs are discs disc_first .. disc_first +
 * disc_count - 1; both ranges lie inside the pack's arrays. Values are the result's raw
 * doubles: the four descriptors are NaN in a pack without GP_EXPORT_HAS_DESCRIPTORS, and any
 * value may be non-finite where the result's is (the JSON result writes those as null). */
typedef struct gp_export_grain {
    uint64_t point_first, point_count, disc_first, disc_count;
    double area, orientation_deg, elongation, roundness, circularity, regularity;
} gp_export_grain;

/* The header of the pack behind src, checked as gp_export_open checks it (GP_ERR_INVALID when
 * it is not a pack or cannot be read, GP_ERR_NOMEM). */
gp_status gp_export_pack_info(const gp_export_source *src, gp_export_info *info, gp_error *err);

/* Opens a reader of the pack behind src (GP_ERR_INVALID when it is not one, GP_ERR_NOMEM). */
gp_status gp_export_reader_open(const gp_export_source *src, gp_export_reader **out,
                                gp_error *err);
/* The pack's header; valid until gp_export_reader_destroy. */
const gp_export_info *gp_export_reader_info(const gp_export_reader *r);
/* 3D: sphere i as x, y, z, r (m). */
gp_status gp_export_reader_sphere(gp_export_reader *r, uint64_t i, double q[4], gp_error *err);
/* 2D: grain g's record. */
gp_status gp_export_reader_grain(gp_export_reader *r, uint64_t g, gp_export_grain *out,
                                 gp_error *err);
/* 2D: contour point k (of all grains' points) as x, y; ODEC disc k as x, y, r. */
gp_status gp_export_reader_point(gp_export_reader *r, uint64_t k, double p[2], gp_error *err);
gp_status gp_export_reader_disc(gp_export_reader *r, uint64_t k, double d[3], gp_error *err);
/* fv3d: grain g's record; clump sphere k (of all grains') as x, y, z, r; direction k of the
 * icosphere; triangle t (indices of directions, checked below npoints); and the npoints placed
 * vertices of grain g into xyz (3 x npoints doubles), as gp_fv3d_grain_vertices gives them. */
gp_status gp_export_reader_grain3(gp_export_reader *r, uint64_t g, gp_export_grain3 *out,
                                  gp_error *err);
gp_status gp_export_reader_clump_sphere(gp_export_reader *r, uint64_t k, double q[4],
                                        gp_error *err);
gp_status gp_export_reader_direction(gp_export_reader *r, uint64_t k, double d[3], gp_error *err);
gp_status gp_export_reader_triangle(gp_export_reader *r, uint64_t t, uint32_t tri[3],
                                    gp_error *err);
gp_status gp_export_reader_vertices(gp_export_reader *r, uint64_t g, double *xyz, gp_error *err);
/* fv3d: the npoints radii of grain g into radii (the result's "radii", the same doubles), for a
 * caller that places the vertices itself. */
gp_status gp_export_reader_radii(gp_export_reader *r, uint64_t g, double *radii, gp_error *err);
void gp_export_reader_destroy(gp_export_reader *r);

#endif /* GP_EXPORT_H */
