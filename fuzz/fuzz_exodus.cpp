// SPDX-License-Identifier: MIT
// libFuzzer entry point of the structured Exodus II target (body in fuzz_targets.h, shared with
// the regression test).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    uvr::fuzz::fuzzExodus(data, size);
    return 0;
}
