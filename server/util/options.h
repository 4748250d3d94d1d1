/* options.h -- grainpackd's options in one table: each one's flag (and one-letter alias), its
 * environment variable, default, allowed values and help text. The parse of the command line
 * and the environment, `grainpackd --help` and `grainpackd --help-markdown` (the table of
 * docs/operations.md) all come from it.
 *
 * A setting comes from the command line, else from its environment variable (an empty one
 * counts as unset), else from its default. A bad value is said on stderr under the flag's name
 * ("grainpackd: --workers expects an integer in [1, 1024], got \"0\""), wherever it came from.
 * The parse uses getopt_long (not thread-safe; it resets getopt's state, so that it can run
 * more than once).
 */
#ifndef GPD_OPTIONS_H
#define GPD_OPTIONS_H

#include <stdio.h>

/* The options, in the order of the table (and of --help, of the Markdown table and of the
 * checks: the first bad value is the one said). */
typedef enum gpd_opt_id {
    GPD_OPT_LISTEN,
    GPD_OPT_DB,
    GPD_OPT_LEASE,
    GPD_OPT_DB_CONNECTIONS,
    GPD_OPT_WORKERS,
    GPD_OPT_JOB_THREADS,
    GPD_OPT_LOG_LEVEL,
    GPD_OPT_HTTP_THREADS,
    GPD_OPT_MAX_CONNECTIONS,
    GPD_OPT_MAX_CONNECTIONS_PER_IP,
    GPD_OPT_TIMEOUT,
    GPD_OPT_HEADER_TIMEOUT,
    GPD_OPT_MAX_BODY,
    GPD_OPT_MAX_PENDING,
    GPD_OPT_MAX_RESULT_MB,
    GPD_OPT_JOB_TIMEOUT,
    GPD_OPT_RETAIN_DAYS,
    GPD_OPT_MAX_QUEUED,
    GPD_OPT_ALLOW_ORIGIN,
    GPD_OPT_VERSION,
    GPD_OPT_HELP,
    GPD_OPT_HELP_MARKDOWN,
    GPD_OPT_COUNT
} gpd_opt_id;

/* What an option's value is, which says how it is checked. */
typedef enum gpd_opt_kind {
    GPD_OPT_TEXT,   /* any text (an address, a path or URL), not checked here */
    GPD_OPT_INT,    /* a decimal integer in [min, max] */
    GPD_OPT_REAL,   /* a real number of `unit` in [min, max] */
    GPD_OPT_CHOICE, /* one of `choices`, read by pick() */
    GPD_OPT_LIST,   /* comma-separated and repeatable: each flag's value, else the
                     * environment's, goes to the parse's add_list (any flag replaces the
                     * environment) */
    GPD_OPT_ACTION  /* no value: the parse stops and says which (--help, --version, ...) */
} gpd_opt_kind;

typedef struct gpd_option {
    const char *flag;  /* the long flag without its "--": "listen" */
    char letter;       /* its one-letter alias ('l' for -l), 0 when none */
    const char *arg;   /* the value's name in --help: "HOST:PORT"; NULL for an action */
    const char *env;   /* its environment variable; NULL for an action */
    gpd_opt_kind kind;
    const char *dflt;  /* the default as text; NULL when none or computed by dflt_fn */
    void (*dflt_fn)(char *buf, size_t len); /* a default found at run time (the CPU cores) */
    const char *dflt_note; /* what the default means ("keep every job"), or NULL */
    double min, max;   /* GPD_OPT_INT, GPD_OPT_REAL: the range, both ends allowed */
    const char *unit;  /* GPD_OPT_REAL: "days" */
    const char *choices; /* GPD_OPT_CHOICE: "error|warn|info|debug" */
    int (*pick)(const char *s); /* GPD_OPT_CHOICE: the value's number, -1 when refused */
    const char *range_note; /* said after the range, in errors too, or NULL */
    const char *help;  /* what it does, one paragraph (wrapped by --help) */
} gpd_option;

/* the table, indexed by gpd_opt_id */
extern const gpd_option gpd_options_table[GPD_OPT_COUNT];

/* where a value came from */
typedef enum gpd_opt_from {
    GPD_OPT_FROM_DEFAULT,
    GPD_OPT_FROM_ENV,
    GPD_OPT_FROM_FLAG
} gpd_opt_from;

typedef struct gpd_opt_value {
    const char *text; /* as given (for a list: the last flag's, else the environment's); NULL
                       * for an action, and for a list or option without default left unset */
    long n;           /* GPD_OPT_INT: the value; GPD_OPT_CHOICE: pick()'s */
    double x;         /* GPD_OPT_REAL: the value */
    gpd_opt_from from;
    char buf[24];     /* holds a default made by dflt_fn */
} gpd_opt_value;

typedef struct gpd_options {
    gpd_opt_value v[GPD_OPT_COUNT]; /* indexed by gpd_opt_id */
} gpd_options;

/* What the parse found. GPD_OPTS_RUN: every value good, start. The actions: print what they
 * ask and exit 0. GPD_OPTS_USAGE: an unknown option, a missing value or a stray argument (said
 * on stderr; print the usage on stderr, exit 2). GPD_OPTS_BAD: a value refused (said on
 * stderr, by the parse or by add_list; exit 2). */
typedef enum gpd_opts_rc {
    GPD_OPTS_RUN,
    GPD_OPTS_HELP,
    GPD_OPTS_VERSION,
    GPD_OPTS_HELP_MARKDOWN,
    GPD_OPTS_USAGE,
    GPD_OPTS_BAD
} gpd_opts_rc;

/* Reads argv (the command line) and the environment into *o, in that order of precedence,
 * and checks every value. add_list takes each value of a list option (the --allow-origin
 * list, as it is met on the command line), returning 0, or non-zero having said why it is
 * refused on stderr. An action stops the parse where it is met. */
gpd_opts_rc gpd_options_parse(int argc, char **argv, gpd_options *o,
                              int (*add_list)(const char *list));

/* The CPU cores online, at least 1 (the default of --workers). */
long gpd_options_cpus(void);

/* The options part of --help: one entry per option, wrapped to 80 columns. */
void gpd_options_help(FILE *f);
/* The table as a Markdown table (flag, environment variable, default, allowed values, what it
 * does), for docs/operations.md: `grainpackd --help-markdown`. */
void gpd_options_markdown(FILE *f);

#endif /* GPD_OPTIONS_H */
