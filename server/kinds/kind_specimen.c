/* kind_specimen.c -- what the kinds made on a sphere specimen share (see kind_specimen.h). */
#include "kinds/kind_specimen.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gp_spec_specimen.h"
#include "jobs/result_json.h"
#include "kinds/kind.h"

gp_status gpd_specimen_failed_in(gp_status st, gp_error *err, const char *what)
{
    if (st == GP_OK || st == GP_ERR_CANCELLED) return st;
    char m[GP_ERROR_MESSAGE_MAX];
    snprintf(m, sizeof m, "%s", err->message);
    return gp_error_set(err, st, "%s: %.200s", what, m);
}

gp_status gpd_specimen_build(const gp_spec3d *spec, int threads, gp_progress_fn fn, void *user,
                             const volatile int *cancel, gp_specimen3d **out, int *ok,
                             gp_error *err)
{
    gp_spec3d sp = *spec; /* its sieve shared, read only */
    sp.threads = threads;
    gp_status st = gp_specimen3d_build(&sp, fn, user, cancel, out, err);
    if (!st && (!(*out)->spheres || !(*out)->count))
        st = gp_error_set(err, GP_ERR_INTERNAL, "the specimen has no spheres");
    *ok = st == GP_OK;
    return gpd_specimen_failed_in(st, err, "the specimen");
}

int gpd_specimen_phases(const gp_spec3d *spec, const json_t *inner, gpd_phase *out)
{
    const gpd_kind *sk = gpd_kind_find(gp_spec_specimen_kind());
    int n = sk && sk->plan ? sk->plan(spec, inner, out, GPD_PLAN_MAX) : 0;
    if (n > 0 && !strcmp(out[n - 1].name, "result")) n--;
    return n > 0 ? n : 0;
}

json_t *gpd_specimen_material_json(const gp_material3d *m)
{
    return json_pack("{s:o, s:o, s:o, s:o, s:o}", "density", gpd_jreal(m->density), "young",
                     gpd_jreal(m->young), "poisson", gpd_jreal(m->poisson), "friction_deg",
                     gpd_jreal(m->friction_deg), "damping", gpd_jreal(m->damping));
}

void gpd_warnf(json_t *warnings, const char *fmt, ...)
{
    char line[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    json_array_append_new(warnings, json_string(line));
}
