/* gp_export_internal.h -- the record-writer interface shared by the export format families.
 *
 * A format is a step function called by gp_export_read() whenever its staging buffer is empty.
 * Each call writes one record (a line, or a header block) with gp_xw_printf() and advances
 * e->section / e->index / e->sub; it returns 0 while there is more, 1 after the last record and
 * -1 on a failed read (the reader functions below set the error). Keeping a step to one record
 * is what bounds memory: the staging buffer only ever holds the largest single record.
 */
#ifndef GP_EXPORT_INTERNAL_H
#define GP_EXPORT_INTERNAL_H

#include "gp_export.h"

#define GP_PACK_MAGIC "GPEXPACK"
#define GP_PACK_BOM 0x01020304u
#define GP_PACK_VERSION 1u
#define GP_PACK_HEADER 128u
#define GP_PACK_GRAIN 80u /* bytes per 2D grain record */
#define GP_PACK_DEM 128u  /* bytes of the 3D DEM block (GP_EXPORT_HAS_DEM) */
#define GP_PACK_DEM_MAGIC "GPEXDEM3"
#define GP_PACK_FV3D 128u   /* bytes of the fv3d block */
#define GP_PACK_GRAIN3 176u /* bytes per fv3d grain record */
#define GP_PACK_FV3D_MAGIC "GPEXFV3D"

/* The 3D DEM block of a pack (gp_export.h has its layout); present = 0 without one. */
typedef struct gp_xdem {
    int present;
    double young, poisson, friction_deg, damping, relax_damping, gravity;
    double dt, scaled_radius, stability, rmin, rmax, porosity, coordination;
    int32_t tiling[3];
} gp_xdem;

/* A fv3d pack's block (gp_export.h) and the state of its formats. */
typedef struct gp_x3 {
    uint64_t data_bytes, rigid_bytes; /* lammps: the tar members' sizes (0: not counted) */
    double rmin, rmax;                /* clump spheres */
    uint64_t off_radii, off_dirs, off_tris; /* byte offsets of the arrays */
    gp_export_grain3 grain;           /* the grain at e->index, loaded by the family */
    double rho;                       /* lammps: the density of its atoms */
    double *verts;                    /* vtk, stl: grain e->index's vertices (3 x npoints) */
    double *dirs;                     /* the icosphere's directions, loaded once */
    uint32_t *tris;                   /* the icosphere's triangles, loaded once */
    uint64_t member, member_written;  /* lammps: the tar member being written, its bytes */
    /* the second read window: grain records, beside the array a format walks */
    unsigned char *cache;
    uint64_t cache_off;
    size_t cache_len;
} gp_x3;

struct gp_export {
    gp_export_format format;
    gp_export_source src;
    gp_export_info info;  /* the header */
    gp_xdem dem;          /* 3D: the DEM block, if the pack has one */
    gp_x3 x3;             /* fv3d */
    uint64_t off_items, off_points, off_discs; /* byte offsets of the arrays */
    /* read cache */
    unsigned char *cache;
    uint64_t cache_off;
    size_t cache_len;
    /* staging buffer: the current record */
    char *buf;
    size_t len, pos, cap;
    /* the format's cursor */
    int (*step)(gp_export *e);
    int section;
    uint64_t index, sub;
    gp_export_grain grain; /* the grain at e->index (2D), loaded by the family */
    double aux;           /* per-grain scratch (e.g. LAMMPS 2D density scale) */
    uint64_t file_bytes;  /* lammps-relax: size of the data file in the tar */
    uint64_t relax_bytes; /* lammps-relax: that size as counted into the pack (0: not) */
    uint64_t written;     /* lammps-relax: bytes of the data file written so far */
    int ntypes;           /* lammps-relax: size classes (atom types) */
    double type_ratio;    /* lammps-relax: radius ratio of one class */
    int done;
    gp_error err;
    int failed;
};

/* Appends formatted text to the staging buffer (grows it); -1 on out of memory. */
int gp_xw_printf(gp_export *e, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Appends n raw bytes (p == NULL: n zero bytes); -1 on out of memory. */
int gp_xw_bytes(gp_export *e, const void *p, size_t n);

/* POSIX ustar members for the formats that are a tar (gp_export_tar.c); each returns 0, or -1
 * on out of memory:
 *   header  the header block of a file (type '0') or a folder ('5', size 0) of size bytes, with
 *           owner, group and time 0 (a job gives the same bytes at every download);
 *   file    a file whose size is known once it is written: a header block, the file as write
 *           appends it (its -1 passed on), the header filled in with its size, then the padding;
 *   pad     the zero bytes that fill a member of size bytes up to whole blocks;
 *   end     the two zero blocks that end an archive. */
#define GP_XW_TAR_BLOCK 512
#define GP_XW_TAR_MAX_SIZE 077777777777ull /* a member's size: 11 octal digits */
int gp_xw_tar_header(gp_export *e, const char *name, char type, uint64_t size);
int gp_xw_tar_file(gp_export *e, const char *name, int (*write)(gp_export *e));
int gp_xw_tar_pad(gp_export *e, uint64_t size);
int gp_xw_tar_end(gp_export *e);

/* Record readers (0 on success, -1 with e->err set). */
int gp_xr_sphere(gp_export *e, uint64_t i, double q[4]);
int gp_xr_grain(gp_export *e, uint64_t g, gp_export_grain *out);
int gp_xr_point(gp_export *e, uint64_t k, double p[2]);
int gp_xr_disc(gp_export *e, uint64_t k, double d[3]);
/* A window of the pack (the read cache): [off, off + n) with n <= 64 KiB; NULL with e->err set.
 * gp_xr_window2 reads through the second window (allocated at its first use). */
const unsigned char *gp_xr_window(gp_export *e, uint64_t off, size_t n);
const unsigned char *gp_xr_window2(gp_export *e, uint64_t off, size_t n);

/* fv3d records (gp_export_fv3d.c; 0, or -1 with e->err set): grain g's record (through the
 * second window; a sphere range outside the array refused), clump sphere k, direction k,
 * triangle t (an index past the directions refused), and grain g's placed vertices into xyz
 * (3 x npoints doubles; g's record in gr) with the directions loaded once into e->x3.dirs. */
int gp_xr_grain3(gp_export *e, uint64_t g, gp_export_grain3 *out);
int gp_xr_clump(gp_export *e, uint64_t k, double q[4]);
int gp_xr_direction(gp_export *e, uint64_t k, double d[3]);
int gp_xr_triangle(gp_export *e, uint64_t t, uint32_t tri[3]);
int gp_x3_vertices(gp_export *e, uint64_t g, const gp_export_grain3 *gr, double *xyz);
/* The icosphere into e->x3.dirs and e->x3.tris (triangles checked), once. */
int gp_x3_mesh(gp_export *e);
/* The fv3d block after the header into e->x3 and e->info; -1 when it is not one. */
int gp_x3_read_block(gp_export *e);
/* The byte size a fv3d pack of these counts must have (as a double: a corrupt count cannot
 * wrap). */
double gp_x3_pack_size(const gp_export_info *in);

/* A format that is a header, then one line per sphere (3D) or per ODEC disc (2D, grain by
 * grain, disc e->sub of grain e->index): lammps / liggghts, yade and csv. gp_xw_lines() is the
 * step of such a format: section 0 writes the header and loads grain 0 (2D), then each call
 * writes the line of the next sphere or disc, loading the next grain after a grain's last
 * disc. The writers return 0, or -1 with e->err set:
 *   header  the header record (e->index and e->sub are 0);
 *   sphere  the line of sphere e->index, q = x, y, z, r;
 *   disc    the line of disc e->sub of grain e->index (in e->grain), d = x, y, r;
 *   grain   loads grain e->index into e->grain (NULL: gp_xr_grain alone). */
typedef struct gp_xlines {
    int (*header)(gp_export *e);
    int (*sphere)(gp_export *e, const double q[4]);
    int (*disc)(gp_export *e, const double d[3]);
    int (*grain)(gp_export *e);
} gp_xlines;

int gp_xw_lines(gp_export *e, const gp_xlines *f);

/* The step functions of the families. */
int gp_export_step_lammps(gp_export *e);     /* lammps (3D and 2D) and liggghts */
int gp_export_step_yade(gp_export *e);
int gp_export_step_vtk3d(gp_export *e);
int gp_export_step_vtk2d(gp_export *e);
int gp_export_step_csv(gp_export *e);
int gp_export_step_lammps_relax(gp_export *e);
int gp_export_step_fv3d_lammps(gp_export *e);   /* gp_export_fv3d_dem.c */
int gp_export_step_fv3d_liggghts(gp_export *e);
int gp_export_step_fv3d_yade(gp_export *e);
int gp_export_step_fv3d_vtk(gp_export *e);      /* gp_export_fv3d_mesh.c */
int gp_export_step_fv3d_stl(gp_export *e);

/* lammps' tar of a fv3d pack: its members' layout (the counted sizes in a fv3d block hold for
 * this layout only, as GP_EXPORT_RELAX_LAYOUT), and the sizes of grains.data and grains.rigid
 * for the pack of e (an export opened in format lammps, not yet read): every line formatted
 * once. 0, or -1 with e->err set. */
#define GP_EXPORT_FV3D_LAYOUT 1u
int gp_export_fv3d_count(gp_export *e, uint64_t *data_bytes, uint64_t *rigid_bytes);

/* lammps-relax's data file layout: a pack's counted size (gp_export.h, "relax_bytes") holds for
 * this layout only; change it with the data file's format, and older packs are counted again
 * at the download. */
#define GP_EXPORT_RELAX_LAYOUT 1u
/* The bytes of lammps-relax's data file for the pack of e (an export opened in that format,
 * not yet read): every atom line formatted once. 0, or -1 with e->err set. */
int gp_export_relax_count(gp_export *e, uint64_t *bytes);

#endif /* GP_EXPORT_INTERNAL_H */
