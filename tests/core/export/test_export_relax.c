/* test_export_relax.c -- the lammps-relax export on a hand-made specimen: a valid ustar archive
 * (checksums, sizes, padding, the end blocks) of lammps-relax/{relax.in, spheres.data}, the same
 * bytes whatever the read size; the data file's atoms read back bit for bit with their size
 * classes; the script carries the DEM block's numbers; packs without (or with a broken) DEM
 * block are refused. (Running the script in LAMMPS under mpirun is
 * tests/integration/test_lammps_relax.py.)
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_export.h"
#include "gp_test.h"

/* radii from 1 to 3.9 mm: a span of 3.9 wants 28 classes of 5 % */
static double sph[6][4] = {{0.01, 0.02, 0.03, 0.001},   {0.05, 0.05, 0.05, 0.0039},
                           {0.02, 0.08, 0.01, 0.002},   {1.0 / 3.0 * 0.1, 0.03, 0.07, 0.00105},
                           {0.09, 0.09, 0.09, 0.003},   {0.07, 0.01, 0.05, 0.0025}};

static void make(gp_specimen3d *s, gp_spec3d *spec)
{
    memset(s, 0, sizeof *s);
    s->spheres = &sph[0][0];
    s->count = 6;
    s->box[0] = 0.1;
    s->box[1] = 0.1;
    s->box[2] = 0.1;
    s->stats.dt = 1.25e-5;
    s->stats.scaled_radius = 0.0021;
    s->stats.porosity = 0.41;
    s->stats.coordination_number = 4.5;
    gp_spec3d_defaults(spec);
    spec->material.density = 2650.5;
    spec->material.young = 2e7;
    spec->material.friction_deg = 25;
    spec->tiling[0] = 2;
}

typedef struct bytes {
    unsigned char *p;
    size_t n;
} bytes;

/* the export of pack in format f, read in pieces of `piece` bytes; p = NULL on error */
static bytes read_all(gp_export_format f, const void *pack, size_t len, size_t piece)
{
    bytes b = {NULL, 0};
    gp_export_source src = gp_export_memory_source(pack, len);
    gp_export *e;
    if (gp_export_open(f, &src, &e, NULL)) return b;
    size_t cap = 1 << 16;
    b.p = malloc(cap);
    char *buf = malloc(piece);
    for (;;) {
        size_t n;
        if (gp_export_read(e, buf, piece, &n, NULL)) {
            free(b.p);
            b.p = NULL;
            break;
        }
        if (n == 0) break;
        if (b.n + n > cap) b.p = realloc(b.p, cap = 2 * (b.n + n));
        memcpy(b.p + b.n, buf, n);
        b.n += n;
    }
    free(buf);
    gp_export_destroy(e);
    return b;
}

/* One member of a ustar archive: its header checked, its name, type and data. */
typedef struct member {
    char name[101];
    char type;
    const unsigned char *data;
    size_t size;
} member;

static int tar_member(const unsigned char *h, member *m)
{
    unsigned sum = 0;
    for (int k = 0; k < 512; k++) sum += (k >= 148 && k < 156) ? ' ' : h[k];
    if (strtoul((const char *)h + 148, NULL, 8) != sum) return -1;
    if (memcmp(h + 257, "ustar", 6) || memcmp(h + 263, "00", 2)) return -1;
    memcpy(m->name, h, 100);
    m->name[100] = 0;
    m->type = (char)h[156];
    m->size = strtoull((const char *)h + 124, NULL, 8);
    m->data = h + 512;
    return 0;
}

/* the archive's members (at most max); -1 when it is not a well-formed ustar archive ending in
 * two zero blocks */
static int tar_members(const bytes *b, member *m, int max)
{
    if (b->n % 512 || b->n < 1024) return -1;
    size_t off = 0;
    int k = 0;
    while (off + 512 <= b->n && b->p[off]) {
        if (k == max || tar_member(b->p + off, &m[k])) return -1;
        off += 512 + (m[k].size + 511) / 512 * 512;
        if (off > b->n) return -1;
        k++;
    }
    for (size_t i = off; i < b->n; i++)
        if (b->p[i]) return -1;
    return b->n - off == 1024 ? k : -1;
}

/* the first occurrence of what in the n bytes at s, or NULL */
static const char *find(const void *s, size_t n, const char *what)
{
    size_t w = strlen(what);
    for (size_t i = 0; i + w <= n; i++)
        if (!memcmp((const char *)s + i, what, w)) return (const char *)s + i;
    return NULL;
}

static int count(const char *s, size_t n, const char *what)
{
    int c = 0;
    size_t w = strlen(what);
    for (size_t i = 0; i + w <= n; i++) c += !memcmp(s + i, what, w);
    return c;
}

static int contains(const member *m, const char *what)
{
    return count((const char *)m->data, m->size, what) > 0;
}

static void test_registry(void)
{
    CHECK(gp_export_format_parse("lammps-relax") == GP_EXPORT_LAMMPS_RELAX);
    CHECK(gp_export_format_supports(GP_EXPORT_LAMMPS_RELAX, 3));
    CHECK(!gp_export_format_supports(GP_EXPORT_LAMMPS_RELAX, 2));
    CHECK(!strcmp(gp_export_format_extension(GP_EXPORT_LAMMPS_RELAX), "tar"));
    CHECK(!strcmp(gp_export_format_mime(GP_EXPORT_LAMMPS_RELAX), "application/x-tar"));
    CHECK(strstr(gp_export_format_list(3), "lammps-relax") != NULL);
}

/* the data file: header counts, then atoms whose numbers read back bit for bit, types rising
 * with the radius from 1 to K */
static void check_data(const member *d, int K)
{
    char *t = malloc(d->size + 1);
    memcpy(t, d->data, d->size);
    t[d->size] = 0;
    char want[64];
    snprintf(want, sizeof want, "\n6 atoms\n%d atom types\n", K);
    CHECK(strstr(t, want) != NULL);
    CHECK(strstr(t, "\n0 0.10000000000000001 xlo xhi\n") != NULL);
    char *p = strstr(t, "Atoms # sphere\n\n");
    CHECK(p != NULL);
    int exact = 0, tmin = 1 << 30, tmax = 0, ordered = 1;
    long types[6];
    if (p) p += strlen("Atoms # sphere\n\n");
    for (int i = 0; p && i < 6; i++) {
        long id = strtol(p, &p, 10);
        types[i] = strtol(p, &p, 10);
        double dia = strtod(p, &p), rho = strtod(p, &p);
        double q[3];
        for (int a = 0; a < 3; a++) q[a] = strtod(p, &p);
        exact += id == i + 1 && dia == 2 * sph[i][3] && rho == 2650.5 && !memcmp(q, sph[i], 24);
        tmin = types[i] < tmin ? (int)types[i] : tmin;
        tmax = types[i] > tmax ? (int)types[i] : tmax;
        for (int j = 0; j < i; j++) /* the type rises with the radius */
            ordered &= (sph[j][3] < sph[i][3]) ? types[j] <= types[i] : types[j] >= types[i];
        if (*p == '\n') p++;
    }
    CHECK(exact == 6);
    CHECK(tmin == 1 && tmax == K);
    CHECK(ordered);
    CHECK(p && *p == 0);
    free(t);
}

/* the script: the numbers of the DEM block and one pair_coeff per type pair */
static void check_script(const member *s, int K)
{
    CHECK(contains(s, "read_data       spheres.data\n"));
    CHECK(contains(s, "timestep        1.2500000000000001e-05\n"));
    CHECK(contains(s, "pair_style      granular\n"));
    CHECK(count((const char *)s->data, s->size, "\npair_coeff ") == K * (K + 1) / 2);
    /* k_n of two spheres of the smallest class: 2 E r r / 2r = E r, r = 1 mm * q^0.5; k_t */
    double q = pow(3.9, 1.0 / K);
    const char *kn = find(s->data, s->size, "pair_coeff      1 1 hooke ");
    CHECK(kn != NULL);
    if (kn) {
        char *end;
        CHECK_REL(strtod(kn + 26, &end), 2e7 * 0.001 * sqrt(q), 1e-12);
        CHECK(!strncmp(end, " 0 tangential linear_history ", 29));
        CHECK_REL(strtod(end + 29, &end), 0.5 * 2e7 * 0.001 * sqrt(q), 1e-12);
    }
    char want[128];
    snprintf(want, sizeof want, " 0 %.17g damping velocity\n", tan(25 * M_PI / 180));
    CHECK(contains(s, want));
    CHECK(contains(s, "fix             halt all halt ${every} v_Sc <= 0.0001 error continue\n"));
    CHECK(contains(s, "variable        dx atom -0.69999999999999996*abs(fx)*((vx>0)-(vx<0))\n"));
    CHECK(contains(s, "c_r*c_r*c_r*((c_r<0.0020999999999999999)*(0.0020999999999999999/c_r)^2"));
    CHECK(contains(s, "fw") && contains(s, "*c_r*(v_hxl-v_hxh)\n"));
    /* the top wall at ${ztop}, the box's top unless the run lifts it; the others fixed */
    CHECK(contains(s, "variable        ztop index 0.10000000000000001\n"));
    CHECK(contains(s, "change_box      all z final 0 ${ztop} units box\n"));
    CHECK(contains(s, "variable        hzh atom 0.5*(c_r-(${ztop}-z)+abs(c_r-(${ztop}-z)))\n"));
    CHECK(contains(s, "variable        hyh atom 0.5*(c_r-(0.10000000000000001-y)+"));
    CHECK(contains(s, "# grainpack measured porosity 0.410000 and coordination number 4.5000.\n"));
    CHECK(contains(s, "(tiling 2 x 1 x 1)"));
    CHECK(contains(s, "\"grainpack\": {\"porosity\": 0.40999999999999998, \"coordination_number\": 4.5}"));
    CHECK(contains(s, "group           nearwall dynamic all region core every 1\n"));
    CHECK(s->data[s->size - 1] == '\n');
}

static void test_archive(void)
{
    gp_specimen3d s;
    gp_spec3d spec;
    make(&s, &spec);
    void *pack;
    size_t len;
    CHECK(gp_export_pack_3d_dem(&s, &spec, &pack, &len, NULL) == GP_OK);
    bytes ref = read_all(GP_EXPORT_LAMMPS_RELAX, pack, len, 65536);
    CHECK(ref.p != NULL);
    size_t pieces[2] = {1, 509};
    for (int k = 0; k < 2 && ref.p; k++) {
        bytes b = read_all(GP_EXPORT_LAMMPS_RELAX, pack, len, pieces[k]);
        CHECK(b.p && b.n == ref.n && !memcmp(b.p, ref.p, ref.n));
        free(b.p);
    }
    member m[4];
    int nm = ref.p ? tar_members(&ref, m, 4) : -1;
    CHECK(nm == 3);
    if (nm == 3) {
        CHECK(!strcmp(m[0].name, "lammps-relax/") && m[0].type == '5' && m[0].size == 0);
        CHECK(!strcmp(m[1].name, "lammps-relax/relax.in") && m[1].type == '0');
        CHECK(!strcmp(m[2].name, "lammps-relax/spheres.data") && m[2].type == '0');
        int K = (int)ceil(log(3.9) / log(1.05));
        check_script(&m[1], K);
        check_data(&m[2], K);
    }
    /* the other formats read the same pack as before */
    bytes csv = read_all(GP_EXPORT_CSV, pack, len, 100);
    CHECK(csv.p && csv.n > 6 * 20);
    free(csv.p);
    free(ref.p);
    free(pack);
}

/* equal spheres: one class, whose radius is theirs */
static void test_one_class(void)
{
    gp_specimen3d s;
    gp_spec3d spec;
    make(&s, &spec);
    double eq[2][4] = {{0.02, 0.02, 0.006, 0.004}, {0.05, 0.02, 0.006, 0.004}};
    s.spheres = &eq[0][0];
    s.count = 2;
    s.box[2] = 0.012; /* thinner than 4 radii: every sphere is near a wall */
    void *pack;
    size_t len;
    CHECK(gp_export_pack_3d_dem(&s, &spec, &pack, &len, NULL) == GP_OK);
    bytes b = read_all(GP_EXPORT_LAMMPS_RELAX, pack, len, 4096);
    member m[4];
    CHECK(b.p && tar_members(&b, m, 4) == 3);
    if (b.p) {
        const char *kn = find(m[1].data, m[1].size, "pair_coeff      1 1 hooke ");
        CHECK(kn && fabs(strtod(kn + 26, NULL) - 2e7 * 0.004) < 1e-9);
        CHECK(count((const char *)m[1].data, m[1].size, "\npair_coeff ") == 1);
        CHECK(contains(&m[2], "\n1 atom types\n"));
        CHECK(contains(&m[1], "group           nearwall union all\n"));
        CHECK(!contains(&m[1], "region"));
    }
    free(b.p);
    free(pack);
}

static void test_refusals(void)
{
    gp_specimen3d s;
    gp_spec3d spec;
    make(&s, &spec);
    void *pack;
    size_t len;
    gp_error err;
    gp_export *e = NULL;
    /* a pack made without the DEM block (as every pack before lammps-relax) */
    CHECK(gp_export_pack_3d(&s, 2600, &pack, &len, NULL) == GP_OK);
    gp_export_source src = gp_export_memory_source(pack, len);
    CHECK(gp_export_open(GP_EXPORT_LAMMPS_RELAX, &src, &e, &err) == GP_ERR_INVALID);
    CHECK(e == NULL && strstr(err.message, "submit the job again") != NULL);
    CHECK(gp_export_open(GP_EXPORT_LAMMPS, &src, &e, &err) == GP_OK);
    gp_export_destroy(e);
    free(pack);
    CHECK(gp_export_pack_3d_dem(&s, NULL, &pack, &len, &err) == GP_ERR_INVALID);

    CHECK(gp_export_pack_3d_dem(&s, &spec, &pack, &len, NULL) == GP_OK);
    unsigned char *p = pack, *dem = p + 128 + 32 * 6;
    src = gp_export_memory_source(pack, len);
    dem[0] ^= 1; /* its magic: not a pack at all */
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_ERR_INVALID);
    CHECK(strstr(err.message, "DEM block") != NULL);
    dem[0] ^= 1;
    double zero = 0, dt; /* a time step of 0: the other formats open, lammps-relax does not */
    memcpy(&dt, dem + 8 + 6 * 8, 8);
    CHECK(dt == 1.25e-5);
    memcpy(dem + 8 + 6 * 8, &zero, 8);
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_OK);
    gp_export_destroy(e);
    CHECK(gp_export_open(GP_EXPORT_LAMMPS_RELAX, &src, &e, &err) == GP_ERR_INVALID);
    CHECK(strstr(err.message, "out of range") != NULL);
    src = gp_export_memory_source(pack, len - 1); /* truncated block */
    CHECK(gp_export_open(GP_EXPORT_CSV, &src, &e, &err) == GP_ERR_INVALID);
    free(pack);
}

int main(void)
{
    test_registry();
    test_archive();
    test_one_class();
    test_refusals();
    return gp_test_summary();
}
