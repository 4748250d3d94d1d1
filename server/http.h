/* http.h -- the HTTP front of grainpackd (libmicrohttpd): routing, bodies, errors.
 *
 * Routes (shared/spec/api.md; extensions marked +):
 *   GET  /                         dashboard (text/html)
 *   GET  /v1/health                liveness, queue depth, workers
 *   GET  /v1/schema[?kind=K]       the JSON Schema (+ ?kind= one kind's schema)
 *   POST /v1/jobs                  201 job object (+ full job object, not only id/status), Location
 *   GET  /v1/jobs?status=&limit=&after=   newest first, keyset cursor "next"
 *   GET  /v1/jobs/{id}             job object
 *   DELETE /v1/jobs/{id}           cancel (200 job object; 409 already_finished)
 *   GET  /v1/jobs/{id}/result      result JSON (409 not_ready)
 *   GET  /v1/jobs/{id}/svg?view=V  image/svg+xml (409 not_ready)
 *   GET  /v1/jobs/{id}/export?format=F   (501 not_implemented for now)
 *   GET  /v1/jobs/{id}/spec        + the effective spec (defaults filled in)
 * HEAD is accepted wherever GET is. Every 4xx/5xx body is
 *   {"error": {"code": "...", "message": "...", "pointer": "/json/pointer"}}
 * (pointer only where a field of the spec or a query parameter is at fault).
 */
#ifndef GPD_HTTP_H
#define GPD_HTTP_H

#include <stddef.h>

typedef struct gpd_http_config {
    int listen_fd;               /* bound and listening (gpd_listen_socket) */
    unsigned threads;            /* MHD thread pool size */
    unsigned max_connections;    /* connection limit */
    unsigned timeout_s;          /* idle timeout per connection */
    size_t max_body;             /* request body limit in bytes (413 above) */
    double max_result_mb;        /* specs whose estimated result is larger get 422 too_large */
} gpd_http_config;

/* Parses "HOST:PORT" ("[v6]:PORT", ":PORT" = 127.0.0.1), binds and listens. Returns the fd
 * and the bound port in *port (the actual one when PORT was 0), -1 with a message on stderr
 * on failure. host_out receives the host as it should appear in a URL. */
int gpd_listen_socket(const char *listen, char *host_out, size_t host_len, int *port);

int gpd_http_start(const gpd_http_config *cfg);
/* Stops accepting, closes connections, joins the pool. */
void gpd_http_stop(void);

#endif /* GPD_HTTP_H */
