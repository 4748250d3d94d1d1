/* fuzz_replay.h -- runs a fuzz target's saved inputs under the normal builds: the regular files
 * of one directory (fuzz/regressions/..., fuzz/corpus/...), in the order of their names, each
 * read whole and handed to a callback. Used by the regression ctests (tests/schema/
 * test_spec_regressions.c, tests/schema/test_spec_outline_regressions.c, tests/core/2d/
 * test_trace_regressions.c), so that a reproducer the fuzzer found keeps running in every
 * build, not only in the clang one. Subdirectories are skipped: the spec target's files sit
 * at the top of fuzz/corpus/ and fuzz/regressions/, the other targets' in a folder each.
 * Header only (static functions); no state.
 */
#ifndef GP_FUZZ_REPLAY_H
#define GP_FUZZ_REPLAY_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* called with the file's name (no directory), its bytes and their count */
typedef void (*gp_fuzz_replay_fn)(const char *name, const unsigned char *buf, size_t len,
                                  void *user);

/* the whole file at path into a new buffer (freed by the caller); NULL when unreadable */
static unsigned char *gp_fuzz_read_file(const char *path, size_t *len)
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

static int gp_fuzz_by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* the names of dir's regular files, not hidden ones, sorted; *n of them; NULL when dir cannot
 * be opened (an empty directory gives a non-NULL empty list) */
static char **gp_fuzz_list_files(const char *dir, size_t *n)
{
    DIR *d = opendir(dir);
    if (!d) return NULL;
    char **names = malloc(sizeof *names);
    size_t cap = 1;
    *n = 0;
    struct dirent *e;
    while (names && (e = readdir(d))) {
        char path[4096];
        struct stat st;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (e->d_name[0] == '.' || stat(path, &st) != 0 || !S_ISREG(st.st_mode)) continue;
        if (*n == cap) {
            char **nn = realloc(names, 2 * cap * sizeof *nn);
            if (!nn) break;
            names = nn;
            cap *= 2;
        }
        names[*n] = strdup(e->d_name);
        if (names[*n]) (*n)++;
    }
    closedir(d);
    if (names && *n) qsort(names, *n, sizeof *names, gp_fuzz_by_name);
    return names;
}

/* Calls fn on every regular file of dir; returns how many, or -1 when dir cannot be opened or
 * a file cannot be read (the caller fails then: a missing corpus must not pass quietly). */
static int gp_fuzz_replay_dir(const char *dir, gp_fuzz_replay_fn fn, void *user)
{
    size_t n = 0;
    char **names = gp_fuzz_list_files(dir, &n);
    if (!names) {
        fprintf(stderr, "cannot open %s\n", dir);
        return -1;
    }
    int count = 0;
    for (size_t i = 0; i < n; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        size_t len = 0;
        unsigned char *buf = gp_fuzz_read_file(path, &len);
        if (!buf) {
            fprintf(stderr, "cannot read %s\n", path);
            count = -1;
        } else {
            fn(names[i], buf, len, user);
            if (count >= 0) count++;
        }
        free(buf);
        free(names[i]);
    }
    free(names);
    return count;
}

/* dir relative to the directory of the source file src (__FILE__ of the caller) */
static void gp_fuzz_path_from(const char *src, const char *rel, char *path, size_t n)
{
    const char *slash = strrchr(src, '/');
    snprintf(path, n, "%.*s/%s", slash ? (int)(slash - src) : 1, slash ? src : ".", rel);
}

/* One target's saved inputs, as each regression ctest runs them: the regressions (fn's user
 * points to 0: their names promise nothing), then the seeds (to 1: ok-* and bad-* promise a
 * verdict), both folders relative to from_file's (the test's __FILE__); prints the counts. 0,
 * or -1 when a folder could not be read or there is no seed. */
static int gp_fuzz_replay_target(const char *from_file, const char *regressions_rel,
                                 const char *seeds_rel, gp_fuzz_replay_fn fn)
{
    char dir[1024];
    int names_promise_nothing = 0, names_promise = 1;
    gp_fuzz_path_from(from_file, regressions_rel, dir, sizeof dir);
    int nreg = gp_fuzz_replay_dir(dir, fn, &names_promise_nothing);
    gp_fuzz_path_from(from_file, seeds_rel, dir, sizeof dir);
    int nseed = gp_fuzz_replay_dir(dir, fn, &names_promise);
    printf("replayed %d regression inputs and %d seeds\n", nreg, nseed);
    return nreg >= 0 && nseed > 0 ? 0 : -1;
}

#endif /* GP_FUZZ_REPLAY_H */
