/* progress.c -- a running job's fraction and ETA from its plan and the core's reports (see
 * progress.h). */
#include "jobs/progress.h"

#include <math.h>
#include <string.h>

#define ETA_MIN_S 0.1       /* the least ETA while work remains: never "0 s" before the end */
#define FRACTION_MAX 0.999  /* a running job never shows 100 % */
#define REPASS_SHARE 0.5    /* a phase run again beyond its plan is planned at this share of its
                               last pass (the second 2D refill: about half the first) */
#define REPASS_DROP 0.05    /* a phase fraction falling by more than this starts a new pass */
#define SPEED_PRIOR_S 0.5   /* planned seconds of prior weight on speed 1 (few data: no swings) */
#define RATE_MIN_SPAN_S 0.5 /* the current phase's rate is taken over at least this ... */
#define RATE_SPAN_SHARE 0.3 /* ... and this share of the phase's time so far */
#define SAMPLE_SHARE 0.05   /* the rate's samples are this share of the phase's time apart ... */
#define SAMPLE_MIN_S 0.2    /* ... and at least this */

static int find(const gpd_progress_model *m, const char *name, int from)
{
    for (int i = from < 0 ? 0 : from; name && i < m->nplan; i++)
        if (!strcmp(m->plan[i].name, name)) return i;
    return -1;
}

void gpd_progress_init(gpd_progress_model *m, const gpd_phase *plan, int n, double t0)
{
    memset(m, 0, sizeof *m);
    if (n > GPD_PLAN_MAX) n = GPD_PLAN_MAX;
    for (int i = 0; i < n; i++) m->plan[i] = plan[i];
    m->nplan = n > 0 ? n : 0;
    /* writing the result is always the last phase (workers.c enters it): a plan without it
     * gets it, in place of its last phase when it is full (a full plan that ends with it, as
     * the kinds' do, is kept whole) */
    if (find(m, "result", 0) < 0) {
        if (m->nplan == GPD_PLAN_MAX) m->nplan--;
        m->plan[m->nplan++] = (gpd_phase){"result", 0, 1};
    }
    m->cur = -1;
    m->t0 = t0;
    m->t_phase = t0;
}

/* Closes the current pass (a sized one adds to the speed's measure) and starts phase i at now,
 * planned at cost seconds. */
static void enter(gpd_progress_model *m, int i, double now, double cost)
{
    if (m->cur >= 0 && m->plan[m->cur].sized) {
        m->sized_actual += now - m->t_phase;
        m->sized_cost += m->cost_cur;
    }
    m->cur = i;
    m->t_phase = now;
    m->cost_cur = cost;
    m->pf = 0;
    m->nwin = 0;
}

/* Keeps (now, pf) for the rate when the last sample is old enough (spacing in proportion to
 * the phase's time, so that 16 samples span most of a long phase). */
static void remember(gpd_progress_model *m, double now)
{
    double gap = fmax(SAMPLE_MIN_S, SAMPLE_SHARE * (now - m->t_phase));
    if (m->nwin > 0 && now - m->win_t[m->nwin - 1] < gap) return;
    if (m->nwin == GPD_RATE_WINDOW) {
        memmove(m->win_t, m->win_t + 1, (GPD_RATE_WINDOW - 1) * sizeof *m->win_t);
        memmove(m->win_pf, m->win_pf + 1, (GPD_RATE_WINDOW - 1) * sizeof *m->win_pf);
        m->nwin--;
    }
    m->win_t[m->nwin] = now;
    m->win_pf[m->nwin++] = m->pf;
}

void gpd_progress_report(gpd_progress_model *m, const char *phase, double pf, double now)
{
    if (!(pf >= 0)) pf = 0;
    if (pf > 1) pf = 1;
    int i = find(m, phase, m->cur);
    if (i < 0) return;
    if (i != m->cur) {
        enter(m, i, now, m->plan[i].cost_s);
    } else if (pf < m->pf - REPASS_DROP) {
        /* the phase again: its next entry in the plan when it has one (the 2D refill pass),
         * else a part of it */
        if (i + 1 < m->nplan && !strcmp(m->plan[i + 1].name, phase))
            enter(m, i + 1, now, m->plan[i + 1].cost_s);
        else
            enter(m, i, now, m->plan[i].cost_s * REPASS_SHARE);
    }
    if (pf > m->pf) m->pf = pf; /* within a pass it only goes on */
    remember(m, now);
}

void gpd_progress_result(gpd_progress_model *m, double cost_s, double now)
{
    int i = find(m, "result", 0);
    enter(m, i, now, cost_s >= 0 ? cost_s : m->plan[i].cost_s);
}

const char *gpd_progress_phase(const gpd_progress_model *m)
{
    return m->cur >= 0 ? m->plan[m->cur].name : "starting";
}

/* The machine's speed: seconds taken per planned second, over the sized work done so far (the
 * current phase's part once it has some), pulled towards 1 while there is little of it. */
static double speed(const gpd_progress_model *m, double now)
{
    double a = m->sized_actual, c = m->sized_cost;
    if (m->cur >= 0 && m->plan[m->cur].sized && m->pf >= 0.1) {
        a += now - m->t_phase;
        c += m->cost_cur * m->pf;
    }
    return (a + SPEED_PRIOR_S) / (c + SPEED_PRIOR_S);
}

/* The current phase's rate (fraction per second) over its last stretch; 0 when unknown. */
static double rate(const gpd_progress_model *m)
{
    if (m->nwin < 2) return 0;
    double t1 = m->win_t[m->nwin - 1], pf1 = m->win_pf[m->nwin - 1];
    double span = fmax(RATE_MIN_SPAN_S, RATE_SPAN_SHARE * (t1 - m->t_phase));
    int j = 0; /* the latest sample at least span before the last, else the first */
    for (int k = m->nwin - 2; k >= 0; k--)
        if (t1 - m->win_t[k] >= span) {
            j = k;
            break;
        }
    double dt = t1 - m->win_t[j];
    return dt > 0 ? (pf1 - m->win_pf[j]) / dt : 0;
}

/* Seconds left in the current phase: the plan (times the speed k) blended, as the phase
 * advances, with what its own rate says; the result phase moves with the clock alone. */
static double left_in_phase(const gpd_progress_model *m, double now, double k)
{
    double t = now - m->t_phase, plan = m->cost_cur * k, pf = m->pf;
    if (!strcmp(m->plan[m->cur].name, "result")) return fmax(plan - t, 0.1 * t);
    double obs = -1;
    if (pf > 0.02 && t > 0) {
        double r = rate(m);
        if (!(r > 0)) r = pf / t; /* stalled over the last stretch: the phase's mean rate */
        obs = (1 - pf) / r;
    }
    double plan_left = plan > t ? plan - t : (obs >= 0 ? obs : 0.1 * t);
    return obs < 0 ? plan_left : (1 - pf) * plan_left + pf * obs;
}

void gpd_progress_estimate(gpd_progress_model *m, double now, double *fraction, double *eta_s)
{
    double k = speed(m, now), left = 0;
    if (m->cur >= 0) left = left_in_phase(m, now, k);
    for (int j = m->cur + 1; j < m->nplan; j++) left += k * m->plan[j].cost_s;
    double eta = fmax(left, ETA_MIN_S), e = fmax(now - m->t0, 0);
    double f = fmin(e / (e + eta), FRACTION_MAX);
    if (f < m->fraction) f = m->fraction;
    m->fraction = f;
    *fraction = f;
    *eta_s = eta;
}
