/* offload.h -- request work that costs CPU in proportion to a body, off the HTTP threads.
 *
 * Why: parsing and validating a 1 MB spec takes tens of milliseconds (more under sanitizers).
 * Done on the libmicrohttpd threads, four such posts at once occupy every HTTP thread, and a
 * GET /v1/health queued behind them waited over 100 ms. The HTTP layer now suspends such a
 * connection (MHD_suspend_connection), hands the work here, and the task resumes the connection
 * when its response is ready; the HTTP threads only move bytes.
 *
 * The pool: a few threads at a lower scheduling priority (nice +5), so that cheap requests and
 * the job workers keep the CPU first, in lanes. A lane is a FIFO queue with threads of its own:
 * submits (a spec is checked in milliseconds) never wait behind shape analyses (seconds each,
 * tens of seconds for the largest), whatever number of analyses is queued.
 *
 * Bounds: each lane queues at most `max_queued` tasks beyond the ones running; a task past it is
 * refused (gpd_offload_submit returns 1 with the seconds after which to try again, judged from
 * the lane's recent task times), which the HTTP layer answers 503 busy with Retry-After. Every
 * task may carry a `gone` test (its client closed the connection): a full lane first drops
 * its queued tasks whose client has gone, running them at once so that they answer nothing.
 *
 * Thread safety: gpd_offload_submit may be called from any thread; start and stop from one. */
#ifndef GPD_OFFLOAD_H
#define GPD_OFFLOAD_H

/* the lanes: spec checks (POST /v1/jobs) and shape analyses (POST /v1/shapes/analyze) */
typedef enum gpd_lane { GPD_LANE_SPEC = 0, GPD_LANE_ANALYSIS, GPD_LANES } gpd_lane;

/* Starts threads pool threads, split between the lanes (at least one each), each lane
 * queueing at most max_queued tasks (>= 1). 0, or -1 (a thread could not be created; none is
 * left). */
int gpd_offload_start(unsigned threads, unsigned max_queued);

/* Queues run(arg) on lane. gone(arg) (may be NULL) says whether the task's client has gone; a
 * full lane runs its gone tasks at once, on the caller's thread, to make room. Returns 0
 * (queued), 1 (the lane is full: *retry_s, >= 1, the seconds after which to try again), or -1
 * when the pool is not running (stopping, or never started): the caller then does the work
 * itself. */
int gpd_offload_submit(gpd_lane lane, void (*run)(void *arg), int (*gone)(void *arg), void *arg,
                       int *retry_s);

/* Refuses new tasks, runs every queued one, and joins the threads. */
void gpd_offload_stop(void);

#endif /* GPD_OFFLOAD_H */
