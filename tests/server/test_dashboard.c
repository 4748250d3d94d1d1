/* test_dashboard.c -- the dashboard page: self-contained HTML that polls the job list, submits,
 * cancels and shows SVG views and exports; a finished job's warnings (amber) and fit table; and
 * dashboard.c is in sync with dashboard.html. With node installed, the page's script also runs
 * against a stand-in DOM (tests/server/dashboard_check.js) to check how a finished job is drawn. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../../server/dashboard.c"
#include "gp_test.h"

/* a path relative to this file's directory */
static void here(char *path, size_t n, const char *rel)
{
    const char *me = __FILE__;
    const char *slash = strrchr(me, '/');
    snprintf(path, n, "%.*s/%s", slash ? (int)(slash - me) : 1, slash ? me : ".", rel);
}

/* server/dashboard.html, two levels up from this file */
static char *read_html(void)
{
    char path[1024];
    here(path, sizeof path, "../../server/dashboard.html");
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "cannot open %s\n", path);
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) == (size_t)n) buf[n] = 0;
    fclose(f);
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
    CHECK(fd >= 0);
    if (fd < 0) return;
    FILE *f = fdopen(fd, "w");
    fputs(page, f);
    fclose(f);
    char js[1024], cmd[2200];
    here(js, sizeof js, "dashboard_check.js");
    snprintf(cmd, sizeof cmd, "node '%s' '%s'", js, html);
    CHECK(system(cmd) == 0);
    unlink(html);
}

int main(void)
{
    const char *h = gp_dashboard_html();
    CHECK(h != NULL && strlen(h) > 1000);
    CHECK(strncmp(h, "<!DOCTYPE html>", 15) == 0);
    CHECK(strstr(h, "</html>") != NULL);
    CHECK(strstr(h, "<meta charset=\"utf-8\">") != NULL);
    /* polling, every second */
    CHECK(strstr(h, "setInterval(refresh, POLL_MS)") != NULL);
    CHECK(strstr(h, "POLL_MS = 1000") != NULL);
    /* the endpoints it uses */
    CHECK(strstr(h, "\"/v1/jobs?limit=50\"") != NULL);
    CHECK(strstr(h, "api(\"POST\", \"/v1/jobs\"") != NULL);
    CHECK(strstr(h, "api(\"DELETE\", \"/v1/jobs/\"") != NULL);
    CHECK(strstr(h, "/svg?view=") != NULL);
    CHECK(strstr(h, "/export?format=") != NULL);
    CHECK(strstr(h, "/v1/health") != NULL);
    CHECK(strstr(h, "\"fraction\"") != NULL || strstr(h, ".fraction") != NULL);
    /* every view and export format of api.md */
    const char *names[] = {"packing", "cells", "size", "orientation", "descriptors", "section", "psd",
                           "lammps", "liggghts", "yade", "vtk", "csv"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) CHECK(strstr(h, names[i]) != NULL);
    /* the api.md example spec */
    CHECK(strstr(h, "solid_fraction: 0.65") != NULL && strstr(h, "porosity: 0.38") != NULL);
    /* a finished job: warnings from its progress detail in amber, the fit report as a table */
    CHECK(strstr(h, "detail.warnings") != NULL || strstr(h, "jobDetail(job).warnings") != NULL);
    CHECK(strstr(h, "--amber: #bf8700") != NULL && strstr(h, ".bar.done.warn > div { background: var(--amber)"));
    CHECK(strstr(h, "\"warnmark\"") != NULL && strstr(h, "s-warn") != NULL);
    const char *fit_keys[] = {"cell_area", "grain_area", "cell_orientation", "grain_orientation",
                              "passing", "ks_critical", "max_error_pp", "w1", "fitTable(fit)"};
    for (size_t i = 0; i < sizeof fit_keys / sizeof *fit_keys; i++) CHECK(strstr(h, fit_keys[i]) != NULL);
    CHECK(strstr(h, "b.ks > b.ks_critical") != NULL);
    run_in_node(h);
    /* self-contained: nothing fetched from elsewhere */
    CHECK(strstr(h, "http://") == NULL && strstr(h, "https://") == NULL);
    CHECK(strstr(h, "<script src") == NULL && strstr(h, "<link") == NULL);
    /* in sync with the HTML source */
    char *src = read_html();
    CHECK(src != NULL);
    if (src) {
        CHECK(strcmp(src, h) == 0);
        if (strcmp(src, h)) fprintf(stderr, "server/dashboard.c is stale: run python3 server/dashboard_gen.py\n");
    }
    free(src);
    return gp_test_summary();
}
