// SPDX-License-Identifier: MIT
// libFuzzer entry point of the vtkhdf target (body in fuzz_targets.h, shared with the regression
// test; the input is built by fuzz_vtkhdf_input.h).
#include "fuzz_targets.h"
#include "uvr/mesh/io/isolated_probe.h"

// The structure pass runs in this process, not in a probe child: the inputs are written through
// the library itself (they do not crash it), and a sanitizer finding in uvr's own pass would be
// hidden in a child (its report discarded, its death read as a malformed file).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    uvr::ProbeLimits limits = uvr::probeLimits();
    limits.isolate = false;
    uvr::setProbeLimits(limits);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    uvr::fuzz::fuzzVtkHdf(data, size);
    return 0;
}
