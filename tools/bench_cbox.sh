#!/usr/bin/env bash
# Speed benchmark on ../shared/peers/cbox.usda: 256x256, 64 spp, max depth 7 (Mitsuba's
# max_depth 8), ours and Mitsuba 3 (scalar_spectral, llvm_ad_spectral) in the same run, with
# ratios. Mitsuba needs the peers venv (../shared/peers/README.md): PEERS_VENV, default
# ~/peers/venv; without it only our figures are printed.
#
# Usage: tools/bench_cbox.sh [REPEATS]      (default 3; prints a table, writes nothing in the repo)
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

ours=()
"$BIN" "$SHARED/peers/cbox.usda" -o "$OUT/warm.exr" --integrator path --spp 4 --resolution ${RES}x${RES} 2>/dev/null
for i in $(seq 1 "$REPEATS"); do
  line=$("$BIN" "$SHARED/peers/cbox.usda" -o "$OUT/ours.exr" --integrator path --spp $SPP --resolution ${RES}x${RES} --max-depth 7 --seed "$i" 2>&1 | grep '^wrote')
  secs=$(echo "$line" | sed -E 's/.*spp, ([0-9.]+) s,.*/\1/')
  ours+=("$secs")
  echo "ours run $i: $secs s"
done

VENV="${PEERS_VENV:-$HOME/peers/venv}"
MITSUBA_JSON="$OUT/mitsuba.json"
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import mitsuba" 2>/dev/null; then
  export DRJIT_LIBLLVM_PATH="${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}"
  PEERS_OUT="$OUT" "$VENV/bin/python" "$SHARED/peers/mitsuba_bench.py" --variants scalar_spectral llvm_ad_spectral \
    --spp $SPP --res $RES --repeats "$REPEATS" --json "$MITSUBA_JSON"
else
  echo "(Mitsuba not installed in $VENV: see ../shared/peers/README.md; printing ours only)"
fi

python3 - "$MITSUBA_JSON" "$RES" "$SPP" "${ours[@]}" <<'PY'
import json, os, statistics, sys
path, res, spp, *ours = sys.argv[1:]
n = int(res) ** 2 * int(spp)
med = statistics.median(float(t) for t in ours)
rows = [("spectral-render path", med, n / med)]
if os.path.exists(path):
    runs = json.load(open(path))["runs"]
    for key, r in sorted(runs.items()):
        rows.append((f"Mitsuba {r['variant']}", r["median_s"], r["samples_per_s_median"]))
print(f"\ncbox {res}x{res}, {spp} spp, max depth 7 (Mitsuba max_depth 8), median of runs")
print(f"{'renderer':32} {'median s':>9} {'Msamples/s':>11} {'ours / theirs (speed)':>22}")
for name, t, sps in rows:
    ratio = rows[0][2] / sps
    print(f"{name:32} {t:9.3f} {sps / 1e6:11.3f} {ratio:22.2f}")
PY
