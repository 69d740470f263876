#!/bin/sh
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (CMake preset 'asan': clang, ASan + UBSan) and runs them.
#
#   scripts/fuzz.sh SECONDS [TARGET...]   run each target (all by default) for SECONDS, one after
#                                         the other, growing build/asan/corpus/<target>
#   scripts/fuzz.sh --ci [SECONDS]        CI's short pass: every target over its seeds and the
#                                         kept regression inputs, SECONDS in all (60)
#
# Seeds: scripts/fuzz_seeds.sh (real meshes from ../shared/data, generated variants, fuzz/seeds/).
# Crashing, leaking or slow inputs land in build/asan/findings/<target>/; logs in build/asan/logs/.
# Prints one line per target (executions, coverage, findings) and exits 1 when anything was found.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
ALL="fuzz_vtk_legacy fuzz_vtu fuzz_pvtu fuzz_pvd fuzz_native fuzz_colormap_json fuzz_pvcc fuzz_specs fuzz_render fuzz_view_message"
# The VTKHDF target exists where HDF5 does (libhdf5-dev; CMake's UVR_ENABLE_HDF5).
pkg-config --exists hdf5 2>/dev/null && ALL="$ALL fuzz_vtkhdf"
pkg-config --exists netcdf 2>/dev/null && ALL="$ALL fuzz_exodus"
ci=0
if [ "${1:-}" = "--ci" ]; then
  ci=1
  total=${2:-60}
  set -- $ALL
  per=$((total / $#))
else
  per=${1:?usage: scripts/fuzz.sh SECONDS [TARGET...] | scripts/fuzz.sh --ci [SECONDS]}
  shift
  [ $# -gt 0 ] || set -- $ALL
fi

bin=build/asan
# The seeds are written with a uvr binary: the release build's when there is one (CI builds it
# first), else the fuzz build's own.
seeder=build/release/uvr
[ -x $seeder ] || seeder=$bin/uvr
cli=""
[ $seeder = build/release/uvr ] || cli=uvr_cli
if [ -z "${FUZZ_SKIP_BUILD:-}" ]; then  # set when another fuzz.sh has just built
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"${FUZZ_BUILD_JOBS:-2}" --target $cli $ALL >/dev/null
fi
[ -d $bin/seeds ] || scripts/fuzz_seeds.sh $bin/seeds $seeder
mkdir -p $bin/logs

status=0
printf '%-20s %8s %12s %8s %8s %s\n' target seconds executions cov features findings
for t in "$@"; do
  name=${t#fuzz_}
  corpus=$bin/corpus/$name
  findings=$bin/findings/$name
  mkdir -p "$corpus" "$findings"
  inputs="$corpus $bin/seeds/$name"
  [ -d tests/fuzz_regressions/$name ] && inputs="$inputs tests/fuzz_regressions/$name"
  # -rss_limit_mb: a load may use the 256 MiB --max-memory of the targets plus working space.
  # -timeout: 10 s per input is a hang. Leak detection stays on (a leak is a finding). Long runs
  # go on after a finding (fork mode) to collect every one; CI's pass stops at the first.
  keepgoing=""
  # -max_len: long enough for deep nesting (a 200 KB JSON), zlib header bombs and reused blocks
  # (a 330 KB .vtu), many pieces and fields; the render target's input is a few hundred bytes.
  case $name in
    vtk_legacy|vtu|native) maxlen=1048576 ;;
    colormap_json) maxlen=262144 ;;
    pvtu|pvd|pvcc) maxlen=65536 ;;
    specs) maxlen=4096 ;;
    view_message) maxlen=65536 ;;
    *) maxlen=2048 ;;
  esac
  [ $ci -eq 1 ] || keepgoing="-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1"
  set +e
  $bin/fuzz/$t -max_total_time="$per" -max_len=$maxlen -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    $keepgoing -artifact_prefix="$findings/" $inputs >$bin/logs/$name.log 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' $bin/logs/$name.log | tail -1)
  # Fork mode prints no final stats: its last status line "#N: cov: ..." counts executions.
  [ -n "$execs" ] || execs=$(sed -n 's/^#\([0-9]*\):* .*cov: .*/\1/p' $bin/logs/$name.log | tail -1)
  cov=$(grep -o 'cov: [0-9]*' $bin/logs/$name.log | tail -1 | cut -d' ' -f2)
  ft=$(grep -o 'ft: [0-9]*' $bin/logs/$name.log | tail -1 | cut -d' ' -f2)
  found=$(find "$findings" -type f | wc -l)
  printf '%-20s %8s %12s %8s %8s %s\n' "$name" "$per" "${execs:-?}" "${cov:-?}" "${ft:-?}" "$found"
  if [ $rc -ne 0 ] || [ "$found" -ne 0 ]; then
    status=1
    echo "  $t failed (exit $rc): see $bin/logs/$name.log and $findings/" >&2
    grep -m3 -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error|terminate called)' $bin/logs/$name.log \
      >&2 || true
  fi
done
[ $ci -eq 0 ] || [ $status -eq 0 ] || echo "fuzz.sh --ci: findings above" >&2
exit $status
