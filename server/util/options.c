/* options.c -- grainpackd's table of options, its parse, --help and the Markdown table (see
 * options.h). */
#include "util/options.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util/util.h"

static void default_cpus(char *buf, size_t len)
{
    snprintf(buf, len, "%ld", gpd_options_cpus());
}

/* One row per option; the fields a row leaves out are 0 / NULL. */
const gpd_option gpd_options_table[GPD_OPT_COUNT] = {
    [GPD_OPT_LISTEN] = {.flag = "listen", .letter = 'l', .arg = "HOST:PORT",
                        .env = "GRAINPACK_LISTEN", .kind = GPD_OPT_TEXT,
                        .dflt = "127.0.0.1:8080",
                        .help = "address to listen on (port 0 = pick a free port; the first "
                                "stdout line is 'listening on http://HOST:PORT')"},
    [GPD_OPT_DB] = {.flag = "db", .letter = 'd', .arg = "PATH|URL", .env = "GRAINPACK_DB",
                    .kind = GPD_OPT_TEXT, .dflt = "./grainpack.db",
                    .help = "the job database: a file path is SQLite (one daemon per file); a "
                            "URL postgresql://user@host:port/dbname is PostgreSQL, where many "
                            "daemons (on any hosts) share one queue"},
    [GPD_OPT_LEASE] = {.flag = "lease", .arg = "S", .env = "GRAINPACK_LEASE",
                       .kind = GPD_OPT_INT, .dflt = "30", .min = 1, .max = 86400,
                       .help = "PostgreSQL: seconds a running job stays claimed without its "
                               "daemon renewing it (every S/3 s); a job whose lease lapsed is "
                               "taken over by another daemon"},
    [GPD_OPT_DB_CONNECTIONS] = {.flag = "db-connections", .arg = "N",
                                .env = "GRAINPACK_DB_CONNECTIONS", .kind = GPD_OPT_INT,
                                .dflt = "32", .min = 1, .max = 100000,
                                .help = "PostgreSQL: the most database connections this daemon "
                                        "holds at once: one for each of its threads that uses "
                                        "the database, the rest for downloads in progress (one "
                                        "each); a download beyond it gets 503 busy with "
                                        "Retry-After. The daemons on one server share its "
                                        "max_connections"},
    [GPD_OPT_WORKERS] = {.flag = "workers", .letter = 'w', .arg = "N",
                         .env = "GRAINPACK_WORKERS", .kind = GPD_OPT_INT,
                         .dflt_fn = default_cpus, .dflt_note = "the number of CPU cores",
                         .min = 1, .max = 1024, .help = "worker threads running jobs"},
    [GPD_OPT_JOB_THREADS] = {.flag = "job-threads", .arg = "N", .env = "GRAINPACK_JOB_THREADS",
                             .kind = GPD_OPT_INT, .dflt = "0",
                             .dflt_note = "the CPU cores over the workers, at least 1",
                             .min = 0, .max = 1024,
                             .help = "threads each job runs on (the IMC, filling, ODEC and "
                                     "descriptors of a 2D job, the DEM of a 3D one; results "
                                     "are the same whatever N)"},
    [GPD_OPT_LOG_LEVEL] = {.flag = "log-level", .letter = 'L', .arg = "LEVEL",
                           .env = "GRAINPACK_LOG_LEVEL", .kind = GPD_OPT_CHOICE,
                           .dflt = "info", .choices = "error|warn|info|debug",
                           .pick = gpd_log_parse_level,
                           .help = "what is logged on stderr; debug logs every request"},
    [GPD_OPT_HTTP_THREADS] = {.flag = "http-threads", .letter = 't', .arg = "N",
                              .env = "GRAINPACK_HTTP_THREADS", .kind = GPD_OPT_INT,
                              .dflt = "4", .min = 1, .max = 256,
                              .help = "HTTP thread pool size"},
    [GPD_OPT_MAX_CONNECTIONS] = {.flag = "max-connections", .letter = 'c', .arg = "N",
                                 .env = "GRAINPACK_MAX_CONNECTIONS", .kind = GPD_OPT_INT,
                                 .dflt = "1024", .min = 1, .max = 1000000,
                                 .help = "concurrent connection limit (lowered at start-up to "
                                         "what the open-file limit leaves after a reserve "
                                         "for the database and files)"},
    [GPD_OPT_MAX_CONNECTIONS_PER_IP] = {.flag = "max-connections-per-ip", .arg = "N",
                                        .env = "GRAINPACK_MAX_CONNECTIONS_PER_IP",
                                        .kind = GPD_OPT_INT, .dflt = "256", .min = 0,
                                        .max = 1000000,
                                        .help = "connections one client address may hold at "
                                                "once (0 = no limit); more are closed as they "
                                                "come. Behind a reverse proxy every client has "
                                                "the proxy's address: raise it, or 0"},
    [GPD_OPT_TIMEOUT] = {.flag = "timeout", .letter = 'T', .arg = "S",
                         .env = "GRAINPACK_TIMEOUT", .kind = GPD_OPT_INT, .dflt = "30",
                         .min = 1, .max = 86400,
                         .help = "idle timeout per connection, seconds"},
    [GPD_OPT_HEADER_TIMEOUT] = {.flag = "header-timeout", .arg = "S",
                                .env = "GRAINPACK_HEADER_TIMEOUT", .kind = GPD_OPT_INT,
                                .dflt = "10", .min = 1, .max = 86400,
                                .help = "seconds a request's line and headers may take from "
                                        "the connection's start (a further request on a "
                                        "kept-alive connection: from the previous answer, at "
                                        "least --timeout); a slower connection is closed"},
    [GPD_OPT_MAX_BODY] = {.flag = "max-body", .letter = 'b', .arg = "BYTES",
                          .env = "GRAINPACK_MAX_BODY", .kind = GPD_OPT_INT,
                          .dflt = "134217728", .min = 1024, .max = 1L << 30,
                          .help = "body limit of POST /v1/jobs and POST /v1/shapes/analyze "
                                  "(the default takes 10,000 outlines of 200 points), 413 "
                                  "above; other requests take no body (64 KiB at most)"},
    [GPD_OPT_MAX_PENDING] = {.flag = "max-pending", .arg = "N", .env = "GRAINPACK_MAX_PENDING",
                             .kind = GPD_OPT_INT, .dflt = "16", .min = 1, .max = 100000,
                             .help = "bodies waiting to be checked, per lane (submits; shape "
                                     "analyses, which never hold submits up): one more gets "
                                     "503 busy with Retry-After"},
    [GPD_OPT_MAX_RESULT_MB] = {.flag = "max-result-mb", .letter = 'R', .arg = "MB",
                               .env = "GRAINPACK_MAX_RESULT_MB", .kind = GPD_OPT_INT,
                               .dflt = "8192", .min = 1, .max = 1L << 20,
                               .help = "refuse (422 too_large) a spec whose result would be "
                                       "larger, which bounds the disk one job takes"},
    [GPD_OPT_JOB_TIMEOUT] = {.flag = "job-timeout", .letter = 'J', .arg = "S",
                             .env = "GRAINPACK_JOB_TIMEOUT", .kind = GPD_OPT_INT,
                             .dflt = "3600", .min = 0, .max = 31622400,
                             .help = "a job whose run lasts longer fails with error code "
                                     "'timeout' (per run attempt; 0 = no limit)"},
    [GPD_OPT_RETAIN_DAYS] = {.flag = "retain-days", .arg = "N", .env = "GRAINPACK_RETAIN_DAYS",
                             .kind = GPD_OPT_REAL, .dflt = "0", .dflt_note = "keep every job",
                             .min = 0, .max = 36500, .unit = "days",
                             .range_note = "0 = keep forever; 0.5 = 12 hours",
                             .help = "purge finished jobs (their results and exports) N days "
                                     "after they finished; a real number; checked at "
                                     "start-up and every minute"},
    [GPD_OPT_MAX_QUEUED] = {.flag = "max-queued", .arg = "N", .env = "GRAINPACK_MAX_QUEUED",
                            .kind = GPD_OPT_INT, .dflt = "10000", .min = 1, .max = 1000000000,
                            .help = "a submit while N jobs are queued gets 503 queue_full with "
                                    "Retry-After"},
    [GPD_OPT_ALLOW_ORIGIN] = {.flag = "allow-origin", .arg = "ORIGIN",
                              .env = "GRAINPACK_ALLOW_ORIGIN", .kind = GPD_OPT_LIST,
                              .dflt_note = "none (only the daemon's own pages)",
                              .help = "also serve pages at ORIGIN (scheme://host[:port], e.g. "
                                      "a lab dashboard served elsewhere); repeatable or "
                                      "comma-separated, and any flag replaces the "
                                      "environment's list. Any other Origin, and a Host naming "
                                      "another server, get 403 (see README)"},
    [GPD_OPT_VERSION] = {.flag = "version", .letter = 'V', .kind = GPD_OPT_ACTION,
                         .help = "print the version and exit"},
    [GPD_OPT_HELP] = {.flag = "help", .letter = 'h', .kind = GPD_OPT_ACTION,
                      .help = "print this help and exit"},
    [GPD_OPT_HELP_MARKDOWN] = {.flag = "help-markdown", .kind = GPD_OPT_ACTION,
                               .help = "print this table of options in Markdown (as in "
                                       "docs/operations.md) and exit"},
};

long gpd_options_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n;
}

/* ---- the parse ---- */

/* getopt_long's value for option i given by its long flag (above any letter) */
#define LONG_VAL(i) (1000 + (int)(i))

/* the option getopt_long returned ch for; -1 when none (an unknown one, a missing value) */
static int option_of(int ch)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++)
        if (ch == LONG_VAL(i) || (gpd_options_table[i].letter && ch == gpd_options_table[i].letter))
            return i;
    return -1;
}

/* getopt_long's long options and short option string, from the table */
static void getopt_tables(struct option *lo, char *so)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        const gpd_option *o = &gpd_options_table[i];
        int has_arg = o->kind == GPD_OPT_ACTION ? no_argument : required_argument;
        lo[i] = (struct option){o->flag, has_arg, NULL, LONG_VAL(i)};
        if (!o->letter) continue;
        *so++ = o->letter;
        if (has_arg) *so++ = ':';
    }
    lo[GPD_OPT_COUNT] = (struct option){0, 0, 0, 0};
    *so = '\0';
}

static gpd_opts_rc action_rc(int i)
{
    if (i == GPD_OPT_VERSION) return GPD_OPTS_VERSION;
    if (i == GPD_OPT_HELP_MARKDOWN) return GPD_OPTS_HELP_MARKDOWN;
    return GPD_OPTS_HELP;
}

/* One option met on the command line, with its value; GPD_OPTS_RUN to go on. */
static gpd_opts_rc take_flag(int i, const char *value, gpd_options *o,
                             int (*add_list)(const char *))
{
    const gpd_option *op = &gpd_options_table[i];
    if (op->kind == GPD_OPT_ACTION) return action_rc(i);
    if (op->kind == GPD_OPT_LIST && add_list && add_list(value)) return GPD_OPTS_BAD;
    o->v[i].text = value;
    o->v[i].from = GPD_OPT_FROM_FLAG;
    return GPD_OPTS_RUN;
}

/* The command line up to its end or an action; GPD_OPTS_RUN when every option is known. */
static gpd_opts_rc read_flags(int argc, char **argv, gpd_options *o,
                              int (*add_list)(const char *))
{
    struct option lo[GPD_OPT_COUNT + 1];
    char so[2 * GPD_OPT_COUNT + 1];
    getopt_tables(lo, so);
    optind = 0; /* glibc: start again from argv[1], whatever an earlier parse left */
    int ch;
    while ((ch = getopt_long(argc, argv, so, lo, NULL)) != -1) {
        int i = option_of(ch);
        if (i < 0) return GPD_OPTS_USAGE; /* getopt_long said why */
        gpd_opts_rc rc = take_flag(i, optarg, o, add_list);
        if (rc != GPD_OPTS_RUN) return rc;
    }
    return GPD_OPTS_RUN;
}

/* The value of an option the command line left unset: its environment variable (when not
 * empty), else its default. */
static void fill_unset(int i, gpd_opt_value *v)
{
    const gpd_option *op = &gpd_options_table[i];
    const char *env = op->env ? getenv(op->env) : NULL;
    if (v->from == GPD_OPT_FROM_FLAG || op->kind == GPD_OPT_ACTION) return;
    if (env && *env) {
        v->text = env;
        v->from = GPD_OPT_FROM_ENV;
    } else if (op->dflt_fn) {
        op->dflt_fn(v->buf, sizeof v->buf);
        v->text = v->buf;
    } else {
        v->text = op->dflt;
    }
}

/* "an integer in [1, 1024]": what option op takes, as errors, --help and Markdown say it;
 * "" for text, lists and actions */
static void expectation(const gpd_option *op, char *buf, size_t len)
{
    int n = 0;
    if (op->kind == GPD_OPT_INT)
        n = snprintf(buf, len, "an integer in [%ld, %ld]", (long)op->min, (long)op->max);
    else if (op->kind == GPD_OPT_REAL)
        n = snprintf(buf, len, "a number of %s in [%g, %g]", op->unit, op->min, op->max);
    else if (op->kind == GPD_OPT_CHOICE)
        n = snprintf(buf, len, "%s", op->choices);
    else
        buf[0] = '\0';
    if (op->range_note && n > 0 && (size_t)n < len)
        snprintf(buf + n, len - (size_t)n, " (%s)", op->range_note);
}

static int read_int(const gpd_option *op, const char *s, gpd_opt_value *v)
{
    char *end = NULL;
    errno = 0;
    long x = strtol(s, &end, 10);
    if (errno || !end || *end || end == s || x < (long)op->min || x > (long)op->max) return -1;
    v->n = x;
    return 0;
}

static int read_real(const gpd_option *op, const char *s, gpd_opt_value *v)
{
    char *end = NULL;
    errno = 0;
    double x = strtod(s, &end);
    if (errno || !end || *end || end == s || !isfinite(x) || x < op->min || x > op->max)
        return -1;
    v->x = x;
    return 0;
}

/* Reads option i's text into its number; 0, or -1 said on stderr. */
static int check(int i, gpd_opt_value *v)
{
    const gpd_option *op = &gpd_options_table[i];
    int rc = 0;
    if (op->kind == GPD_OPT_INT) rc = read_int(op, v->text, v);
    if (op->kind == GPD_OPT_REAL) rc = read_real(op, v->text, v);
    if (op->kind == GPD_OPT_CHOICE) rc = (v->n = op->pick(v->text)) < 0 ? -1 : 0;
    if (rc == 0) return 0;
    char want[160];
    expectation(op, want, sizeof want);
    fprintf(stderr, "grainpackd: --%s expects %s, got \"%s\"\n", op->flag, want, v->text);
    return -1;
}

/* The lists no flag gave: the environment's value to add_list; 0, or -1 (refused). */
static int env_lists(gpd_options *o, int (*add_list)(const char *))
{
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        if (gpd_options_table[i].kind != GPD_OPT_LIST) continue;
        fill_unset(i, &o->v[i]);
        if (o->v[i].from == GPD_OPT_FROM_ENV && add_list && add_list(o->v[i].text)) return -1;
    }
    return 0;
}

/* The values but the lists': each filled in and checked, in the table's order; 0, or -1 at
 * the first bad one (said on stderr). */
static int check_values(gpd_options *o)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        if (gpd_options_table[i].kind == GPD_OPT_LIST) continue;
        fill_unset(i, &o->v[i]);
        if (o->v[i].text && check(i, &o->v[i])) return -1;
    }
    return 0;
}

gpd_opts_rc gpd_options_parse(int argc, char **argv, gpd_options *o,
                              int (*add_list)(const char *list))
{
    memset(o, 0, sizeof *o);
    gpd_opts_rc rc = read_flags(argc, argv, o, add_list);
    if (rc != GPD_OPTS_RUN) return rc;
    if (env_lists(o, add_list)) return GPD_OPTS_BAD;
    if (optind < argc) {
        fprintf(stderr, "grainpackd: unexpected argument \"%s\"\n", argv[optind]);
        return GPD_OPTS_USAGE;
    }
    return check_values(o) ? GPD_OPTS_BAD : GPD_OPTS_RUN;
}

/* ---- --help ---- */

#define HELP_COL 30   /* where the descriptions start */
#define HELP_WIDTH 79 /* the last column used */

/* "--listen HOST:PORT" */
static void flag_text(const gpd_option *op, char *buf, size_t len)
{
    snprintf(buf, len, "--%s%s%s", op->flag, op->arg ? " " : "", op->arg ? op->arg : "");
}

/* "default 0: keep every job", "default: the number of CPU cores", "default 30"; "" when the
 * option has none. code puts the value in Markdown backquotes. */
static void default_text(const gpd_option *op, int code, char *buf, size_t len)
{
    const char *q = code ? "`" : "", *note = op->dflt_note;
    if (op->dflt)
        snprintf(buf, len, "%s%s%s%s%s", q, op->dflt, q, note ? ": " : "", note ? note : "");
    else
        snprintf(buf, len, "%s", note ? note : "");
}

/* Appends to buf (len bytes, n used; n grows past len when cut) like snprintf. */
#define APPEND(buf, len, n, ...) \
    ((n) += snprintf((buf) + ((n) < (len) ? (n) : (len)), (n) < (len) ? (len) - (n) : 0, \
                     __VA_ARGS__))

/* the description --help gives: the help text, [ENV], what it takes and its default */
static void help_text(const gpd_option *op, char *buf, size_t len)
{
    char want[160], dflt[160];
    expectation(op, want, sizeof want);
    default_text(op, 0, dflt, sizeof dflt);
    size_t n = 0;
    APPEND(buf, len, n, "%s", op->help);
    if (op->env) APPEND(buf, len, n, " [%s]", op->env);
    if (*want) APPEND(buf, len, n, "; %s", want);
    if (*dflt)
        APPEND(buf, len, n, "%sdefault%s%s", *want ? ", " : "; ", op->dflt ? " " : ": ", dflt);
}

/* the length of the word text starts with: up to a space, but a range "[1, 1024]" is one */
static size_t word_len(const char *text)
{
    size_t w = 0;
    for (int in_range = 0; text[w] && (text[w] != ' ' || in_range); w++)
        in_range = text[w] == '[' ? 1 : text[w] == ']' ? 0 : in_range;
    return w;
}

/* Writes text from column col, wrapping words at HELP_WIDTH to lines indented HELP_COL. */
static void wrap(FILE *f, const char *text, int col)
{
    while (*text) {
        size_t w = word_len(text);
        if (col > HELP_COL && col + 1 + (int)w > HELP_WIDTH) {
            fprintf(f, "\n%*s", HELP_COL, "");
            col = HELP_COL;
        } else if (col > HELP_COL) {
            fputc(' ', f);
            col++;
        }
        fprintf(f, "%.*s", (int)w, text);
        col += (int)w;
        text += w;
        text += strspn(text, " ");
    }
    fputc('\n', f);
}

void gpd_options_help(FILE *f)
{
    for (int i = 0; i < GPD_OPT_COUNT; i++) {
        const gpd_option *op = &gpd_options_table[i];
        char flag[64], text[1024];
        flag_text(op, flag, sizeof flag);
        int col = op->letter ? fprintf(f, "  -%c, %s", op->letter, flag)
                             : fprintf(f, "      %s", flag);
        if (col >= HELP_COL - 1) {
            fputc('\n', f);
            col = 0;
        }
        fprintf(f, "%*s", HELP_COL - col, "");
        help_text(op, text, sizeof text);
        wrap(f, text, HELP_COL);
    }
}

/* ---- the Markdown table ---- */

/* one cell: s with its pipes escaped (GitHub's tables split on them, even in code) */
static void md_cell(FILE *f, const char *s)
{
    fputs(" ", f);
    for (; *s; s++) {
        if (*s == '|') fputc('\\', f);
        fputc(*s, f);
    }
    fputs(" |", f);
}

/* "`--listen HOST:PORT` (`-l`)" */
static void md_flag(const gpd_option *op, char *buf, size_t len)
{
    char flag[64];
    flag_text(op, flag, sizeof flag);
    if (op->letter)
        snprintf(buf, len, "`%s` (`-%c`)", flag, op->letter);
    else
        snprintf(buf, len, "`%s`", flag);
}

static void md_row(FILE *f, const gpd_option *op)
{
    char flag[96], env[64], dflt[160], want[160];
    md_flag(op, flag, sizeof flag);
    env[0] = '\0';
    if (op->env) snprintf(env, sizeof env, "`%s`", op->env);
    default_text(op, 1, dflt, sizeof dflt);
    expectation(op, want, sizeof want);
    fputs("|", f);
    md_cell(f, flag);
    md_cell(f, env);
    md_cell(f, dflt);
    md_cell(f, want);
    md_cell(f, op->help);
    fputs("\n", f);
}

void gpd_options_markdown(FILE *f)
{
    fputs("| flag | environment | default | allowed values | what it does |\n"
          "|---|---|---|---|---|\n",
          f);
    for (int i = 0; i < GPD_OPT_COUNT; i++) md_row(f, &gpd_options_table[i]);
}
