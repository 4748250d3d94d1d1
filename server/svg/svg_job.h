/* svg_job.h -- one SVG view of a stored job as a stream: what GET /v1/jobs/{id}/svg serves.
 *
 * The view reads the job's summary (store_get_summary: stats, warnings, container, box) and,
 * when it draws geometry, its items one at a time: 2D grains and 3D spheres from the job's
 * pack (SQLite incremental blob I/O, as the export download; a 2D job without odec stores a
 * view pack, its grains without discs, for this), cells (which packs do not hold), and grains
 * or spheres of a job without a pack, from the stored result text, walked element by element
 * (server/util/json_scan.h). Memory is bounded whatever the job's size: the summary, one
 * item, two 64 KiB caches, the private connections' page caches (256 KiB each) and a staging
 * buffer of about 16 KiB of SVG; nothing is proportional to the result.
 *
 * The stream holds private SQLite connections: read it from one thread at a time, and close
 * it. Closing gives the freed heap back to the system (malloc_trim), so that the daemon's RSS
 * returns to its idle value after a large picture. */
#ifndef GPD_SVG_JOB_H
#define GPD_SVG_JOB_H

#include <stddef.h>

#include "svg/svg.h"

typedef struct svg_job svg_job;

typedef enum {
    SVG_JOB_OK = 0,
    SVG_JOB_NOT_FOUND,   /* unknown job */
    SVG_JOB_NOT_READY,   /* the job has not succeeded (its status in status) */
    SVG_JOB_STORE_ERROR, /* the database failed */
    SVG_JOB_BUSY,        /* no database connection for the job's values (store.h STORE_BUSY) */
    SVG_JOB_VIEW_ERROR   /* the view cannot be drawn: err (400, 409, 500 and the message) */
} svg_job_rc;

/* Opens view of job id, whose kind is known (store_get_text(id, "kind")); opt may be NULL.
 * On SVG_JOB_OK *out is the stream. status gets the job's status. */
svg_job_rc svg_job_open(const char *id, const char *kind, const char *view,
                        const gp_svg_options *opt, svg_job **out, char status[16], gpd_err *err);

/* Copies up to cap bytes of the document into buf; *n = 0 at the end. -1 when reading the job
 * failed mid-way (logged; drop the document). */
int svg_job_read(svg_job *j, char *buf, size_t cap, size_t *n);

void svg_job_close(svg_job *j);

#endif /* GPD_SVG_JOB_H */
