#!/usr/bin/env bash
# ptc set-up, build and run.  usage:
#   ./run.sh          install what is missing, build (Release), run the main job: the paper's
#                     experiment (sweep, compare, drift) on scenes/paper-default.json -> out/
#   ./run.sh full     the same study on the four full-size scenes -> out-full/ (about an hour; README)
#   ./run.sh test     install what is missing, build, run the whole test suite (ctest), then every
#                     fuzz target for a few seconds (PTC_FUZZ_SECONDS, default 3)
#   ./run.sh fuzz [SECONDS]  the libFuzzer targets of every reader, SECONDS each (default 60;
#                     clang build in build-fuzz; docs/fuzzing.md)
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
  libcgal-demo assimp-testmodels xvfb xauth clang libclang-rt-14-dev
  python3-pandas python3-matplotlib python3-nbformat jupyter-nbconvert python3-ipykernel
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

# The key numbers of a study directory (sweep/, compare/, drift/ of ptc experiment), from its CSVs.
key_numbers() {
  local d=$1
  echo
  echo "key numbers ($d, from the CSVs there; sweep and compare: medians over the frames after the first; drift:"
  echo "correlations over the clusters and the last frame's values):"
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    $c["stage"] == "build" { b[$c["max_count"]] = $c["speedup_vs_max_count_0"] }
    $c["stage"] == "trace" { t[$c["max_count"]] = $c["speedup_vs_max_count_0"] }
    $c["stage"] == "total" { o[$c["max_count"]] = $c["speedup_vs_max_count_0"]; n[++k] = $c["max_count"] }
    END { for (i = 1; i <= k; i++) printf "  sweep  MaxCount %4s: build %6.2fx faster, trace %5.2fx, frame %5.2fx than MaxCount 0\n", n[i], b[n[i]], t[n[i]], o[n[i]] }' \
    "$d/sweep/sweep_summary.csv"
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { printf "  compare %-16s frame time %8.2f ms, perf_factor %5.2f (first %5.2f, last %5.2f) against %s\n", $c["config"], $c["total_ms"], $c["perf_factor"], $c["perf_factor_first"], $c["perf_factor_last"], $c["reference"] }' \
    "$d/compare/compare_summary.csv"
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    $c["y"] == "box_area_drift" { printf "  drift  %-16s Spearman(connectivity, box-area drift) %7.3f over %s clusters\n", $c["clustering"], $c["spearman"], $c["clusters"] }' \
    "$d/drift/correlation.csv"
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { last[$c["clustering"]] = $0; if (!($c["clustering"] in seen)) { seen[$c["clustering"]] = 1; order[++k] = $c["clustering"] } }
    END { for (i = 1; i <= k; i++) { split(last[order[i]], f, ","); if (order[i] != "triangles")
      printf "  drift  %-16s last frame: box area ratio p95 %6.3f, max %6.3f; SAH cost %7.2f (triangle BVH %7.2f)\n", order[i], f[c["box_area_ratio_p95"]], f[c["box_area_ratio_max"]], f[c["sah_cost"]], f[c["sah_cost_triangles"]] } }' \
    "$d/drift/frames.csv"
}

# The fuzz build (fuzz/, docs/fuzzing.md): clang with libFuzzer, ASan and UBSan, toolkit/ only.
fuzz_build() {
  cmake -S . -B build-fuzz -G Ninja -DPTC_FUZZ=ON -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
  cmake --build build-fuzz -j "$jobs"
}

case "$mode" in
  build) ;;
  test)
    ctest --test-dir "$build" --output-on-failure -j "$jobs"
    fuzz_build
    scripts/fuzz.sh build-fuzz "${PTC_FUZZ_SECONDS:-3}" ;;
  fuzz)
    fuzz_build
    scripts/fuzz.sh build-fuzz "${2:-60}" ;;
  run)
    # The main job (docs/experiments.md): the paper's experiment on the armadillo of Debian's
    # libcgal-demo, Loop-subdivided once (208k triangles) and twisted more every frame over 61 frames: the
    # clusterings, Figure 6 (sweep), Figure 7 (compare) and the drift of cluster quality, every
    # table under out/ with its manifest; then the key numbers. About five minutes on two cores.
    ptc="$build/bin/ptc"
    scene=${PTC_SCENE:-scenes/paper-default.json}
    rm -rf out.tmp && mkdir -p out.tmp
    run_experiment() {  # KIND [flags]: out.tmp/KIND, moved to out/KIND when all have run
      local kind=$1; shift
      echo "== ptc experiment $kind $scene $*" >&2
      "$ptc" experiment "$kind" "$scene" "$@" --out "out.tmp/$kind"
    }
    run_experiment sweep --width 512 --height 512
    run_experiment compare --width 512 --height 512
    run_experiment drift --width 512 --height 512
    # The pictures: the paper's figures as a notebook (executed headless) and PNG/SVG, and a
    # partition | shaded | heatmap panel of the scene's last frame with the method's clusters of
    # its mesh (the armadillo Loop-subdivided once, as the scene file does).
    echo "== ptc notebook out/{sweep,compare,drift} --execute; ptc viz panel $scene" >&2
    "$ptc" notebook out.tmp/sweep out.tmp/compare out.tmp/drift --execute --out out.tmp/notebooks >/dev/null
    if [ "$scene" = scenes/paper-default.json ]; then
      "$ptc" subdivide "$build/data/meshes/armadillo.off" --levels 1 --scheme loop --out "$build/data/armadillo-loop1.off" >/dev/null
      "$ptc" cluster "$build/data/armadillo-loop1.off" --out out.tmp/clusters >/dev/null
      "$ptc" viz panel "$scene" --clusters out.tmp/clusters --frame 60 --shadows --out out.tmp/panel >/dev/null
    fi
    # Nothing of an earlier out/ is lost: it is replaced only once every step has finished.
    if [ -e out ]; then rm -rf out.old && mv out out.old; fi
    mv out.tmp out && rm -rf out.old
    key_numbers out
    echo
    echo "figures: out/notebooks/paper_figures.ipynb (executed; open with jupyter), out/notebooks/*.png and *.svg"
    echo "         (redraw: /usr/bin/python3 out/notebooks/paper_figures.py)"
    [ -e out/panel/panel.png ] && echo "panel:   out/panel/panel.png (partition | shaded | nodes visited per pixel, frame 60)"
    true ;;
  full)
    # The full-size study: the four animated scenes from real data, as the paper had four (a
    # keyframed one, a skinned one, the cloth, a real mesh under a deformer) at 670k-1.3M
    # triangles, their first 30 frames; into out-full/ (out/ is the main job's).
    ptc="$build/bin/ptc"
    for scene in faerie-670k epileptic-1.3m cloth-sphere-832k armadillo-832k-twist; do
      for kind in sweep compare drift; do
        rays=1024; [ "$kind" = drift ] && rays=512
        echo "== ptc experiment $kind $scene --frames 0:29 --width $rays --height $rays" >&2
        "$ptc" experiment "$kind" "$scene" --frames 0:29 --width "$rays" --height "$rays" --out "out-full/$scene/$kind"
      done
      "$ptc" notebook "out-full/$scene/sweep" "out-full/$scene/compare" "out-full/$scene/drift" --out "out-full/$scene/notebooks" >/dev/null
      key_numbers "out-full/$scene"
      echo "figures: out-full/$scene/notebooks/ (paper_figures.ipynb, *.png, *.svg)"
    done ;;
  *) echo "usage: ./run.sh [run|full|test|fuzz [SECONDS]|build]" >&2; exit 2 ;;
esac
