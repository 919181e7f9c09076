#!/usr/bin/env bash
# ptc set-up, build and run.  usage:
#   ./run.sh          install what is missing, build (Release), run the default job
#   ./run.sh test     install what is missing, build, run the whole test suite (ctest)
#   ./run.sh build    install what is missing and build only
# Environment: BUILD_DIR (default build), PTC_SANITIZE=1 (ASan+UBSan build in build-asan),
#              JOBS (parallel build jobs, default: number of cores).
set -euo pipefail
cd "$(dirname "$0")"
mode=${1:-run}

# The one list of dependencies: Debian 12 packages, installed with --no-install-recommends.
PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config git
  libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev libboost-graph-dev libopenmesh-dev
  libvtk9-dev libgtest-dev libgmock-dev libbenchmark-dev libembree-dev libtbb-dev
  libcli11-dev libfmt-dev nlohmann-json3-dev libmeshoptimizer-dev libassimp-dev
  libcgal-demo assimp-testmodels xvfb xauth
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "run.sh: installing ${#missing[@]} Debian packages: ${missing[*]}" >&2
  if [ "$(id -u)" -eq 0 ]; then SUDO=(); elif command -v sudo >/dev/null; then SUDO=(sudo); else
    echo "run.sh: missing packages and not root (no sudo): ${missing[*]}" >&2; exit 1; fi
  export DEBIAN_FRONTEND=noninteractive
  "${SUDO[@]}" apt-get update -qq
  "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

jobs=${JOBS:-$(nproc)}
if [ "${PTC_SANITIZE:-0}" = 1 ]; then
  build=${BUILD_DIR:-build-asan}; extra=(-DPTC_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPTC_BUILD_BENCH=OFF)
else
  build=${BUILD_DIR:-build}; extra=(-DCMAKE_BUILD_TYPE=Release)
fi
cmake -S . -B "$build" -G Ninja "${extra[@]}" >/dev/null
cmake --build "$build" -j "$jobs"

case "$mode" in
  build) ;;
  test)
    ctest --test-dir "$build" --output-on-failure -j "$jobs" ;;
  run)
    mesh="$build/data/meshes/armadillo.off"
    "$build/bin/ptc" info "$mesh"
    "$build/bin/ptc" spheres "$mesh" --out "$build/out/spheres"
    "$build/bin/ptc" cluster "$mesh" --method growth --objective acc --max-count 50 --max-size 50 \
      --out "$build/out/cluster"
    "$build/bin/ptc" trace "$mesh" --clusters "$build/out/cluster" --shadows --out "$build/out/trace"
    "$build/bin/ptc" bench armadillo-twist --frames 0:3 --width 512 --height 512 --out "$build/out/bench" ;;
  *) echo "usage: ./run.sh [run|test|build]" >&2; exit 2 ;;
esac
