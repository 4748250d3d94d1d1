/* util.c -- errors, the logger, the clock, job ids, the growable buffer (see util.h). */
#include "util/util.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

void gpd_err_set(gpd_err *e, int status, const char *fmt, ...)
{
    if (!e) return;
    e->status = status;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
}

/* ------------------------------------------------------------------ logging */

static int log_threshold = GPD_LOG_INFO; /* atomic: set at start-up, read by every thread */
static pthread_mutex_t log_mu = PTHREAD_MUTEX_INITIALIZER;

int gpd_log_parse_level(const char *s)
{
    if (!s) return -1;
    if (!strcmp(s, "error")) return GPD_LOG_ERROR;
    if (!strcmp(s, "warn") || !strcmp(s, "warning")) return GPD_LOG_WARN;
    if (!strcmp(s, "info")) return GPD_LOG_INFO;
    if (!strcmp(s, "debug")) return GPD_LOG_DEBUG;
    return -1;
}

void gpd_log_set_level(gpd_log_level level)
{
    __atomic_store_n(&log_threshold, (int)level, __ATOMIC_RELAXED);
}

int gpd_log_enabled(gpd_log_level level)
{
    return (int)level <= __atomic_load_n(&log_threshold, __ATOMIC_RELAXED);
}

void gpd_log(gpd_log_level level, const char *fmt, ...)
{
    static const char *names[] = {"error", "warn", "info", "debug"};
    if (!gpd_log_enabled(level)) return;
    char ts[40];
    gpd_now_rfc3339(ts, sizeof ts);
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    pthread_mutex_lock(&log_mu);
    fprintf(stderr, "%s %-5s %s\n", ts, names[level], msg);
    fflush(stderr);
    pthread_mutex_unlock(&log_mu);
}

/* ------------------------------------------------------------------ time, ids */

void gpd_now_rfc3339(char *buf, size_t len)
{
    gpd_past_rfc3339(0, buf, len);
}

void gpd_past_rfc3339(double ago_s, char *buf, size_t len)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    if (ago_s > 0) {
        long long ms = (long long)ts.tv_sec * 1000 + ts.tv_nsec / 1000000L -
                       (long long)(ago_s * 1000.0 + 0.5);
        if (ms < 0) ms = 0;
        ts.tv_sec = (time_t)(ms / 1000);
        ts.tv_nsec = (long)(ms % 1000) * 1000000L;
    }
    struct tm tm;
    gmtime_r(&ts.tv_sec, &tm);
    size_t n = strftime(buf, len, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(buf + n, len - n, ".%03dZ", (int)(ts.tv_nsec / 1000000L));
}

double gpd_monotonic_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void gpd_sleep_s(double s)
{
    if (!(s > 0)) return;
    struct timespec ts = {.tv_sec = (time_t)s, .tv_nsec = (long)((s - (double)(time_t)s) * 1e9)};
    while (nanosleep(&ts, &ts) != 0) {
    }
}

int gpd_new_id(char out[33])
{
    unsigned char b[16];
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd < 0) return -1;
    size_t got = 0;
    while (got < sizeof b) {
        ssize_t r = read(fd, b + got, sizeof b - got);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
            close(fd);
            return -1;
        }
        got += (size_t)r;
    }
    close(fd);
    static const char hex[] = "0123456789abcdef";
    for (int i = 0; i < 16; i++) {
        out[2 * i] = hex[b[i] >> 4];
        out[2 * i + 1] = hex[b[i] & 15];
    }
    out[32] = '\0';
    return 0;
}

int gpd_id_is_plausible(const char *s)
{
    size_t n = 0;
    for (; s[n]; n++) {
        char c = s[n];
        int ok = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                 c == '-' || c == '_';
        if (!ok || n >= 64) return 0;
    }
    return n > 0;
}

/* ------------------------------------------------------------------ buffer */

int gpd_buf_reserve(gpd_buf *b, size_t n)
{
    if (b->oom) return -1;
    if (b->len + n + 1 <= b->cap) return 0;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap < b->len + n + 1) cap *= 2;
    char *p = realloc(b->buf, cap);
    if (!p) {
        b->oom = 1;
        return -1;
    }
    b->buf = p;
    b->cap = cap;
    return 0;
}

int gpd_buf_add(gpd_buf *b, const void *p, size_t n)
{
    if (gpd_buf_reserve(b, n)) return -1;
    memcpy(b->buf + b->len, p, n);
    b->len += n;
    b->buf[b->len] = '\0';
    return 0;
}

int gpd_buf_printf(gpd_buf *b, const char *fmt, ...)
{
    char small[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) return -1;
    if ((size_t)n < sizeof small) return gpd_buf_add(b, small, (size_t)n);
    if (gpd_buf_reserve(b, (size_t)n)) return -1;
    va_start(ap, fmt);
    vsnprintf(b->buf + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
    return 0;
}

/* ---- the heap ---- */

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define GPD_SANITIZED_HEAP 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define GPD_SANITIZED_HEAP 1
#endif
#endif

void gpd_heap_trim(void)
{
#if defined(__GLIBC__) && !defined(GPD_SANITIZED_HEAP)
    malloc_trim(0);
#endif
}
