#!/usr/bin/env bash
# Time saved by leaving out the machinery a scene does not use (src/scene/machinery.rs):
# UsdPreviewSurface lobes of weight 0, the light-selection table of a single light, the
# per-vertex dispersion check. Each scene renders with the default (pruned) build and with
# everything forced on (the hidden --force-machinery all), interleaved in the same run; the
# table prints the median render times (the "wrote" line's wall time, loading excluded) and
# their ratio. The Cornell box of tests/data/usd/cbox.usda (= ../shared/peers/cbox.usda) is
# also rendered with its walls as spectral:diffuse, a yardstick that is NOT the same BSDF:
# its UsdPreviewSurfaces have specularColor 0 with the specification's white edge colour
# (F90 = 1), a coat that reflects 0.3 % of diffuse light, which pruning must keep.
#
# Usage: tools/bench_pruning.sh [REPEATS [SPP [RES]]]   (default 5 repeats, 32 spp, 256x256;
#        path tracing, default depth: unlimited; writes nothing in the repo)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
REPEATS="${1:-5}"
SPP="${2:-32}"
RES="${3:-256}"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml"
BIN="$ROOT/target/release/spectral-render"

# The Lambertian yardstick: the same box with spectral:diffuse walls of the same colours.
sed -e 's/"UsdPreviewSurface"/"spectral:diffuse"/' -e 's/inputs:diffuseColor/inputs:reflectance/' \
    -e '/inputs:metallic/d' -e '/inputs:roughness/d' -e '/inputs:specularColor/d' \
    -e '/inputs:useSpecularWorkflow/d' "$ROOT/tests/data/usd/cbox.usda" > "$OUT/cbox-diffuse.usda"

SCENES=("$ROOT/tests/data/usd/cbox.usda" "$ROOT/scenes/cornell-box.usda"
        "$ROOT/scenes/materials.usda" "$ROOT/scenes/room.usda")

# Seconds of the render itself, from the "wrote …, N spp, S s, …" line. The path tracer, not
# the default auto, whose pilot would time two integrators.
render_s() {
  "$BIN" "$@" -o "$OUT/x.exr" --spp "$SPP" --resolution "${RES}x${RES}" --integrator path 2>&1 |
    grep '^wrote' | sed -E 's/.*spp, ([0-9.]+) s,.*/\1/'
}

# Rows "name<TAB>A times<TAB>B times": A and B alternate run by run, so each B/A is paired.
ROWS="$OUT/rows"
for s in "${SCENES[@]}"; do
  render_s "$s" >/dev/null   # warm-up
  a=() b=()
  for i in $(seq 1 "$REPEATS"); do
    a+=("$(render_s "$s" --seed "$i")")
    b+=("$(render_s "$s" --seed "$i" --force-machinery all)")
  done
  printf '%s\t%s\t%s\n' "$(basename "$s"): pruned | forced" "${a[*]}" "${b[*]}" >> "$ROWS"
done
a=() b=()
for i in $(seq 1 "$REPEATS"); do
  a+=("$(render_s "$OUT/cbox-diffuse.usda" --seed "$i")")
  b+=("$(render_s "$ROOT/tests/data/usd/cbox.usda" --seed "$i")")
done
printf '%s\t%s\t%s\n' "cbox.usda: spectral:diffuse twin | pruned" "${a[*]}" "${b[*]}" >> "$ROWS"

python3 - "$SPP" "$RES" "$REPEATS" "$ROWS" <<'PY'
import statistics, sys
spp, res, reps, rows = sys.argv[1:]
print(f"\n{res}x{res}, {spp} spp, default depth, median of {reps} paired runs "
      "(render wall time, loading excluded)")
print(f"{'scene: A | B':44} {'A s':>8} {'B s':>8} {'B/A':>7}")
for line in open(rows):
    name, a, b = line.rstrip("\n").split("\t")
    a = [float(x) for x in a.split()]
    b = [float(x) for x in b.split()]
    ratio = statistics.median(y / x for x, y in zip(a, b))
    print(f"{name:44} {statistics.median(a):8.3f} {statistics.median(b):8.3f} {ratio:7.3f}")
print("B/A > 1: B is slower. The last row compares two different BSDFs (see the header).")
PY
