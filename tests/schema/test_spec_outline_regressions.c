/* test_spec_outline_regressions.c -- replays the outlines fuzzer's inputs under the normal
 * build: every file of fuzz/regressions/outlines/ (inputs that once broke the outlines reader
 * or their analysis: keep them there) and of its seed corpus fuzz/corpus/outlines/, through
 * the same calls and contract checks as the libFuzzer target (fuzz/fuzz_outlines_check.h).
 * Seeds named ok-* must be valid outlines and bad-* must be refused, so the corpus keeps
 * covering both the reader and the submit check's refusals. */
#include <stdio.h>
#include <string.h>

#include "../../fuzz/fuzz_outlines_check.h"
#include "../../fuzz/fuzz_replay.h"
#include "gp_test.h"

/* one saved input: its contracts, and with check_names the verdict its name promises */
static void replay_one(const char *name, const unsigned char *buf, size_t len, void *user)
{
    int check_names = *(const int *)user;
    gp_fuzz_outlines_result res;
    const char *broken = gp_fuzz_outlines_one(buf, len, &res);
    if (broken) fprintf(stderr, "%s: %s\n", name, broken);
    CHECK(broken == NULL);
    if (check_names && !strncmp(name, "ok-", 3)) {
        if (!res.valid) fprintf(stderr, "%s: expected valid, got: %s\n", name,
                                res.json_ok ? res.problem.message : "not JSON");
        CHECK(res.valid);
    } else if (check_names && !strncmp(name, "bad-", 4)) {
        if (res.valid) fprintf(stderr, "%s: expected a refusal, got valid outlines\n", name);
        CHECK(res.json_ok && !res.valid);
    }
}

int main(void)
{
    CHECK(gp_fuzz_replay_target(__FILE__, "../../fuzz/regressions/outlines", "../../fuzz/corpus/outlines", replay_one) == 0);
    return gp_test_summary();
}
