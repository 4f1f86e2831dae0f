#!/usr/bin/env bash
# Builds the benchmark program (Release) and runs it: markdown tables on stdout, progress on stderr.
# Arguments go to the program, e.g. `tools/bench.sh --only paper` or `--max-points 1000000`
# (see `tools/bench.sh --help`). Set MRTILE_BENCH_BUILD_DIR to build somewhere other than build/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${MRTILE_BENCH_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$(nproc)" --target mrtile_bench >&2
exec "$build/tools/bench" "$@"
