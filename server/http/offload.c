/* offload.c -- a small FIFO thread pool for request work (see offload.h). */
#define _GNU_SOURCE /* syscall */
#include "http/offload.h"

#include <pthread.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#define OFFLOAD_MAX_THREADS 16
#define OFFLOAD_NICE 5

typedef struct task {
    void (*run)(void *);
    void *arg;
    struct task *next;
} task;

static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv = PTHREAD_COND_INITIALIZER;
static task *head = NULL, *tail = NULL;
static int running = 0; /* accepting tasks */
static unsigned n_threads = 0;
static pthread_t threads_[OFFLOAD_MAX_THREADS];

static void *pool_main(void *unused)
{
    (void)unused;
    /* Linux: a thread's nice value is its own (best effort: an unprivileged process may
     * always lower its priority) */
    (void)setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), OFFLOAD_NICE);
    pthread_mutex_lock(&mu);
    for (;;) {
        while (!head && running) pthread_cond_wait(&cv, &mu);
        task *t = head;
        if (!t) break; /* stopped and drained */
        head = t->next;
        if (!head) tail = NULL;
        pthread_mutex_unlock(&mu);
        t->run(t->arg);
        free(t);
        pthread_mutex_lock(&mu);
    }
    pthread_mutex_unlock(&mu);
    return NULL;
}

int gpd_offload_start(unsigned threads)
{
    if (threads < 1) threads = 1;
    if (threads > OFFLOAD_MAX_THREADS) threads = OFFLOAD_MAX_THREADS;
    running = 1;
    for (n_threads = 0; n_threads < threads; n_threads++)
        if (pthread_create(&threads_[n_threads], NULL, pool_main, NULL) != 0) {
            gpd_offload_stop();
            return -1;
        }
    return 0;
}

int gpd_offload_submit(void (*run)(void *arg), void *arg)
{
    task *t = malloc(sizeof *t);
    if (!t) return -1;
    t->run = run;
    t->arg = arg;
    t->next = NULL;
    pthread_mutex_lock(&mu);
    if (!running) {
        pthread_mutex_unlock(&mu);
        free(t);
        return -1;
    }
    if (tail) tail->next = t;
    else head = t;
    tail = t;
    pthread_cond_signal(&cv);
    pthread_mutex_unlock(&mu);
    return 0;
}

void gpd_offload_stop(void)
{
    pthread_mutex_lock(&mu);
    running = 0;
    pthread_cond_broadcast(&cv);
    pthread_mutex_unlock(&mu);
    for (unsigned i = 0; i < n_threads; i++) pthread_join(threads_[i], NULL);
    n_threads = 0;
}
