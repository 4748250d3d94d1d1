/* test_spec_regressions.c -- replays the spec fuzzer's inputs under the normal build: every file
 * of fuzz/regressions/ (inputs that once broke the validator or a parser: keep them there) and
 * of the seed corpus fuzz/corpus/, through the same calls and contract checks as the libFuzzer
 * target (fuzz/fuzz_spec_check.h). Seeds named ok-*.json must be valid specs and bad-*.json
 * must be refused, so the corpus keeps covering both the parsers and the semantic checks. The
 * other targets' folders (fuzz/corpus/pgm, fuzz/regressions/outlines, ...) have their own
 * ctests. */
#include <stdio.h>
#include <string.h>

#include "../../fuzz/fuzz_replay.h"
#include "../../fuzz/fuzz_spec_check.h"
#include "gp_test.h"

/* one saved input: its contracts, and with check_names the verdict its name promises */
static void replay_one(const char *name, const unsigned char *buf, size_t len, void *user)
{
    int check_names = *(const int *)user;
    gp_fuzz_spec_result res;
    const char *broken = gp_fuzz_spec_one(buf, len, &res);
    if (broken) fprintf(stderr, "%s: %s\n", name, broken);
    CHECK(broken == NULL);
    if (check_names && !strncmp(name, "ok-", 3)) {
        if (!res.valid) fprintf(stderr, "%s: expected valid, got: %s\n", name,
                                res.json_ok ? res.problem.message : "not JSON");
        CHECK(res.valid);
    } else if (check_names && !strncmp(name, "bad-", 4)) {
        if (res.valid) fprintf(stderr, "%s: expected a refusal, got a valid spec\n", name);
        CHECK(res.json_ok && !res.valid);
    }
}

int main(void)
{
    CHECK(gp_fuzz_replay_target(__FILE__, "../../fuzz/regressions", "../../fuzz/corpus", replay_one) == 0);
    return gp_test_summary();
}
