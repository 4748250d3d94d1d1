/* conns.c -- the headers' deadline of every connection (see conns.h). */
#include "http/conns.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <time.h>

#include "util/util.h"

#define SWEEP_EVERY_S 1.0

typedef struct conn {
    int fd;
    int waiting;     /* 1 while the headers of a request are awaited */
    double deadline; /* gpd_monotonic_s by which they must be in (INFINITY: shut already) */
    struct conn *prev, *next;
} conn;

static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t cv = PTHREAD_COND_INITIALIZER;
static conn *head = NULL;
static double header_s = 10, keep_s = 30;
static int sweeping = 0;
static pthread_t sweeper;
static long timed_out = 0;

static conn *entry_of(struct MHD_Connection *c)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

static void track(struct MHD_Connection *c, void **ctx)
{
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    conn *e = ci ? calloc(1, sizeof *e) : NULL;
    *ctx = e;
    if (!e) return; /* no deadline for it: the idle timeout still holds */
    e->fd = ci->connect_fd;
    e->waiting = 1;
    e->deadline = gpd_monotonic_s() + header_s;
    pthread_mutex_lock(&mu);
    e->next = head;
    if (head) head->prev = e;
    head = e;
    pthread_mutex_unlock(&mu);
}

static void forget(void **ctx)
{
    conn *e = *ctx;
    *ctx = NULL;
    if (!e) return;
    pthread_mutex_lock(&mu);
    if (e->prev) e->prev->next = e->next;
    else head = e->next;
    if (e->next) e->next->prev = e->prev;
    pthread_mutex_unlock(&mu);
    free(e);
}

void gpd_conns_notify(void *cls, struct MHD_Connection *c, void **socket_context,
                      enum MHD_ConnectionNotificationCode code)
{
    (void)cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) track(c, socket_context);
    else forget(socket_context);
}

void gpd_conns_headers_done(struct MHD_Connection *c)
{
    conn *e = entry_of(c);
    if (!e) return;
    pthread_mutex_lock(&mu);
    e->waiting = 0;
    pthread_mutex_unlock(&mu);
}

void gpd_conns_request_done(struct MHD_Connection *c)
{
    conn *e = entry_of(c);
    if (!e) return;
    pthread_mutex_lock(&mu);
    if (isfinite(e->deadline)) {
        e->waiting = 1;
        e->deadline = gpd_monotonic_s() + (keep_s > header_s ? keep_s : header_s);
    }
    pthread_mutex_unlock(&mu);
}

long gpd_conns_timed_out(void)
{
    pthread_mutex_lock(&mu);
    long n = timed_out;
    pthread_mutex_unlock(&mu);
    return n;
}

/* Shuts every connection past its deadline; how many (call with mu held). */
static int sweep(double now)
{
    int n = 0;
    for (conn *e = head; e; e = e->next)
        if (e->waiting && now > e->deadline) {
            shutdown(e->fd, SHUT_RDWR);
            e->deadline = INFINITY;
            n++;
        }
    timed_out += n;
    return n;
}

static void *sweep_main(void *unused)
{
    (void)unused;
    pthread_mutex_lock(&mu);
    while (sweeping) {
        int n = sweep(gpd_monotonic_s());
        if (n)
            gpd_log(GPD_LOG_INFO, "closed %d connection(s) whose request headers took over %g s",
                    n, header_s);
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until); /* the condition's clock */
        until.tv_sec += (time_t)SWEEP_EVERY_S;
        pthread_cond_timedwait(&cv, &mu, &until);
    }
    pthread_mutex_unlock(&mu);
    return NULL;
}

int gpd_conns_start(double header_timeout_s, double keepalive_s)
{
    header_s = header_timeout_s;
    keep_s = keepalive_s;
    sweeping = 1;
    if (pthread_create(&sweeper, NULL, sweep_main, NULL) == 0) return 0;
    sweeping = 0;
    return -1;
}

void gpd_conns_stop(void)
{
    pthread_mutex_lock(&mu);
    int was = sweeping;
    sweeping = 0;
    pthread_cond_broadcast(&cv);
    pthread_mutex_unlock(&mu);
    if (was) pthread_join(sweeper, NULL);
}
