#!/usr/bin/env bash
# Runs every libFuzzer target of ptc (fuzz/, docs/fuzzing.md) for SECONDS each, two at a time:
#   scripts/fuzz.sh BUILD_DIR SECONDS [TARGET...]
# BUILD_DIR is a -DPTC_FUZZ=ON build (./run.sh fuzz makes it). Seeds: the generated ones
# (make_fuzz_seeds), the small sample meshes of libcgal-demo, the scene files of scenes/ and every
# regression input of tests/fuzz_inputs/TARGET/. The corpus grows in BUILD_DIR/corpus/TARGET and
# is kept between runs; a finding (crash, sanitizer report, uncaught exception other than
# InputError, hang over 10 s, more than 2 GB) is written to BUILD_DIR/findings/ and makes the
# script exit 1 after every target has run. Limits per input: 10 s, 2048 MB, 64 KiB.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$1 secs=$2; shift 2
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(off obj ply stl md2 md3 scene_json frame_dir triangles_csv)

seeds=$build/seeds
rm -rf "$seeds" && "$build/bin/make_fuzz_seeds" "$seeds" >/dev/null
for f in "$build"/data/meshes/*; do
  [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 16384 ] || continue
  ext=${f##*.}; ext=${ext,,}
  [ -d "$seeds/$ext" ] && cp "$f" "$seeds/$ext/"
done
cp scenes/*.json "$seeds/scene_json/"
mkdir -p "$build/findings"

run_one() {
  local t=$1 extra=()
  [ -d "tests/fuzz_inputs/$t" ] && extra=("tests/fuzz_inputs/$t")
  mkdir -p "$build/corpus/$t"
  # The regression inputs once each, then the timed run from the corpus and the seeds.
  if [ ${#extra[@]} -gt 0 ] && ls "${extra[0]}"/* >/dev/null 2>&1; then
    "$build/bin/fuzz_$t" -rss_limit_mb=2048 -timeout=10 "${extra[0]}"/* >"$build/findings/$t.replay.log" 2>&1 ||
      { echo "fuzz $t: a regression input fails again: $build/findings/$t.replay.log"; return 1; }
  fi
  if "$build/bin/fuzz_$t" -max_total_time="$secs" -rss_limit_mb=2048 -timeout=10 -max_len=65536 \
      -artifact_prefix="$build/findings/$t-" -print_final_stats=1 \
      "$build/corpus/$t" "$seeds/$t" "${extra[@]}" >"$build/findings/$t.log" 2>&1; then
    echo "fuzz $t: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/findings/$t.log" | grep -o '[0-9]*$') inputs in ${secs} s, nothing found (corpus $(ls "$build/corpus/$t" | wc -l) files)"
  else
    echo "fuzz $t: FINDING, see $build/findings/$t.log and $(ls -t "$build/findings/$t"-* 2>/dev/null | head -1)"
    return 1
  fi
}
export -f run_one
export build secs seeds
printf '%s\n' "${targets[@]}" | xargs -P 2 -I{} bash -c 'run_one {}'
