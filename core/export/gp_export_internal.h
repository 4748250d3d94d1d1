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

/* The 3D DEM block of a pack (gp_export.h has its layout); present = 0 without one. */
typedef struct gp_xdem {
    int present;
    double young, poisson, friction_deg, damping, relax_damping, gravity;
    double dt, scaled_radius, stability, rmin, rmax, porosity, coordination;
    int32_t tiling[3];
} gp_xdem;

struct gp_export {
    gp_export_format format;
    gp_export_source src;
    gp_export_info info;  /* the header */
    gp_xdem dem;          /* 3D: the DEM block, if the pack has one */
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

/* Record readers (0 on success, -1 with e->err set). */
int gp_xr_sphere(gp_export *e, uint64_t i, double q[4]);
int gp_xr_grain(gp_export *e, uint64_t g, gp_export_grain *out);
int gp_xr_point(gp_export *e, uint64_t k, double p[2]);
int gp_xr_disc(gp_export *e, uint64_t k, double d[3]);

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

/* lammps-relax's data file layout: a pack's counted size (gp_export.h, "relax_bytes") holds for
 * this layout only; change it with the data file's format, and older packs are counted again
 * at the download. */
#define GP_EXPORT_RELAX_LAYOUT 1u
/* The bytes of lammps-relax's data file for the pack of e (an export opened in that format,
 * not yet read): every atom line formatted once. 0, or -1 with e->err set. */
int gp_export_relax_count(gp_export *e, uint64_t *bytes);

#endif /* GP_EXPORT_INTERNAL_H */
