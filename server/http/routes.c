/* routes.c -- the route table and its matcher (routes.h). */
#include "http/routes.h"

#include <string.h>

#include "http/offload.h"

#define ON_GET(h) [GPD_ROUTE_GET] = {(h), 0, 0}
#define ON_POST_OFFLOADED(h, lane) [GPD_ROUTE_POST] = {(h), 1, (lane)}
#define ON_DELETE(h) [GPD_ROUTE_DELETE] = {(h), 0, 0}

/* A row: the pattern (as api.md heads it), the metrics label, and for each method it answers
 * its handler (http.c) and whether it is offloaded (run on the request pool, in which lane).
 * In the order grainpack_http_requests_total lists the routes (api.md, "GET /metrics"). */
static const gpd_route table[] = {
    {"/", "/", {ON_GET(GPD_H_DASHBOARD)}},
    {"/metrics", "/metrics", {ON_GET(GPD_H_METRICS)}},
    {"/v1/health", "/v1/health", {ON_GET(GPD_H_HEALTH)}},
    {"/v1/schema", "/v1/schema", {ON_GET(GPD_H_SCHEMA)}},
    /* the analysis costs CPU in proportion to the body: off the HTTP threads, in a lane of
     * its own (seconds each: submits must not wait behind it) */
    {"/v1/shapes/analyze", "/v1/shapes/analyze",
     {ON_POST_OFFLOADED(GPD_H_SHAPES, GPD_LANE_ANALYSIS)}},
    /* parsing and validating a body costs CPU in proportion to it: off the HTTP threads */
    {"/v1/jobs", "/v1/jobs", {ON_GET(GPD_H_LIST), ON_POST_OFFLOADED(GPD_H_SUBMIT, GPD_LANE_SPEC)}},
    {"/v1/jobs/{id}", "/v1/jobs/:id", {ON_GET(GPD_H_JOB), ON_DELETE(GPD_H_CANCEL)}},
    {"/v1/jobs/{id}/result", "/v1/jobs/:id/result", {ON_GET(GPD_H_RESULT)}},
    {"/v1/jobs/{id}/svg", "/v1/jobs/:id/svg", {ON_GET(GPD_H_SVG)}},
    {"/v1/jobs/{id}/export", "/v1/jobs/:id/export", {ON_GET(GPD_H_EXPORT)}},
    {"/v1/jobs/{id}/spec", "/v1/jobs/:id/spec", {ON_GET(GPD_H_SPEC)}},
    {"/v1/jobs/{id}/summary", "/v1/jobs/:id/summary", {ON_GET(GPD_H_SUMMARY)}},
};
#define NROUTES (sizeof table / sizeof *table)
_Static_assert(NROUTES <= GPD_ROUTES_MAX, "the route table is over GPD_ROUTES_MAX");

#undef ON_GET
#undef ON_POST_OFFLOADED
#undef ON_DELETE

const gpd_route *gpd_routes(size_t *n)
{
    if (n) *n = NROUTES;
    return table;
}

/* Whether path[0..len) matches pattern, its parameter (if any) copied to param. */
static int match(const char *pattern, const char *path, size_t len, char *param,
                 size_t param_size)
{
    const char *p = pattern, *s = path, *end = path + len;
    while (*p) {
        if (*p == '{') {
            const char *close = strchr(p, '}');
            if (!close) return 0;
            const char *slash = memchr(s, '/', (size_t)(end - s));
            size_t n = (size_t)((slash ? slash : end) - s);
            if (n == 0 || n >= GPD_ROUTE_PARAM_MAX) return 0;
            if (param && n < param_size) {
                memcpy(param, s, n);
                param[n] = '\0';
            }
            s += n;
            p = close + 1;
            continue;
        }
        if (s == end || *s != *p) return 0;
        p++;
        s++;
    }
    return s == end;
}

const gpd_route *gpd_route_match(const char *path, char *param, size_t param_size)
{
    if (param && param_size) param[0] = '\0';
    if (!path) return NULL;
    /* one trailing slash dropped, but not from "/" */
    size_t len = strlen(path);
    if (len > 1 && path[len - 1] == '/') len--;
    for (size_t i = 0; i < NROUTES; i++) {
        if (match(table[i].pattern, path, len, param, param_size)) return &table[i];
        if (param && param_size) param[0] = '\0'; /* a partial match's parameter */
    }
    return NULL;
}

int gpd_route_method_of(const char *method)
{
    if (!method) return -1;
    if (!strcmp(method, "GET") || !strcmp(method, "HEAD")) return GPD_ROUTE_GET;
    if (!strcmp(method, "POST")) return GPD_ROUTE_POST;
    if (!strcmp(method, "DELETE")) return GPD_ROUTE_DELETE;
    return -1;
}

const char *gpd_route_method_name(int m)
{
    static const char *const names[GPD_ROUTE_NMETHODS] = {
        [GPD_ROUTE_GET] = "GET", [GPD_ROUTE_POST] = "POST", [GPD_ROUTE_DELETE] = "DELETE"};
    return m >= 0 && m < GPD_ROUTE_NMETHODS ? names[m] : NULL;
}

int gpd_route_answers(const gpd_route *r, int m)
{
    return r && m >= 0 && m < GPD_ROUTE_NMETHODS && r->op[m].handler != GPD_H_NONE;
}

const char *gpd_route_allow(const gpd_route *r)
{
    /* by the set of methods (bit m for method m): GET brings HEAD */
    static const char *const allow[1u << GPD_ROUTE_NMETHODS] = {
        "",
        "GET, HEAD",
        "POST",
        "GET, HEAD, POST",
        "DELETE",
        "GET, HEAD, DELETE",
        "POST, DELETE",
        "GET, HEAD, POST, DELETE",
    };
    _Static_assert(GPD_ROUTE_GET == 0 && GPD_ROUTE_POST == 1 && GPD_ROUTE_DELETE == 2 &&
                       GPD_ROUTE_NMETHODS == 3,
                   "gpd_route_allow's strings follow the order of gpd_route_method");
    unsigned set = 0;
    for (int m = 0; m < GPD_ROUTE_NMETHODS; m++)
        if (gpd_route_answers(r, m)) set |= 1u << m;
    return allow[set];
}
