/* progress.h -- a running job's progress as the job object shows it: a fraction that moves with
 * the clock and an ETA, from the core's phase reports (gp_progress.h) and the kind's plan.
 *
 * The core says which phase it is in and how far that phase has come (phase_fraction, made
 * roughly proportional to the phase's time: steps, items, or the log of a converging error).
 * The kind says which phases a job of its spec goes through and what each should cost
 * (gpd_kind.plan: seconds on one core, from the work's size; "result", the writing of the
 * result, last). The model then estimates the time left:
 *   - in the current phase: the plan's figure, trusted less as the phase advances, and more
 *     the phase's own rate over its last stretch (a convergence that slows shows at once, and
 *     the estimate does not grow without bound as the phase runs);
 *   - in the phases to come: their planned seconds times the machine's speed, measured on the
 *     phases whose cost comes from their size (a loaded machine makes every phase slower
 *     alike);
 * and reports eta_s = that time (never 0 while work remains) and fraction = elapsed /
 * (elapsed + eta_s), never going down: so fraction tracks elapsed / total as well as the ETA
 * tracks the time left. bench/bench_progress.py measures both. */
#ifndef GPD_PROGRESS_H
#define GPD_PROGRESS_H

/* One phase of a plan. */
typedef struct gpd_phase {
    const char *name; /* as the core reports it; "result": writing the result (workers.c); a
                         name twice in a row: the phase runs again (its fraction starts over) */
    double cost_s;    /* expected seconds on one core */
    int sized;        /* 1: cost_s follows from the work's size (it calibrates the speed);
                         0: the phase runs until something converges (cost_s is a guess) */
} gpd_phase;

/* Writing a result (the "result" phase: its JSON tree, export pack, text, summary and SQLite
 * commit) costs about this many seconds a byte of its text where it is arrays of numbers
 * (measured with bench/bench_progress.py, at the speed of the plans' other figures: 21 MB of
 * spheres, 66 MB of 2D grains with their discs; a result of JSON objects, such as the 3D
 * contacts, costs about twice as much a byte). */
#define GPD_RESULT_S_PER_BYTE 0.05e-6

#define GPD_PLAN_MAX 12
#define GPD_RATE_WINDOW 16 /* reports kept for the current phase's rate */

typedef struct gpd_progress_model {
    gpd_phase plan[GPD_PLAN_MAX];
    int nplan;
    int cur;             /* index in plan; -1 before the first report */
    double t0;           /* the run's start (gpd_monotonic_s) */
    double t_phase;      /* when the current phase (or its latest pass) began */
    double cost_cur;     /* planned seconds of the current pass (a phase run again: a part) */
    double pf;           /* the current phase's fraction, as last reported */
    double sized_actual; /* seconds spent in finished sized phases ... */
    double sized_cost;   /* ... and what the plan gave them */
    int nwin;
    double win_t[GPD_RATE_WINDOW], win_pf[GPD_RATE_WINDOW]; /* the current pass's reports */
    double fraction;     /* the last fraction reported (they never go down) */
} gpd_progress_model;

/* A model for plan (n phases, copied; the names must outlive the model) of a run that began at
 * t0. */
void gpd_progress_init(gpd_progress_model *m, const gpd_phase *plan, int n, double t0);

/* The core reported phase at phase_fraction pf at time now: the model moves to it (a name not
 * in the plan, such as the core's final "done", leaves it where it is). */
void gpd_progress_report(gpd_progress_model *m, const char *phase, double pf, double now);

/* Enters the "result" phase at now, with its cost as the kind now knows it (< 0: the plan's);
 * its fraction then moves with the time (gpd_progress_report is not called during it). */
void gpd_progress_result(gpd_progress_model *m, double cost_s, double now);

/* The current phase's name ("starting" before the first report), and at time now the fraction
 * (in [0, 1), never less than the last one) and the seconds left (> 0). */
const char *gpd_progress_phase(const gpd_progress_model *m);
void gpd_progress_estimate(gpd_progress_model *m, double now, double *fraction, double *eta_s);

#endif /* GPD_PROGRESS_H */
