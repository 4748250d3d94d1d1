/* test_spec_regressions.c -- replays the spec fuzzer's inputs under the normal build: every file
 * of fuzz/regressions/ (inputs that once broke the validator or a parser: keep them there) and
 * of the seed corpus fuzz/corpus/, through the same calls and contract checks as the libFuzzer
 * target (fuzz/fuzz_spec_check.h). Seeds named ok-*.json must be valid specs and bad-*.json
 * must be refused, so the corpus keeps covering both the parsers and the semantic checks. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../fuzz/fuzz_spec_check.h"
#include "gp_test.h"

/* a path relative to this file's directory */
static void here(char *path, size_t n, const char *rel)
{
    const char *me = __FILE__;
    const char *slash = strrchr(me, '/');
    snprintf(path, n, "%.*s/%s", slash ? (int)(slash - me) : 1, slash ? me : ".", rel);
}

static unsigned char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    unsigned char *buf = NULL;
    size_t cap = 0, n = 0;
    for (;;) {
        if (n == cap) {
            cap = cap ? 2 * cap : 4096;
            unsigned char *b = realloc(buf, cap);
            if (!b) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = b;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    fclose(f);
    *len = n;
    return buf;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* runs every regular file of dir (relative to tests/); returns how many */
static int replay(const char *rel, int check_names)
{
    char dir[1024];
    here(dir, sizeof dir, rel);
    DIR *d = opendir(dir);
    if (!d) {
        fprintf(stderr, "cannot open %s\n", dir);
        CHECK(d != NULL);
        return 0;
    }
    char **names = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            char **nn = realloc(names, cap * sizeof *nn);
            if (!nn) break;
            names = nn;
        }
        names[n] = strdup(e->d_name);
        if (names[n]) n++;
    }
    closedir(d);
    if (n) qsort(names, n, sizeof *names, by_name);
    for (size_t i = 0; i < n; i++) {
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        size_t len = 0;
        unsigned char *buf = read_file(path, &len);
        CHECK(buf != NULL);
        if (buf) {
            gp_fuzz_spec_result res;
            const char *broken = gp_fuzz_spec_one(buf, len, &res);
            if (broken) fprintf(stderr, "%s: %s\n", path, broken);
            CHECK(broken == NULL);
            if (check_names && !strncmp(names[i], "ok-", 3)) {
                if (!res.valid) fprintf(stderr, "%s: expected valid, got: %s\n", path,
                                        res.json_ok ? res.problem.message : "not JSON");
                CHECK(res.valid);
            } else if (check_names && !strncmp(names[i], "bad-", 4)) {
                if (res.valid) fprintf(stderr, "%s: expected a refusal, got a valid spec\n", path);
                CHECK(res.json_ok && !res.valid);
            }
            free(buf);
        }
        free(names[i]);
    }
    free(names);
    return (int)n;
}

int main(void)
{
    int nreg = replay("../../fuzz/regressions", 0);
    int nseed = replay("../../fuzz/corpus", 1);
    printf("replayed %d regression inputs and %d seeds\n", nreg, nseed);
    CHECK(nseed > 0);
    return gp_test_summary();
}
