# SPDX-License-Identifier: MIT
# Warnings for the project's own targets, as one INTERFACE target.
add_library(uvr_warnings INTERFACE)
target_compile_options(uvr_warnings INTERFACE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow>
    # GCC 12 reports false -Wrestrict positives inside libstdc++'s std::string (GCC bug 105329).
    $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CXX_COMPILER_ID:GNU>>:-Wno-restrict>)
