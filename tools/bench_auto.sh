#!/usr/bin/env bash
# The "Pilot" benchmark of issue 11: `--integrator auto` against every fixed integrator, on the
# stages the issue names, and the figures behind auto's cost model.
#
#   1. Mean luminance error over many seeds (examples/equal_time.rs --seeds, which runs `auto`
#      through the library: its pilot counts in its CPU time) of path, bdpt, vcm and auto at a
#      fixed sample count, one thread, renders in sequence, at the render command's defaults
#      (unlimited depth), against a long reference of the same stage (bdpt; path on the
#      prism, where bdpt's dispersed light subpaths converge slowest): per integrator the mean
#      MSE with its standard error, the mean CPU time, and mean MSE × mean CPU time over the
#      best fixed integrator's with a 95 % interval from the seeds (paired bootstrap). Single
#      renders cannot decide: on scenes/caustic.usda their error swings 2–5× from seed to seed.
#      Auto passes when its ratio is at most 1.1 × (1 + its losing pilots' share of the run).
#   2. Per stage, ns per ray query of each integrator and its ratio to path's
#      (examples/auto_pilot.rs), which `session::auto::cost_per_ray` rounds.
#
#   With METRIC=relmse the figures of part 1 are of pbrt-v4's relMSE over the pixels that do
#   not see an emitter (the `converge` report's measure; `equal_time --metric`), not of the
#   luminance MSE.
#
# Usage: [REFS=DIR] [COST=0] [METRIC=mse|relmse] tools/bench_auto.sh [SEEDS [SPP [REFERENCE_SPP [RESOLUTION [STAGE…]]]]]
#   (defaults 16, 64, 4096, 160x120, the six stages below)
# Prints tables; writes references to a temporary directory, nothing in the repository, or
# with REFS=DIR keeps them in DIR (named STAGE-RES-REFSPP.exr) and reuses them on the next
# run; COST=0 leaves out part 2.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
SEEDS="${1:-16}"
SPP="${2:-64}"
REF_SPP="${3:-4096}"
RES="${4:-160x120}"
shift $(($# < 4 ? $# : 4))
STAGES=("$@")
[ ${#STAGES[@]} -gt 0 ] || STAGES=(scenes/cornell-box.usda tests/data/usd/cbox.usda scenes/gap.usda
  scenes/prism.usda scenes/caustic.usda scenes/caustic-mirror.usda)
cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml" --example equal_time --example auto_pilot
EQ="$ROOT/target/release/examples/equal_time"
PILOT="$ROOT/target/release/examples/auto_pilot"
if [ -n "${REFS:-}" ]; then
  mkdir -p "$REFS"
  TMP="$REFS"
else
  TMP="$(mktemp -d)"
  trap 'rm -rf "$TMP"' EXIT
fi

# On scenes/caustic.usda the lamp's glints through and on the ball (E S+ L, found by hitting
# the lamp in every integrator) carry most of every integrator's error, where the ratio is
# only that of the costs: the figures are also given without them (--exclude), and over the
# caustic, at the two resolutions whose rectangles are known.
declare -A CAUSTIC=(
  [160x120]="--exclude 78,19,83,24 --exclude 77,31,83,36 --exclude 77,46,83,54 --region caustic=62,55,98,76"
  [96x72]="--exclude 47,11,50,15 --exclude 46,18,50,22 --exclude 46,27,50,33 --region caustic=37,33,59,46"
)
for s in "${STAGES[@]}"; do
  ref=bdpt
  [[ "$s" == *prism* ]] && ref=path
  extra=()
  [[ "$s" == */caustic.usda ]] && read -r -a extra <<<"${CAUSTIC[$RES]:-}"
  echo "== $s ($RES, $SPP spp, seeds 1–$SEEDS, reference $ref $REF_SPP spp)"
  "$EQ" "$ROOT/$s" --resolution "$RES" --max-depth unlimited --threads 1 --spp "$SPP" \
    --seeds "$SEEDS" --seed 1 --reference "$TMP/$(basename "$s" .usda)-$RES-$REF_SPP.exr" \
    --reference-spp "$REF_SPP" --reference-integrator "$ref" --integrators path,bdpt,vcm,auto \
    --metric "${METRIC:-mse}" "${extra[@]}"
done
[ "${COST:-1}" = 0 ] && exit 0
echo "== cost per ray query (8 spp at $RES)"
for s in "${STAGES[@]}" scenes/materials.usda scenes/room.usda; do
  "$PILOT" "$ROOT/$s" --spp 8 --resolution "$RES"
done
