/* fuzz_pgm.c -- libFuzzer target for the PGM reader and the tracer (core/2d/gp_trace.c): the
 * bytes of the image a POST /v1/shapes/analyze body carries in base64.
 *
 * Each input goes through gp_trace_pgm_header, gp_trace_pgm_parse and, for a small image, the
 * threshold and the tracer, with the contracts of fuzz_pgm_check.h checked. A broken contract
 * aborts, so libFuzzer saves the input as a crash; ASan and UBSan catch memory errors, leaks
 * and undefined behaviour, and bench/fuzz.sh runs it with a malloc limit, so a header that
 * makes the reader allocate for pixels it does not hold is a crash too.
 *
 * Build and run: bench/fuzz.sh pgm (clang, -DGP_FUZZ=ON). Seeds: fuzz/corpus/pgm; dictionary:
 * fuzz/pgm.dict; reproducers: fuzz/regressions/pgm (tests/core/2d/test_trace_regressions.c).
 * Set FUZZ_VERBOSE=1 to print each input's verdict.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_pgm_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int verbose = -1;
    if (verbose < 0) verbose = getenv("FUZZ_VERBOSE") != NULL;
    gp_fuzz_pgm_result res;
    const char *broken = gp_fuzz_pgm_one(data, size, &res);
    if (verbose) {
        if (res.parsed_ok) fprintf(stderr, "fuzz_pgm: %zu x %zu image\n", res.w, res.h);
        else fprintf(stderr, "fuzz_pgm: %s\n", res.error.message);
    }
    if (broken) {
        fprintf(stderr, "fuzz_pgm: contract broken: %s\n", broken);
        abort();
    }
    return 0;
}
