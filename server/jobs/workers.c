/* workers.c -- worker threads: claim, run, progress, cancel, requeue on shutdown. */
#include "jobs/workers.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

#include "kinds/kind.h"
#include "jobs/metrics.h"
#include "jobs/progress.h"
#include "jobs/result_json.h"
#include "util/util.h"

#define PROGRESS_MIN_INTERVAL_S 0.25 /* <= 4 Hz per job */
#define STORE_RETRY_PAUSE_S 0.5      /* before the one retry of a failed final write */
#define STORE_OUTAGE_WAIT_S 600       /* a result's wait for a database that does not answer */
#define STORE_OUTAGE_PAUSE_S 1.0      /* between its tries */

/* Why a slot's cancel flag was raised: the first reason wins (compare-and-swap), so that a
 * job that overran its time limit fails with "timeout" even when a shutdown follows, and one
 * that a DELETE cancelled stays cancelled. */
enum { REASON_NONE = 0, REASON_DELETE, REASON_SHUTDOWN, REASON_TIMEOUT };

typedef struct slot {
    pthread_t thread;
    int index;
    char id[33];          /* job being run ("" when idle); guarded by reg_mu */
    double deadline;      /* monotonic time the run must end by, 0 = none; guarded by reg_mu */
    volatile int cancel;  /* read by the core; written with __atomic_store_n */
    int reason;           /* REASON_*, atomic */
} slot;

static slot *slots = NULL;
static int nslots = 0;
static pthread_mutex_t reg_mu = PTHREAD_MUTEX_INITIALIZER; /* claims, cancels, slot ids */
static pthread_mutex_t wake_mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t wake_cv;
static unsigned long wake_gen = 0; /* guarded by wake_mu */
static int stopping = 0;           /* atomic */
static int busy = 0;               /* atomic */
static long job_timeout_s = 3600;  /* set before workers_start; 0 = no limit */
static int job_threads = 1;        /* each job's core threads; set before workers_start */

/* the watchdog: raises the cancel flag of a job whose run passed its deadline */
static pthread_t wd_thread;
static int wd_running = 0;
static pthread_mutex_t wd_mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t wd_cv;
static unsigned long wd_gen = 0; /* guarded by wd_mu */

int workers_total(void) { return nslots; }

void workers_set_job_timeout(long seconds) { job_timeout_s = seconds > 0 ? seconds : 0; }
void workers_set_job_threads(int threads) { job_threads = threads > 1 ? threads : 1; }

/* Raises s's cancel flag for reason r unless another reason came first; 1 when r won. */
static int raise_cancel(slot *s, int r)
{
    int none = REASON_NONE;
    int won = __atomic_compare_exchange_n(&s->reason, &none, r, 0, __ATOMIC_RELAXED,
                                          __ATOMIC_RELAXED);
    __atomic_store_n(&s->cancel, 1, __ATOMIC_RELAXED);
    return won;
}

static void wd_kick(void)
{
    pthread_mutex_lock(&wd_mu);
    wd_gen++;
    pthread_cond_broadcast(&wd_cv);
    pthread_mutex_unlock(&wd_mu);
}
int workers_busy(void) { return __atomic_load_n(&busy, __ATOMIC_RELAXED); }

void workers_notify(void)
{
    pthread_mutex_lock(&wake_mu);
    wake_gen++;
    pthread_cond_broadcast(&wake_cv);
    pthread_mutex_unlock(&wake_mu);
}

store_rc workers_cancel(const char *id, char status_out[16])
{
    int was_running = 0;
    char kind[64];
    pthread_mutex_lock(&reg_mu);
    store_rc rc = store_cancel(id, &was_running, status_out, kind);
    if (rc == STORE_OK && was_running) {
        for (int i = 0; i < nslots; i++)
            if (!strcmp(slots[i].id, id)) raise_cancel(&slots[i], REASON_DELETE);
    }
    pthread_mutex_unlock(&reg_mu);
    if (rc == STORE_OK) {
        gpd_log(GPD_LOG_INFO, "job %s cancelled (was %s)", id, was_running ? "running" : "queued");
        metrics_job_finished(kind, "cancelled", -1);
    }
    return rc;
}

/* The store saw a cancel made by another daemon (PostgreSQL: NOTIFY gp_cancel): the job is
 * already cancelled in the database; if it runs here, its flag goes up as for a local DELETE.
 * Called on the store's thread, possibly while the workers stop (slots NULL then). */
static void cancel_seen(const char *id)
{
    pthread_mutex_lock(&reg_mu);
    for (int i = 0; slots && i < nslots; i++)
        if (!strcmp(slots[i].id, id) && raise_cancel(&slots[i], REASON_DELETE))
            gpd_log(GPD_LOG_INFO, "job %s cancelled by another daemon; stopping it", id);
    pthread_mutex_unlock(&reg_mu);
}

/* ------------------------------------------------------------------ progress */

typedef struct run_ctx {
    slot *s;
    const char *id;
    const gpd_kind *kind;
    const json_t *spec_json; /* the effective spec */
    double t0;
    double last_write;
    char phase[32]; /* the last phase the core reported ("starting" before the first) */
    gpd_progress_model pm; /* the fraction and ETA (progress.h); planned: it has a plan */
    int planned;
    /* the ticker: a thread that writes the progress of the "result" phase, during which the
     * worker builds, packs and serialises the result and no core reports come */
    pthread_t tick_thread;
    int ticking;
    int tick_stop; /* guarded by tick_mu */
    pthread_mutex_t tick_mu;
    pthread_cond_t tick_cv;
} run_ctx;

/* detail: NULL = {} (taken); eta: NaN = null */
static char *progress_text(const char *phase, double fraction, double eta, json_t *detail)
{
    if (!detail) detail = json_object();
    json_t *p = json_pack("{s:s, s:o, s:o, s:o}", "phase", phase ? phase : "", "fraction",
                          gpd_jreal(fraction), "eta_s", gpd_jreal(eta), "detail", detail);
    char *t = p ? json_dumps(p, JSON_COMPACT) : NULL;
    json_decref(p);
    return t;
}

/* Writes a progress text (taken); a job that is no longer running was cancelled meanwhile:
 * its flag goes up. */
static void write_progress(run_ctx *c, char *text)
{
    if (text && store_progress(c->id, text) == STORE_CONFLICT)
        __atomic_store_n(&c->s->cancel, 1, __ATOMIC_RELAXED);
    free(text);
}

/* The fraction and ETA at now: the progress model's; without a plan (the kind could not make
 * one) the core's own fraction, extrapolated. */
static void estimate(run_ctx *c, const gp_progress *p, double now, double *f, double *eta)
{
    if (c->planned) {
        gpd_progress_estimate(&c->pm, now, f, eta);
        return;
    }
    *f = p && p->fraction >= 0 ? fmin(p->fraction, 1) : 0;
    double elapsed = now - c->t0;
    *eta = (*f >= 0.01 && *f < 1) ? elapsed * (1 - *f) / *f : NAN;
}

/* The core's progress callback: a throttled write, with the kind's detail; returns non-zero
 * when the job must stop. */
static int on_progress(void *user, const gp_progress *p)
{
    run_ctx *c = user;
    if (p->phase && strncmp(c->phase, p->phase, sizeof c->phase - 1))
        snprintf(c->phase, sizeof c->phase, "%s", p->phase);
    if (__atomic_load_n(&c->s->cancel, __ATOMIC_RELAXED)) return 1;
    double now = gpd_monotonic_s();
    gpd_progress_report(&c->pm, p->phase, p->phase_fraction, now);
    if (now - c->last_write < PROGRESS_MIN_INTERVAL_S) return 0;
    c->last_write = now;
    double f, eta;
    estimate(c, p, now, &f, &eta);
    /* the core's "done" comes before the result is written: the model's phase stays shown */
    const char *name = p->phase && strcmp(p->phase, "done") ? p->phase
                                                             : gpd_progress_phase(&c->pm);
    write_progress(c, progress_text(name, f, eta, c->kind->progress_detail(p)));
    return __atomic_load_n(&c->s->cancel, __ATOMIC_RELAXED);
}

/* One write of the "result" phase's progress (the ticker's; the interval is its own). */
static void write_result_progress(run_ctx *c)
{
    double now = gpd_monotonic_s(), f, eta;
    estimate(c, NULL, now, &f, &eta);
    c->last_write = now;
    write_progress(c, progress_text("result", c->planned ? f : 1.0, c->planned ? eta : NAN,
                                    NULL));
}

static void *ticker_main(void *arg)
{
    run_ctx *c = arg;
    pthread_mutex_lock(&c->tick_mu);
    while (!c->tick_stop) {
        struct timespec dl;
        clock_gettime(CLOCK_REALTIME, &dl);
        dl.tv_nsec += (long)(PROGRESS_MIN_INTERVAL_S * 1e9);
        if (dl.tv_nsec >= 1000000000L) {
            dl.tv_sec++;
            dl.tv_nsec -= 1000000000L;
        }
        if (pthread_cond_timedwait(&c->tick_cv, &c->tick_mu, &dl) != ETIMEDOUT) continue;
        pthread_mutex_unlock(&c->tick_mu);
        write_result_progress(c);
        pthread_mutex_lock(&c->tick_mu);
    }
    pthread_mutex_unlock(&c->tick_mu);
    store_thread_done(); /* its connection */
    return NULL;
}

/* Enters the "result" phase (its cost from the built specimen) and starts the ticker that
 * shows it moving; without a thread the phase shows once. */
static void result_phase_start(run_ctx *c, const void *specimen)
{
    snprintf(c->phase, sizeof c->phase, "result");
    gpd_progress_result(&c->pm, c->kind->result_cost(specimen), gpd_monotonic_s());
    c->tick_stop = 0;
    pthread_mutex_init(&c->tick_mu, NULL);
    pthread_cond_init(&c->tick_cv, NULL);
    c->ticking = pthread_create(&c->tick_thread, NULL, ticker_main, c) == 0;
    if (!c->ticking) {
        pthread_mutex_destroy(&c->tick_mu);
        pthread_cond_destroy(&c->tick_cv);
        write_result_progress(c);
    }
}

/* Stops the ticker (at once; no write of it comes after); a no-op when none runs. */
static void result_phase_stop(run_ctx *c)
{
    if (!c->ticking) return;
    pthread_mutex_lock(&c->tick_mu);
    c->tick_stop = 1;
    pthread_cond_signal(&c->tick_cv);
    pthread_mutex_unlock(&c->tick_mu);
    pthread_join(c->tick_thread, NULL);
    pthread_mutex_destroy(&c->tick_mu);
    pthread_cond_destroy(&c->tick_cv);
    c->ticking = 0;
}

/* ------------------------------------------------------------------ one job */

/* Final states that could not be written (the database refused every try): kept here and
 * written by the next worker that comes by (each idle second at least, and at shutdown), so
 * that no job stays 'running' silently while the daemon lives. Guarded by pend_mu. */
typedef struct pending {
    struct pending *next;
    char id[33];
    char kind[64];
    char code[32];
    char *msg;
} pending;
static pending *pend_head = NULL;
static int pend_count = 0; /* atomic; guarded by pend_mu for writes */
static pthread_mutex_t pend_mu = PTHREAD_MUTEX_INITIALIZER;

static void pending_add(const char *id, const char *kind, const char *code, const char *msg)
{
    pending *p = calloc(1, sizeof *p);
    if (p) p->msg = strdup(msg ? msg : "");
    if (!p || !p->msg) {
        free(p);
        gpd_log(GPD_LOG_ERROR, "job %s stays running in the database (out of memory); it is "
                               "requeued at the next start", id);
        return;
    }
    snprintf(p->id, sizeof p->id, "%s", id);
    snprintf(p->kind, sizeof p->kind, "%s", kind);
    snprintf(p->code, sizeof p->code, "%s", code);
    pthread_mutex_lock(&pend_mu);
    p->next = pend_head;
    pend_head = p;
    __atomic_add_fetch(&pend_count, 1, __ATOMIC_RELAXED);
    pthread_mutex_unlock(&pend_mu);
}

/* Tries to write every pending final state once; `last`: at shutdown, say what is left. */
static void pending_drain(int last)
{
    if (!__atomic_load_n(&pend_count, __ATOMIC_RELAXED)) return;
    if (last)
        pthread_mutex_lock(&pend_mu);
    else if (pthread_mutex_trylock(&pend_mu) != 0)
        return; /* another worker is at it */
    pending **pp = &pend_head;
    while (*pp) {
        pending *p = *pp;
        store_rc rc = store_fail(p->id, p->code, p->msg);
        if (rc == STORE_ERROR && !last) {
            pp = &p->next;
            continue;
        }
        if (rc == STORE_ERROR) /* the daemon is stopping: the restart rule takes it over */
            gpd_log(GPD_LOG_ERROR, "job %s stays running in the database (it cannot be marked "
                                   "failed: %s: %s); it is requeued at the next start",
                    p->id, p->code, p->msg);
        else if (rc == STORE_OK) {
            gpd_log(GPD_LOG_INFO, "job %s failed: %s: %s (written late)", p->id, p->code,
                    p->msg);
            metrics_job_finished(p->kind, "failed", -1);
        }
        *pp = p->next;
        free(p->msg);
        free(p);
        __atomic_sub_fetch(&pend_count, 1, __ATOMIC_RELAXED);
    }
    pthread_mutex_unlock(&pend_mu);
}

/* Marks a running job of kind (its name) failed; t0: when its run began (monotonic; 0 before
 * it began). A write the database refuses is tried again after a pause, then left to
 * pending_drain, and said in the log at level error: never silently running. */
static void finish_failed(const char *id, const char *kind, double t0, const char *code,
                          const char *msg)
{
    store_rc rc = store_fail(id, code, msg);
    if (rc == STORE_ERROR) {
        gpd_sleep_s(STORE_RETRY_PAUSE_S);
        rc = store_fail(id, code, msg);
    }
    if (rc == STORE_OK) {
        gpd_log(GPD_LOG_INFO, "job %s failed: %s: %s", id, code, msg);
        metrics_job_finished(kind, "failed", t0 > 0 ? gpd_monotonic_s() - t0 : -1);
    } else if (rc == STORE_ERROR) {
        gpd_log(GPD_LOG_ERROR, "job %s: cannot mark it failed (%s: %s); it shows running until "
                               "a retry succeeds",
                id, code, msg);
        pending_add(id, kind, code, msg);
    }
    /* STORE_CONFLICT: no longer running (cancelled meanwhile); nothing to write */
}

/* The run passed --job-timeout (the watchdog raised the flag): the job fails with "timeout". */
static void finish_timeout(run_ctx *ctx, const char *phase)
{
    char msg[200];
    snprintf(msg, sizeof msg,
             "stopped after running longer than the job time limit of %ld s (--job-timeout), "
             "in phase \"%s\"",
             job_timeout_s, phase);
    finish_failed(ctx->id, ctx->kind->name, ctx->t0, "timeout", msg);
}

/* A build that did not succeed: cancelled (by DELETE or shutdown) or failed; err may be NULL
 * only with GP_ERR_CANCELLED; extra (may be NULL) is appended to the message. */
static void finish_not_ok(run_ctx *ctx, gp_status st, const gp_error *err, const char *extra)
{
    if (__atomic_load_n(&ctx->s->reason, __ATOMIC_RELAXED) == REASON_TIMEOUT) {
        finish_timeout(ctx, ctx->phase);
        return;
    }
    if (st == GP_ERR_CANCELLED || __atomic_load_n(&ctx->s->cancel, __ATOMIC_RELAXED)) {
        if (__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
            if (store_requeue(ctx->id) == STORE_OK)
                gpd_log(GPD_LOG_INFO, "job %s requeued (shutdown)", ctx->id);
        }
        /* else: a DELETE already marked it cancelled */
        return;
    }
    char msg[GP_ERROR_MESSAGE_MAX + 128];
    snprintf(msg, sizeof msg, "%s%s",
             err && err->message[0] ? err->message : gp_status_name(st),
             extra ? extra : "");
    finish_failed(ctx->id, ctx->kind->name, ctx->t0, gp_status_name(st), msg);
}

/* store_result's write while the database does not answer (a restart, a network cut): tried
 * again every STORE_OUTAGE_PAUSE_S for STORE_OUTAGE_WAIT_S at most, so that a finished job
 * outlasts an outage instead of failing for the database's sake; the daemon stopping meanwhile
 * leaves it running in the database, where the restart rule requeues it. rc: the last try's. */
static store_rc store_result_outlasting(run_ctx *ctx, store_rc rc, const store_text *text,
                                        const char *prog, const char *brief, const void *pack,
                                        size_t pack_len, gpd_err *why)
{
    if (rc != STORE_ERROR || store_reachable()) return rc;
    gpd_log(GPD_LOG_WARN, "job %s: the database does not answer; its result waits for it (at "
                          "most %d s)",
            ctx->id, STORE_OUTAGE_WAIT_S);
    double until = gpd_monotonic_s() + STORE_OUTAGE_WAIT_S;
    while (rc == STORE_ERROR && !store_reachable() && gpd_monotonic_s() < until &&
           !__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
        gpd_sleep_s(STORE_OUTAGE_PAUSE_S);
        rc = store_succeed(ctx->id, text, prog, brief, pack, pack_len, why);
    }
    if (rc == STORE_OK) gpd_log(GPD_LOG_WARN, "job %s: its result stored after the outage", ctx->id);
    return rc;
}

/* The result text (in memory or in its temporary file), the "done" progress and the pack
 * committed with status succeeded; a write the database refuses is tried once more, and a
 * result it can never take fails the job. timings: the result's "timings" (may be NULL),
 * observed by the metrics once it is stored. */
static void store_result(run_ctx *ctx, const store_text *text, const char *prog,
                         const char *brief, const void *pack, size_t pack_len,
                         const json_t *timings)
{
    gpd_err why;
    store_rc rc = store_succeed(ctx->id, text, prog, brief, pack, pack_len, &why);
    if (rc == STORE_ERROR) { /* maybe passing (busy, I/O): once more after a pause */
        gpd_log(GPD_LOG_WARN, "job %s: storing the result failed (%s); retrying once", ctx->id,
                why.msg);
        gpd_sleep_s(STORE_RETRY_PAUSE_S);
        rc = store_succeed(ctx->id, text, prog, brief, pack, pack_len, &why);
    }
    int away = rc == STORE_ERROR && !store_reachable();
    rc = store_result_outlasting(ctx, rc, text, prog, brief, pack, pack_len, &why);
    char msg[600];
    if (rc == STORE_OK) {
        double run_s = gpd_monotonic_s() - ctx->t0;
        gpd_log(GPD_LOG_INFO, "job %s succeeded in %.3f s (%llu bytes)", ctx->id, run_s,
                (unsigned long long)text->len);
        metrics_job_finished(ctx->kind->name, "succeeded", run_s);
        metrics_job_timings(ctx->kind, timings);
    } else if (rc == STORE_TOOBIG) {
        snprintf(msg, sizeof msg, "the result cannot be stored: %s", why.msg);
        finish_failed(ctx->id, ctx->kind->name, ctx->t0, "too_large", msg);
    } else if (rc == STORE_ERROR && !store_reachable() &&
               __atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
        gpd_log(GPD_LOG_ERROR, "job %s: its result is not stored (the database does not answer) "
                               "and the daemon stops: it stays running in the database and is "
                               "requeued at the next start",
                ctx->id);
    } else if (rc == STORE_ERROR) {
        snprintf(msg, sizeof msg, "the result could not be stored (%s): %s",
                 away ? "the database did not answer within the wait" : "tried twice", why.msg);
        finish_failed(ctx->id, ctx->kind->name, ctx->t0, "store_error", msg);
    }
    /* STORE_CONFLICT: cancelled by a DELETE meanwhile */
}

/* Stores a result (its text, in memory or in its temporary file: both taken; head: its small
 * members, taken) and the export pack (takes pack, may be NULL) together with status succeeded
 * and the "done" progress (takes detail, NULL = {}). The text was written to the end
 * (finish_built); it is stored even when a shutdown came meanwhile, not after a DELETE (the job
 * is cancelled). */
static void finish_succeeded(run_ctx *ctx, store_text text, json_t *head, json_t *detail,
                             void *pack, size_t pack_len)
{
    result_phase_stop(ctx); /* what follows writes the job's final state */
    /* the brief with what was achieved, from the result's stats (NULL: the submit's is kept) */
    json_t *bj = ctx->kind->brief(ctx->spec_json, json_object_get(head, "stats"));
    char *brief = bj ? json_dumps(bj, JSON_COMPACT) : NULL;
    json_decref(bj);
    int reason = __atomic_load_n(&ctx->s->reason, __ATOMIC_RELAXED);
    int stopped = __atomic_load_n(&ctx->s->cancel, __ATOMIC_RELAXED) &&
                  reason == REASON_DELETE;
    char *prog = NULL;
    if (!stopped) {
        prog = progress_text("done", 1.0, 0.0, detail); /* takes detail */
        detail = NULL;
    }
    if (reason == REASON_TIMEOUT) {
        /* the limit passed while the result was being built */
        finish_timeout(ctx, "result");
    } else if (stopped) {
        finish_not_ok(ctx, GP_ERR_CANCELLED, NULL, NULL); /* a DELETE already marked it */
    } else if (!prog) {
        finish_failed(ctx->id, ctx->kind->name, ctx->t0, "internal",
                      "out of memory while serialising the result");
    } else {
        store_result(ctx, &text, prog, brief, pack, pack_len, json_object_get(head, "timings"));
    }
    /* the memory first: closing the unlinked file deletes it, which takes seconds for
     * gigabytes, and the pack (2.5 GB at 10^6 grains) would stay allocated meanwhile */
    free(pack);
    free(prog);
    free(brief);
    json_decref(head);
    json_decref(detail);
    free((char *)text.mem);
    if (text.fd >= 0) close(text.fd); /* the unlinked file goes with it */
}

/* The result could not be written: cancelled meanwhile, out of memory, or its temporary file
 * could not be written (io_errno, 0: it was not that). */
static void result_not_built(run_ctx *ctx, int io_errno)
{
    char msg[200];
    if (__atomic_load_n(&ctx->s->cancel, __ATOMIC_RELAXED)) {
        finish_not_ok(ctx, GP_ERR_CANCELLED, NULL, NULL);
    } else if (io_errno) {
        snprintf(msg, sizeof msg, "the result's temporary file could not be written: %s",
                 strerror(io_errno));
        finish_failed(ctx->id, ctx->kind->name, ctx->t0, "store_error", msg);
    } else {
        finish_failed(ctx->id, ctx->kind->name, ctx->t0, "internal",
                      "out of memory while building the result");
    }
}

static void unavailable(const char *id, const char *kind)
{
    char msg[200];
    snprintf(msg, sizeof msg, "kind %s is not available in this build of grainpackd", kind);
    finish_failed(id, kind, 0, "not_implemented", msg);
}

/* A built specimen (taken) becomes the result, the export pack and the final "done" detail of
 * the job, stored together; a result that could not be written is dropped (cancelled, out of
 * memory, its file not written). The result's text is written straight from the specimen
 * (result_json.h) and, past a few MB, straight into a temporary file that the store copies
 * into the database in pieces (store_spill_dir: SQLite): the worker holds the specimen, a few
 * MB of text and the pack, never a tree of the specimen nor the text twice. */
static void finish_built(run_ctx *ctx, const void *spec, const json_t *spec_json, void *out)
{
    const gpd_kind *k = ctx->kind;
    result_phase_start(ctx, out);
    gpd_jw w;
    gpd_jw_init(&w, &ctx->s->cancel);
    char *dir = store_spill_dir();
    if (dir) gpd_jw_spill(&w, dir, 0);
    free(dir);
    /* a testing hook: GRAINPACK_TEST_RESULT_PAUSE_MS slows the writing (a pause at each look
     * at the flag), so that the tests can cancel a job in its result phase */
    const char *pause = getenv("GRAINPACK_TEST_RESULT_PAUSE_MS");
    w.pause_s = pause ? atof(pause) / 1e3 : 0;
    json_t *head = k->result(out, spec, spec_json, &w);
    char *mem = NULL;
    store_text text = {NULL, -1, 0};
    int frc = head ? gpd_jw_finish(&w, &mem, &text.fd, &text.len) : -1;
    text.mem = mem;
    gpd_jw_free(&w);
    if (frc != 0) { /* cancelled (the writer stopped at the flag), out of memory, a failed write */
        result_phase_stop(ctx);
        json_decref(head);
        k->destroy(out);
        result_not_built(ctx, frc > 0 ? frc : 0);
        return;
    }
    void *pack = NULL;
    size_t pack_len = 0;
    gp_error perr;
    if (k->pack(out, spec, &pack, &pack_len, &perr) < 0)
        gpd_log(GPD_LOG_WARN, "job %s: no export pack: %s", ctx->id, perr.message);
    json_t *detail = k->done_detail ? k->done_detail(ctx->id, out) : NULL;
    k->destroy(out);
    /* the specimen's heap back before the store copies the text and the pack (100,000 grains:
     * ~350 MB, which glibc would otherwise keep resident through the write) */
    gpd_heap_trim();
    finish_succeeded(ctx, text, head, detail, pack, pack_len);
}

/* Runs a job of kind k: its spec parsed for the core, the specimen built on this thread. */
static void run_kind(slot *s, const char *id, const gpd_kind *k, const json_t *spec_json)
{
    gp_spec_problem prob;
    memset(&prob, 0, sizeof prob);
    void *spec = calloc(1, k->spec_size);
    if (!spec) {
        finish_failed(id, k->name, 0, "internal", "out of memory while reading the spec");
        return;
    }
    if (k->read_spec(spec_json, spec, job_threads, &prob)) {
        k->free_spec(spec);
        free(spec);
        finish_failed(id, k->name, 0, "invalid_spec", prob.message);
        return;
    }
    run_ctx ctx = {.s = s, .id = id, .kind = k, .spec_json = spec_json, .t0 = gpd_monotonic_s(),
                   .last_write = 0, .phase = "starting"};
    gpd_phase plan[GPD_PLAN_MAX];
    int nplan = k->plan(spec, spec_json, plan, GPD_PLAN_MAX);
    ctx.planned = nplan > 0;
    gpd_progress_init(&ctx.pm, plan, nplan, ctx.t0);
    gp_error err;
    gp_error_clear(&err);
    gp_status st = GP_ERR_INTERNAL;
    void *out = k->build(spec, on_progress, &ctx, &s->cancel, &st, &err);
    if (st == GP_OK && out) {
        finish_built(&ctx, spec, spec_json, out);
    } else {
        char note[96] = "";
        if (out && k->failure_note) k->failure_note(out, note, sizeof note);
        if (out) k->destroy(out);
        finish_not_ok(&ctx, st, &err, note);
    }
    k->free_spec(spec);
    free(spec);
}

static void run_job(slot *s, const char *id, const char *kind, const char *spec_text)
{
    json_error_t je;
    json_t *spec = json_loads(spec_text, 0, &je);
    if (!spec) {
        finish_failed(id, kind, 0, "internal", "stored spec is not valid JSON");
        return;
    }
    const gpd_kind *k = gpd_kind_find(kind);
    if (k)
        run_kind(s, id, k, spec);
    else
        unavailable(id, kind);
    json_decref(spec);
}

/* ------------------------------------------------------------------ threads */

static void *worker_main(void *arg)
{
    slot *s = arg;
    int claim_failing = 0;
    while (!__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
        pthread_mutex_lock(&wake_mu);
        unsigned long gen = wake_gen;
        pthread_mutex_unlock(&wake_mu);

        pending_drain(0);

        char id[33];
        char *kind = NULL, *spec = NULL;
        int attempts = 0;
        pthread_mutex_lock(&reg_mu);
        store_rc rc = STORE_NOT_FOUND;
        if (!__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
            rc = store_claim(id, &kind, &spec, &attempts);
            if (rc == STORE_OK) {
                snprintf(s->id, sizeof s->id, "%s", id);
                __atomic_store_n(&s->cancel, 0, __ATOMIC_RELAXED);
                __atomic_store_n(&s->reason, REASON_NONE, __ATOMIC_RELAXED);
                /* the limit is per run attempt: a job requeued by a restart starts afresh */
                s->deadline = job_timeout_s > 0 ? gpd_monotonic_s() + (double)job_timeout_s : 0;
            }
        }
        pthread_mutex_unlock(&reg_mu);

        if (rc == STORE_OK) {
            if (job_timeout_s > 0) wd_kick();
            __atomic_add_fetch(&busy, 1, __ATOMIC_RELAXED);
            gpd_log(GPD_LOG_INFO, "job %s started on worker %d (attempt %d)", id, s->index,
                    attempts);
            run_job(s, id, kind, spec);
            free(kind);
            free(spec);
            /* a big job leaves hundreds of MB of freed heap (its specimen, its result text)
             * that glibc keeps resident; hand it back so that an idle daemon is small again */
            gpd_heap_trim();
            pthread_mutex_lock(&reg_mu);
            s->id[0] = '\0';
            s->deadline = 0;
            pthread_mutex_unlock(&reg_mu);
            __atomic_sub_fetch(&busy, 1, __ATOMIC_RELAXED);
            continue;
        }
        if ((rc == STORE_ERROR) != claim_failing) { /* said once when it starts and ends */
            claim_failing = rc == STORE_ERROR;
            if (claim_failing)
                gpd_log(GPD_LOG_WARN, "worker %d: cannot claim a job (the database failed); "
                                      "trying every second",
                        s->index);
            else
                gpd_log(GPD_LOG_WARN, "worker %d: claims again", s->index);
        }
        /* idle: wait for a notification or poll again after a second */
        struct timespec dl;
        clock_gettime(CLOCK_MONOTONIC, &dl);
        dl.tv_sec += 1;
        pthread_mutex_lock(&wake_mu);
        while (wake_gen == gen && !__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
            if (pthread_cond_timedwait(&wake_cv, &wake_mu, &dl) != 0) break;
        }
        pthread_mutex_unlock(&wake_mu);
    }
    store_thread_done();
    return NULL;
}

/* One thread for all the slots: it sleeps until the earliest deadline of a running job (or a
 * claim, or the stop), then raises the cancel flag of every job past its deadline. The core
 * polls the flag in every phase, so the job stops there and its worker fails it with
 * "timeout" (finish_timeout). */
static void *watchdog_main(void *arg)
{
    (void)arg;
    while (!__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
        pthread_mutex_lock(&wd_mu);
        unsigned long gen = wd_gen;
        pthread_mutex_unlock(&wd_mu);

        double now = gpd_monotonic_s(), next = 0;
        pthread_mutex_lock(&reg_mu);
        for (int i = 0; i < nslots; i++) {
            slot *s = &slots[i];
            if (!s->id[0] || s->deadline <= 0 ||
                __atomic_load_n(&s->reason, __ATOMIC_RELAXED) != REASON_NONE)
                continue;
            if (now >= s->deadline) {
                if (raise_cancel(s, REASON_TIMEOUT))
                    gpd_log(GPD_LOG_INFO, "job %s: over the job time limit (%ld s), stopping it",
                            s->id, job_timeout_s);
            } else if (next == 0 || s->deadline < next) {
                next = s->deadline;
            }
        }
        pthread_mutex_unlock(&reg_mu);

        struct timespec dl;
        if (next > 0) {
            double t = next + 0.001; /* past it, so that the next pass sees it due */
            dl.tv_sec = (time_t)t;
            dl.tv_nsec = (long)((t - (double)dl.tv_sec) * 1e9);
            if (dl.tv_nsec >= 1000000000L) dl.tv_nsec = 999999999L;
        }
        pthread_mutex_lock(&wd_mu);
        while (wd_gen == gen && !__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
            if (next > 0) {
                if (pthread_cond_timedwait(&wd_cv, &wd_mu, &dl) != 0) break;
            } else {
                pthread_cond_wait(&wd_cv, &wd_mu);
            }
        }
        pthread_mutex_unlock(&wd_mu);
    }
    return NULL;
}

int workers_start(int n)
{
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&wake_cv, &ca);
    pthread_cond_init(&wd_cv, &ca);
    pthread_condattr_destroy(&ca);
    slots = calloc((size_t)n, sizeof *slots);
    if (!slots) return -1;
    nslots = n;
    store_on_cancel(cancel_seen);
    if (job_timeout_s > 0) {
        if (pthread_create(&wd_thread, NULL, watchdog_main, NULL) != 0) {
            gpd_log(GPD_LOG_ERROR, "cannot start the job-timeout watchdog");
            nslots = 0;
            return -1;
        }
        wd_running = 1;
    }
    for (int i = 0; i < n; i++) {
        slots[i].index = i;
        if (pthread_create(&slots[i].thread, NULL, worker_main, &slots[i]) != 0) {
            gpd_log(GPD_LOG_ERROR, "cannot start worker %d", i);
            nslots = i;
            return -1;
        }
    }
    return 0;
}

void workers_stop(void)
{
    if (!slots) return;
    __atomic_store_n(&stopping, 1, __ATOMIC_RELAXED);
    pthread_mutex_lock(&reg_mu);
    for (int i = 0; i < nslots; i++)
        if (slots[i].id[0]) raise_cancel(&slots[i], REASON_SHUTDOWN);
    pthread_mutex_unlock(&reg_mu);
    workers_notify();
    if (wd_running) {
        wd_kick();
        pthread_join(wd_thread, NULL);
        wd_running = 0;
    }
    for (int i = 0; i < nslots; i++) pthread_join(slots[i].thread, NULL);
    pending_drain(1);
    store_on_cancel(NULL);
    pthread_mutex_lock(&reg_mu); /* cancel_seen may be running on the store's thread */
    free(slots);
    slots = NULL;
    nslots = 0;
    pthread_mutex_unlock(&reg_mu);
    pthread_cond_destroy(&wake_cv);
    pthread_cond_destroy(&wd_cv);
}
