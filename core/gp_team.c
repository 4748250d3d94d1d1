/* gp_team.c -- see gp_team.h. */
#include "gp_team.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <unistd.h>

#include "gp_clock.h"

/* how long a helper spins after a round before it sleeps, and the caller before it yields */
#define SPIN_S 100e-6

typedef struct helper {
    struct gp_team *t;
    int tid;
} helper;

struct gp_team {
    int size;
    unsigned gen;    /* atomic: the round number; a change starts a round (or quits) */
    int done;        /* atomic: helpers finished with this round */
    int quit;        /* atomic */
    int sleepers;    /* atomic, changed under mu: helpers in (or entering) cond_wait */
    gp_team_fn fn;   /* the round's work, published by the release of gen */
    void *ctx;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    pthread_t *th;
    helper *args;
};

static inline void cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

/* The round after `seen`: spins for SPIN_S (the clock read every 64 pauses), then sleeps. */
static unsigned wait_round(gp_team *t, unsigned seen)
{
    unsigned g;
    double t0 = -1.0;
    for (int k = 0; (g = __atomic_load_n(&t->gen, __ATOMIC_ACQUIRE)) == seen; k++) {
        cpu_relax();
        if ((k & 63) != 63) continue;
        double now = gp_clock_seconds();
        if (t0 < 0) t0 = now;
        if (now - t0 < SPIN_S) continue;
        pthread_mutex_lock(&t->mu);
        __atomic_add_fetch(&t->sleepers, 1, __ATOMIC_SEQ_CST);
        while (__atomic_load_n(&t->gen, __ATOMIC_SEQ_CST) == seen) pthread_cond_wait(&t->cv, &t->mu);
        __atomic_sub_fetch(&t->sleepers, 1, __ATOMIC_SEQ_CST);
        pthread_mutex_unlock(&t->mu);
    }
    return g;
}

static void *helper_main(void *arg)
{
    helper *h = arg;
    gp_team *t = h->t;
    unsigned seen = 0;
    for (;;) {
        seen = wait_round(t, seen);
        if (__atomic_load_n(&t->quit, __ATOMIC_ACQUIRE)) return NULL;
        t->fn(t->ctx, h->tid);
        __atomic_add_fetch(&t->done, 1, __ATOMIC_RELEASE);
    }
}

/* a new round: publishes fn/ctx (release of gen) and wakes the helpers that sleep */
static void start_round(gp_team *t)
{
    __atomic_add_fetch(&t->gen, 1, __ATOMIC_SEQ_CST);
    /* a helper counts itself a sleeper and re-reads gen under mu, so either it sees the new
     * round or it is counted here; the broadcast under mu cannot fall between its check and
     * its wait */
    if (__atomic_load_n(&t->sleepers, __ATOMIC_SEQ_CST) > 0) {
        pthread_mutex_lock(&t->mu);
        pthread_cond_broadcast(&t->cv);
        pthread_mutex_unlock(&t->mu);
    }
}

gp_team *gp_team_create(int size, gp_error *err)
{
    gp_team *t = calloc(1, sizeof *t);
    if (!t) {
        gp_error_set(err, GP_ERR_NOMEM, "team: out of memory");
        return NULL;
    }
    t->size = 1;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpus >= 1 && size > cpus) size = (int)cpus; /* a spinning team beyond the CPUs only waits */
    if (size <= 1) return t;
    t->th = calloc((size_t)size, sizeof *t->th);
    t->args = calloc((size_t)size, sizeof *t->args);
    if (!t->th || !t->args) {
        gp_team_destroy(t);
        gp_error_set(err, GP_ERR_NOMEM, "team: out of memory");
        return NULL;
    }
    pthread_mutex_init(&t->mu, NULL);
    pthread_cond_init(&t->cv, NULL);
    for (int k = 1; k < size; k++) {
        t->args[k] = (helper){t, k};
        if (pthread_create(&t->th[k], NULL, helper_main, &t->args[k]) != 0) break;
        t->size = k + 1;
    }
    return t;
}

void gp_team_destroy(gp_team *t)
{
    if (!t) return;
    if (t->size > 1) {
        __atomic_store_n(&t->quit, 1, __ATOMIC_RELEASE);
        start_round(t);
        for (int k = 1; k < t->size; k++) pthread_join(t->th[k], NULL);
    }
    if (t->th && t->args) {
        pthread_mutex_destroy(&t->mu);
        pthread_cond_destroy(&t->cv);
    }
    free(t->th);
    free(t->args);
    free(t);
}

int gp_team_size(const gp_team *t) { return t ? t->size : 1; }

void gp_team_run(gp_team *t, gp_team_fn fn, void *ctx)
{
    if (t->size <= 1) {
        fn(ctx, 0);
        return;
    }
    t->fn = fn;
    t->ctx = ctx;
    __atomic_store_n(&t->done, 0, __ATOMIC_RELAXED);
    start_round(t);
    fn(ctx, 0);
    double t0 = -1.0;
    for (int k = 0; __atomic_load_n(&t->done, __ATOMIC_ACQUIRE) < t->size - 1; k++) {
        cpu_relax();
        if ((k & 63) != 63) continue;
        double now = gp_clock_seconds();
        if (t0 < 0) t0 = now;
        if (now - t0 >= SPIN_S) sched_yield(); /* a helper was preempted: let it run */
    }
}
