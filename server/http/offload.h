/* offload.h -- request work that costs CPU in proportion to a body, off the HTTP threads.
 *
 * Why: parsing and validating a 1 MB spec takes tens of milliseconds (more under sanitizers).
 * Done on the libmicrohttpd threads, four such posts at once occupy every HTTP thread, and a
 * GET /v1/health queued behind them waited over 100 ms. The HTTP layer now suspends such a
 * connection (MHD_suspend_connection), hands the work here, and the task resumes the connection
 * when its response is ready; the HTTP threads only move bytes.
 *
 * The pool: a few threads at a lower scheduling priority (nice +5), so that cheap requests and
 * the job workers keep the CPU first, and a FIFO queue. The queue needs no bound of its own:
 * every task holds one suspended connection, and connections are bounded by
 * --max-connections.
 *
 * Thread safety: gpd_offload_submit may be called from any thread; start and stop from one. */
#ifndef GPD_OFFLOAD_H
#define GPD_OFFLOAD_H

/* Starts threads pool threads. 0, or -1 (a thread could not be created; none is left). */
int gpd_offload_start(unsigned threads);

/* Queues run(arg). 0, or -1 when the pool is not running (stopping, or never started): the
 * caller then does the work itself. */
int gpd_offload_submit(void (*run)(void *arg), void *arg);

/* Refuses new tasks, runs every queued one, and joins the threads. */
void gpd_offload_stop(void);

#endif /* GPD_OFFLOAD_H */
