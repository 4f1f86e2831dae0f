#!/usr/bin/env bash
# README command 1: install, build, and run the main job on the built-in default input.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/tools/setup.sh"
bash "$root/tools/build.sh" -DMRTILE_BUILD_TESTS=OFF >/dev/null
"$root/build/tools/mrtile" demo -o "$root/out/demo"
