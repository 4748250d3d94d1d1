/* file_errors.h -- the last failed write of a file the workers make themselves (the temporary
 * file of a large result), for GET /v1/health.
 *
 * Why: a full disk may fail a result's temporary file (beside the SQLite database, or in TMPDIR
 * for PostgreSQL) while the database's own small writes still pass; the job then fails with
 * store_error, and health must say that writes fail as it does for the database's
 * (store_last_write_error, store.h), not "ok". Thread-safe: one mutex. */
#ifndef GPD_FILE_ERRORS_H
#define GPD_FILE_ERRORS_H

#include <stddef.h>

/* Records a failed write: what was being written and errno's err. */
void gpd_file_error_note(const char *what, int err);

/* The last failed write as store_last_write_error gives the database's: 1 with its message
 * ("what: strerror"), time (RFC 3339) and how many have failed since the start, or 0 when none
 * has failed within the last window_s seconds. */
int gpd_file_error_last(double window_s, char *msg, size_t msg_len, char at[40], long *count);

#endif /* GPD_FILE_ERRORS_H */
