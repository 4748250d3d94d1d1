/* test_store_write.c -- results written straight into the store: the writer's spill into an
 * unlinked temporary file (result_json.h), the SQLite store's copy of it in pieces
 * (zeroblob + sqlite3_blob_write, store.h), and the checkpoints left to the maintenance thread
 * (maint.h).
 *
 * The truths: the same values written by a writer that keeps its text in memory (itself held
 * to jansson by test_result_json) -- a spilled text and a stored one must be the same bytes;
 * the summary and its spans recomputed with json_scan_object_without over the original text; the
 * sizes of the database and its WAL on disk (a commit that checkpointed would have copied the
 * result into the database file); the process's peak RSS (VmHWM, reset through
 * /proc/self/clear_refs) while a result in a file is stored; rows counted with SQLite itself.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <sqlite3.h>

#include "gp_test.h"
#include "util/json_scan.h"
#include "jobs/maint.h"
#include "jobs/result_json.h"
#include "store/store.h"

#if defined(__SANITIZE_ADDRESS__)
#define UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UNDER_ASAN 1
#endif
#endif
#ifndef UNDER_ASAN
#define UNDER_ASAN 0
#endif

/* grains of the test result: ~5 MB, past STORE_WAL_KICK_BYTES */
#define NGRAINS 50000

static char dir[64];
static char db[128];

/* A result-like object of n grains: head members, then "grains" (the bulk), then a tail
 * member, written into w (deterministic; ~120 bytes a grain). Checks that the writer's buffer
 * stays bounded once it spilled. */
static void write_result(gpd_jw *w, size_t n, int *bounded)
{
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "kind");
    gpd_jw_string(w, "fourier-voronoi-2d");
    gpd_jw_key(w, "stats");
    gpd_jw_begin_object(w);
    gpd_jw_key(w, "solid_fraction");
    gpd_jw_real(w, 0.65);
    gpd_jw_key(w, "note");
    gpd_jw_string(w, "tab\there \"quoted\"");
    gpd_jw_end_object(w);
    gpd_jw_key(w, "grains");
    gpd_jw_begin_array(w);
    uint64_t x = 88172645463325252ull;
    for (size_t i = 0; i < n; i++) {
        gpd_jw_begin_object(w);
        gpd_jw_key(w, "id");
        gpd_jw_integer(w, (long long)i);
        double v[4];
        for (int k = 0; k < 4; k++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            v[k] = (double)(x >> 11) * 0x1.0p-53 * (k + 1);
        }
        gpd_jw_key(w, "xy");
        gpd_jw_reals(w, v, 4);
        gpd_jw_end_object(w);
        if (bounded && w->spilled > 0 && w->b.cap > 2 * GPD_JW_CHUNK + 4096) *bounded = 0;
    }
    gpd_jw_end_array(w);
    gpd_jw_key(w, "warnings");
    gpd_jw_begin_array(w);
    gpd_jw_end_array(w);
    gpd_jw_end_object(w);
}

/* the whole of fd (pread from 0), NUL-terminated; NULL on a failed read */
static char *read_fd(int fd, uint64_t len)
{
    char *t = malloc(len + 1);
    uint64_t off = 0;
    while (t && off < len) {
        ssize_t k = pread(fd, t + off, len - off, (off_t)off);
        if (k <= 0) {
            free(t);
            return NULL;
        }
        off += (uint64_t)k;
    }
    if (t) t[len] = 0;
    return t;
}

static long long file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (long long)sb.st_size : -1;
}

static long long wal_size(void)
{
    char wal[160];
    snprintf(wal, sizeof wal, "%s-wal", db);
    long long n = file_size(wal);
    return n < 0 ? 0 : n;
}

/* ---- the writer ---- */

/* A text past the threshold goes to an unlinked file, byte for byte what a writer in memory
 * writes; one below it stays in memory. */
static char *test_spill_same_bytes(size_t *len_out)
{
    gpd_jw m;
    gpd_jw_init(&m, NULL);
    write_result(&m, NGRAINS, NULL);
    size_t mlen = 0;
    char *want = gpd_jw_take(&m, &mlen);
    CHECK(want && mlen > (size_t)STORE_WAL_KICK_BYTES + 65536);

    gpd_jw w;
    gpd_jw_init(&w, NULL);
    CHECK(gpd_jw_spill(&w, dir, 256 * 1024) == 0);
    int bounded = 1;
    write_result(&w, NGRAINS, &bounded);
    CHECK(bounded); /* the writer held at most ~2 chunks once the text was in its file */
    char *mem = NULL;
    int fd = -1;
    uint64_t len = 0;
    CHECK(gpd_jw_finish(&w, &mem, &fd, &len) == 0);
    CHECK(mem == NULL && fd >= 0 && len == mlen);
    struct stat sb;
    CHECK(fd >= 0 && fstat(fd, &sb) == 0 && sb.st_nlink == 0 && (uint64_t)sb.st_size == len);
    char *got = fd >= 0 ? read_fd(fd, len) : NULL;
    CHECK(got && want && !memcmp(got, want, mlen));
    free(got);
    if (fd >= 0) close(fd);

    /* gpd_jw_take reads a spilled text back */
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 100000);
    write_result(&w, NGRAINS, NULL);
    size_t tlen = 0;
    char *back = gpd_jw_take(&w, &tlen);
    CHECK(back && tlen == mlen && !memcmp(back, want, mlen));
    free(back);

    /* below the threshold: in memory */
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 0);
    write_result(&w, 100, NULL);
    CHECK(gpd_jw_finish(&w, &mem, &fd, &len) == 0);
    CHECK(mem && fd == -1 && len == strlen(mem) && len < GPD_JW_SPILL_AT);
    free(mem);
    *len_out = mlen;
    return want;
}

static int open_fds(void)
{
    int n = 0;
    for (int fd = 0; fd < 1024; fd++) n += fcntl(fd, F_GETFD) != -1;
    return n;
}

/* A writer cancelled after it spilled drops its file: finish gives nothing, no descriptor is
 * left open (nor by gpd_jw_free on a spilled writer). */
static void test_spill_cancel(void)
{
    int fds = open_fds();
    volatile int flag = 0;
    gpd_jw w;
    gpd_jw_init(&w, &flag);
    gpd_jw_spill(&w, dir, 65536);
    write_result(&w, 2000, NULL);
    CHECK(w.fd >= 0 && w.spilled > 0);
    CHECK(open_fds() == fds + 1);
    __atomic_store_n(&flag, 1, __ATOMIC_RELAXED);
    write_result(&w, 2 * GPD_JW_CANCEL_EVERY, NULL); /* reaches a look at the flag */
    CHECK(w.state == GPD_JW_CANCELLED);
    char *mem = NULL;
    int fd = 0;
    uint64_t len = 0;
    CHECK(gpd_jw_finish(&w, &mem, &fd, &len) == -1 && !mem && fd == -1);
    CHECK(open_fds() == fds);
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 65536);
    write_result(&w, 2000, NULL);
    gpd_jw_free(&w);
    CHECK(open_fds() == fds);
}

/* A directory where no file can be made leaves the text in memory, whole and right. */
static void test_spill_no_dir(const char *want, size_t wlen)
{
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, "/nonexistent/grainpack-test", 4096);
    write_result(&w, NGRAINS, NULL);
    char *mem = NULL;
    int fd = -1;
    uint64_t len = 0;
    CHECK(gpd_jw_finish(&w, &mem, &fd, &len) == 0);
    CHECK(mem && fd == -1 && len == wlen && !memcmp(mem, want, wlen));
    free(mem);
}

/* A file write that fails (the file size limit, as a full disk) stops the writer: finish
 * gives the errno and nothing else. */
static void test_spill_write_fails(void)
{
    struct rlimit old, lim;
    if (getrlimit(RLIMIT_FSIZE, &old) != 0) return;
    signal(SIGXFSZ, SIG_IGN);
    lim = old;
    lim.rlim_cur = 2 * 1024 * 1024;
    CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 65536);
    write_result(&w, 60000, NULL);
    CHECK(w.state == GPD_JW_IO && w.err == EFBIG);
    char *mem = (char *)1;
    int fd = 7;
    uint64_t len = 1;
    CHECK(gpd_jw_finish(&w, &mem, &fd, &len) == EFBIG);
    CHECK(mem == NULL && fd == -1 && len == 0);
    setrlimit(RLIMIT_FSIZE, &old);
}

/* ---- the store ---- */

/* A queued job claimed: its id (the store hands out the oldest queued job). */
static int new_running_job(char id[33])
{
    char claimed[33], *kind = NULL, *spec = NULL;
    int attempts = 0;
    if (store_insert("fourier-voronoi-2d", "{}", NULL, 0, id) != STORE_OK) return -1;
    store_rc rc = store_claim(claimed, &kind, &spec, &attempts);
    free(kind);
    free(spec);
    return rc == STORE_OK && !strcmp(claimed, id) ? 0 : -1;
}

/* The stored result of id read back whole through a stream (small: 0, always streamed). */
static char *stored_result(const char *id, uint64_t *len)
{
    store_stream *s = NULL;
    char *text = NULL, st[16];
    size_t tlen = 0;
    if (store_stream_open(id, "result", 0, &s, &text, &tlen, st) != STORE_OK) return NULL;
    if (text) { /* an empty value */
        *len = tlen;
        return text;
    }
    if (!s) return NULL;
    *len = store_stream_size(s);
    char *buf = malloc(*len + 1);
    if (buf && store_stream_read(s, 0, buf, *len) != 0) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[*len] = 0;
    store_stream_close(s);
    return buf;
}

/* One query's integer, on a connection of the test's own. */
static long long sql_long(const char *sql, const char *id)
{
    sqlite3 *h = NULL;
    sqlite3_stmt *st = NULL;
    long long v = -1;
    if (sqlite3_open(db, &h) == SQLITE_OK &&
        sqlite3_prepare_v2(h, sql, -1, &st, NULL) == SQLITE_OK) {
        if (id) sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
        if (sqlite3_step(st) == SQLITE_ROW) v = sqlite3_column_int64(st, 0);
    }
    sqlite3_finalize(st);
    sqlite3_close(h);
    return v;
}

/* A result in a file stored: the same bytes come back, the summary and spans are those of the
 * text, the status is succeeded -- and the commit left the result in the WAL: no checkpoint ran
 * on the committing connection (it would have copied it into the database file). */
static void test_store_file(const char *want, size_t wlen)
{
    char id[33];
    CHECK(new_running_job(id) == 0);
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 65536);
    write_result(&w, NGRAINS, NULL);
    store_text t = {NULL, -1, 0};
    CHECK(gpd_jw_finish(&w, (char **)&t.mem, &t.fd, &t.len) == 0 && t.fd >= 0);
    long long db_before = file_size(db);
    gpd_err why;
    CHECK(store_succeed(id, &t, "{\"phase\":\"done\"}", NULL, NULL, 0, &why) == STORE_OK);
    close(t.fd);

    CHECK(wal_size() >= (long long)wlen);                 /* the result is in the WAL ... */
    CHECK(file_size(db) - db_before < (long long)wlen / 4); /* ... and not yet in the file */

    uint64_t len = 0;
    char *got = stored_result(id, &len);
    CHECK(got && len == wlen && !memcmp(got, want, wlen));
    free(got);
    CHECK(sql_long("SELECT typeof(r.result) = 'blob' AND j.result IS NULL FROM results r "
                   "JOIN jobs j USING (seq) WHERE j.id = ?1", id) == 1);

    char *summary = NULL, st[16];
    size_t slen = 0;
    uint64_t spans[STORE_SUMMARY_NSKIP][2], want_spans[STORE_SUMMARY_NSKIP][2];
    CHECK(store_get_summary(id, &summary, &slen, spans, st) == STORE_OK);
    CHECK(!strcmp(st, "succeeded"));
    static const char *const skip[] = STORE_SUMMARY_SKIP;
    js_source src = json_scan_memory_source(want, wlen);
    size_t wslen = 0;
    char *wsum = json_scan_object_without(&src, skip, &wslen, want_spans);
    CHECK(summary && wsum && slen == wslen && !memcmp(summary, wsum, slen));
    CHECK(!memcmp(spans, want_spans, sizeof spans));
    CHECK(want_spans[0][1] > want_spans[0][0] && want[want_spans[0][0]] == '[');
    free(summary);
    free(wsum);

    /* the maintenance thread's checkpoint: the WAL back to nothing, the result in the file */
    CHECK(store_reclaim() == 0);
    CHECK(wal_size() == 0);
    CHECK(file_size(db) - db_before >= (long long)wlen);
}

/* The same from memory (a small result, and a pack): the bytes come back. */
static void test_store_memory(void)
{
    char id[33];
    CHECK(new_running_job(id) == 0);
    const char *text = "{\"kind\":\"x\",\"grains\":[1,2,3],\"stats\":{\"a\":1.5}}";
    char pack[3000];
    for (size_t i = 0; i < sizeof pack; i++) pack[i] = (char)(i * 7);
    store_text t = {text, -1, strlen(text)};
    CHECK(store_succeed(id, &t, "{}", "{\"b\":1}", pack, sizeof pack, NULL) == STORE_OK);
    uint64_t len = 0;
    char *got = stored_result(id, &len);
    CHECK(got && len == strlen(text) && !strcmp(got, text));
    free(got);
    char st[16];
    store_stream *s = NULL;
    char *small = NULL;
    size_t slen = 0;
    CHECK(store_stream_open(id, "pack", 0, &s, &small, &slen, st) == STORE_OK && s);
    char back[sizeof pack];
    CHECK(s && store_stream_size(s) == sizeof pack && store_stream_read(s, 0, back, sizeof back) == 0 &&
          !memcmp(back, pack, sizeof pack));
    store_stream_close(s);
}

/* A file that cannot be read: nothing is written, the job stays running, why says so. A job
 * no longer running: STORE_CONFLICT, no result row. */
static void test_store_failures(void)
{
    char id[33];
    CHECK(new_running_job(id) == 0);
    int dfd = open(dir, O_RDONLY | O_DIRECTORY); /* pread: EISDIR */
    store_text t = {NULL, dfd, 5000000};
    gpd_err why;
    CHECK(store_succeed(id, &t, "{}", NULL, NULL, 0, &why) == STORE_ERROR);
    CHECK(strstr(why.msg, "temporary file") != NULL);
    close(dfd);
    store_rc rc;
    json_t *j = store_get_job(id, &rc);
    CHECK(j && !strcmp(json_string_value(json_object_get(j, "status")), "running"));
    json_decref(j);
    CHECK(sql_long("SELECT count(*) FROM results r JOIN jobs j USING (seq) WHERE j.id = ?1",
                   id) == 0);

    int was_running = 0;
    char status[16];
    CHECK(store_cancel(id, &was_running, status, NULL) == STORE_OK && was_running);
    store_text ok = {"{}", -1, 2};
    CHECK(store_succeed(id, &ok, "{}", NULL, NULL, 0, NULL) == STORE_CONFLICT);
    CHECK(sql_long("SELECT count(*) FROM results r JOIN jobs j USING (seq) WHERE j.id = ?1",
                   id) == 0);
}

/* A job stored before the results table (its text in jobs.result) reads as before; a purge
 * removes a new job's result row. */
static void test_store_legacy_and_purge(const char *want, size_t wlen)
{
    char id[33];
    CHECK(store_insert("fourier-voronoi-2d", "{}", NULL, 0, id) == STORE_OK);
    sqlite3 *h = NULL;
    sqlite3_stmt *st = NULL;
    CHECK(sqlite3_open(db, &h) == SQLITE_OK);
    sqlite3_busy_timeout(h, 5000);
    CHECK(sqlite3_prepare_v2(h, "UPDATE jobs SET status='succeeded', result=?2 WHERE id=?1", -1,
                             &st, NULL) == SQLITE_OK);
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, want, (int)wlen, SQLITE_STATIC);
    CHECK(sqlite3_step(st) == SQLITE_DONE);
    sqlite3_finalize(st);
    sqlite3_close(h);
    uint64_t len = 0;
    char *got = stored_result(id, &len);
    CHECK(got && len == wlen && !memcmp(got, want, wlen));
    free(got);
    char *summary = NULL, status[16];
    CHECK(store_get_summary(id, &summary, NULL, NULL, status) == STORE_OK && summary &&
          strstr(summary, "\"stats\"") && !strstr(summary, "\"grains\""));
    free(summary);
    CHECK(store_purge(id, status) == STORE_OK);

    long long rows = sql_long("SELECT count(*) FROM results", NULL);
    char nid[33];
    CHECK(new_running_job(nid) == 0);
    store_text t = {"{\"grains\":[]}", -1, 13};
    CHECK(store_succeed(nid, &t, "{}", NULL, NULL, 0, NULL) == STORE_OK);
    CHECK(sql_long("SELECT count(*) FROM results", NULL) == rows + 1);
    CHECK(store_purge(nid, status) == STORE_OK);
    /* out of view at once; its result freed by store_free_purged, a row a call */
    store_rc rc;
    CHECK(store_get_job(nid, &rc) == NULL && rc == STORE_NOT_FOUND);
    CHECK(store_purge(nid, status) == STORE_NOT_FOUND);
    CHECK(sql_long("SELECT count(*) FROM results", NULL) == rows + 1);
    CHECK(sql_long("SELECT count(*) FROM purged", NULL) == 2); /* and the older job's */
    int steps = 0;
    while (store_free_purged() > 0) steps++;
    /* the older job's entry (its row held its result); the new job's result row, its entry */
    CHECK(steps == 3);
    CHECK(sql_long("SELECT count(*) FROM results", NULL) == rows);
    CHECK(sql_long("SELECT count(*) FROM purged", NULL) == 0);
}

/* Bytes [off, off + n) of id's value `what` through a stream of its own (small: 0). */
static int read_range(const char *id, const char *what, uint64_t off, size_t n, char *dst)
{
    store_stream *s = NULL;
    char *text = NULL, st[16];
    size_t tlen = 0;
    if (store_stream_open(id, what, 0, &s, &text, &tlen, st) != STORE_OK || !s) {
        free(text);
        return -1;
    }
    int rc = store_stream_read(s, off, dst, n);
    store_stream_close(s);
    return rc;
}

/* Values over the database's limit on one value (lowered to 100 kB by the testing hook) are
 * stored in parts (store.h "Values in parts"): the bytes come back whole, in ranges across the
 * parts' seams and read small; a stream opened before a purge reads every part as it was; the
 * purge removes the parts. */
static void test_store_parts(const char *want, size_t wlen)
{
    const size_t lim = 100000 - 1024; /* a part: store_part_size */
    setenv("GRAINPACK_TEST_SQLITE_MAX_LENGTH", "100000", 1);
    CHECK(store_open(db) == 0);
    char id[33], st[16];
    CHECK(new_running_job(id) == 0);
    int fd = open(dir, O_TMPFILE | O_RDWR, 0600);
    CHECK(fd >= 0 && write(fd, want, wlen) == (ssize_t)wlen);
    store_text t = {NULL, fd, wlen};
    static char pack[250001];
    for (size_t i = 0; i < sizeof pack; i++) pack[i] = (char)(i * 13 + i / 977);
    CHECK(store_succeed(id, &t, "{}", NULL, pack, sizeof pack, NULL) == STORE_OK);
    close(fd);
    CHECK(sql_long("SELECT count(*) FROM value_parts p JOIN jobs j USING (seq) "
                   "WHERE j.id = ?1 AND p.what = 0", id) == (long long)((wlen - 1) / lim));
    CHECK(sql_long("SELECT count(*) FROM value_parts p JOIN jobs j USING (seq) "
                   "WHERE j.id = ?1 AND p.what = 1", id) == 2);
    CHECK(sql_long("SELECT max(length(data)) FROM value_parts", NULL) == (long long)lim);
    uint64_t len = 0;
    char *got = stored_result(id, &len);
    CHECK(got && len == wlen && !memcmp(got, want, wlen));
    free(got);
    /* ranges over the seams: the last bytes of a part and the first of the next */
    char buf[3000];
    for (size_t seam = lim; seam + 1500 < wlen && seam <= 20 * lim; seam += lim) {
        CHECK(read_range(id, "result", seam - 1500, sizeof buf, buf) == 0 &&
              !memcmp(buf, want + seam - 1500, sizeof buf));
    }
    CHECK(read_range(id, "pack", 99999, 2, buf) == 0 && !memcmp(buf, pack + 99999, 2));
    /* read whole when it is small enough, though in three parts */
    store_stream *s = NULL;
    char *text = NULL;
    size_t tlen = 0;
    CHECK(store_stream_open(id, "pack", sizeof pack, &s, &text, &tlen, st) == STORE_OK && !s &&
          text && tlen == sizeof pack && !memcmp(text, pack, sizeof pack));
    free(text);
    /* the snapshot: a stream open before the purge reads every part after it */
    CHECK(store_stream_open(id, "result", 0, &s, &text, &tlen, st) == STORE_OK && s);
    CHECK(store_purge(id, st) == STORE_OK);
    while (store_free_purged() > 0) {
    }
    CHECK(sql_long("SELECT count(*) FROM value_parts", NULL) == 0);
    char *again = malloc(wlen);
    CHECK(s && again && store_stream_size(s) == wlen && store_stream_read(s, 0, again, wlen) == 0 &&
          !memcmp(again, want, wlen));
    free(again);
    store_stream_close(s);
    store_close();
    unsetenv("GRAINPACK_TEST_SQLITE_MAX_LENGTH");
}

static long vm_kb(const char *key)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long v = -1;
    size_t n = strlen(key);
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ':') v = strtol(line + n + 1, NULL, 10);
    if (f) fclose(f);
    return v;
}

/* The peak RSS (VmHWM, reset first) that reading fd whole into memory adds: the control of
 * the measurement below (it must see the text). -1 when VmHWM cannot be reset. */
static long hwm_growth(int fd, uint64_t len, int read_whole, char id[33], store_text *t)
{
    FILE *cr = fopen("/proc/self/clear_refs", "w");
    int reset = cr && fputs("5", cr) >= 0;
    if (cr && fclose(cr) != 0) reset = 0;
    long before = vm_kb("VmRSS");
    if (!reset || vm_kb("VmHWM") > before + 1024) return -1;
    if (read_whole) {
        char *all = read_fd(fd, len);
        CHECK(all != NULL);
        free(all);
    } else {
        CHECK(store_succeed(id, t, "{}", NULL, NULL, 0, NULL) == STORE_OK);
    }
    return vm_kb("VmHWM") - before;
}

/* Storing a 34 MB result from its file costs a few MB of memory, not the text: the peak RSS
 * (VmHWM, reset first) during store_succeed, next to the same measure of reading the file into
 * memory. Skipped under ASan (its allocator keeps freed blocks) and where VmHWM cannot be
 * reset. */
static void test_store_memory_bound(void)
{
    if (UNDER_ASAN) return;
    char id[33];
    CHECK(new_running_job(id) == 0);
    gpd_jw w;
    gpd_jw_init(&w, NULL);
    gpd_jw_spill(&w, dir, 0);
    write_result(&w, 350000, NULL);
    store_text t = {NULL, -1, 0};
    CHECK(gpd_jw_finish(&w, (char **)&t.mem, &t.fd, &t.len) == 0 && t.fd >= 0);
    CHECK(t.len > 32u * 1024 * 1024);
    long control = hwm_growth(t.fd, t.len, 1, id, &t);
    long grew = control >= 0 ? hwm_growth(t.fd, t.len, 0, id, &t) : -1;
    if (grew >= 0) {
        printf("peak RSS: reading the %.1f MB result into memory +%.1f MB; store_succeed from "
               "its file +%.1f MB\n", t.len / 1e6, control / 1024.0, grew / 1024.0);
        CHECK(control >= (long)(t.len / 1024) * 3 / 4); /* the measure sees a copy of the text */
        CHECK(grew < 12 * 1024); /* a piece, the page cache, the summary: not the text */
    } else {
        CHECK(store_succeed(id, &t, "{}", NULL, NULL, 0, NULL) == STORE_OK);
        printf("VmHWM cannot be reset here: the memory bound is not checked\n");
    }
    close(t.fd);
}

/* A VFS over the default one that, while armed, makes every write to a main database file
 * a claim (store_checkpoint_yield): in WAL mode only a checkpoint's copy writes there, so the
 * claim lands during the copy, after its first page, at a known moment -- not whenever a
 * spinning thread happens to be scheduled, which a loaded 2-core machine may never do within
 * a copy of 5 MB. */
typedef struct {
    sqlite3_file base;
    sqlite3_file *real;
    int main_db;
} yfile;

static sqlite3_vfs *real_vfs;
static sqlite3_vfs yield_vfs;
static sqlite3_io_methods yield_io;
static int yield_armed;  /* only the checkpointing thread touches these while armed */
static int yield_claims; /* claims made by armed writes */

#define REAL(f) (((yfile *)(f))->real)
static int y_close(sqlite3_file *f) { return REAL(f)->pMethods->xClose(REAL(f)); }
static int y_read(sqlite3_file *f, void *b, int n, sqlite3_int64 o)
{
    return REAL(f)->pMethods->xRead(REAL(f), b, n, o);
}
static int y_write(sqlite3_file *f, const void *b, int n, sqlite3_int64 o)
{
    if (yield_armed && ((yfile *)f)->main_db) {
        store_checkpoint_yield();
        yield_claims++;
    }
    return REAL(f)->pMethods->xWrite(REAL(f), b, n, o);
}
static int y_truncate(sqlite3_file *f, sqlite3_int64 n)
{
    return REAL(f)->pMethods->xTruncate(REAL(f), n);
}
static int y_sync(sqlite3_file *f, int fl) { return REAL(f)->pMethods->xSync(REAL(f), fl); }
static int y_size(sqlite3_file *f, sqlite3_int64 *n)
{
    return REAL(f)->pMethods->xFileSize(REAL(f), n);
}
static int y_lock(sqlite3_file *f, int l) { return REAL(f)->pMethods->xLock(REAL(f), l); }
static int y_unlock(sqlite3_file *f, int l) { return REAL(f)->pMethods->xUnlock(REAL(f), l); }
static int y_reserved(sqlite3_file *f, int *r)
{
    return REAL(f)->pMethods->xCheckReservedLock(REAL(f), r);
}
static int y_fcntl(sqlite3_file *f, int op, void *a)
{
    return REAL(f)->pMethods->xFileControl(REAL(f), op, a);
}
static int y_sector(sqlite3_file *f) { return REAL(f)->pMethods->xSectorSize(REAL(f)); }
static int y_devchar(sqlite3_file *f)
{
    return REAL(f)->pMethods->xDeviceCharacteristics(REAL(f));
}
static int y_shm_map(sqlite3_file *f, int pg, int sz, int ext, void volatile **pp)
{
    return REAL(f)->pMethods->xShmMap(REAL(f), pg, sz, ext, pp);
}
static int y_shm_lock(sqlite3_file *f, int off, int n, int fl)
{
    return REAL(f)->pMethods->xShmLock(REAL(f), off, n, fl);
}
static void y_shm_barrier(sqlite3_file *f) { REAL(f)->pMethods->xShmBarrier(REAL(f)); }
static int y_shm_unmap(sqlite3_file *f, int del)
{
    return REAL(f)->pMethods->xShmUnmap(REAL(f), del);
}
static int y_fetch(sqlite3_file *f, sqlite3_int64 o, int n, void **pp)
{
    return REAL(f)->pMethods->xFetch(REAL(f), o, n, pp);
}
static int y_unfetch(sqlite3_file *f, sqlite3_int64 o, void *p)
{
    return REAL(f)->pMethods->xUnfetch(REAL(f), o, p);
}
#undef REAL

static int y_open(sqlite3_vfs *vfs, const char *name, sqlite3_file *f, int flags, int *out)
{
    (void)vfs;
    yfile *y = (yfile *)f;
    y->real = (sqlite3_file *)(y + 1);
    y->main_db = (flags & SQLITE_OPEN_MAIN_DB) != 0;
    int rc = real_vfs->xOpen(real_vfs, name, y->real, flags, out);
    /* the unix VFS's methods are version 3: every slot above exists */
    y->base.pMethods = rc == SQLITE_OK && y->real->pMethods ? &yield_io : NULL;
    return rc;
}

/* registered as the default before the store opens its connections */
static int yield_vfs_register(void)
{
    real_vfs = sqlite3_vfs_find(NULL);
    if (!real_vfs || real_vfs->iVersion < 1) return -1;
    yield_vfs = *real_vfs; /* the other methods ignore which VFS they are called through */
    yield_vfs.zName = "grainpack-test-yield";
    yield_vfs.szOsFile = (int)sizeof(yfile) + real_vfs->szOsFile;
    yield_vfs.xOpen = y_open;
    yield_vfs.pNext = NULL;
    yield_io = (sqlite3_io_methods){3, y_close, y_read, y_write, y_truncate, y_sync, y_size,
                                    y_lock, y_unlock, y_reserved, y_fcntl, y_sector,
                                    y_devchar, y_shm_map, y_shm_lock, y_shm_barrier,
                                    y_shm_unmap, y_fetch, y_unfetch};
    return sqlite3_vfs_register(&yield_vfs, 1) == SQLITE_OK ? 0 : -1;
}

/* A checkpoint that may yield stops when a claim (store_checkpoint_yield) comes during its copy:
 * 2, the WAL left as it was; one that may not yield is not stopped by the same claims; after
 * it the WAL is empty. */
static void test_checkpoint_yields(const char *want, size_t wlen)
{
    char id[33];
    CHECK(new_running_job(id) == 0);
    store_text t = {want, -1, wlen};
    CHECK(store_succeed(id, &t, "{}", NULL, NULL, 0, NULL) == STORE_OK);
    long long wal = wal_size();
    CHECK(wal >= (long long)wlen);
    yield_claims = 0;
    yield_armed = 1;
    int rc = store_checkpoint(1);
    yield_armed = 0;
    CHECK(rc == 2);
    CHECK(yield_claims == 1); /* stopped at the next page after the first claim */
    CHECK(wal_size() == wal);
    yield_claims = 0;
    yield_armed = 1;
    CHECK(store_checkpoint(0) == 0); /* not interrupted by the claims */
    yield_armed = 0;
    CHECK(yield_claims > 100); /* the claims came: the copy went on through them */
    CHECK(wal_size() == 0);
}

/* The maintenance thread checkpoints after a large commit (the store's WAL hook kicks it):
 * the WAL goes back to nothing without anyone calling store_reclaim. */
static void test_maint_checkpoints(const char *want, size_t wlen)
{
    CHECK(store_reclaim() == 0 && wal_size() == 0); /* what the tests above left */
    CHECK(maint_start(0) == 0);
    char id[33];
    CHECK(new_running_job(id) == 0);
    store_text t = {want, -1, wlen};
    CHECK(store_succeed(id, &t, "{}", NULL, NULL, 0, NULL) == STORE_OK);
    /* wait for the thread (bounded; not a timing check: it may take long on a loaded box) */
    long long wal = -1;
    for (int i = 0; i < 600 && (wal = wal_size()) != 0; i++) usleep(50000);
    CHECK(wal == 0);
    maint_stop();
    uint64_t len = 0;
    char *got = stored_result(id, &len);
    CHECK(got && len == wlen && !memcmp(got, want, wlen));
    free(got);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/test_store_write-XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(db, sizeof db, "%s/jobs.db", dir);
    size_t wlen = 0;
    CHECK(yield_vfs_register() == 0);
    char *want = test_spill_same_bytes(&wlen);
    if (want) {
        test_spill_no_dir(want, wlen);
        test_spill_cancel();
        CHECK(store_open(db) == 0);
        char *sd = store_spill_dir();
        CHECK(sd && !strcmp(sd, dir));
        free(sd);
        test_store_file(want, wlen);
        test_store_memory();
        test_store_failures();
        test_store_legacy_and_purge(want, wlen);
        test_store_memory_bound();
        test_checkpoint_yields(want, wlen);
        test_maint_checkpoints(want, wlen);
        store_close();
        test_store_parts(want, wlen);
        test_spill_write_fails();
    }
    free(want);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    return gp_test_summary();
}
