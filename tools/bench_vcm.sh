#!/usr/bin/env bash
# VCM at equal time against our path tracer and BDPT, on the caustic scenes and the Cornell
# box, and VCM's samples/s next to LuxCore BIDIRVMCPU's on the Cornell box, in one run.
#
#   1. Equal-time luminance error (examples/equal_time.rs) on
#      - scenes/caustic-mirror.usda (E-S-D-S-S-L: the caustic seen only in a mirror) and
#        scenes/caustic.usda (L-S-S-D-E: the caustic seen directly), against a long VCM
#        render (no closed form; VCM is the only estimator that converges on the first);
#      - ../shared/peers/cbox.usda (or tests/data/usd/cbox.usda), against a long BDPT render.
#   2. Samples/s of our VCM on the Cornell box (256², 64 spp, depth 64 as LuxCore's benchmark)
#      and of LuxCore BIDIRVMCPU (../shared/peers/luxcore_bench.py, pyluxcore in PEERS_VENV,
#      default ~/peers/venv); without pyluxcore only ours is printed.
#
# Usage: tools/bench_vcm.sh [SECONDS [REFERENCE_SECONDS]]     (default 60 and 900)
# Prints tables; writes nothing in the repository.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
SHARED="$ROOT/../shared"
T="${1:-60}"
TREF="${2:-900}"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml" --example equal_time
cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml"
EQ="$ROOT/target/release/examples/equal_time"
BIN="$ROOT/target/release/spectral-render"
CBOX="$SHARED/peers/cbox.usda"
[ -f "$CBOX" ] || CBOX="$ROOT/tests/data/usd/cbox.usda"

for s in caustic-mirror caustic; do
  echo "== $s.usda (160x120, max depth 10)"
  "$EQ" "$ROOT/scenes/$s.usda" --resolution 160x120 --max-depth 10 --time "$T" \
    --reference-time "$TREF" --reference-integrator vcm --integrators vcm,path,bdpt
done
echo "== cbox.usda (128x128, max depth 7)"
"$EQ" "$CBOX" --resolution 128x128 --max-depth 7 --time "$T" --reference-time "$TREF" \
  --reference-integrator bdpt --integrators bdpt,vcm,path

echo "== samples/s on the Cornell box, 256x256, 64 spp, depth 64"
"$BIN" "$CBOX" -o "$OUT/warm.exr" --integrator vcm --spp 2 --resolution 256x256 2>/dev/null
for i in 1 2 3; do
  "$BIN" "$CBOX" -o "$OUT/vcm.exr" --integrator vcm --spp 64 --resolution 256x256 \
    --max-depth 64 --seed "$i" 2>&1 | grep '^wrote' | sed -E 's/.*spp, ([0-9.]+) s, ([0-9.]+) Msamples.*/ours vcm: \1 s, \2 Msamples\/s/'
done
VENV="${PEERS_VENV:-$HOME/peers/venv}"
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import OpenEXR, pyluxcore" 2>/dev/null; then
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/export_scene.py" >/dev/null 2>&1 || true
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/luxcore_bench.py" --engines BIDIRVMCPU \
    --spp 64 --res 256 --repeats 3 --json "$OUT/luxcore.json"
else
  echo "(pyluxcore not installed in $VENV: see ../shared/peers/README.md; printing ours only)"
fi
