/* result_json.c -- the pieces every result writer uses (see result_json.h). */
#include "result_json.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"

json_t *gpd_jreal(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

json_t *gpd_jreals(const double *v, size_t n)
{
    if (!v) return json_null();
    json_t *a = json_array();
    for (size_t i = 0; i < n; i++) json_array_append_new(a, gpd_jreal(v[i]));
    return a;
}

json_t *gpd_result_new(const char *kind, uint64_t seed, const json_t *spec_json)
{
    json_t *r = json_object();
    if (!r) return NULL;
    json_object_set_new(r, "kind", json_string(kind));
    json_object_set_new(r, "seed", json_integer((json_int_t)seed));
    json_t *o = json_object_get(spec_json, "outputs");
    if (o) json_object_set(r, "outputs", o);
    return r;
}

int gpd_cancel_raised(const volatile int *cancel)
{
    return cancel && __atomic_load_n((const int *)cancel, __ATOMIC_RELAXED) != 0;
}

typedef struct dump_buf {
    gpd_buf b;
    unsigned long calls;
    const volatile int *cancel;
} dump_buf;

/* json_dump_callback's sink: appends, and gives up (-1: jansson stops writing) when the flag
 * is up, looked at every 4096 pieces (a piece is a number, a string or a bracket). */
static int dump_piece(const char *buffer, size_t size, void *data)
{
    dump_buf *d = data;
    if (++d->calls % 4096 == 0 && gpd_cancel_raised(d->cancel)) return -1;
    return gpd_buf_add(&d->b, buffer, size);
}

char *gpd_dumps_c(const json_t *r, size_t flags, const volatile int *cancel)
{
    dump_buf d = {{NULL, 0, 0, 0}, 0, cancel};
    if (!r || json_dump_callback(r, dump_piece, &d, flags) != 0 || !d.b.buf) {
        free(d.b.buf);
        return NULL;
    }
    char *fit = realloc(d.b.buf, d.b.len + 1); /* the doubling's slack back (up to half of it) */
    return fit ? fit : d.b.buf;
}
