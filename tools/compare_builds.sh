#!/usr/bin/env bash
# Before/after of a change that must not change answers: the same renders and readings from two
# builds of spectral-render, compared bit for bit (EXR pixel data by examples/exr_diff.rs, meter
# and light-report JSON as values).
#
# Usage: tools/compare_builds.sh OLD_BIN NEW_BIN [OUTDIR]
#   e.g. git worktree add /tmp/old <rev> && cargo build --release --manifest-path /tmp/old/Cargo.toml
#        tools/compare_builds.sh /tmp/old/target/release/spectral-render target/release/spectral-render
# Renders 6 scenes × path, light, bdpt (96×64, 8 spp, seed 3), reads room.usda's meters with each
# integrator and its light report. Prints one line per comparison; exits 1 if any differs.
# RENDER_ARGS (environment) is added to every render, e.g. RENDER_ARGS="--rr-depth 2" to hold
# a default that one of the builds changes; NEW_ARGS to the new build's renders only, for an
# option the old build does not have (NEW_ARGS="--split 1").
set -uo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OLD="$1"; NEW="$2"; OUT="${3:-$(mktemp -d)}"; mkdir -p "$OUT"
S="$ROOT/scenes"
cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml" --example exr_diff
DIFF="$ROOT/target/release/examples/exr_diff"
status=0
same_json() {
  python3 -c 'import json,sys; sys.exit(json.load(open(sys.argv[1])) != json.load(open(sys.argv[2])))' "$1" "$2"
}
verdict() { if "$@"; then echo IDENTICAL; else status=1; echo DIFFERENT; fi; }
for scene in cornell-box materials room prism colorchecker gap; do
  for integ in path light bdpt; do
    for which in old new; do
      bin=$OLD; extra=""; [ $which = new ] && bin=$NEW && extra="${NEW_ARGS:-}"
      "$bin" "$S/$scene.usda" -o "$OUT/${scene}_${integ}_$which.exr" --integrator $integ \
        --spp 8 --resolution 96x64 --seed 3 --threads 2 --max-depth 7 ${RENDER_ARGS:-} $extra >/dev/null 2>&1 \
        || echo "render failed: $which $scene $integ"
    done
    printf '%-13s %-6s ' "$scene" "$integ"
    "$DIFF" "$OUT/${scene}_${integ}_old.exr" "$OUT/${scene}_${integ}_new.exr" || status=1
  done
done
for integ in path light bdpt; do
  for which in old new; do
    bin=$OLD; [ $which = new ] && bin=$NEW
    "$bin" meter "$S/room.usda" --at 2.5,0.75,2 --normal 0,1,0 --at 1,0.75,1 --normal 0,1,0 \
      --spp 4096 --seed 5 --integrator $integ --max-depth 7 --json 2>/dev/null > "$OUT/meter_${integ}_$which.json"
  done
  echo "meter (lux)   $integ  $(verdict same_json "$OUT/meter_${integ}_old.json" "$OUT/meter_${integ}_new.json")"
done
for which in old new; do
  bin=$OLD; [ $which = new ] && bin=$NEW
  "$bin" meter "$S/room.usda" --luminance --at 2.5,1.5,2 --dir 0,-1,0 --spp 4096 --seed 5 \
    --integrator bdpt --max-depth 7 --json 2>/dev/null > "$OUT/lum_$which.json"
  "$bin" lights "$S/room.usda" --json 2>/dev/null > "$OUT/lights_$which.json"
done
echo "meter (cd/m²) bdpt  $(verdict same_json "$OUT/lum_old.json" "$OUT/lum_new.json")"
echo "lights report       $(verdict same_json "$OUT/lights_old.json" "$OUT/lights_new.json")"
exit $status
