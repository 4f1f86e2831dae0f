#!/usr/bin/env bash
# README command 2: install, build (warnings as errors) and run the whole test suite.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/tools/setup.sh"
bash "$root/tools/build.sh" -DMRTILE_BUILD_TESTS=ON -DMRTILE_WERROR=ON ${MRTILE_SHARED_DATA:+"-DMRTILE_SHARED_DATA=$MRTILE_SHARED_DATA"}
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" --timeout 900
