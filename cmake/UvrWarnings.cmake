# SPDX-License-Identifier: MIT
# Warnings for the project's own targets, as one INTERFACE target.
add_library(uvr_warnings INTERFACE)
option(UVR_WERROR "Treat the project's warnings as errors (the release and asan presets, which CI builds; CUDA's too)" OFF)
target_compile_options(uvr_warnings INTERFACE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow>
    # The host side of the CUDA sources, through nvcc.
    $<$<COMPILE_LANGUAGE:CUDA>:-Xcompiler=-Wall,-Wextra,-Wshadow>
    $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<BOOL:${UVR_WERROR}>>:-Werror>
    # nvcc's own warnings and the host compiler's.
    "$<$<AND:$<COMPILE_LANGUAGE:CUDA>,$<BOOL:${UVR_WERROR}>>:--Werror=all-warnings;-Xcompiler=-Werror>"
    # GCC 12 reports false -Wrestrict positives inside libstdc++'s std::string (GCC bug 105329).
    $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CXX_COMPILER_ID:GNU>>:-Wno-restrict>)
