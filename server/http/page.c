/* page.c -- the dashboard page as served, and its Content-Security-Policy (see page.h). */
#include "http/page.h"

#include <ctype.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "http/dashboard.h"
#include "kinds/kind.h"
#include "util/util.h"

/* where dashboard.html's script takes the kinds: "var KINDS = <marker>;" */
#define KINDS_MARKER "/*@KINDS@*/{}"

static pthread_once_t once = PTHREAD_ONCE_INIT;
static char *page = NULL; /* built once, kept for the life of the process */
static char csp[3072];

/* ------------------------------------------------------------------ SHA-256 */

/* SHA-256 (FIPS 180-4), for the hashes of the dashboard's inline script and style */
static const uint32_t sha_k[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
    0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
    0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
    0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
    0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
    0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
    0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
    0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
    0xc67178f2};

#define ROR32(x, n) (((x) >> (n)) | ((x) << (32 - (n))))

static void sha256_block(uint32_t h[8], const unsigned char *p)
{
    uint32_t w[64];
    for (int i = 0; i < 16; i++)
        w[i] = (uint32_t)p[4 * i] << 24 | (uint32_t)p[4 * i + 1] << 16 |
               (uint32_t)p[4 * i + 2] << 8 | p[4 * i + 3];
    for (int i = 16; i < 64; i++) {
        uint32_t s0 = ROR32(w[i - 15], 7) ^ ROR32(w[i - 15], 18) ^ (w[i - 15] >> 3);
        uint32_t s1 = ROR32(w[i - 2], 17) ^ ROR32(w[i - 2], 19) ^ (w[i - 2] >> 10);
        w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; i++) {
        uint32_t t1 = hh + (ROR32(e, 6) ^ ROR32(e, 11) ^ ROR32(e, 25)) + ((e & f) ^ (~e & g)) +
                      sha_k[i] + w[i];
        uint32_t t2 = (ROR32(a, 2) ^ ROR32(a, 13) ^ ROR32(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        hh = g;
        g = f;
        f = e;
        e = d + t1;
        d = c;
        c = b;
        b = a;
        a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += hh;
}

/* 'sha256-BASE64' of n bytes at s, into out (at least 60 bytes) */
static void csp_hash(const char *s, size_t n, char *out)
{
    uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                     0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    const unsigned char *p = (const unsigned char *)s;
    size_t left = n;
    for (; left >= 64; left -= 64, p += 64) sha256_block(h, p);
    unsigned char last[128];
    memset(last, 0, sizeof last);
    memcpy(last, p, left);
    last[left] = 0x80;
    size_t nb = left + 9 <= 64 ? 64 : 128;
    uint64_t bits = (uint64_t)n * 8;
    for (int i = 0; i < 8; i++) last[nb - 1 - i] = (unsigned char)(bits >> (8 * i));
    sha256_block(h, last);
    if (nb == 128) sha256_block(h, last + 64);
    unsigned char dg[33];
    for (int i = 0; i < 8; i++)
        for (int j = 0; j < 4; j++) dg[4 * i + j] = (unsigned char)(h[i] >> (24 - 8 * j));
    dg[32] = 0;
    static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *o = out + sprintf(out, "'sha256-");
    for (int i = 0; i < 33; i += 3) {
        uint32_t v = (uint32_t)dg[i] << 16 | (uint32_t)dg[i + 1] << 8 | dg[i + 2];
        *o++ = b64[v >> 18 & 63];
        *o++ = b64[v >> 12 & 63];
        *o++ = i + 1 < 32 ? b64[v >> 6 & 63] : '=';
        *o++ = i + 2 < 32 ? b64[v & 63] : '=';
    }
    *o++ = '\'';
    *o = '\0';
}

/* appends ' item' to a source list, unless it is there already */
static void csp_add(char *list, size_t cap, const char *item)
{
    if (strstr(list, item)) return;
    size_t n = strlen(list);
    snprintf(list + n, cap - n, " %s", item);
}

/* ------------------------------------------------------------------ the policy */

/* The dashboard is one static page with an inline <script> and <style> and a few style=""
 * attributes: the policy allows exactly those (by their SHA-256, computed here from the page
 * served, so it follows any edit of dashboard.html and of the kinds) and nothing from elsewhere. */
static void build_csp(const char *html)
{
    char scripts[1024] = "", styles[1024] = "", attrs[1024] = "", hash[64];
    const char *p = html;
    const char *tag;
    while ((tag = strchr(p, '<')) != NULL) {
        const char *gt = strchr(tag, '>');
        if (!gt) break;
        int is_script = !strncmp(tag, "<script", 7) &&
                        (tag[7] == '>' || isspace((unsigned char)tag[7]));
        int is_style = !strncmp(tag, "<style", 6) &&
                       (tag[6] == '>' || isspace((unsigned char)tag[6]));
        /* the style="..." attributes of this tag */
        for (const char *a = tag; a < gt; a++) {
            if (isspace((unsigned char)a[0]) && !strncmp(a + 1, "style=\"", 7)) {
                const char *v = a + 8, *ve = memchr(v, '"', (size_t)(gt - v));
                if (ve) {
                    csp_hash(v, (size_t)(ve - v), hash);
                    csp_add(attrs, sizeof attrs, hash);
                    a = ve;
                }
            }
        }
        if (is_script || is_style) {
            const char *close = strstr(gt + 1, is_script ? "</script>" : "</style>");
            if (!close) break;
            csp_hash(gt + 1, (size_t)(close - gt - 1), hash);
            csp_add(is_script ? scripts : styles, is_script ? sizeof scripts : sizeof styles,
                    hash);
            p = close + 2;
        } else {
            p = gt + 1;
        }
    }
    if (attrs[0]) {
        csp_add(styles, sizeof styles, "'unsafe-hashes'");
        csp_add(styles, sizeof styles, attrs + 1);
    }
    snprintf(csp, sizeof csp,
             "default-src 'self'; script-src%s; style-src%s; img-src 'self'; "
             "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
             "frame-ancestors 'none'",
             scripts[0] ? scripts : " 'none'", styles[0] ? styles : " 'none'");
}

/* ------------------------------------------------------------------ the page */

/* The template with the kinds in place of its marker (as JSON, "/" escaped so that nothing in
 * it can close the script); NULL on out of memory. */
static char *fill_kinds(const char *tpl)
{
    json_t *kinds = gpd_kinds_json();
    char *text = kinds ? json_dumps(kinds, JSON_COMPACT | JSON_ESCAPE_SLASH |
                                               JSON_REAL_PRECISION(15))
                       : NULL;
    json_decref(kinds);
    const char *at = strstr(tpl, KINDS_MARKER);
    gpd_buf b = {0};
    if (text && at) {
        gpd_buf_add(&b, tpl, (size_t)(at - tpl));
        gpd_buf_add(&b, text, strlen(text));
        gpd_buf_add(&b, at + strlen(KINDS_MARKER), strlen(at + strlen(KINDS_MARKER)));
    } else if (text) {
        gpd_buf_add(&b, tpl, strlen(tpl)); /* a page that takes no kinds */
    }
    free(text);
    if (b.oom) {
        free(b.buf);
        return NULL;
    }
    return b.buf;
}

static void build(void)
{
    page = fill_kinds(gp_dashboard_html());
    if (page) build_csp(page);
}

int gpd_page_init(void)
{
    pthread_once(&once, build);
    return page ? 0 : -1;
}

const char *gpd_page_html(void)
{
    return gpd_page_init() ? NULL : page;
}

const char *gpd_page_csp(void)
{
    return gpd_page_init() ? NULL : csp;
}
