/* workers.c -- worker threads: claim, run, progress, cancel, requeue on shutdown. */
#include "workers.h"

#include <malloc.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <jansson.h>

#include "gp_export.h"
#include "result_json.h"
#ifdef GPD_HAVE_SCHEMA
#include "gp_spec.h"
#endif
#include "gp_specimen2d.h"
#include "gp_specimen3d.h"

#define PROGRESS_MIN_INTERVAL_S 0.25 /* <= 4 Hz per job */

typedef struct slot {
    pthread_t thread;
    int index;
    char id[33];          /* job being run ("" when idle); guarded by reg_mu */
    volatile int cancel;  /* read by the core; written with __atomic_store_n */
} slot;

static slot *slots = NULL;
static int nslots = 0;
static int started = 0;
static pthread_mutex_t reg_mu = PTHREAD_MUTEX_INITIALIZER; /* claims, cancels, slot ids */
static pthread_mutex_t wake_mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t wake_cv;
static unsigned long wake_gen = 0; /* guarded by wake_mu */
static int stopping = 0;           /* atomic */
static int busy = 0;               /* atomic */

int workers_total(void) { return nslots; }
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
    pthread_mutex_lock(&reg_mu);
    store_rc rc = store_cancel(id, &was_running, status_out);
    if (rc == STORE_OK && was_running) {
        for (int i = 0; i < nslots; i++)
            if (!strcmp(slots[i].id, id)) __atomic_store_n(&slots[i].cancel, 1, __ATOMIC_RELAXED);
    }
    pthread_mutex_unlock(&reg_mu);
    if (rc == STORE_OK) gpd_log(GPD_LOG_INFO, "job %s cancelled (was %s)", id,
                                was_running ? "running" : "queued");
    return rc;
}

/* ------------------------------------------------------------------ progress */

typedef struct run_ctx {
    slot *s;
    const char *id;
    double t0;
    double last_write;
} run_ctx;

/* detail: NULL = {} (taken) */
static char *progress_text(const char *phase, double fraction, double eta, json_t *detail)
{
    if (!detail) detail = json_object();
    json_t *p = json_pack("{s:s, s:o, s:o, s:o}", "phase", phase ? phase : "", "fraction",
                          gpd_jreal(fraction), "eta_s", gpd_jreal(eta), "detail", detail);
    char *t = p ? json_dumps(p, JSON_COMPACT) : NULL;
    json_decref(p);
    return t;
}

/* Throttled progress write; returns non-zero when the job must stop. */
/* 2D detail: {steps, error}; 3D detail: {steps, porosity, stability}. */
__attribute__((unused)) static int report(run_ctx *c, const char *phase, double f, long steps,
                                          double error, int is3d, double porosity,
                                          double stability)
{
    if (__atomic_load_n(&c->s->cancel, __ATOMIC_RELAXED)) return 1;
    double now = gpd_monotonic_s();
    if (now - c->last_write < PROGRESS_MIN_INTERVAL_S) return 0;
    c->last_write = now;
    if (!(f >= 0)) f = 0;
    if (f > 1) f = 1;
    double elapsed = now - c->t0;
    double eta = (f >= 0.01 && f < 1) ? elapsed * (1 - f) / f : (f >= 1 ? 0 : NAN);
    json_t *detail = is3d ? json_pack("{s:I, s:o, s:o}", "steps", (json_int_t)steps, "porosity",
                                      gpd_jreal(porosity), "stability", gpd_jreal(stability))
                          : json_pack("{s:I, s:o}", "steps", (json_int_t)steps, "error",
                                      gpd_jreal(error));
    char *t = progress_text(phase, f, eta, detail);
    if (t) {
        if (store_progress(c->id, t) == STORE_CONFLICT) /* no longer running: cancelled */
            __atomic_store_n(&c->s->cancel, 1, __ATOMIC_RELAXED);
        free(t);
    }
    return __atomic_load_n(&c->s->cancel, __ATOMIC_RELAXED);
}

#ifdef GPD_HAVE_SPECIMEN2D
static int on_progress2d(void *user, const gp_progress *p)
{
    return report(user, p->phase, p->fraction, p->steps, p->error, 0, 0, 0);
}
#endif
#ifdef GPD_HAVE_SPECIMEN3D
static int on_progress3d(void *user, const gp_progress3d *p)
{
    return report(user, p->phase, p->fraction, p->steps, 0, 1, p->porosity, p->stability);
}
#endif

/* ------------------------------------------------------------------ one job */

static void finish_failed(const char *id, const char *code, const char *msg)
{
    if (store_fail(id, code, msg) == STORE_OK)
        gpd_log(GPD_LOG_INFO, "job %s failed: %s: %s", id, code, msg);
}

/* Stores a result (takes r) and the export pack (takes pack, may be NULL) together with status
 * succeeded and the "done" progress (takes detail, NULL = {}). Reals get 17 significant digits:
 * the geometry reads back bit for bit, as in the exports. */
__attribute__((unused)) static void finish_succeeded(run_ctx *ctx, json_t *r, json_t *detail,
                                                     void *pack, size_t pack_len)
{
    char *text = r ? json_dumps(r, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
    json_decref(r);
    char *prog = progress_text("done", 1.0, 0.0, detail);
    if (!text || !prog) {
        finish_failed(ctx->id, "internal", "out of memory while serialising the result");
    } else {
        store_rc rc = store_succeed(ctx->id, text, prog, pack, pack_len);
        if (rc == STORE_OK)
            gpd_log(GPD_LOG_INFO, "job %s succeeded in %.3f s (%zu bytes)", ctx->id,
                    gpd_monotonic_s() - ctx->t0, strlen(text));
        else if (rc == STORE_ERROR)
            gpd_log(GPD_LOG_ERROR, "job %s: cannot store the result", ctx->id);
    }
    free(text);
    free(prog);
    free(pack);
}

/* A build that did not succeed: cancelled (by DELETE or shutdown) or failed. */
__attribute__((unused)) static void finish_not_ok(run_ctx *ctx, gp_status st, const gp_error *err,
                                                  const char *extra)
{
    if (st == GP_ERR_CANCELLED || __atomic_load_n(&ctx->s->cancel, __ATOMIC_RELAXED)) {
        if (__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
            if (store_requeue(ctx->id) == STORE_OK)
                gpd_log(GPD_LOG_INFO, "job %s requeued (shutdown)", ctx->id);
        }
        /* else: a DELETE already marked it cancelled */
        return;
    }
    char msg[GP_ERROR_MESSAGE_MAX + 128];
    snprintf(msg, sizeof msg, "%s%s", err->message[0] ? err->message : gp_status_name(st),
             extra ? extra : "");
    finish_failed(ctx->id, gp_status_name(st), msg);
}

#ifdef GPD_HAVE_SPECIMEN2D
/* The "done" detail of a 2D job: how the IMC ended, the warnings and the fit summary (stats.fit
 * without its CDF curves), so that a poller of GET /v1/jobs/{id} sees them without the result. */
__attribute__((unused)) static json_t *done_detail_2d(const char *id, const gp_specimen2d *s)
{
    json_t *w = gpd_warnings_2d(s);
    for (size_t i = 0; i < json_array_size(w); i++)
        gpd_log(GPD_LOG_WARN, "job %s: %s", id, json_string_value(json_array_get(w, i)));
    return json_pack("{s:I, s:o, s:s, s:o, s:o}", "steps", (json_int_t)s->imc_steps, "error",
                     gpd_jreal(s->imc_error), "stop_reason",
                     s->imc_stop_reason ? s->imc_stop_reason : "", "warnings", w ? w : json_array(),
                     "fit", gpd_fit_2d(&s->fit, 0));
}
#endif

static void unavailable(const char *id, const char *kind)
{
    char msg[200];
    snprintf(msg, sizeof msg, "kind %s is not available in this build of grainpackd", kind);
    finish_failed(id, "not_implemented", msg);
}

static void run_2d(slot *s, const char *id, json_t *spec_json)
{
#if defined(GPD_HAVE_SCHEMA) && defined(GPD_HAVE_SPECIMEN2D)
    gp_spec2d spec;
    gp_spec_problem prob;
    memset(&prob, 0, sizeof prob);
    if (gp_spec_parse_2d(spec_json, &spec, &prob) != 0) {
        gp_spec_2d_free(&spec);
        finish_failed(id, "invalid_spec", prob.message);
        return;
    }
    spec.threads = 1;
    run_ctx ctx = {.s = s, .id = id, .t0 = gpd_monotonic_s(), .last_write = 0};
    gp_specimen2d *out = NULL;
    gp_error err;
    gp_error_clear(&err);
    gp_status st = gp_specimen2d_build(&spec, on_progress2d, &ctx, &s->cancel, &out, &err);
    if (st == GP_OK && out) {
        json_t *r = gpd_result_2d(out, &spec, spec_json);
        /* exports need the ODEC discs; without them there is no pack and GET .../export
         * answers 409 naming the output to ask for */
        void *pack = NULL;
        size_t pack_len = 0;
        if (spec.outputs & GP_OUT_ODEC) {
            gp_error perr;
            if (gp_export_pack_2d(out, &spec, GP_EXPORT_DEFAULT_DENSITY, &pack, &pack_len, &perr))
                gpd_log(GPD_LOG_WARN, "job %s: no export pack: %s", id, perr.message);
        }
        json_t *detail = done_detail_2d(id, out);
        gp_specimen2d_destroy(out);
        finish_succeeded(&ctx, r, detail, pack, pack_len);
    } else {
        if (out) gp_specimen2d_destroy(out);
        finish_not_ok(&ctx, st, &err, NULL);
    }
    gp_spec_2d_free(&spec);
#else
    (void)s;
    (void)spec_json;
    unavailable(id, "fourier-voronoi-2d");
#endif
}

static void run_3d(slot *s, const char *id, json_t *spec_json)
{
#if defined(GPD_HAVE_SCHEMA) && defined(GPD_HAVE_SPECIMEN3D)
    gp_spec3d spec;
    gp_spec_problem prob;
    memset(&prob, 0, sizeof prob);
    if (gp_spec_parse_3d(spec_json, &spec, &prob) != 0) {
        gp_spec_3d_free(&spec);
        finish_failed(id, "invalid_spec", prob.message);
        return;
    }
    spec.threads = 1;
    run_ctx ctx = {.s = s, .id = id, .t0 = gpd_monotonic_s(), .last_write = 0};
    gp_specimen3d *out = NULL;
    gp_error err;
    gp_error_clear(&err);
    gp_status st = gp_specimen3d_build(&spec, on_progress3d, &ctx, &s->cancel, &out, &err);
    if (st == GP_OK && out) {
        json_t *r = gpd_result_3d(out, &spec, spec_json);
        void *pack = NULL;
        size_t pack_len = 0;
        if (out->spheres) {
            gp_error perr;
            if (gp_export_pack_3d(out, spec.material.density, &pack, &pack_len, &perr))
                gpd_log(GPD_LOG_WARN, "job %s: no export pack: %s", id, perr.message);
        }
        gp_specimen3d_destroy(out);
        finish_succeeded(&ctx, r, NULL, pack, pack_len);
    } else {
        char extra[96] = "";
        if (out && out->stats.stop_reason)
            snprintf(extra, sizeof extra, " (stop reason: %s)", out->stats.stop_reason);
        if (out) gp_specimen3d_destroy(out);
        finish_not_ok(&ctx, st, &err, extra);
    }
    gp_spec_3d_free(&spec);
#else
    (void)s;
    (void)spec_json;
    unavailable(id, "spheres-3d");
#endif
}

static void run_job(slot *s, const char *id, const char *kind, const char *spec_text)
{
    json_error_t je;
    json_t *spec = json_loads(spec_text, 0, &je);
    if (!spec) {
        finish_failed(id, "internal", "stored spec is not valid JSON");
        return;
    }
    if (!strcmp(kind, "fourier-voronoi-2d"))
        run_2d(s, id, spec);
    else if (!strcmp(kind, "spheres-3d"))
        run_3d(s, id, spec);
    else
        unavailable(id, kind);
    json_decref(spec);
}

/* ------------------------------------------------------------------ threads */

static void *worker_main(void *arg)
{
    slot *s = arg;
    while (!__atomic_load_n(&stopping, __ATOMIC_RELAXED)) {
        pthread_mutex_lock(&wake_mu);
        unsigned long gen = wake_gen;
        pthread_mutex_unlock(&wake_mu);

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
            }
        }
        pthread_mutex_unlock(&reg_mu);

        if (rc == STORE_OK) {
            __atomic_add_fetch(&busy, 1, __ATOMIC_RELAXED);
            gpd_log(GPD_LOG_INFO, "job %s started on worker %d (attempt %d)", id, s->index,
                    attempts);
            run_job(s, id, kind, spec);
            free(kind);
            free(spec);
#ifdef __GLIBC__
            /* a big job leaves hundreds of MB of freed heap (its JSON tree) that glibc keeps
             * resident; hand it back so that an idle daemon is small again */
            malloc_trim(0);
#endif
            pthread_mutex_lock(&reg_mu);
            s->id[0] = '\0';
            pthread_mutex_unlock(&reg_mu);
            __atomic_sub_fetch(&busy, 1, __ATOMIC_RELAXED);
            continue;
        }
        if (rc == STORE_ERROR) gpd_log(GPD_LOG_WARN, "worker %d: claim failed", s->index);
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

int workers_start(int n)
{
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&wake_cv, &ca);
    pthread_condattr_destroy(&ca);
    slots = calloc((size_t)n, sizeof *slots);
    if (!slots) return -1;
    nslots = n;
    for (int i = 0; i < n; i++) {
        slots[i].index = i;
        if (pthread_create(&slots[i].thread, NULL, worker_main, &slots[i]) != 0) {
            gpd_log(GPD_LOG_ERROR, "cannot start worker %d", i);
            nslots = i;
            return -1;
        }
    }
    started = 1;
    return 0;
}

void workers_stop(void)
{
    if (!slots) return;
    __atomic_store_n(&stopping, 1, __ATOMIC_RELAXED);
    pthread_mutex_lock(&reg_mu);
    for (int i = 0; i < nslots; i++)
        if (slots[i].id[0]) __atomic_store_n(&slots[i].cancel, 1, __ATOMIC_RELAXED);
    pthread_mutex_unlock(&reg_mu);
    workers_notify();
    for (int i = 0; i < nslots; i++) pthread_join(slots[i].thread, NULL);
    free(slots);
    slots = NULL;
    nslots = 0;
    pthread_cond_destroy(&wake_cv);
    started = 0;
}
