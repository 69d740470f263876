# SPDX-License-Identifier: MIT
# Warnings for the project's own targets, as one INTERFACE target.
add_library(uvr_warnings INTERFACE)
target_compile_options(uvr_warnings INTERFACE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow>)
