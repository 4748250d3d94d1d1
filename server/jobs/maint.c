/* maint.c -- the retention sweep, freeing purged jobs and the reclaim of their space (see
 * maint.h). */
#include "jobs/maint.h"

#include <pthread.h>
#include <time.h>

#include "store/store.h"
#include "util/util.h"
#include "jobs/workers.h"

#define RECLAIM_RETRY_MIN_S 1.0
#define RECLAIM_RETRY_MAX_S 30.0
#define SWEEP_AGAIN_S 1.0 /* a full pass: the next one soon */
/* a checkpoint a large commit asked for waits until the workers have been idle this long (the
 * copy of hundreds of MB would slow the next job: its fsyncs queue behind the copy's), looking
 * every CKPT_POLL_S, and gives way to a claim; after CKPT_DEFER_MAX_S it runs regardless */
#define CKPT_IDLE_S 1.0
#define CKPT_POLL_S 0.25
#define CKPT_DEFER_MAX_S 60.0
/* Pacing of the background writes (store_free_purged, store_vacuum_step): after a step that
 * took t seconds the thread waits PACE_MIN_S + PACE_RATIO * t, so that it holds SQLite's write
 * lock a fifth of the time at most and a writer waiting in SQLite's busy handler (which looks
 * again every 1 to 100 ms) finds it free long before its timeout. */
#define PACE_MIN_S 0.01
#define PACE_RATIO 4.0
/* while freeing or vacuuming, a checkpoint after this many steps: the WAL they write (a
 * vacuum step: up to STORE_VACUUM_STEP) is copied back and reused instead of growing */
#define PACE_CKPT_STEPS 8
#define STEP_RETRY_S 0.5 /* after a step that failed (a busy database): again, backing off */

static pthread_t thread;
static int running = 0;
static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv;
static int quit = 0;   /* guarded by mu */
static int kicked = 0; /* guarded by mu: 1 a purge (at once), 2 a grown WAL (keeps back-off) */
static double retain_s = 0;

/* What the thread has to do, one piece a turn. */
typedef struct maint_state {
    double next_sweep;    /* monotonic; 0: no retention */
    int freeing;          /* purged jobs' values may be left to free (store_free_purged) */
    int vacuuming;        /* free pages may be left to give back (store_vacuum_step) */
    int steps;            /* freeing and vacuum steps since the last checkpoint */
    double step_at;       /* the next such step, not before */
    double step_retry;    /* the back-off of a failed step (0: none) */
    int dirty;            /* a checkpoint due */
    double retry, retry_at;        /* its back-off when blocked */
    double ckpt_asked, last_busy;  /* a checkpoint a grown WAL asked for (0: none) */
} maint_state;

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

/* the earlier of two times, 0 meaning none */
static double earliest(double a, double b)
{
    return a <= 0 ? b : b <= 0 ? a : a < b ? a : b;
}

/* When the thread next has something to do (0: only a kick or the stop wakes it). */
static double next_turn(const maint_state *m)
{
    double now = gpd_monotonic_s(), until = m->next_sweep;
    if (m->freeing || m->vacuuming) return earliest(until, m->step_at > 0 ? m->step_at : now);
    if (m->dirty) until = earliest(until, m->retry_at > 0 ? m->retry_at : now);
    return until;
}

/* One try at a checkpoint that is due: after purges (ckpt_asked 0) at once; for a grown WAL
 * (asked at ckpt_asked) once no worker has been busy for CKPT_IDLE_S, giving way to a claim,
 * until CKPT_DEFER_MAX_S have passed (then it runs whatever runs). 0 done, 1 blocked (back
 * off), 2 deferred or given way (look again in CKPT_POLL_S), -1 an error. */
static int checkpoint_try(maint_state *m, double now)
{
    if (m->ckpt_asked <= 0) return store_checkpoint(0);
    if (workers_busy() > 0) m->last_busy = now;
    int overdue = now - m->ckpt_asked >= CKPT_DEFER_MAX_S;
    if (!overdue && now - m->last_busy < CKPT_IDLE_S) return 2;
    int rc = store_checkpoint(!overdue);
    if (rc == 2) m->last_busy = gpd_monotonic_s();
    if (rc == 0) m->ckpt_asked = 0;
    return rc;
}

/* The checkpoint that is due, with its back-off. */
static void checkpoint_turn(maint_state *m, double now)
{
    if (m->retry_at > 0 && now < m->retry_at) return;
    int rc = checkpoint_try(m, now);
    if (rc == 0) {
        m->dirty = 0;
        m->retry = 0;
        m->retry_at = 0;
    } else if (rc == 2) {
        m->retry_at = gpd_monotonic_s() + CKPT_POLL_S;
    } else { /* blocked by a reader (or an error): later, backing off */
        m->retry = m->retry <= 0 ? RECLAIM_RETRY_MIN_S
                                 : (m->retry * 2 > RECLAIM_RETRY_MAX_S ? RECLAIM_RETRY_MAX_S
                                                                       : m->retry * 2);
        m->retry_at = gpd_monotonic_s() + m->retry;
        gpd_log(GPD_LOG_DEBUG, "reclaim: the checkpoint is blocked; again in %.0f s", m->retry);
    }
}

/* One step of freeing purged values, then of the vacuum, paced (PACE_*); once both are done a
 * checkpoint is due at once. */
static void step_turn(maint_state *m, double now)
{
    if (now < m->step_at) return;
    int rc = m->freeing ? store_free_purged() : store_vacuum_step();
    double end = gpd_monotonic_s();
    if (rc < 0) { /* a busy database (a worker storing a result) or an error: later */
        m->step_retry = m->step_retry <= 0 ? STEP_RETRY_S
                                           : (m->step_retry * 2 > RECLAIM_RETRY_MAX_S
                                                  ? RECLAIM_RETRY_MAX_S
                                                  : m->step_retry * 2);
        m->step_at = end + m->step_retry;
        return;
    }
    m->step_retry = 0;
    m->step_at = end + PACE_MIN_S + PACE_RATIO * (end - now);
    if (rc == 0 && m->freeing) {
        m->freeing = 0;
        m->vacuuming = 1;
    } else if (rc == 0) {
        m->vacuuming = 0;
        m->dirty = 1;
        m->retry_at = 0;
        m->ckpt_asked = 0;
        m->steps = 0;
        return;
    }
    if (++m->steps >= PACE_CKPT_STEPS) {
        m->steps = 0;
        store_checkpoint(1);
        m->step_at = gpd_monotonic_s() + PACE_MIN_S;
    }
}

/* Takes the kicks that came: a purge starts the freeing; a grown WAL asks for a checkpoint
 * (keeping a back-off already running). */
static void take_kicks(maint_state *m, double now)
{
    pthread_mutex_lock(&mu);
    if (kicked == 1) m->freeing = 1;
    if (kicked == 2 && !m->dirty) {
        m->dirty = 1;
        m->retry_at = 0;
        m->ckpt_asked = now;
        m->last_busy = now; /* the commit came from a job: idle is to be seen first */
    }
    kicked = 0;
    pthread_mutex_unlock(&mu);
}

static void *maint_main(void *arg)
{
    (void)arg;
    maint_state m = {0};
    m.next_sweep = retain_s > 0 ? gpd_monotonic_s() : 0; /* at start-up first */
    m.freeing = 1; /* values a purge left before the daemon stopped */
    for (;;) {
        if (wait_until(next_turn(&m))) break;
        double now = gpd_monotonic_s();
        take_kicks(&m, now);
        if (m.next_sweep > 0 && now >= m.next_sweep) {
            int n = sweep();
            if (n > 0) m.freeing = 1;
            m.next_sweep = now + (n >= MAINT_SWEEP_MAX ? SWEEP_AGAIN_S : MAINT_SWEEP_INTERVAL_S);
        }
        if (m.freeing || m.vacuuming)
            step_turn(&m, now);
        else if (m.dirty)
            checkpoint_turn(&m, now);
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
    pthread_mutex_lock(&mu);
    running = 1;
    pthread_mutex_unlock(&mu);
    store_on_wal_grown(maint_wal_grown);
    return 0;
}

/* running is read under mu: a worker's commit may call this while maint_stop destroys cv */
static void kick(int why)
{
    pthread_mutex_lock(&mu);
    if (running) {
        if (kicked != 1) kicked = why; /* a purge's "at once" wins */
        pthread_cond_signal(&cv);
    }
    pthread_mutex_unlock(&mu);
}

void maint_kick(void) { kick(1); }
void maint_wal_grown(void) { kick(2); }

void maint_stop(void)
{
    if (!running) return;
    store_on_wal_grown(NULL);
    pthread_mutex_lock(&mu);
    quit = 1;
    pthread_cond_signal(&cv);
    pthread_mutex_unlock(&mu);
    pthread_join(thread, NULL);
    pthread_mutex_lock(&mu);
    running = 0;
    pthread_mutex_unlock(&mu);
    pthread_cond_destroy(&cv);
}
