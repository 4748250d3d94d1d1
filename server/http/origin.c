/* origin.c -- the Host and Origin headers grainpackd answers to (see origin.h). */
#include "http/origin.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Names this daemon answers to in a Host header (lower case, IPv6 in brackets); "own" ones are
 * also its own origin (http://NAME:PORT), the others come from --allow-origin. */
#define MAX_NAMES 64
#define MAX_ALLOWED 32
typedef struct host_name {
    char name[264];
    int own;
} host_name;
static host_name names[MAX_NAMES];
static size_t n_names = 0;
static char allowed[MAX_ALLOWED][300]; /* normalized origins given with --allow-origin */
static size_t n_allowed = 0;
static int own_port = 0;
static int any_ip = 0;          /* listening on 0.0.0.0 / [::]: any IP literal is ours */
static char own_url[300] = "";  /* http://HOST:PORT, for messages */

static void add_name(const char *name, int own)
{
    for (size_t i = 0; i < n_names; i++)
        if (!strcmp(names[i].name, name)) {
            names[i].own |= own;
            return;
        }
    if (n_names == MAX_NAMES || strlen(name) >= sizeof names[0].name) return;
    snprintf(names[n_names].name, sizeof names[0].name, "%s", name);
    names[n_names++].own = own;
}

/* "host[:port]" (an authority: a Host header, the end of an origin, --listen) into a lower-case
 * host (IPv6 canonical, in brackets; a trailing dot dropped) and *port (-1 when absent).
 * 0, or -1 when malformed. */
static int parse_authority(const char *s, size_t n, char *host, size_t hostlen, int *port)
{
    *port = -1;
    if (n == 0 || hostlen < 3) return -1;
    const char *end = s + n, *rest;
    if (s[0] == '[') {
        const char *rb = memchr(s, ']', n);
        if (!rb || rb - s < 3 || rb - s > 64) return -1;
        char in6[72];
        memcpy(in6, s + 1, (size_t)(rb - s - 1));
        in6[rb - s - 1] = '\0';
        struct in6_addr a6;
        char canon[INET6_ADDRSTRLEN];
        if (inet_pton(AF_INET6, in6, &a6) != 1 || !inet_ntop(AF_INET6, &a6, canon, sizeof canon))
            return -1;
        if (strlen(canon) + 3 > hostlen) return -1;
        snprintf(host, hostlen, "[%s]", canon);
        rest = rb + 1;
    } else {
        const char *colon = memchr(s, ':', n);
        size_t hl = colon ? (size_t)(colon - s) : n;
        if (hl == 0 || hl >= hostlen) return -1;
        for (size_t i = 0; i < hl; i++) {
            unsigned char ch = (unsigned char)s[i];
            if (!isalnum(ch) && ch != '-' && ch != '.' && ch != '_') return -1;
            host[i] = (char)tolower(ch);
        }
        host[hl] = '\0';
        if (hl > 1 && host[hl - 1] == '.') host[hl - 1] = '\0';
        rest = s + hl;
    }
    if (rest < end) {
        if (*rest != ':') return -1;
        long v = 0;
        for (const char *q = rest + 1; q < end; q++) {
            if (!isdigit((unsigned char)*q)) return -1;
            v = v * 10 + (*q - '0');
            if (v > 65535) return -1;
        }
        if (rest + 1 < end) *port = (int)v; /* "host:" is the default port (RFC 3986) */
    }
    return 0;
}

/* "scheme://host[:port]" into its parts (port: -1 = the scheme's default) and its normalized
 * form, as a browser sends it: lower case, no default port. 0, or -1 when malformed. */
static int parse_origin(const char *s, char *scheme, size_t slen, char *host, size_t hostlen,
                        int *port, char *norm, size_t normlen)
{
    const char *sep = strstr(s, "://");
    size_t sl = sep ? (size_t)(sep - s) : 0;
    if (!sep || sl == 0 || sl >= slen || !isalpha((unsigned char)s[0])) return -1;
    for (size_t i = 0; i < sl; i++) {
        unsigned char ch = (unsigned char)s[i];
        if (!isalnum(ch) && ch != '+' && ch != '-' && ch != '.') return -1;
        scheme[i] = (char)tolower(ch);
    }
    scheme[sl] = '\0';
    if (parse_authority(sep + 3, strlen(sep + 3), host, hostlen, port)) return -1;
    int dflt = !strcmp(scheme, "http") ? 80 : !strcmp(scheme, "https") ? 443 : -1;
    if (*port == dflt) *port = -1;
    if (*port > 0)
        snprintf(norm, normlen, "%s://%s:%d", scheme, host, *port);
    else
        snprintf(norm, normlen, "%s://%s", scheme, host);
    return 0;
}

int gpd_allow_origins(const char *list)
{
    const char *p = list;
    while (p && *p) {
        while (*p == ' ' || *p == ',') p++;
        const char *e = p;
        while (*e && *e != ',') e++;
        const char *t = e;
        while (t > p && t[-1] == ' ') t--;
        if (t > p && t[-1] == '/') t--; /* "http://lab.example:3000/" is the same origin */
        if (t > p) {
            char item[300], scheme[32], host[264], norm[300];
            int port;
            size_t il = (size_t)(t - p);
            if (il >= sizeof item ||
                (memcpy(item, p, il), item[il] = '\0',
                 parse_origin(item, scheme, sizeof scheme, host, sizeof host, &port, norm,
                              sizeof norm))) {
                fprintf(stderr,
                        "grainpackd: --allow-origin expects scheme://host[:port] (e.g. "
                        "http://lab.example:3000), got \"%.*s\"\n",
                        (int)(il < 200 ? il : 200), p);
                return -1;
            }
            if (n_allowed == MAX_ALLOWED) {
                fprintf(stderr, "grainpackd: at most %d origins may be allowed\n", MAX_ALLOWED);
                return -1;
            }
            size_t k = 0;
            while (k < n_allowed && strcmp(allowed[k], norm)) k++;
            if (k == n_allowed) snprintf(allowed[n_allowed++], sizeof allowed[0], "%s", norm);
            add_name(host, 0);
        }
        p = e;
    }
    return 0;
}

static int is_ip_literal(const char *name)
{
    struct in_addr a4;
    return name[0] == '[' || inet_pton(AF_INET, name, &a4) == 1;
}

/* the names this daemon answers to: loopback, the --listen host as given and as bound, and on
 * a wildcard address the machine's host name (any IP literal is accepted there as well) */
void origin_setup(const char *listen, const char *host, int port)
{
    char h[264];
    int p;
    add_name("localhost", 1);
    add_name("127.0.0.1", 1);
    add_name("[::1]", 1);
    if (listen && !parse_authority(listen, strlen(listen), h, sizeof h, &p)) add_name(h, 1);
    if (host && !parse_authority(host, strlen(host), h, sizeof h, &p)) {
        add_name(h, 1);
        any_ip = !strcmp(h, "0.0.0.0") || !strcmp(h, "[::]");
    }
    if (any_ip) {
        char hn[256];
        if (gethostname(hn, sizeof hn) == 0) {
            hn[sizeof hn - 1] = '\0';
            if (!parse_authority(hn, strlen(hn), h, sizeof h, &p) && p < 0) add_name(h, 1);
        }
    }
    own_port = port;
    snprintf(own_url, sizeof own_url, "http://%s:%d", host ? host : "127.0.0.1", port);
}

const char *origin_own_url(void) { return own_url; }

int origin_host_ok(const char *host, char *hname, size_t n, int *hport)
{
    if (parse_authority(host, strlen(host), hname, n, hport)) return 0;
    for (size_t i = 0; i < n_names; i++)
        if (!strcmp(names[i].name, hname)) return 1;
    return any_ip && is_ip_literal(hname);
}

/* An Origin is accepted when it was given with --allow-origin, when it is the authority the
 * request was sent to (same origin: the page came from this daemon, as the browser reached it),
 * or when it is http://NAME:PORT with NAME one of the daemon's own names and PORT its port
 * (a page at http://localhost:8080 calling http://127.0.0.1:8080). */
int origin_ok(const char *origin, const char *hname, int hport)
{
    char scheme[32], oh[264], norm[300];
    int op;
    if (parse_origin(origin, scheme, sizeof scheme, oh, sizeof oh, &op, norm, sizeof norm))
        return 0;
    for (size_t i = 0; i < n_allowed; i++)
        if (!strcmp(norm, allowed[i])) return 1;
    int http = !strcmp(scheme, "http"), https = !strcmp(scheme, "https");
    if (!http && !https) return 0;
    int dflt = https ? 443 : 80;
    int oport = op > 0 ? op : dflt;
    if (hname && !strcmp(oh, hname) && oport == (hport > 0 ? hport : dflt)) return 1;
    if (http && oport == own_port)
        for (size_t i = 0; i < n_names; i++)
            if (names[i].own && !strcmp(names[i].name, oh)) return 1;
    return 0;
}

