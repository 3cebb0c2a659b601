#!/usr/bin/env bash
# The "Pilot" benchmark of issue 11: `--integrator auto` against every fixed integrator at
# equal time, on the stages the issue names, and the figures behind auto's cost model.
#
#   1. Equal-time luminance error (examples/equal_time.rs, which runs `auto` through the
#      library: its pilot counts towards its time) of path, bdpt, vcm and auto on
#      scenes/cornell-box.usda, tests/data/usd/cbox.usda and scenes/gap.usda (against a long
#      BDPT render) and on scenes/prism.usda, scenes/caustic.usda and
#      scenes/caustic-mirror.usda (against a long VCM render: only it converges on SDS paths).
#      Auto passes when its MSE × time is at most (1 + its pilot's share) × 1.1 of the best.
#   2. Per stage, ns per ray query of each integrator and its ratio to path's
#      (examples/auto_pilot.rs), which `session::auto::cost_per_ray` rounds.
#
# Usage: tools/bench_auto.sh [SECONDS [REFERENCE_SECONDS [RESOLUTION]]]   (default 30, 600, 160x120)
# Prints tables; writes nothing in the repository.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
T="${1:-30}"
TREF="${2:-600}"
RES="${3:-160x120}"
cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml" --example equal_time --example auto_pilot
EQ="$ROOT/target/release/examples/equal_time"
PILOT="$ROOT/target/release/examples/auto_pilot"

for s in scenes/cornell-box.usda tests/data/usd/cbox.usda scenes/gap.usda; do
  echo "== $s ($RES)"
  "$EQ" "$ROOT/$s" --resolution "$RES" --time "$T" --reference-time "$TREF" \
    --reference-integrator bdpt --integrators path,bdpt,vcm,auto
done
for s in prism caustic caustic-mirror; do
  echo "== scenes/$s.usda ($RES)"
  "$EQ" "$ROOT/scenes/$s.usda" --resolution "$RES" --time "$T" --reference-time "$TREF" \
    --reference-integrator vcm --integrators path,bdpt,vcm,auto
done
echo "== cost per ray query (8 spp at $RES)"
for s in scenes/cornell-box.usda tests/data/usd/cbox.usda scenes/gap.usda scenes/prism.usda \
  scenes/caustic.usda scenes/caustic-mirror.usda scenes/materials.usda scenes/room.usda; do
  "$PILOT" "$ROOT/$s" --spp 8 --resolution "$RES"
done
