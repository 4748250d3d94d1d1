/* fuzz_outlines.c -- libFuzzer target for the reader of JSON grain outlines: shape.outlines of
 * a 2D spec and the outlines of POST /v1/shapes/analyze (schema/kinds/fourier-voronoi-2d/
 * gp_spec2d.c and the schema's bounds), and the outline analysis behind them
 * (core/2d/gp_outline.c).
 *
 * Each input is the JSON array of outlines, run through the calls of fuzz_outlines_check.h
 * with their contracts checked. A broken contract aborts, so libFuzzer saves the input as a
 * crash; ASan and UBSan catch memory errors, leaks and undefined behaviour.
 *
 * Build and run: bench/fuzz.sh outlines (clang, -DGP_FUZZ=ON). Seeds: fuzz/corpus/outlines;
 * dictionary: fuzz/outlines.dict; reproducers: fuzz/regressions/outlines
 * (tests/schema/test_spec_outline_regressions.c). Set FUZZ_VERBOSE=1 to print each input's
 * verdict.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_outlines_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int verbose = -1;
    if (verbose < 0) verbose = getenv("FUZZ_VERBOSE") != NULL;
    gp_fuzz_outlines_result res;
    const char *broken = gp_fuzz_outlines_one(data, size, &res);
    if (verbose) {
        if (!res.json_ok) fprintf(stderr, "fuzz_outlines: not JSON\n");
        else if (res.valid) fprintf(stderr, "fuzz_outlines: %zu outlines\n", res.noutlines);
        else
            fprintf(stderr, "fuzz_outlines: %s at %s: %s\n", res.problem.code,
                    res.problem.pointer, res.problem.message);
    }
    if (broken) {
        fprintf(stderr, "fuzz_outlines: contract broken: %s\n", broken);
        abort();
    }
    return 0;
}
