/* gp_spec_fv.c -- the size law and the shape's D form or spectrum of the two Fourier-Voronoi
 * kinds (see gp_spec_fv.h). */
#include "gp_spec_fv.h"

#include "gp_imc.h"
#include "gp_law.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* o[key] is the string value */
static int str_is(const json_t *o, const char *key, const char *value)
{
    const char *s = json_string_value(json_object_get(o, key));
    return s && !strcmp(s, value);
}

/* a sieve field (sieve, sieve_units) with another law */
static int sieve_field_posted(const json_t *size, const char *law, gp_spec_problem *p)
{
    const char *f = json_object_get(size, "sieve")         ? "sieve"
                    : json_object_get(size, "sieve_units") ? "sieve_units" : NULL;
    if (!f) return 0;
    char ptr[32];
    snprintf(ptr, sizeof ptr, "/size/%s", f);
    return gp_problem(p, "invalid_spec", ptr, "only allowed with law \"sieve\" (the law here "
                      "is \"%s\"); add \"law\": \"sieve\" or leave %s out",
                      law ? law : "lognormal", f);
}

int gp_spec_fv_check_size_posted(const json_t *spec, const char *room, gp_spec_problem *p)
{
    const json_t *size = json_object_get(spec, "size");
    const char *law = json_string_value(json_object_get(size, "law"));
    if (!law || strcmp(law, "sieve") != 0) return sieve_field_posted(size, law, p);
    if (json_object_get(spec, "particles"))
        return gp_problem(p, "invalid_spec", "/particles", "leave particles out with size.law "
                          "\"sieve\": the number of grains follows from %s and solid_fraction",
                          room);
    if (json_object_get(size, "cov"))
        return gp_problem(p, "invalid_spec", "/size/cov", "not allowed with law \"sieve\": the "
                          "sieve curve sets the spread of sizes; leave cov out");
    if (!json_object_get(size, "sieve"))
        return gp_problem(p, "invalid_spec", "/size/sieve", "required with law \"sieve\": "
                          "expected rows [diameter, percent passing by mass]");
    if (str_is(size, "of", "cells"))
        return gp_problem(p, "invalid_spec", "/size/of", "expected \"grains\" (or nothing) with "
                          "law \"sieve\", got \"cells\": a sieve curve is a law of the grains");
    return 0;
}

int gp_spec_fv_settle(json_t *full, int imc_error)
{
    json_t *size = json_object_get(full, "size");
    int rc = 0;
    if (str_is(size, "law", "sieve")) {
        json_object_del(full, "particles");
        json_object_del(size, "cov");
        rc |= json_object_set_new(size, "of", json_string("grains"));
    } else {
        json_object_del(size, "sieve_units");
    }
    json_t *imc = json_object_get(full, "imc");
    if (!json_object_get(imc, "threshold"))
        rc |= json_object_set_new(imc, "threshold",
                                  json_real(gp_imc_default_threshold(imc_error)));
    return rc ? -1 : 0;
}

/* a sieve's rows, their diameters in metres (size.sieve_units); -1 out of memory */
static int read_sieve(gp_spec_reader *r, const json_t *size, gp_spec_fv_size *z)
{
    const json_t *sieve = gp_rd_array(r, size, "/size/sieve", 2, SIZE_MAX, 0);
    double scale = gp_rd_sieve_scale(r, size, "/size/sieve_units");
    size_t n = json_array_size(sieve);
    z->sieve_d = malloc((n ? n : 1) * sizeof *z->sieve_d);
    z->sieve_pass = malloc((n ? n : 1) * sizeof *z->sieve_pass);
    if (!z->sieve_d || !z->sieve_pass) return -1;
    for (size_t i = 0; i < n; i++)
        gp_rd_row(r, sieve, i, "/size/sieve", scale, &z->sieve_d[i], &z->sieve_pass[i]);
    z->nsieve = n;
    return 0;
}

int gp_spec_fv_read_size(gp_spec_reader *r, const json_t *size, gp_spec_fv_size *z)
{
    static const char *const laws[] = {"lognormal", "normal", "uniform", "sieve"}; /* gp_law_kind */
    static const char *const of[] = {"cells", "grains"};
    memset(z, 0, sizeof *z);
    z->law = gp_rd_enum(r, size, "/size/law", laws, 4);
    z->of_grains = gp_rd_enum(r, size, "/size/of", of, 2);
    if (z->law == GP_LAW_SIEVE) return read_sieve(r, size, z);
    z->cov = gp_rd_num(r, size, "/size/cov", -GP_RD_ANY, GP_RD_ANY);
    return 0;
}

int gp_spec_fv_read_shape(gp_spec_reader *r, const json_t *shape, double *const num[5],
                          double **spectrum, size_t *n)
{
    static const char *const ptrs[5] = {"/shape/D2", "/shape/D3", "/shape/D8", "/shape/alpha",
                                        "/shape/beta"};
    const json_t *spec = gp_rd_array(r, shape, "/shape/spectrum", 1, SIZE_MAX, 1);
    if (!spec) {
        for (int k = 0; k < 5; k++) *num[k] = gp_rd_num(r, shape, ptrs[k], -GP_RD_ANY, GP_RD_ANY);
        return 0;
    }
    size_t m = json_array_size(spec);
    double *d = malloc(m * sizeof *d);
    if (!d) return -1;
    for (size_t i = 0; i < m; i++)
        d[i] = gp_rd_value(r, json_array_get(spec, i), "/shape/spectrum", -GP_RD_ANY, GP_RD_ANY);
    *spectrum = d;
    *n = m;
    return 1;
}

/* size.cov of a parametric law: GP_LAW_COV_MIN and each law's own maximum (gp_law.h) */
static int check_cov(int law, double cov, const char *measure, gp_spec_problem *p)
{
    if (cov < GP_LAW_COV_MIN)
        return gp_problem(p, "invalid_spec", "/size/cov", "expected at least %g, got %.15g: equal "
                          "sizes cannot be tessellated exactly; use %g for nearly equal sizes",
                          GP_LAW_COV_MIN, cov, GP_LAW_COV_MIN);
    if (law == GP_LAW_NORMAL && cov > GP_LAW_NORMAL_COV_MAX)
        return gp_problem(p, "invalid_spec", "/size/cov", "expected at most %g for law "
                          "\"normal\", got %.15g (a wider normal law is mostly cut off at %s "
                          "0); use law \"lognormal\" for a wider spread", GP_LAW_NORMAL_COV_MAX,
                          cov, measure);
    if (law == GP_LAW_UNIFORM && cov > GP_LAW_UNIFORM_COV_MAX)
        return gp_problem(p, "invalid_spec", "/size/cov", "expected at most 0.5773 (1/√3) for "
                          "law \"uniform\", got %.15g (its least %s, mean (1 - √3 cov), would "
                          "be negative)", cov, measure);
    return 0;
}

int gp_spec_fv_check_size(const json_t *full, int law, double cov, const char *measure,
                          gp_spec_problem *p)
{
    if (law == GP_LAW_SIEVE)
        return gp_spec_check_sieve_rows(json_object_get(json_object_get(full, "size"), "sieve"),
                                        "/size/sieve", p);
    return check_cov(law, cov, measure, p);
}
