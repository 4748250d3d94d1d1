/* origin.h -- which Host and Origin headers grainpackd answers to (http.h, "Before routing"):
 * its own names (loopback, the --listen host as given and as bound, on a wildcard address any
 * IP and the machine's host name) and the origins allowed with --allow-origin. Set up before
 * the HTTP server starts, read-only afterwards. */
#ifndef GPD_ORIGIN_H
#define GPD_ORIGIN_H

#include <stddef.h>

/* Adds the comma-separated origins of list ("scheme://host[:port]", e.g.
 * http://lab.example:3000) to those allowed to call the daemon besides its own address.
 * Returns 0, or -1 with a message on stderr when one is malformed. Call before
 * gpd_http_start. */
int gpd_allow_origins(const char *list);

/* The daemon's own names: listen is the --listen value as given, host and port the address
 * bound (gpd_listen_socket). */
void origin_setup(const char *listen, const char *host, int port);
/* http://HOST:PORT of the daemon, for messages. */
const char *origin_own_url(void);

/* 1 when host (a Host header) names this daemon; its host (lower case, IPv6 in brackets) in
 * hname (n bytes) and its port in *hport (-1 when absent). */
int origin_host_ok(const char *host, char *hname, size_t n, int *hport);
/* 1 when a page at origin may call the daemon: allowed with --allow-origin, the authority the
 * request was sent to (hname, hport; hname NULL without a Host), or http://NAME:PORT with NAME
 * one of the daemon's own names and PORT its port. */
int origin_ok(const char *origin, const char *hname, int hport);

#endif /* GPD_ORIGIN_H */
