/* file_errors.c -- the last failed write of a worker's own file (see file_errors.h). */
#include "jobs/file_errors.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "util/util.h"

static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static struct {
    long count;
    double when; /* gpd_monotonic_s */
    char at[40];
    char msg[256];
} last;

void gpd_file_error_note(const char *what, int err)
{
    pthread_mutex_lock(&mu);
    last.count++;
    last.when = gpd_monotonic_s();
    gpd_now_rfc3339(last.at, sizeof last.at);
    snprintf(last.msg, sizeof last.msg, "%s: %s", what, strerror(err));
    pthread_mutex_unlock(&mu);
}

int gpd_file_error_last(double window_s, char *msg, size_t msg_len, char at[40], long *count)
{
    pthread_mutex_lock(&mu);
    int recent = last.count > 0 && gpd_monotonic_s() - last.when <= window_s;
    if (recent) {
        snprintf(msg, msg_len, "%s", last.msg);
        snprintf(at, 40, "%s", last.at);
        *count = last.count;
    }
    pthread_mutex_unlock(&mu);
    return recent;
}
