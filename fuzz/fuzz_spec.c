/* fuzz_spec.c -- libFuzzer target for the spec validator and parsers (schema/gp_spec.c).
 *
 * Each input is read as a POST /v1/jobs body (JSON, duplicate keys refused, at most 1 MiB) and
 * run through gp_spec_validate, gp_spec_with_defaults and the parser of its kind, with the
 * contracts of gp_spec.h checked (fuzz_spec_check.h). A broken contract aborts, so libFuzzer
 * saves the input as a crash; ASan and UBSan catch memory errors, leaks and undefined behaviour.
 *
 * Build and run: bench/fuzz_spec.sh (clang, -DGP_FUZZ=ON). Seeds: fuzz/corpus; dictionary:
 * fuzz/spec.dict. Set FUZZ_SPEC_VERBOSE=1 to print each input's verdict (e.g. when running the
 * binary on a few files: ./fuzz_spec fuzz/corpus/ok-2d-circle.json).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_spec_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int verbose = -1;
    if (verbose < 0) verbose = getenv("FUZZ_SPEC_VERBOSE") != NULL;
    gp_fuzz_spec_result res;
    const char *broken = gp_fuzz_spec_one(data, size, &res);
    if (verbose) {
        if (!res.json_ok) fprintf(stderr, "fuzz_spec: not JSON\n");
        else if (res.valid) fprintf(stderr, "fuzz_spec: valid\n");
        else
            fprintf(stderr, "fuzz_spec: %s: %s\n", res.problem.code, res.problem.message);
    }
    if (broken) {
        fprintf(stderr, "fuzz_spec: contract broken: %s\n", broken);
        abort();
    }
    return 0;
}
