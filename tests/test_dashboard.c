/* test_dashboard.c -- the dashboard page: self-contained HTML that polls the job list, submits,
 * cancels and shows SVG views and exports; and dashboard.c is in sync with dashboard.html. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../server/dashboard.c"
#include "gp_test.h"

/* server/dashboard.html next to this file's ../server */
static char *read_html(void)
{
    char path[1024];
    const char *me = __FILE__;
    const char *slash = strrchr(me, '/');
    snprintf(path, sizeof path, "%.*s/../server/dashboard.html", slash ? (int)(slash - me) : 1,
             slash ? me : ".");
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
