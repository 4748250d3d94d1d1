/* http.h -- the HTTP front of grainpackd (libmicrohttpd): routing, bodies, errors.
 *
 * Routes: one table, routes.c (routes.h), walked by the router and read by the metrics; each
 * route and method is described in docs/api.md under "### METHOD /path" (the contract is
 * shared/spec/api.md; tests/server/test_routes.c checks every route has its heading). A path
 * no route matches is 404 not_found, a method its route does not answer 405
 * method_not_allowed with an Allow header, an {id} that cannot be a job id 404 not_found.
 * HEAD is accepted wherever GET is. Every 4xx/5xx body is
 *   {"error": {"code": "...", "message": "...", "pointer": "/json/pointer"}}
 * (pointer only where a field of the spec or a query parameter is at fault).
 *
 * Before routing (docs/api.md, "Limits" and "Origin, Host and security headers"):
 *   414 uri_too_long      the request target (path and query) is over GPD_MAX_URL bytes
 *   403 forbidden_host    the Host header names a host this daemon does not answer to
 *                         (DNS rebinding): accepted are localhost, 127.0.0.1, [::1], the
 *                         --listen host (as given and as bound), the host of each allowed
 *                         origin, and for a daemon on 0.0.0.0 / [::] also any IP address and
 *                         the machine's host name. The Host port is not compared.
 *   403 forbidden_origin  an Origin header other than the daemon's own address (the page's
 *                         origin equals the Host it sent, or is http://NAME:PORT with NAME one
 *                         of the daemon's own names above and PORT its port) or an origin given
 *                         with --allow-origin. No Origin (curl, scripts): no check.
 * An allowed Origin gets Access-Control-Allow-Origin, and its preflight (OPTIONS with
 * Access-Control-Request-Method) 204. GET / carries a Content-Security-Policy with the
 * SHA-256 of its inline script and style; every response has X-Content-Type-Options: nosniff
 * and X-Frame-Options: DENY.
 */
#ifndef GPD_HTTP_H
#define GPD_HTTP_H

#include <stddef.h>

#include "http/origin.h" /* gpd_allow_origins */

typedef struct gpd_http_config {
    int listen_fd;               /* bound and listening (gpd_listen_socket) */
    unsigned threads;            /* MHD thread pool size */
    unsigned max_connections;    /* connection limit (main.c keeps it within the descriptors
                                    the process may open, less a reserve) */
    unsigned per_ip;             /* connections of one client address at most; 0 = no limit */
    unsigned timeout_s;          /* idle timeout per connection */
    unsigned header_timeout_s;   /* a request's headers must be in within this (conns.h) */
    unsigned max_pending;        /* requests each lane of the request pool queues (offload.h):
                                    503 busy beyond */
    size_t max_body;             /* body limit in bytes of the methods that take one (POST
                                    /v1/jobs, POST /v1/shapes/analyze; 413 above) */
    double max_result_mb;        /* specs whose estimated result is larger get 422 too_large */
    long max_queued;             /* a submit while this many jobs are queued gets 503 queue_full
                                    (with Retry-After); 0 = no cap */
    const char *listen;          /* the --listen value as given (its host is an accepted Host) */
    const char *host;            /* the bound host as gpd_listen_socket wrote it */
    int port;                    /* the bound port */
} gpd_http_config;

/* request targets longer than this get 414 uri_too_long (JSON); libmicrohttpd itself answers
 * (with its own HTML body) only past its per-connection buffer of GPD_CONN_MEMORY bytes */
#define GPD_MAX_URL 8192
/* a request line and headers of more bytes than this get 431 headers_too_large (JSON); past
 * GPD_CONN_MEMORY libmicrohttpd answers 431 itself, with its own HTML body */
#define GPD_MAX_HEADERS (64u * 1024u)
#define GPD_CONN_MEMORY (1024u * 1024u)
/* A body announced over its limit by a client that does not wait for 100 Continue is read and
 * dropped, up to this many bytes over the limit, before the 413: a client that is still
 * sending when the answer comes and the connection closes sees a reset, not the answer. */
#define GPD_DRAIN_MAX ((size_t)64 << 20)

/* Parses "HOST:PORT" ("[v6]:PORT", ":PORT" = 127.0.0.1), binds and listens. Returns the fd
 * and the bound port in *port (the actual one when PORT was 0), -1 with a message on stderr
 * on failure. host_out receives the host as it should appear in a URL. */
int gpd_listen_socket(const char *listen, char *host_out, size_t host_len, int *port);

int gpd_http_start(const gpd_http_config *cfg);
/* Stops accepting, closes connections, joins the pool. */
void gpd_http_stop(void);

#endif /* GPD_HTTP_H */
