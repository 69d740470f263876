// SPDX-License-Identifier: MIT
// libFuzzer entry point of the pvd target (body in fuzz_targets.h, shared with the regression
// test).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    uvr::fuzz::fuzzPvd(data, size);
    return 0;
}
