#!/bin/sh
# SPDX-License-Identifier: MIT
# The style check: every C++ and CUDA source git tracks in the repository at $1 (default: this
# script's repository) is formatted as its .clang-format says. Prints clang-format's findings and
# exits 1 when a file is not; exits 77 (skipped) without clang-format or outside a git checkout.
# Fix with: git ls-files '*.cpp' '*.cxx' '*.h' '*.cu' '*.cuh' | xargs clang-format-14 -i
set -eu
root=${1:-"$(dirname "$0")/../.."}
cd "$root"
format=$(command -v clang-format-14 || command -v clang-format || true)
if [ -z "$format" ]; then
    echo "check_format: no clang-format-14 or clang-format on PATH (skipped)" >&2
    exit 77
fi
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    echo "check_format: $root is not a git checkout (skipped)" >&2
    exit 77
fi
files=$(git ls-files '*.cpp' '*.cxx' '*.h' '*.cu' '*.cuh')
count=$(printf '%s\n' "$files" | wc -l)
# --dry-run -Werror: a finding is an error naming the file and line; nothing is rewritten.
if printf '%s\n' "$files" | xargs "$format" --dry-run -Werror; then
    echo "check_format: $count files formatted as .clang-format says"
else
    echo "check_format: files above are not formatted; fix with:" >&2
    echo "  git ls-files '*.cpp' '*.cxx' '*.h' '*.cu' '*.cuh' | xargs $(basename "$format") -i" >&2
    exit 1
fi
