#!/usr/bin/env bash
# VCM at equal time against our path tracer and BDPT, on the caustic scenes and the Cornell
# box, and VCM's samples/s next to LuxCore BIDIRVMCPU's on the Cornell box, in one run.
#
#   1. Equal-time luminance error (examples/equal_time.rs) on
#      - scenes/caustic-mirror.usda (E-S-D-S-S-L: the caustic seen only in a mirror) and
#        scenes/caustic.usda (L-S-S-D-E: the caustic seen directly), against a long VCM
#        render (no closed form; VCM is the only estimator that converges on the first);
#      - ../shared/peers/cbox.usda (or tests/data/usd/cbox.usda), against a long BDPT render.
#      On the caustic scenes the figures are also given without the lamp's glints (the lamp
#      seen in or through the ball: 2-10 pixels that carry over 99 % of every integrator's
#      error, where all of them use the one technique that samples a light seen through
#      specular surfaces, the camera path hitting it, so their ratio there is the ratio of the
#      costs), and over the caustic and the floor (rectangles at 160x120). Compare the
#      CPU-normalised ratios on a loaded machine.
#   2. Samples/s of our VCM on the Cornell box (256², 64 spp, depth 64 as LuxCore's benchmark)
#      and of LuxCore BIDIRVMCPU (../shared/peers/luxcore_bench.py, pyluxcore in PEERS_VENV,
#      default ~/peers/venv); without pyluxcore only ours is printed.
#
# Usage: tools/bench_vcm.sh [SECONDS [REFERENCE_SECONDS]]     (default 60 and 900)
# REF_DIR=DIR keeps the references there (DIR/NAME.exr and .noise.exr) and reuses them; delete
# them when a scene changes. Prints tables; writes nothing in the repository.
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

ref() { [ -n "${REF_DIR:-}" ] && echo --reference "$REF_DIR/$1.exr"; }
# The lamp's glints (excluded) and the caustic and floor regions, in pixels at 160x120.
declare -A REGIONS=(
  [caustic-mirror]="--exclude 77,29,83,34 --region caustic=63,55,96,76 --region floor=41,49,120,98"
  [caustic]="--exclude 78,19,83,24 --exclude 77,31,83,36 --exclude 77,46,83,54 --region caustic=62,55,98,76"
)
for s in caustic-mirror caustic; do
  echo "== $s.usda (160x120, max depth 10)"
  # shellcheck disable=SC2046,SC2086
  "$EQ" "$ROOT/scenes/$s.usda" --resolution 160x120 --max-depth 10 --time "$T" \
    --reference-time "$TREF" --reference-integrator vcm --integrators vcm,path,bdpt \
    $(ref "$s") ${REGIONS[$s]}
done
echo "== cbox.usda (128x128, max depth 7)"
# Also without the light's pixels (7x24 at 128x128), whose variance is the emission's
# spectral noise (three quarters of the image's summed variance), found by the camera ray in
# every integrator.
# shellcheck disable=SC2046
"$EQ" "$CBOX" --resolution 128x128 --max-depth 7 --time "$T" --reference-time "$TREF" \
  --reference-integrator bdpt --integrators bdpt,vcm,path --exclude 52,15,76,22 $(ref cbox)

echo "== samples/s on the Cornell box, 256x256, 64 spp, depth 64"
"$BIN" "$CBOX" -o "$OUT/warm.exr" --integrator vcm --spp 2 --resolution 256x256 2>/dev/null
for i in 1 2 3; do
  "$BIN" "$CBOX" -o "$OUT/vcm.exr" --integrator vcm --spp 64 --resolution 256x256 \
    --max-depth 64 --seed "$i" 2>&1 | grep '^wrote' | sed -E 's/.*spp, ([0-9.]+) s, ([0-9.]+) Msamples.*/ours vcm: \1 s, \2 Msamples\/s/'
done
VENV="${PEERS_VENV:-$HOME/peers/venv}"
# Mitsuba (export_scene.py) needs LLVM for its JIT: the newest of the system's, unless given.
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  DRJIT_LIBLLVM_PATH="$(ls /usr/lib/x86_64-linux-gnu/libLLVM-[0-9]*.so 2>/dev/null | sort -V | tail -n 1 || true)"
  if [ -n "$DRJIT_LIBLLVM_PATH" ]; then export DRJIT_LIBLLVM_PATH; fi
fi
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import OpenEXR, pyluxcore" 2>/dev/null; then
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/export_scene.py" >/dev/null 2>&1 || true
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/luxcore_bench.py" --engines BIDIRVMCPU \
    --spp 64 --res 256 --repeats 3 --json "$OUT/luxcore.json"
else
  echo "(pyluxcore not installed in $VENV: see ../shared/peers/README.md; printing ours only)"
fi
