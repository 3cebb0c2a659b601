#!/usr/bin/env bash
# Equal-time image error of path tracing vs BDPT against a long BDPT reference (RMSE of
# luminance, reference noise subtracted), by default on scenes/gap.usda, the room lit through
# the gap of an ajar door. Arguments are passed on to examples/equal_time.rs, e.g.
#
#   tools/equal_time.sh                                   # gap scene, 160x120, 30 s each, 10 min reference
#   tools/equal_time.sh scenes/gap.usda --time 60 --reference /tmp/gap_ref.exr
#
# Prints a table; writes nothing in the repository.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
if [ $# -eq 0 ] || [[ "$1" == -* ]]; then
  set -- "$ROOT/scenes/gap.usda" --resolution 160x120 "$@"
fi
cargo run --release --quiet --manifest-path "$ROOT/Cargo.toml" --example equal_time -- "$@"
