// SPDX-License-Identifier: MIT
// libFuzzer entry point of the vtkhdf target (body in fuzz_targets.h, shared with the regression
// test; the input is built by fuzz_vtkhdf_input.h).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    uvr::fuzz::fuzzVtkHdf(data, size);
    return 0;
}
