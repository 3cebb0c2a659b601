#!/usr/bin/env bash
# BDPT speed on ../shared/peers/cbox.usda (256x256, 64 spp) next to LuxCore BIDIRCPU
# (../shared/peers/luxcore_bench.py) in the same run, with ratios. LuxCore renders full global
# illumination (depth 64, Russian roulette from depth 5, its benchmark defaults; with RR on its
# BIDIRCPU is 2.8 % too bright, see ../shared/peers/RESULTS.md); ours runs at the same depth 64
# and at our default 7. LuxCore needs pyluxcore in the peers venv (PEERS_VENV, default
# ~/peers/venv; `pip install pyluxcore==2.11.2`); without it only our figures are printed.
#
# Usage: tools/bench_bdpt.sh [REPEATS]      (default 3; LUX_RR_DEPTH=1000 turns LuxCore's RR off)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
SHARED="$ROOT/../shared"
REPEATS="${1:-3}"
SPP=64
RES=256
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml"
BIN="$ROOT/target/release/spectral-render"

run_ours() { # depth seed -> seconds
  "$BIN" "$SHARED/peers/cbox.usda" -o "$OUT/ours.exr" --integrator bdpt --spp $SPP \
    --resolution ${RES}x${RES} --max-depth "$1" --seed "$2" 2>&1 | grep '^wrote' |
    sed -E 's/.*spp, ([0-9.]+) s,.*/\1/'
}

"$BIN" "$SHARED/peers/cbox.usda" -o "$OUT/warm.exr" --integrator bdpt --spp 2 --resolution ${RES}x${RES} 2>/dev/null
ours64=(); ours7=()
for i in $(seq 1 "$REPEATS"); do
  ours64+=("$(run_ours 64 "$i")"); echo "ours bdpt depth 64 run $i: ${ours64[-1]} s"
  ours7+=("$(run_ours 7 "$i")"); echo "ours bdpt depth 7 run $i: ${ours7[-1]} s"
done

VENV="${PEERS_VENV:-$HOME/peers/venv}"
LUX_JSON="$OUT/luxcore.json"
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import OpenEXR, pyluxcore" 2>/dev/null; then
  export DRJIT_LIBLLVM_PATH="${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}"
  # The triangles LuxCore renders (export_scene.py also writes a USD copy, which needs usd-core;
  # only the JSON is used here).
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/export_scene.py" >/dev/null 2>&1 || true
  [ -f "$OUT/cbox_scene.json" ] || { echo "export_scene.py failed" >&2; exit 1; }
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/luxcore_bench.py" --engines BIDIRCPU \
    --spp $SPP --res $RES --repeats "$REPEATS" --rr-depth "${LUX_RR_DEPTH:-5}" --json "$LUX_JSON"
else
  echo "(pyluxcore not installed in $VENV: see ../shared/peers/README.md; printing ours only)"
fi

python3 - "$LUX_JSON" "$RES" "$SPP" "$REPEATS" "${ours64[@]}" "${ours7[@]}" <<'PY'
import json, os, statistics, sys
path, res, spp, repeats, *times = sys.argv[1:]
r = int(repeats)
n = int(res) ** 2 * int(spp)
rows = []
for name, ts in (("spectral-render bdpt, depth 64", times[:r]), ("spectral-render bdpt, depth 7", times[r:])):
    med = statistics.median(float(t) for t in ts)
    rows.append((name, med, n / med))
if os.path.exists(path):
    for key, run in sorted(json.load(open(path))["runs"].items()):
        rows.append((f"LuxCore {run['engine']} d{run['depth']} RR@{run['rr_depth']}", run["median_s"], run["samples_per_s_median"]))
print(f"\ncbox {res}x{res}, {spp} spp, median of {r} runs, same machine, same run")
print(f"{'renderer':36} {'median s':>9} {'Msamples/s':>11} {'ours d64 / this':>16}")
for name, t, sps in rows:
    print(f"{name:36} {t:9.2f} {sps / 1e6:11.3f} {rows[0][2] / sps:16.2f}")
PY
