/* offload.c -- a small thread pool of FIFO lanes for request work (see offload.h). */
#define _GNU_SOURCE /* syscall */
#include "http/offload.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#define OFFLOAD_MAX_THREADS 16
#define OFFLOAD_NICE 5
#define RETRY_MAX_S 600
/* weight of the newest task time in a lane's running mean */
#define EWMA_NEW 0.3

typedef struct task {
    void (*run)(void *);
    int (*gone)(void *);
    void *arg;
    struct task *next;
} task;

typedef struct lane {
    task *head, *tail;
    unsigned queued;   /* tasks waiting */
    unsigned busy;     /* tasks running */
    unsigned threads;
    double mean_s;     /* recent task time, for Retry-After (0: none finished yet) */
} lane;

static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv = PTHREAD_COND_INITIALIZER;
static lane lanes[GPD_LANES];
static unsigned max_queued_ = 16;
static int running = 0; /* accepting tasks */
static unsigned n_threads = 0;
static pthread_t threads_[OFFLOAD_MAX_THREADS];
static gpd_lane thread_lane[OFFLOAD_MAX_THREADS];

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* the head of l, unlinked; NULL when empty (call with mu held) */
static task *take(lane *l)
{
    task *t = l->head;
    if (!t) return NULL;
    l->head = t->next;
    if (!l->head) l->tail = NULL;
    l->queued--;
    return t;
}

static void *pool_main(void *lane_arg)
{
    lane *l = &lanes[*(gpd_lane *)lane_arg];
    /* Linux: a thread's nice value is its own (best effort: an unprivileged process may
     * always lower its priority) */
    (void)setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), OFFLOAD_NICE);
    pthread_mutex_lock(&mu);
    for (;;) {
        while (!l->head && running) pthread_cond_wait(&cv, &mu);
        task *t = take(l);
        if (!t) break; /* stopped and drained */
        l->busy++;
        pthread_mutex_unlock(&mu);
        double t0 = now_s();
        t->run(t->arg);
        free(t);
        double took = now_s() - t0;
        pthread_mutex_lock(&mu);
        l->busy--;
        l->mean_s = l->mean_s > 0 ? (1 - EWMA_NEW) * l->mean_s + EWMA_NEW * took : took;
    }
    pthread_mutex_unlock(&mu);
    return NULL;
}

int gpd_offload_start(unsigned threads, unsigned max_queued)
{
    if (threads < GPD_LANES) threads = GPD_LANES;
    if (threads > OFFLOAD_MAX_THREADS) threads = OFFLOAD_MAX_THREADS;
    max_queued_ = max_queued ? max_queued : 1;
    running = 1;
    for (n_threads = 0; n_threads < threads; n_threads++) {
        /* round robin: every lane gets a thread before any gets two */
        gpd_lane ln = (gpd_lane)(n_threads % GPD_LANES);
        thread_lane[n_threads] = ln;
        lanes[ln].threads++;
        if (pthread_create(&threads_[n_threads], NULL, pool_main, &thread_lane[n_threads]) != 0) {
            lanes[ln].threads--;
            gpd_offload_stop();
            return -1;
        }
    }
    return 0;
}

/* Unlinks l's queued tasks whose client has gone into a list (call with mu held). */
static task *unlink_gone(lane *l)
{
    task *dropped = NULL, **p = &l->head, *prev = NULL;
    while (*p) {
        task *t = *p;
        if (t->gone && t->gone(t->arg)) {
            *p = t->next;
            l->queued--;
            t->next = dropped;
            dropped = t;
            continue;
        }
        prev = t;
        p = &t->next;
    }
    l->tail = prev;
    return dropped;
}

/* the seconds after which a lane as full as l has room again (call with mu held) */
static int retry_after(const lane *l)
{
    double per = l->mean_s > 0 ? l->mean_s : 1.0;
    double s = ceil(per * (double)(l->queued + l->busy) / (double)(l->threads ? l->threads : 1));
    return s < 1 ? 1 : s > RETRY_MAX_S ? RETRY_MAX_S : (int)s;
}

int gpd_offload_submit(gpd_lane lane_id, void (*run)(void *arg), int (*gone)(void *arg),
                       void *arg, int *retry_s)
{
    task *t = malloc(sizeof *t);
    if (!t) return -1;
    *t = (task){run, gone, arg, NULL};
    lane *l = &lanes[lane_id];
    task *dropped = NULL;
    int rc = 0;
    pthread_mutex_lock(&mu);
    if (!running) rc = -1;
    if (rc == 0 && l->queued >= max_queued_) dropped = unlink_gone(l);
    if (rc == 0 && l->queued >= max_queued_) {
        rc = 1;
        if (retry_s) *retry_s = retry_after(l);
    }
    if (rc == 0) {
        if (l->tail) l->tail->next = t;
        else l->head = t;
        l->tail = t;
        l->queued++;
        pthread_cond_broadcast(&cv);
    }
    pthread_mutex_unlock(&mu);
    if (rc != 0) free(t);
    /* outside the lock: a dropped task answers nothing and resumes its connection */
    while (dropped) {
        task *d = dropped;
        dropped = d->next;
        d->run(d->arg);
        free(d);
    }
    return rc;
}

void gpd_offload_stop(void)
{
    pthread_mutex_lock(&mu);
    running = 0;
    pthread_cond_broadcast(&cv);
    pthread_mutex_unlock(&mu);
    for (unsigned i = 0; i < n_threads; i++) pthread_join(threads_[i], NULL);
    n_threads = 0;
    for (int k = 0; k < GPD_LANES; k++) lanes[k].threads = 0;
}
