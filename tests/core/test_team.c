/* test_team.c -- gp_team: every round runs fn once per thread, each tid once, and returns only
 * after all of them; rounds back to back (the spinning path) and after idle spells longer than
 * the spin (the sleeping path); a team of 1 runs inline; asked for more threads than CPUs, a
 * team has as many as there are CPUs. */
#include <stdint.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "gp_team.h"
#include "gp_test.h"

#define MAXT 8

typedef struct round_ctx {
    int calls[MAXT];      /* per tid, over all rounds */
    int round_seen[MAXT]; /* the round number each tid saw last */
    int round;
    int late;             /* a call that saw a stale round number */
    uint64_t work[MAXT];
} round_ctx;

static void fn(void *c, int tid)
{
    round_ctx *r = c;
    if (tid < 0 || tid >= MAXT) return;
    r->calls[tid]++;
    if (r->round_seen[tid] != r->round - 1) r->late++;
    r->round_seen[tid] = r->round;
    /* a little work of uneven length, so that threads finish at different times */
    uint64_t x = (uint64_t)tid + 1;
    for (int k = 0; k < 200 * (tid + 1); k++) x = x * 6364136223846793005ull + 1442695040888963407ull;
    r->work[tid] = x;
}

static void sleep_us(long us)
{
    struct timespec ts = {us / 1000000, (us % 1000000) * 1000};
    nanosleep(&ts, NULL);
}

static void team_rounds(int size, int rounds, int idle_every)
{
    gp_team *t = gp_team_create(size, NULL);
    CHECK(t != NULL);
    if (!t) return;
    int nt = gp_team_size(t);
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    int want = size < 1 ? 1 : size;
    if (cpus >= 1 && want > cpus) want = (int)cpus; /* the team stops at the CPUs online */
    CHECK(nt == want);
    round_ctx r;
    memset(&r, 0, sizeof r);
    for (int k = 0; k < MAXT; k++) r.round_seen[k] = 0;
    int incomplete = 0;
    for (int k = 1; k <= rounds; k++) {
        r.round = k;
        gp_team_run(t, fn, &r);
        /* gp_team_run returned: every tid has run this round */
        for (int q = 0; q < nt; q++)
            if (r.round_seen[q] != k) incomplete++;
        if (idle_every && k % idle_every == 0) sleep_us(300); /* past the spin: helpers sleep */
    }
    int calls_ok = 1;
    for (int q = 0; q < MAXT; q++) calls_ok = calls_ok && r.calls[q] == (q < nt ? rounds : 0);
    printf("team of %d, %d rounds%s: %s\n", nt, rounds, idle_every ? " with idle spells" : "",
           calls_ok && !incomplete && !r.late ? "each tid once a round" : "WRONG");
    CHECK(calls_ok);
    CHECK(incomplete == 0);
    CHECK(r.late == 0);
    gp_team_destroy(t);
}

int main(void)
{
    team_rounds(1, 1000, 0);
    team_rounds(0, 10, 0);
    team_rounds(2, 20000, 0);
    team_rounds(2, 200, 1);
    team_rounds(3, 2000, 7);
    team_rounds(5, 500, 0);
    gp_team_destroy(NULL);
    CHECK(gp_team_size(NULL) == 1);
    return gp_test_summary();
}
