/* test_trace_regressions.c -- replays the PGM fuzzer's inputs under the normal build: every
 * file of fuzz/regressions/pgm/ (inputs that once broke the PGM reader or the tracer: keep them
 * there) and of its seed corpus fuzz/corpus/pgm/, through the same calls and contract checks
 * as the libFuzzer target (fuzz/fuzz_pgm_check.h). Seeds named ok-* must parse and bad-* must
 * be refused, so the corpus keeps covering both the reader and its refusals. */
#include <stdio.h>
#include <string.h>

#include "../../../fuzz/fuzz_pgm_check.h"
#include "../../../fuzz/fuzz_replay.h"
#include "gp_test.h"

/* one saved input: its contracts, and with check_names the verdict its name promises */
static void replay_one(const char *name, const unsigned char *buf, size_t len, void *user)
{
    int check_names = *(const int *)user;
    gp_fuzz_pgm_result res;
    const char *broken = gp_fuzz_pgm_one(buf, len, &res);
    if (broken) fprintf(stderr, "%s: %s\n", name, broken);
    CHECK(broken == NULL);
    if (check_names && !strncmp(name, "ok-", 3)) {
        if (!res.parsed_ok) fprintf(stderr, "%s: expected an image, got: %s\n", name,
                                    res.error.message);
        CHECK(res.parsed_ok);
    } else if (check_names && !strncmp(name, "bad-", 4)) {
        if (res.parsed_ok) fprintf(stderr, "%s: expected a refusal, got an image\n", name);
        CHECK(!res.parsed_ok);
    }
}

int main(void)
{
    CHECK(gp_fuzz_replay_target(__FILE__, "../../../fuzz/regressions/pgm",
                                "../../../fuzz/corpus/pgm", replay_one) == 0);
    return gp_test_summary();
}
