#!/usr/bin/env bash
# Installs what the build and the tests need, and nothing when it is all there (a second run takes
# seconds). Debian 12 packages through apt; the npm validators pinned by tests/npm/package-lock.json.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

debs=(build-essential cmake pkg-config git ca-certificates
      libopenmesh-dev libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
      libdraco-dev draco libtinygltf-dev libmeshoptimizer-dev libnanoflann-dev
      nlohmann-json3-dev libcli11-dev zlib1g-dev libgtest-dev)
command -v node >/dev/null 2>&1 || debs+=(nodejs)
command -v npm >/dev/null 2>&1 || debs+=(npm)

missing=()
for p in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# npm validators (gltf-validator, draco3d, @gltf-transform/cli), only when the lock changed.
npm_dir="$root/tests/npm"
if [ -f "$npm_dir/package-lock.json" ]; then
  stamp="$npm_dir/node_modules/.mrtile-lock"
  if [ ! -f "$stamp" ] || ! cmp -s "$npm_dir/package-lock.json" "$stamp"; then
    echo "setup: installing npm validators" >&2
    (cd "$npm_dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
    cp "$npm_dir/package-lock.json" "$stamp"
  fi
fi
