/* test_routes.c -- the route table (server/http/routes.h): every route and method it serves is
 * documented in docs/api.md under a heading "### METHOD /path" (path parameters as "{id}"),
 * and every such heading is a route the table serves; the matcher finds each pattern from a
 * real URL (and its trailing-slash form) and not from near misses; the metrics labels, Allow
 * headers and offloading follow from the table as the router and the metrics use them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_test.h"
#include "http/offload.h"
#include "http/routes.h"

#define ID "0123456789abcdef0123456789abcdef"

/* a path relative to this file's directory */
static void here(char *path, size_t n, const char *rel)
{
    const char *me = __FILE__;
    const char *slash = strrchr(me, '/');
    snprintf(path, n, "%.*s/%s", slash ? (int)(slash - me) : 1, slash ? me : ".", rel);
}

/* a whole file, NUL-terminated; NULL when unreadable */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n = -1;
    if (f && fseek(f, 0, SEEK_END) == 0) n = ftell(f);
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0) buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) == (size_t)n) buf[n] = 0;
    else {
        free(buf);
        buf = NULL;
    }
    if (f) fclose(f);
    return buf;
}

/* whether doc has a line that is exactly line (a "\r" before the newline allowed) */
static int has_line(const char *doc, const char *line)
{
    size_t n = strlen(line);
    for (const char *p = doc; (p = strstr(p, line)) != NULL; p++) {
        int starts = p == doc || p[-1] == '\n';
        const char *e = p + n;
        if (*e == '\r') e++;
        if (starts && (*e == '\n' || *e == '\0')) return 1;
    }
    return 0;
}

/* pattern with each "{name}" replaced by with (e.g. ID, or ":id" for the label) */
static void fill(char *out, size_t size, const char *pattern, const char *with)
{
    size_t o = 0;
    for (const char *p = pattern; *p && o + 1 < size; p++) {
        if (*p == '{') {
            const char *close = strchr(p, '}');
            if (close) {
                const char *w = with ? with : "";
                if (!strcmp(w, ":")) { /* ":name" */
                    out[o++] = ':';
                    for (const char *q = p + 1; q < close && o + 1 < size; q++) out[o++] = *q;
                } else {
                    for (const char *q = w; *q && o + 1 < size; q++) out[o++] = *q;
                }
                p = close;
                continue;
            }
        }
        out[o++] = *p;
    }
    out[o] = '\0';
}

/* every route and method served has its heading in docs/api.md; returns the undocumented */
static int check_documented(const gpd_route *rt, size_t n, const char *doc, const char *docpath)
{
    int missing = 0;
    for (size_t i = 0; i < n; i++)
        for (int m = 0; m < GPD_ROUTE_NMETHODS; m++) {
            if (!gpd_route_answers(&rt[i], m)) continue;
            char line[256];
            snprintf(line, sizeof line, "### %s %s", gpd_route_method_name(m), rt[i].pattern);
            int ok = has_line(doc, line);
            CHECK(ok);
            if (!ok) {
                fprintf(stderr, "undocumented route: %s %s (no heading line \"%s\" in %s)\n",
                        gpd_route_method_name(m), rt[i].pattern, line, docpath);
                missing++;
            }
        }
    return missing;
}

/* every "### METHOD /path" heading of docs/api.md is a route and method the table serves */
static void check_headings_served(const char *doc, const char *docpath)
{
    static const char *const verbs[] = {"GET", "HEAD", "POST", "PUT", "PATCH", "DELETE",
                                        "OPTIONS"};
    for (const char *p = doc; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL) {
        if (strncmp(p, "### ", 4)) continue;
        const char *v = p + 4;
        for (size_t k = 0; k < sizeof verbs / sizeof *verbs; k++) {
            size_t vl = strlen(verbs[k]);
            if (strncmp(v, verbs[k], vl) || v[vl] != ' ' || v[vl + 1] != '/') continue;
            const char *path = v + vl + 1;
            size_t pl = strcspn(path, "\r\n");
            char pattern[256];
            snprintf(pattern, sizeof pattern, "%.*s", (int)pl, path);
            size_t n = 0;
            const gpd_route *rt = gpd_routes(&n), *found = NULL;
            for (size_t i = 0; i < n; i++)
                if (!strcmp(rt[i].pattern, pattern)) found = &rt[i];
            int m = gpd_route_method_of(verbs[k]);
            int ok = found && gpd_route_answers(found, m) && strcmp(verbs[k], "HEAD");
            CHECK(ok);
            if (!ok)
                fprintf(stderr, "%s heads \"### %s %s\", which the route table does not serve "
                        "(HEAD is documented with GET)\n", docpath, verbs[k], pattern);
        }
    }
}

/* a real URL of each pattern matches its route, with its parameter; near misses do not */
static void check_matcher(const gpd_route *rt, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const char *pat = rt[i].pattern;
        int has_param = strchr(pat, '{') != NULL;
        char url[512], param[GPD_ROUTE_PARAM_MAX], miss[600];
        fill(url, sizeof url, pat, ID);
        memset(param, 'x', sizeof param);
        const gpd_route *got = gpd_route_match(url, param, sizeof param);
        CHECK(got == &rt[i]);
        if (got != &rt[i]) fprintf(stderr, "%s does not match its route %s\n", url, pat);
        CHECK(!strcmp(param, has_param ? ID : ""));
        /* one trailing slash is ignored; two are not */
        snprintf(miss, sizeof miss, "%s/", url);
        CHECK(gpd_route_match(miss, param, sizeof param) == &rt[i]);
        snprintf(miss, sizeof miss, "%s//", url);
        CHECK(gpd_route_match(miss, param, sizeof param) == NULL);
        CHECK(param[0] == '\0');
        /* near misses: a byte more or less (unless that only changes the id at the end), a
         * segment more, another case */
        size_t pl = strlen(pat);
        if (pat[pl - 1] != '}') {
            snprintf(miss, sizeof miss, "%sx", url);
            CHECK(gpd_route_match(miss, NULL, 0) != &rt[i]);
            if (strlen(url) > 1) {
                snprintf(miss, sizeof miss, "%.*s", (int)strlen(url) - 1, url);
                CHECK(gpd_route_match(miss, NULL, 0) != &rt[i]);
            }
        }
        snprintf(miss, sizeof miss, "%s/x", strcmp(url, "/") ? url : "");
        CHECK(gpd_route_match(miss, NULL, 0) != &rt[i]);
        char upper[512];
        snprintf(upper, sizeof upper, "%s", url);
        for (char *p = upper; *p; p++)
            if (*p >= 'a' && *p <= 'z' && (p == upper + 1 || p[-1] == '/')) *p -= 'a' - 'A';
        if (strcmp(upper, url)) CHECK(gpd_route_match(upper, NULL, 0) == NULL);
        if (!has_param) continue;
        /* an empty id, an id of 79 bytes (the most), of 80 */
        fill(miss, sizeof miss, pat, "");
        CHECK(gpd_route_match(miss, NULL, 0) != &rt[i]);
        char id79[GPD_ROUTE_PARAM_MAX], id80[GPD_ROUTE_PARAM_MAX + 1];
        memset(id79, 'a', sizeof id79 - 1);
        id79[sizeof id79 - 1] = '\0';
        memset(id80, 'a', sizeof id80 - 1);
        id80[sizeof id80 - 1] = '\0';
        fill(miss, sizeof miss, pat, id79);
        CHECK(gpd_route_match(miss, param, sizeof param) == &rt[i] && !strcmp(param, id79));
        fill(miss, sizeof miss, pat, id80);
        CHECK(gpd_route_match(miss, NULL, 0) == NULL);
    }
    /* paths of no route */
    static const char *const none[] = {"", "/v1", "/v1/", "/v1/jobs//", "/v1/jobs//result",
                                       "/v1/jobs/" ID "/nope", "/v1/jobs/" ID "/result/x",
                                       "/v1/shapes", "/metrics/x", "/V1/health", "//x"};
    for (size_t k = 0; k < sizeof none / sizeof *none; k++) {
        const gpd_route *got = gpd_route_match(none[k], NULL, 0);
        CHECK(got == NULL);
        if (got) fprintf(stderr, "\"%s\" matches %s\n", none[k], got->pattern);
    }
    CHECK(gpd_route_match("//", NULL, 0) == &rt[0]); /* "/" with its trailing slash */
    CHECK(gpd_route_match(NULL, NULL, 0) == NULL);
}

/* the labels, methods, Allow headers and offloading */
static void check_table(const gpd_route *rt, size_t n)
{
    CHECK(n > 0 && n <= GPD_ROUTES_MAX);
    for (size_t i = 0; i < n; i++) {
        char label[256];
        fill(label, sizeof label, rt[i].pattern, ":");
        CHECK(!strcmp(rt[i].label, label));
        CHECK(strcmp(rt[i].label, GPD_ROUTE_OTHER_LABEL));
        CHECK(strchr(rt[i].label, '}') == NULL);
        int methods = 0;
        for (int m = 0; m < GPD_ROUTE_NMETHODS; m++) {
            if (!gpd_route_answers(&rt[i], m)) continue;
            methods++;
            CHECK(rt[i].op[m].handler > GPD_H_NONE && rt[i].op[m].handler < GPD_H_COUNT);
            /* a body comes only with POST (http.c ignores the others'): only POST costs in
             * proportion to it */
            CHECK(!rt[i].op[m].offload || m == GPD_ROUTE_POST);
            CHECK(strstr(gpd_route_allow(&rt[i]), gpd_route_method_name(m)) != NULL);
        }
        CHECK(methods > 0);
        /* HEAD wherever GET, right after it */
        if (gpd_route_answers(&rt[i], GPD_ROUTE_GET))
            CHECK(!strncmp(gpd_route_allow(&rt[i]), "GET, HEAD", 9));
        else
            CHECK(strstr(gpd_route_allow(&rt[i]), "HEAD") == NULL);
        for (size_t j = 0; j < i; j++) {
            CHECK(strcmp(rt[i].pattern, rt[j].pattern));
            CHECK(strcmp(rt[i].label, rt[j].label));
        }
    }
    /* the Allow headers the router has always sent */
    static const struct {
        const char *path, *allow;
    } allow[] = {{"/", "GET, HEAD"},
                 {"/metrics", "GET, HEAD"},
                 {"/v1/health", "GET, HEAD"},
                 {"/v1/schema", "GET, HEAD"},
                 {"/v1/jobs", "GET, HEAD, POST"},
                 {"/v1/shapes/analyze", "POST"},
                 {"/v1/jobs/" ID, "GET, HEAD, DELETE"},
                 {"/v1/jobs/" ID "/result", "GET, HEAD"},
                 {"/v1/jobs/" ID "/summary", "GET, HEAD"}};
    for (size_t k = 0; k < sizeof allow / sizeof *allow; k++) {
        const gpd_route *r = gpd_route_match(allow[k].path, NULL, 0);
        CHECK(r && !strcmp(gpd_route_allow(r), allow[k].allow));
    }
    /* offloaded: the submit and the shape analysis, each in its own lane (a submit never
     * waits behind an analysis) */
    const gpd_route *jobs = gpd_route_match("/v1/jobs", NULL, 0);
    const gpd_route *shapes = gpd_route_match("/v1/shapes/analyze", NULL, 0);
    CHECK(jobs && jobs->op[GPD_ROUTE_POST].offload && !jobs->op[GPD_ROUTE_GET].offload);
    CHECK(shapes && shapes->op[GPD_ROUTE_POST].offload);
    CHECK(jobs && jobs->op[GPD_ROUTE_POST].lane == GPD_LANE_SPEC);
    CHECK(shapes && shapes->op[GPD_ROUTE_POST].lane == GPD_LANE_ANALYSIS);
    /* methods */
    CHECK(gpd_route_method_of("GET") == GPD_ROUTE_GET);
    CHECK(gpd_route_method_of("HEAD") == GPD_ROUTE_GET);
    CHECK(gpd_route_method_of("POST") == GPD_ROUTE_POST);
    CHECK(gpd_route_method_of("DELETE") == GPD_ROUTE_DELETE);
    CHECK(gpd_route_method_of("get") == -1);
    CHECK(gpd_route_method_of("OPTIONS") == -1);
    CHECK(gpd_route_method_of("PUT") == -1);
    CHECK(!gpd_route_answers(jobs, -1));
}

int main(void)
{
    size_t n = 0;
    const gpd_route *rt = gpd_routes(&n);
    check_table(rt, n);
    check_matcher(rt, n);

    char docpath[1024];
    here(docpath, sizeof docpath, "../../docs/api.md");
    char *doc = slurp(docpath);
    CHECK(doc != NULL);
    if (!doc) {
        fprintf(stderr, "cannot read %s: every route below is undocumented\n", docpath);
        for (size_t i = 0; i < n; i++)
            for (int m = 0; m < GPD_ROUTE_NMETHODS; m++)
                if (gpd_route_answers(&rt[i], m))
                    fprintf(stderr, "undocumented route: %s %s\n", gpd_route_method_name(m),
                            rt[i].pattern);
    } else {
        int missing = check_documented(rt, n, doc, docpath);
        if (missing) fprintf(stderr, "%d route(s) undocumented in %s\n", missing, docpath);
        check_headings_served(doc, docpath);
    }
    free(doc);
    return gp_test_summary();
}
