/* gp_team.h -- a fork-join team of threads for rounds of a few microseconds.
 *
 * Why not a condition-variable pool (gp_dem3d.c has one, for rounds of milliseconds): waking a
 * sleeping thread through the kernel takes 5-50 us, longer than the rounds this is for (the
 * IMC evaluates one move per thread per round, ~10 us). Here a helper spins on the round
 * counter (with the CPU's pause hint) for a while after each round, and only then sleeps on a
 * condition variable, which the caller signals when it sees sleepers. So back-to-back rounds
 * cost an atomic store and a few loads each, and an idle team (the caller busy elsewhere for
 * more than ~50 us) costs no CPU.
 *
 * gp_team_run(t, fn, ctx) calls fn(ctx, tid) once on each of the team's threads, tid 0 being
 * the caller's own, and returns when every call has returned. What fn does with tid is the
 * caller's: for results that do not depend on the thread count, tid must pick a piece of
 * work, never decide how the work is done.
 *
 * Ownership: gp_team_create starts size - 1 threads, fewer when the machine has fewer CPUs
 * online than size (a thread that spins while another waits for its CPU only slows the round,
 * by far: docs/design/imc.md "Threads") or when the system refuses some; gp_team_size says
 * how many the team has, at least 1. gp_team_destroy joins them. One caller at a time
 * (gp_team_run is not reentrant, nor thread-safe). No global state.
 */
#ifndef GP_TEAM_H
#define GP_TEAM_H

#include "gp_error.h"

typedef struct gp_team gp_team;
typedef void (*gp_team_fn)(void *ctx, int tid);

/* A team of `size` threads (the caller's included; size < 1 counts as 1). NULL with
 * GP_ERR_NOMEM when out of memory. */
gp_team *gp_team_create(int size, gp_error *err);
void gp_team_destroy(gp_team *t); /* NULL is fine */

int gp_team_size(const gp_team *t);

/* fn(ctx, tid) for tid = 0 .. size - 1, tid 0 on the calling thread; returns after all. */
void gp_team_run(gp_team *t, gp_team_fn fn, void *ctx);

#endif /* GP_TEAM_H */
