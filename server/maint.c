/* maint.c -- the retention sweep and the reclaim of purged space (see maint.h). */
#include "maint.h"

#include <pthread.h>
#include <time.h>

#include "store.h"
#include "util.h"

#define RECLAIM_RETRY_MIN_S 1.0
#define RECLAIM_RETRY_MAX_S 30.0
#define SWEEP_AGAIN_S 1.0 /* a full pass: the next one soon */

static pthread_t thread;
static int running = 0;
static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv;
static int quit = 0;   /* guarded by mu */
static int kicked = 0; /* guarded by mu */
static double retain_s = 0;

/* One pass of the sweep: purges up to MAINT_SWEEP_MAX jobs past the limit; their number. */
static int sweep(void)
{
    char before[40];
    gpd_past_rfc3339(retain_s, before, sizeof before);
    int n = store_purge_finished_before(before, MAINT_SWEEP_MAX);
    if (n > 0)
        gpd_log(GPD_LOG_INFO, "retention: purged %d finished job(s) that finished before %s", n,
                before);
    return n;
}

/* waits until the monotonic time `until` (0 = no limit), a kick or the stop; 1 when stopping */
static int wait_until(double until)
{
    pthread_mutex_lock(&mu);
    while (!quit && !kicked) {
        if (until <= 0) {
            pthread_cond_wait(&cv, &mu);
            continue;
        }
        double left = until - gpd_monotonic_s();
        if (left <= 0) break;
        struct timespec dl;
        clock_gettime(CLOCK_MONOTONIC, &dl);
        double t = (double)dl.tv_sec + 1e-9 * (double)dl.tv_nsec + left;
        dl.tv_sec = (time_t)t;
        dl.tv_nsec = (long)((t - (double)dl.tv_sec) * 1e9);
        if (dl.tv_nsec >= 1000000000L) dl.tv_nsec = 999999999L;
        pthread_cond_timedwait(&cv, &mu, &dl);
    }
    int q = quit;
    pthread_mutex_unlock(&mu);
    return q;
}

static void *maint_main(void *arg)
{
    (void)arg;
    double next_sweep = retain_s > 0 ? gpd_monotonic_s() : 0; /* at start-up first */
    int dirty = 0;              /* space to give back */
    double retry = 0, retry_at = 0;
    for (;;) {
        double until = next_sweep;
        if (dirty && retry_at > 0 && (until <= 0 || retry_at < until)) until = retry_at;
        if (wait_until(dirty && retry_at <= 0 ? gpd_monotonic_s() : until)) break;
        pthread_mutex_lock(&mu);
        if (kicked) {
            kicked = 0;
            dirty = 1;
            retry_at = 0; /* at once */
        }
        pthread_mutex_unlock(&mu);
        double now = gpd_monotonic_s();
        if (next_sweep > 0 && now >= next_sweep) {
            int n = sweep();
            if (n > 0) {
                dirty = 1;
                retry_at = 0;
            }
            next_sweep = now + (n >= MAINT_SWEEP_MAX ? SWEEP_AGAIN_S : MAINT_SWEEP_INTERVAL_S);
        }
        if (dirty && (retry_at <= 0 || now >= retry_at)) {
            int rc = store_reclaim();
            if (rc == 0) {
                dirty = 0;
                retry = 0;
                retry_at = 0;
            } else { /* blocked by a reader (or an error): later, backing off */
                retry = retry <= 0 ? RECLAIM_RETRY_MIN_S
                                   : (retry * 2 > RECLAIM_RETRY_MAX_S ? RECLAIM_RETRY_MAX_S
                                                                       : retry * 2);
                retry_at = gpd_monotonic_s() + retry;
                gpd_log(GPD_LOG_DEBUG, "reclaim: the checkpoint is blocked; again in %.0f s",
                        retry);
            }
        }
    }
    store_thread_done();
    return NULL;
}

int maint_start(double retain_days)
{
    retain_s = retain_days > 0 ? retain_days * 86400.0 : 0;
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&cv, &ca);
    pthread_condattr_destroy(&ca);
    quit = 0;
    kicked = 0;
    if (pthread_create(&thread, NULL, maint_main, NULL) != 0) {
        gpd_log(GPD_LOG_ERROR, "cannot start the maintenance thread");
        pthread_cond_destroy(&cv);
        return -1;
    }
    running = 1;
    return 0;
}

void maint_kick(void)
{
    if (!running) return;
    pthread_mutex_lock(&mu);
    kicked = 1;
    pthread_cond_signal(&cv);
    pthread_mutex_unlock(&mu);
}

void maint_stop(void)
{
    if (!running) return;
    pthread_mutex_lock(&mu);
    quit = 1;
    pthread_cond_signal(&cv);
    pthread_mutex_unlock(&mu);
    pthread_join(thread, NULL);
    running = 0;
    pthread_cond_destroy(&cv);
}
