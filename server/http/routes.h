/* routes.h -- the route table of grainpackd: every path the daemon serves, the methods it
 * answers there, what answers each and how, and its label in the metrics. One static const
 * table (routes.c), after redis's command table: the router (http.c) walks it to answer a
 * request, the metrics (jobs/metrics.h) read it for their route labels, tests/server/
 * test_routes.c checks it against docs/api.md. A route is added here and nowhere else (but
 * its handler, in http.c).
 *
 * Matching (gpd_route_match), as the router has always done it:
 *   - the path is the request target's path, without its query (libmicrohttpd splits it off);
 *   - one trailing slash is dropped, but not from "/" ("/v1/jobs/" is "/v1/jobs", "/v1/jobs//"
 *     matches nothing);
 *   - a parameter, "{id}" in a pattern, matches 1 to GPD_ROUTE_PARAM_MAX - 1 bytes without a
 *     "/" (whether an id is plausible is the handler's business: 404 not_found, not a miss);
 *   - everything else is compared byte for byte (case counts).
 * A path no pattern matches is a 404 not_found; a method a route does not answer a 405
 * method_not_allowed with the route's Allow header (gpd_route_allow). HEAD is answered
 * wherever GET is, by the GET handler.
 *
 * The table holds data only (no function of http.c): the handler of a method is a
 * gpd_handler, which http.c maps to its function, so that this module depends on nothing and
 * the metrics can read it without depending on the HTTP front.
 */
#ifndef GPD_ROUTES_H
#define GPD_ROUTES_H

#include <stddef.h>

/* the methods a route can answer, indices into gpd_route.op; HEAD is GPD_ROUTE_GET */
typedef enum gpd_route_method {
    GPD_ROUTE_GET = 0, /* GET and HEAD */
    GPD_ROUTE_POST,
    GPD_ROUTE_DELETE,
    GPD_ROUTE_NMETHODS
} gpd_route_method;

/* what answers a method of a route: one of http.c's handlers (GPD_H_NONE: the route does not
 * answer that method) */
typedef enum gpd_handler {
    GPD_H_NONE = 0,
    GPD_H_DASHBOARD, /* GET /                        the page (page.h) */
    GPD_H_METRICS,   /* GET /metrics                 metrics.h */
    GPD_H_HEALTH,    /* GET /v1/health */
    GPD_H_SCHEMA,    /* GET /v1/schema[?kind=K] */
    GPD_H_SHAPES,    /* POST /v1/shapes/analyze */
    GPD_H_LIST,      /* GET /v1/jobs?status=&limit=&after= */
    GPD_H_SUBMIT,    /* POST /v1/jobs */
    GPD_H_JOB,       /* GET /v1/jobs/{id} */
    GPD_H_CANCEL,    /* DELETE /v1/jobs/{id}[?purge=1] */
    GPD_H_RESULT,    /* GET /v1/jobs/{id}/result */
    GPD_H_SVG,       /* GET /v1/jobs/{id}/svg?view=V */
    GPD_H_EXPORT,    /* GET /v1/jobs/{id}/export?format=F */
    GPD_H_SPEC,      /* GET /v1/jobs/{id}/spec */
    GPD_H_SUMMARY,   /* GET /v1/jobs/{id}/summary */
    GPD_H_COUNT
} gpd_handler;

/* one method of a route */
typedef struct gpd_route_op {
    gpd_handler handler; /* GPD_H_NONE: 405 */
    int offload;         /* 1: run on the request pool (offload.h), off the HTTP threads: its
                            cost grows with the request body; such a method takes a body of
                            up to --max-body, any other one at most GPD_ROUTE_NO_BODY_MAX */
    int lane;            /* the pool's lane (offload.h: gpd_lane) when offloaded */
} gpd_route_op;

/* the body a method that takes none may carry (read and ignored): 413 above */
#define GPD_ROUTE_NO_BODY_MAX (64u * 1024u)

typedef struct gpd_route {
    const char *pattern; /* as docs/api.md writes it: "/v1/jobs/{id}/result" */
    const char *label;   /* its "route" label in grainpack_http_requests_total, the pattern
                            with ":id" for "{id}" (a "}" in a label value trips simple
                            Prometheus line parsers) */
    gpd_route_op op[GPD_ROUTE_NMETHODS]; /* by gpd_route_method */
} gpd_route;

/* the routes the table has room for (the metrics' counters are sized by it) */
#define GPD_ROUTES_MAX 16
/* the bytes of a path parameter, with its NUL: "{id}" matches at most 79 bytes */
#define GPD_ROUTE_PARAM_MAX 80
/* the label of requests no route matches */
#define GPD_ROUTE_OTHER_LABEL "other"

/* The table, in the order the metrics list it; *n its length (<= GPD_ROUTES_MAX). */
const gpd_route *gpd_routes(size_t *n);

/* The route of path (see "Matching" above), or NULL. Its parameter, if it has one, is copied
 * to param (NUL-terminated; param_size >= GPD_ROUTE_PARAM_MAX), else param is "". param may
 * be NULL. */
const gpd_route *gpd_route_match(const char *path, char *param, size_t param_size);

/* The index into gpd_route.op of an HTTP method ("HEAD" is GPD_ROUTE_GET), or -1 for a method
 * no route answers (OPTIONS, PUT, lower case...). */
int gpd_route_method_of(const char *method);

/* "GET", "POST", "DELETE" (NULL out of range): the method as docs/api.md heads it */
const char *gpd_route_method_name(int m);

/* Whether route r answers method m (a gpd_route_method; -1: no). */
int gpd_route_answers(const gpd_route *r, int m);

/* The Allow header of r's 405: its methods in the order GET, HEAD, POST, DELETE
 * ("GET, HEAD, DELETE"). A static string. */
const char *gpd_route_allow(const gpd_route *r);

#endif /* GPD_ROUTES_H */
