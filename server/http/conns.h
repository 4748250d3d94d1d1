/* conns.h -- a deadline on the headers of every request: the slowloris guard.
 *
 * Why: libmicrohttpd's connection timeout is an idle timeout. A client that sends one header
 * line every few seconds keeps its connection for ever, and a thousand such clients hold every
 * connection of the daemon (and, under the common limit of 1,024 open files, every descriptor:
 * GET /v1/health then waited over 40 s). The per-address connection limit and the descriptor
 * reserve (http.h) bound how many a client may hold; this bounds how long.
 *
 * The watch keeps every connection (MHD_OPTION_NOTIFY_CONNECTION) with the time by which the
 * headers of its next request must be complete: header_timeout_s after it was accepted, and
 * for a further request on a kept-alive connection the larger of header_timeout_s and
 * keepalive_s after the previous answer (a client that keeps its connection between polls keeps
 * the idle time it had). Once the headers are in (the access handler's first call) the request
 * has no deadline here: its body and its answer are under the idle timeout. A thread looks once
 * a second and shuts down (shutdown(2), not close: the descriptor stays libmicrohttpd's) every
 * connection past its deadline; libmicrohttpd sees the stream end and closes it as usual.
 *
 * Thread safety: the notify callback and the two marks are called by libmicrohttpd's threads,
 * the sweep runs on its own; one mutex. A connection's entry is freed when libmicrohttpd says
 * it is closed, which it does before it closes the descriptor, so the sweep never shuts a
 * descriptor that another connection has been given since. */
#ifndef GPD_CONNS_H
#define GPD_CONNS_H

#include <microhttpd.h>

/* Starts the sweep; 0, or -1 (no thread). */
int gpd_conns_start(double header_timeout_s, double keepalive_s);
/* Stops the sweep (the entries of connections still open are freed by their notify). */
void gpd_conns_stop(void);

/* MHD_OPTION_NOTIFY_CONNECTION's callback: records and forgets connections. */
void gpd_conns_notify(void *cls, struct MHD_Connection *c, void **socket_context,
                      enum MHD_ConnectionNotificationCode code);

/* The headers of c's request are complete: no deadline until its answer is done. */
void gpd_conns_headers_done(struct MHD_Connection *c);
/* c's request has been answered: the next one's headers have a deadline again. */
void gpd_conns_request_done(struct MHD_Connection *c);

/* Connections shut down for their headers' deadline since the start. */
long gpd_conns_timed_out(void);

#endif /* GPD_CONNS_H */
