/* test_dashboard.c -- the dashboard page: self-contained HTML that polls the job list (paged,
 * rows updated in place), submits (with quick fields), cancels, shows a finished job's result
 * summary (targets next to achieved values, from GET .../summary, never .../result), timings,
 * warnings (amber), SVG views (a download link each, the section's z slider) and exports; the
 * DOM contract the browser test relies on (ids and data- attributes); a URL per job
 * (#/jobs/{id}); an outline file made the spec's shape.outlines and analysed at once (POST
 * /v1/shapes/analyze); the kinds, their examples, views and export formats filled in from the
 * daemon's kind table (server/http/page.c), none of them written in the page itself; and
 * the page compiled in is dashboard.html byte for byte. With node installed, the page's script also runs
 * against a stand-in DOM and service (tests/server/dashboard_check.js) to check how it
 * behaves. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "http/dashboard.h"
#include "gp_test.h"
#include "http/page.h"

/* a path relative to this file's directory */
static void here(char *path, size_t n, const char *rel)
{
    const char *me = __FILE__;
    const char *slash = strrchr(me, '/');
    snprintf(path, n, "%.*s/%s", slash ? (int)(slash - me) : 1, slash ? me : ".", rel);
}

/* a whole file (relative to this one's directory), NUL-terminated; NULL when unreadable */
static char *slurp(const char *rel)
{
    char path[1024];
    here(path, sizeof path, rel);
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n = -1;
    if (f && fseek(f, 0, SEEK_END) == 0) n = ftell(f);
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0) buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) == (size_t)n) buf[n] = 0;
    if (f) fclose(f);
    if (!buf) fprintf(stderr, "cannot read %s\n", path);
    return buf;
}

/* the page's script in node (tests/server/dashboard_check.js); skipped without node */
static void run_in_node(const char *page)
{
    if (system("node --version >/dev/null 2>&1") != 0) {
        printf("node not installed: the dashboard's script is not run (string checks only)\n");
        return;
    }
    char html[] = "/tmp/gp_test_dashboard_XXXXXX";
    int fd = mkstemp(html);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    CHECK(f != NULL);
    if (!f) return;
    fputs(page, f);
    fclose(f);
    char js[1024], cmd[2200];
    here(js, sizeof js, "dashboard_check.js");
    snprintf(cmd, sizeof cmd, "node '%s' '%s'", js, html);
    CHECK(system(cmd) == 0);
    unlink(html);
}

/* every string of a NULL-terminated list is in h */
static void check_all(const char *h, const char *const *want)
{
    for (; *want; want++) {
        int ok = strstr(h, *want) != NULL;
        CHECK(ok);
        if (!ok) fprintf(stderr, "not in the page: %s\n", *want);
    }
}

int main(void)
{
    const char *tpl = gp_dashboard_html(), *h = gpd_page_html();
    CHECK(tpl != NULL && h != NULL && strlen(h) > strlen(tpl));
    if (!tpl || !h) return gp_test_summary();
    static const char *const page[] = {
        "<!DOCTYPE html>", "</html>", "<meta charset=\"utf-8\">",
        /* polling, every second */
        "setInterval(refresh, POLL_MS)", "POLL_MS = 1000",
        /* the endpoints it uses: the list by pages, the summary of a result (not the result) */
        "\"/v1/jobs?limit=\" + PAGE_SIZE", "\"&after=\"", "api(\"POST\", \"/v1/jobs\"",
        "api(\"DELETE\", jobPath(id))", "\"/summary\"", "\"/svg\"", "?view=", "&z=",
        "&color=orientation", "/export?format=", "/v1/health", ".fraction", ".eta_s",
        /* a finished job: warnings in amber, the fit report as rows of the summary */
        "jobDetail(job).warnings", "--amber: #bf8700", ".bar.done.warn > div { background: var(--amber)",
        "\"warnmark\"", "s-warn", "cell_area", "grain_area", "cell_orientation",
        "grain_orientation", "passing", "ks_critical", "max_error_pp", "w1",
        "within(b.ks, b.ks_critical)", "coordination_number", "fabric", "porosity",
        "cells_target_met", "stop_reason", "timings",
        /* a cancelled job grey, not a running bar */
        ".bar.cancelled > div { background: var(--grey)",
        /* the DOM contract of the browser test (tests/integration/browser) */
        "id=\"kind\"", "id=\"spec\"", "id=\"q-particles\"", "id=\"q-seed\"",
        "id=\"q-solid-fraction\"", "id=\"q-porosity\"", "id=\"submit\"", "id=\"submit-msg\"",
        "id=\"jobs\"", "id=\"page-prev\"", "id=\"page-next\"", "id=\"detail\"",
        "id=\"cancel\"", "id=\"summary\"", "id=\"timings\"", "id=\"views\"",
        "id=\"picture\"", "id=\"svg-download\"", "id=\"z\"", "id=\"exports\"",
        "\"data-job-id\"", "\"data-status\"", "\"data-quantity\"", "\"data-view\"",
        "\"data-state\"", "\"data-format\"", "\"class\": \"job\"", "\"target\"", "\"achieved\"",
        /* grain outlines from a file (2D), put in the spec; their analysis at once */
        "id=\"q-outlines\"", "type=\"file\"", "id=\"analyse\"", "shape.outlines",
        "api(\"POST\", \"/v1/shapes/analyze\"",
        /* a URL per job */
        "\"#/jobs/\"", "\"hashchange\"",
        /* filled in from the kind table: every kind, view and export format of api.md, and the
         * api.md example specs */
        "\"fourier-voronoi-2d\":{\"example\":", "\"spheres-3d\":{\"example\":", "\"packing\"",
        "\"cells\"", "\"size\"", "\"orientation\"", "\"descriptors\"", "\"section\"", "\"psd\"",
        "\"lammps\"", "\"liggghts\"", "\"yade\"", "\"vtk\"", "\"csv\"", "\"solid_fraction\":0.65",
        "\"porosity\":0.38", "{\"name\":\"packing\",\"options\":[\"color\"],\"needs\":null}",
        "{\"name\":\"transfer\",\"options\":[],\"needs\":\"stats.transfer\"}", NULL};
    CHECK(strncmp(h, "<!DOCTYPE html>", 15) == 0);
    check_all(h, page);
    /* the page itself names no kind: it takes them from the daemon */
    CHECK(strstr(tpl, "fourier-voronoi-2d") == NULL && strstr(tpl, "spheres-3d") == NULL);
    CHECK(strstr(tpl, "var KINDS = /*@KINDS@*/{};") != NULL);
    /* the whole result (up to ~100 MB) is only ever a download link, never fetched */
    const char *res = strstr(tpl, "\"/result\"");
    CHECK(res != NULL && strstr(res + 1, "\"/result\"") == NULL);
    CHECK(strstr(tpl, "download: job.id + \"-result.json\"") != NULL);
    run_in_node(h);
    /* self-contained: nothing fetched from elsewhere, nothing that would close the script */
    CHECK(strstr(h, "http://") == NULL && strstr(h, "https://") == NULL);
    CHECK(strstr(h, "<script src") == NULL && strstr(h, "<link") == NULL);
    CHECK(strstr(strstr(h, "<script>"), "</script>") == strstr(h, "</script>"));
    /* its policy: the inline script by its hash, nothing from elsewhere */
    const char *csp = gpd_page_csp();
    CHECK(csp && strstr(csp, "script-src 'sha256-") && strstr(csp, "default-src 'self'"));
    /* the build's embedding of the HTML source, byte for byte */
    char *src = slurp("../../server/http/dashboard.html");
    CHECK(src != NULL && strcmp(src, tpl) == 0);
    free(src);
    return gp_test_summary();
}
