#!/bin/sh
# SPDX-License-Identifier: MIT
# Starts `uvr view MESH` on a free port, runs the scripted client against it and stops it.
#   bench/view_latency.sh UVR UVR_VIEW_LATENCY MESH [client flags...] [-- view flags...]
# Prints the client's JSON; exits non-zero when the server or the client fails. VIEW_LOG=FILE
# keeps the server's log there. LAUNCHER="mpirun -n 2 ..." starts the server data-parallel under
# that launcher (rank 0 serves, every rank renders its piece of each frame).
set -eu
uvr=$1 client=$2 mesh=$3
shift 3
client_flags="" view_flags=""
while [ $# -gt 0 ]; do
  [ "$1" = "--" ] && { shift; view_flags="$*"; break; }
  client_flags="$client_flags $1"
  shift
done
log=$(mktemp)
trap 'kill "$pid" 2>/dev/null || true; [ -z "${VIEW_LOG:-}" ] || cp "$log" "$VIEW_LOG"; rm -f "$log"' EXIT
# shellcheck disable=SC2086
${LAUNCHER:-} "$uvr" view "$mesh" --port 0 $view_flags >"$log" 2>&1 &
pid=$!
url=""
for _ in $(seq 1 600); do
  url=$(sed -n 's/^uvr: serving \(http[^ ]*\).*/\1/p' "$log")
  [ -n "$url" ] && break
  kill -0 "$pid" 2>/dev/null || { cat "$log" >&2; exit 1; }
  sleep 0.5
done
[ -n "$url" ] || { echo "uvr view printed no URL" >&2; cat "$log" >&2; exit 1; }
# shellcheck disable=SC2086
"$client" "$url" $client_flags
kill -INT "$pid"
# A launcher ends its ranks with SIGTERM on the interrupt and reports that as a failure.
wait "$pid" || [ -n "${LAUNCHER:-}" ]
