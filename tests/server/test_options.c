/* test_options.c -- grainpackd's table of options (server/util/options.c): every option read
 * from its flag (long and one-letter) and from its environment variable, the flag winning; the
 * defaults; values out of range or malformed refused with a message naming the flag and what
 * it takes; the list option (--allow-origin) handed over value by value; the actions, unknown
 * options and stray arguments; --help and the Markdown table made from the table; and
 * docs/operations.md naming every flag and every environment variable of the table, its options
 * table being the Markdown one, verbatim. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gp_test.h"
#include "util/options.h"
#include "util/util.h"

#define T gpd_options_table

/* ---- running the parse ---- */

static char err_text[4096]; /* what the last parse said on stderr */

/* the lists handed to add_list, "|"-joined; "bad" is refused */
static char lists[512];
static int add_list(const char *list)
{
    size_t n = strlen(lists);
    snprintf(lists + n, sizeof lists - n, "%s%s", n ? "|" : "", list);
    if (strcmp(list, "bad") != 0) return 0;
    fprintf(stderr, "grainpackd: --allow-origin: bad\n");
    return -1;
}

/* Parses the NULL-terminated args (after argv[0]) into *o, with stderr caught in err_text. */
static gpd_opts_rc parse_v(gpd_options *o, const char *const *args)
{
    char *argv[32] = {"grainpackd"};
    int argc = 1;
    while (args[argc - 1] && argc < 31) argv[argc] = (char *)args[argc - 1], argc++;
    argv[argc] = NULL;
    lists[0] = '\0';
    fflush(stderr);
    int saved = dup(2);
    FILE *tmp = tmpfile();
    dup2(fileno(tmp), 2);
    gpd_opts_rc rc = gpd_options_parse(argc, argv, o, add_list);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(tmp);
    size_t n = fread(err_text, 1, sizeof err_text - 1, tmp);
    err_text[n] = '\0';
    fclose(tmp);
    return rc;
}
#define PARSE(o, ...) parse_v((o), (const char *const[]){__VA_ARGS__, NULL})
#define PARSE0(o) parse_v((o), (const char *const[]){NULL})

static void clear_env(void)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++)
        if (T[i].env) unsetenv(T[i].env);
}

/* ---- the table itself ---- */

/* GRAINPACK_ and the flag in capitals, '-' as '_' */
static void env_of_flag(const char *flag, char *buf, size_t len)
{
    size_t n = (size_t)snprintf(buf, len, "GRAINPACK_");
    for (; *flag && n + 1 < len; flag++) buf[n++] = *flag == '-' ? '_' : (char)toupper(*flag);
    buf[n] = '\0';
}

static void test_table(void)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        const gpd_option *op = &T[i];
        CHECK(op->flag && op->help && *op->help);
        CHECK((op->kind == GPD_OPT_ACTION) == (op->env == NULL));
        CHECK((op->kind == GPD_OPT_ACTION) == (op->arg == NULL));
        if (op->env) {
            char want[64];
            env_of_flag(op->flag, want, sizeof want);
            CHECK(strcmp(op->env, want) == 0);
        }
        if (op->kind == GPD_OPT_INT || op->kind == GPD_OPT_REAL) CHECK(op->min <= op->max);
        if (op->kind == GPD_OPT_CHOICE) CHECK(op->choices && op->pick);
        for (int j = 0; j < i; j++) {
            CHECK(strcmp(op->flag, T[j].flag) != 0);
            CHECK(!op->letter || op->letter != T[j].letter);
        }
    }
}

/* ---- defaults ---- */

static void test_defaults(void)
{
    clear_env();
    gpd_options o;
    CHECK(PARSE0(&o) == GPD_OPTS_RUN);
    CHECK(err_text[0] == '\0' && lists[0] == '\0');
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        CHECK(o.v[i].from == GPD_OPT_FROM_DEFAULT);
        if (T[i].dflt) CHECK(o.v[i].text && strcmp(o.v[i].text, T[i].dflt) == 0);
    }
    CHECK(strcmp(o.v[GPD_OPT_LISTEN].text, "127.0.0.1:8080") == 0);
    CHECK(strcmp(o.v[GPD_OPT_DB].text, "./grainpack.db") == 0);
    CHECK(o.v[GPD_OPT_LEASE].n == 30);
    CHECK(o.v[GPD_OPT_WORKERS].n == gpd_options_cpus() && gpd_options_cpus() >= 1);
    CHECK(o.v[GPD_OPT_JOB_THREADS].n == 0);
    CHECK(o.v[GPD_OPT_LOG_LEVEL].n == GPD_LOG_INFO);
    CHECK(o.v[GPD_OPT_HTTP_THREADS].n == 4);
    CHECK(o.v[GPD_OPT_MAX_CONNECTIONS].n == 1024);
    CHECK(o.v[GPD_OPT_MAX_CONNECTIONS_PER_IP].n == 256);
    CHECK(o.v[GPD_OPT_TIMEOUT].n == 30);
    CHECK(o.v[GPD_OPT_HEADER_TIMEOUT].n == 10);
    CHECK(o.v[GPD_OPT_MAX_BODY].n == 134217728);
    CHECK(o.v[GPD_OPT_MAX_PENDING].n == 16);
    CHECK(o.v[GPD_OPT_MAX_RESULT_MB].n == 8192);
    CHECK(o.v[GPD_OPT_JOB_TIMEOUT].n == 3600);
    CHECK(o.v[GPD_OPT_RETAIN_DAYS].x == 0.0);
    CHECK(o.v[GPD_OPT_MAX_QUEUED].n == 10000);
    CHECK(o.v[GPD_OPT_ALLOW_ORIGIN].text == NULL);
    /* an empty variable is unset */
    setenv("GRAINPACK_WORKERS", "", 1);
    setenv("GRAINPACK_ALLOW_ORIGIN", "", 1);
    CHECK(PARSE0(&o) == GPD_OPTS_RUN);
    CHECK(o.v[GPD_OPT_WORKERS].from == GPD_OPT_FROM_DEFAULT && lists[0] == '\0');
    clear_env();
}

/* ---- each option by flag and by environment ---- */

/* a good value of op other than its default, and whether it is the high end (lo = 0: the low
 * one); text for text options */
static const char *good_value(const gpd_option *op, int hi, char *buf, size_t len)
{
    if (op->kind == GPD_OPT_INT) snprintf(buf, len, "%ld", (long)(hi ? op->max : op->min));
    if (op->kind == GPD_OPT_REAL) snprintf(buf, len, "%s", hi ? "36500" : "0.5");
    if (op->kind == GPD_OPT_CHOICE) snprintf(buf, len, "%s", hi ? "debug" : "error");
    if (op->kind == GPD_OPT_TEXT) snprintf(buf, len, "%s", hi ? "hi:1" : "lo:2");
    return buf;
}

/* that o holds value (as given in text) for option i, from where */
static int holds(const gpd_options *o, int i, const char *value, gpd_opt_from from)
{
    const gpd_opt_value *v = &o->v[i];
    if (v->from != from || !v->text || strcmp(v->text, value) != 0) return 0;
    if (T[i].kind == GPD_OPT_INT) return v->n == strtol(value, NULL, 10);
    if (T[i].kind == GPD_OPT_REAL) return v->x == strtod(value, NULL);
    if (T[i].kind == GPD_OPT_CHOICE) return v->n == gpd_log_parse_level(value);
    return 1;
}

static void test_one_option(int i)
{
    const gpd_option *op = &T[i];
    char flag[64], letter[4], hi[32], lo[32], both[128];
    snprintf(flag, sizeof flag, "--%s", op->flag);
    snprintf(letter, sizeof letter, "-%c", op->letter);
    good_value(op, 1, hi, sizeof hi);
    good_value(op, 0, lo, sizeof lo);
    gpd_options o;
    clear_env();
    CHECK(PARSE(&o, flag, hi) == GPD_OPTS_RUN && holds(&o, i, hi, GPD_OPT_FROM_FLAG));
    snprintf(both, sizeof both, "%s=%s", flag, lo);
    CHECK(PARSE(&o, both) == GPD_OPTS_RUN && holds(&o, i, lo, GPD_OPT_FROM_FLAG));
    if (op->letter)
        CHECK(PARSE(&o, letter, lo) == GPD_OPTS_RUN && holds(&o, i, lo, GPD_OPT_FROM_FLAG));
    setenv(op->env, lo, 1);
    CHECK(PARSE0(&o) == GPD_OPTS_RUN && holds(&o, i, lo, GPD_OPT_FROM_ENV));
    /* the flag wins over the environment, and the last flag over an earlier one */
    CHECK(PARSE(&o, flag, hi) == GPD_OPTS_RUN && holds(&o, i, hi, GPD_OPT_FROM_FLAG));
    CHECK(PARSE(&o, flag, lo, flag, hi) == GPD_OPTS_RUN && holds(&o, i, hi, GPD_OPT_FROM_FLAG));
    /* the others keep their defaults */
    for (int j = 0; j < GPD_OPT_COUNT; j++)
        if (j != i) CHECK(o.v[j].from == GPD_OPT_FROM_DEFAULT);
    clear_env();
}

static void test_each_option(void)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++)
        if (T[i].kind != GPD_OPT_ACTION && T[i].kind != GPD_OPT_LIST) test_one_option(i);
    /* log levels: the spelling "warning" too */
    gpd_options o;
    CHECK(PARSE(&o, "--log-level", "warning") == GPD_OPTS_RUN);
    CHECK(o.v[GPD_OPT_LOG_LEVEL].n == GPD_LOG_WARN);
}

/* ---- values refused ---- */

/* that value is refused for option i, by flag and by environment, with the message want */
static void refused(int i, const char *value, const char *want)
{
    char flag[64], full[512];
    snprintf(flag, sizeof flag, "--%s", T[i].flag);
    snprintf(full, sizeof full, "grainpackd: %s expects %s, got \"%s\"\n", flag, want, value);
    gpd_options o;
    clear_env();
    CHECK(PARSE(&o, flag, value) == GPD_OPTS_BAD);
    CHECK(strcmp(err_text, full) == 0);
    if (strcmp(err_text, full) != 0) fprintf(stderr, "said: %sexpected: %s", err_text, full);
    setenv(T[i].env, value, 1);
    CHECK(PARSE0(&o) == GPD_OPTS_BAD && strcmp(err_text, full) == 0);
    /* a good flag hides a bad environment */
    char good[32];
    CHECK(PARSE(&o, flag, good_value(&T[i], 1, good, sizeof good)) == GPD_OPTS_RUN);
    clear_env();
}

static void test_int_refused(int i)
{
    char want[96], below[32], above[32];
    snprintf(want, sizeof want, "an integer in [%ld, %ld]", (long)T[i].min, (long)T[i].max);
    snprintf(below, sizeof below, "%ld", (long)T[i].min - 1);
    snprintf(above, sizeof above, "%ld", (long)T[i].max + 1);
    const char *bad[] = {below, above, "abc", "12x", " ", "1.5", "99999999999999999999999"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) refused(i, bad[k], want);
}

static void test_refused(void)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++)
        if (T[i].kind == GPD_OPT_INT) test_int_refused(i);
    const char *days = "a number of days in [0, 36500] (0 = keep forever; 0.5 = 12 hours)";
    const char *bad_days[] = {"-1", "-0.001", "36500.5", "nan", "inf", "1e400", "2d", "x"};
    for (size_t k = 0; k < sizeof bad_days / sizeof bad_days[0]; k++)
        refused(GPD_OPT_RETAIN_DAYS, bad_days[k], days);
    refused(GPD_OPT_LOG_LEVEL, "verbose", "error|warn|info|debug");
    refused(GPD_OPT_LOG_LEVEL, "INFO", "error|warn|info|debug");
    /* the messages, spelled out */
    gpd_options o;
    CHECK(PARSE(&o, "--workers", "0") == GPD_OPTS_BAD);
    CHECK(strcmp(err_text, "grainpackd: --workers expects an integer in [1, 1024], got \"0\"\n")
          == 0);
    CHECK(PARSE(&o, "--max-body", "1023") == GPD_OPTS_BAD);
    CHECK(strstr(err_text, "--max-body expects an integer in [1024, 1073741824]") != NULL);
    setenv("GRAINPACK_JOB_TIMEOUT", "-1", 1);
    CHECK(PARSE0(&o) == GPD_OPTS_BAD);
    CHECK(strstr(err_text, "--job-timeout expects an integer in [0, 31622400], got \"-1\""));
    clear_env();
    /* the ends of each range are allowed */
    CHECK(PARSE(&o, "--job-timeout", "0", "--retain-days", "36500", "--job-threads", "1024")
          == GPD_OPTS_RUN);
}

/* ---- the list option ---- */

static void test_lists(void)
{
    gpd_options o;
    clear_env();
    CHECK(PARSE(&o, "--allow-origin", "http://a:1", "--allow-origin", "http://b,http://c")
          == GPD_OPTS_RUN);
    CHECK(strcmp(lists, "http://a:1|http://b,http://c") == 0);
    CHECK(o.v[GPD_OPT_ALLOW_ORIGIN].from == GPD_OPT_FROM_FLAG);
    setenv("GRAINPACK_ALLOW_ORIGIN", "http://e", 1);
    CHECK(PARSE0(&o) == GPD_OPTS_RUN && strcmp(lists, "http://e") == 0);
    CHECK(o.v[GPD_OPT_ALLOW_ORIGIN].from == GPD_OPT_FROM_ENV);
    /* any flag replaces the environment's list */
    CHECK(PARSE(&o, "--allow-origin", "http://f") == GPD_OPTS_RUN);
    CHECK(strcmp(lists, "http://f") == 0);
    /* refused: by flag at once (before a later --help), by the environment */
    CHECK(PARSE(&o, "--allow-origin", "bad", "--help") == GPD_OPTS_BAD);
    CHECK(strstr(err_text, "--allow-origin") != NULL);
    setenv("GRAINPACK_ALLOW_ORIGIN", "bad", 1);
    CHECK(PARSE0(&o) == GPD_OPTS_BAD && strcmp(lists, "bad") == 0);
    CHECK(PARSE(&o, "--help") == GPD_OPTS_HELP && lists[0] == '\0');
    clear_env();
}

/* ---- actions and a bad command line ---- */

static void test_command_line(void)
{
    gpd_options o;
    clear_env();
    CHECK(PARSE(&o, "--help") == GPD_OPTS_HELP);
    CHECK(PARSE(&o, "-h") == GPD_OPTS_HELP);
    CHECK(PARSE(&o, "--version") == GPD_OPTS_VERSION);
    CHECK(PARSE(&o, "-V") == GPD_OPTS_VERSION);
    CHECK(PARSE(&o, "--help-markdown") == GPD_OPTS_HELP_MARKDOWN);
    /* an action is taken where it is met, before values are checked */
    CHECK(PARSE(&o, "--workers", "0", "--help") == GPD_OPTS_HELP && err_text[0] == '\0');
    CHECK(PARSE(&o, "--version", "--bogus") == GPD_OPTS_VERSION);
    CHECK(PARSE(&o, "--bogus") == GPD_OPTS_USAGE && strstr(err_text, "bogus") != NULL);
    CHECK(PARSE(&o, "-x") == GPD_OPTS_USAGE);
    CHECK(PARSE(&o, "--workers") == GPD_OPTS_USAGE && strstr(err_text, "workers") != NULL);
    CHECK(PARSE(&o, "--help=1") == GPD_OPTS_USAGE);
    CHECK(PARSE(&o, "stray") == GPD_OPTS_USAGE);
    CHECK(strcmp(err_text, "grainpackd: unexpected argument \"stray\"\n") == 0);
    /* a stray argument is said before values are checked */
    CHECK(PARSE(&o, "--workers", "0", "stray") == GPD_OPTS_USAGE);
    CHECK(strstr(err_text, "unexpected argument") != NULL);
}

/* ---- --help and --help-markdown ---- */

/* what print writes, NUL-terminated (free it) */
static char *printed(void (*print)(FILE *))
{
    FILE *f = tmpfile();
    print(f);
    long n = ftell(f);
    char *buf = malloc((size_t)n + 1);
    rewind(f);
    buf[fread(buf, 1, (size_t)n, f)] = '\0';
    fclose(f);
    return buf;
}

/* 1 when s holds word not inside a longer name ("--help" is not in "--help-markdown") */
static int mentions(const char *s, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = strstr(s, word); p; p = strstr(p + 1, word)) {
        unsigned char before = p > s ? (unsigned char)p[-1] : ' ', after = (unsigned char)p[n];
        int name_before = isalnum(before) || before == '-' || before == '_';
        if (!name_before && !isalnum(after) && after != '-' && after != '_') return 1;
    }
    return 0;
}

/* s with each run of white space one space, in place */
static void squash(char *s)
{
    char *w = s;
    for (const char *r = s; *r; r++) {
        int space = isspace((unsigned char)*r);
        if (!space || (w > s && w[-1] != ' ')) *w++ = space ? ' ' : *r;
    }
    *w = '\0';
}

static void test_help(void)
{
    char *h = printed(gpd_options_help);
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        char flag[64];
        snprintf(flag, sizeof flag, "--%s%s%s", T[i].flag, T[i].arg ? " " : "",
                 T[i].arg ? T[i].arg : "");
        CHECK(strstr(h, flag) != NULL);
        if (T[i].env) CHECK(mentions(h, T[i].env));
    }
    CHECK(strstr(h, "--allow-origin ORIGIN") && strstr(h, "-l, --listen HOST:PORT"));
    for (const char *line = h; *line;) {
        size_t n = strcspn(line, "\n");
        CHECK(n <= 80);
        line += n + (line[n] == '\n');
    }
    squash(h);
    CHECK(strstr(h, "[GRAINPACK_WORKERS]; an integer in [1, 1024], default: the number of CPU "
                    "cores") != NULL);
    CHECK(strstr(h, "[GRAINPACK_RETAIN_DAYS]; a number of days in [0, 36500] (0 = keep forever; "
                    "0.5 = 12 hours), default 0: keep every job") != NULL);
    CHECK(strstr(h, "[GRAINPACK_LISTEN]; default 127.0.0.1:8080") != NULL);
    free(h);
}

/* the cells of a Markdown row: its unescaped pipes less one */
static int cells(const char *row, size_t n)
{
    int pipes = 0;
    for (size_t k = 0; k < n; k++) pipes += row[k] == '|' && (k == 0 || row[k - 1] != '\\');
    return pipes - 1;
}

static void test_markdown(void)
{
    char *md = printed(gpd_options_markdown);
    int rows = 0;
    for (const char *line = md; *line;) {
        size_t n = strcspn(line, "\n");
        CHECK(n > 0 && line[0] == '|' && cells(line, n) == 5);
        if (strncmp(line, "| `--", 5) == 0) rows++;
        line += n + (line[n] == '\n');
    }
    CHECK(rows == GPD_OPT_COUNT);
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        char flag[64];
        snprintf(flag, sizeof flag, "| `--%s", T[i].flag);
        CHECK(strstr(md, flag) != NULL);
        if (T[i].env) CHECK(mentions(md, T[i].env));
    }
    CHECK(strstr(md, "`--db PATH\\|URL` (`-d`)") != NULL);
    CHECK(strstr(md, "error\\|warn\\|info\\|debug") != NULL);
    free(md);
}

/* ---- docs/operations.md ---- */

/* the file at rel from this one's directory, NUL-terminated (free it); NULL when unreadable */
static char *slurp(const char *rel)
{
    const char *me = __FILE__, *slash = strrchr(me, '/');
    char path[1024];
    snprintf(path, sizeof path, "%.*s/%s", slash ? (int)(slash - me) : 1, slash ? me : ".", rel);
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n = -1;
    if (f && fseek(f, 0, SEEK_END) == 0) n = ftell(f);
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0) buf = malloc((size_t)n + 1);
    if (buf) buf[fread(buf, 1, (size_t)n, f)] = '\0';
    if (f) fclose(f);
    if (!buf) fprintf(stderr, "cannot read %s\n", path);
    return buf;
}

static void test_docs(void)
{
    char *doc = slurp("../../docs/operations.md");
    CHECK(doc != NULL);
    if (!doc) return;
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        char flag[64];
        snprintf(flag, sizeof flag, "--%s", T[i].flag);
        CHECK(mentions(doc, flag));
        if (!mentions(doc, flag)) fprintf(stderr, "docs/operations.md: no %s\n", flag);
        if (T[i].env && !mentions(doc, T[i].env))
            fprintf(stderr, "docs/operations.md: no %s\n", T[i].env);
        if (T[i].env) CHECK(mentions(doc, T[i].env));
    }
    /* the docs' table is the one the daemon prints, verbatim */
    char *md = printed(gpd_options_markdown);
    CHECK(md && strstr(doc, md) != NULL);
    if (md && !strstr(doc, md))
        fprintf(stderr, "docs/operations.md: its options table is not `grainpackd --help-markdown`\n");
    free(md);
    free(doc);
}

int main(void)
{
    test_table();
    test_defaults();
    test_each_option();
    test_refused();
    test_lists();
    test_command_line();
    test_help();
    test_markdown();
    test_docs();
    return gp_test_summary();
}
