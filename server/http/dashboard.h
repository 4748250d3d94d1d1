/* dashboard.h -- the dashboard page served at GET / (text/html; charset=utf-8).
 *
 * One self-contained page (inline CSS and JS, nothing fetched from elsewhere) that lists jobs
 * (GET /v1/jobs), polls them every second (progress bar, phase, error), submits a spec from a
 * textarea (POST /v1/jobs), cancels (DELETE /v1/jobs/{id}), shows the SVG views of a finished
 * job (/v1/jobs/{id}/svg?view=V) and links its exports (/v1/jobs/{id}/export?format=F).
 */
#ifndef GP_DASHBOARD_H
#define GP_DASHBOARD_H

/* The page, static and NUL-terminated. */
const char *gp_dashboard_html(void);

#endif /* GP_DASHBOARD_H */
