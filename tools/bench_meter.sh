#!/usr/bin/env bash
# Meter benchmark: wall time for 100 illuminance readings (a 10 × 10 grid of --at points on a
# work plane) to reach ci95/value < 0.5 % (--rel-error 0.005).
#
#   tools/bench_meter.sh                          # the built-in office room (below)
#   tools/bench_meter.sh STAGE ORIGIN U V NORMAL  # any stage: work-plane rectangle, stage units
#   e.g. tools/bench_meter.sh scenes/room.usda 0.5,0.8,0.5 5,0,0 0,0,3 0,1,0
#
# Extra options go through $METER_ARGS (e.g. METER_ARGS="--threads 1 --max-depth 20").
# The built-in room: 6 × 4 × 3 m, white ceiling (ρ 0.8), walls 0.5, floor 0.2, a desk, and
# four 0.6 × 0.6 m ceiling RectLights of 3000 lm each; work plane at 0.8 m, 0.5 m from walls.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/spectral-render
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

if [[ $# -ge 5 ]]; then
    stage=$1 origin=$2 u=$3 v=$4 normal=$5
else
    stage=$tmp/office.usda origin=0.5,0.8,0.5 u=5,0,0 v=0,0,3 normal=0,1,0
    python3 - "$stage" <<'EOF'
import sys
def mat(name, rho):
    return f'''    def Material "{name}"
    {{
        token outputs:surface.connect = </Looks/{name}/S.outputs:surface>
        def Shader "S"
        {{
            uniform token info:id = "spectral:diffuse"
            float2[] inputs:reflectance:samples = [(360, {rho}), (830, {rho})]
            token outputs:surface
        }}
    }}
'''
def quad(name, pts, look):
    p = ", ".join(f"({x}, {y}, {z})" for x, y, z in pts)
    return f'''def Mesh "{name}" (
    prepend apiSchemas = ["MaterialBindingAPI"]
)
{{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [{p}]
    rel material:binding = </Looks/{look}>
}}
'''
def box(name, lo, hi, look):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = [[(x0,y1,z0),(x0,y1,z1),(x1,y1,z1),(x1,y1,z0)], [(x0,y0,z0),(x1,y0,z0),(x1,y0,z1),(x0,y0,z1)],
             [(x0,y0,z0),(x0,y0,z1),(x0,y1,z1),(x0,y1,z0)], [(x1,y0,z0),(x1,y1,z0),(x1,y1,z1),(x1,y0,z1)],
             [(x0,y0,z0),(x0,y1,z0),(x1,y1,z0),(x1,y0,z0)], [(x0,y0,z1),(x1,y0,z1),(x1,y1,z1),(x0,y1,z1)]]
    return "".join(quad(f"{name}{i}", f, look) for i, f in enumerate(faces))
W, D, H = 6.0, 4.0, 3.0
s = '#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = "Y"\n)\n\ndef Scope "Looks"\n{\n'
s += mat("Ceiling", 0.8) + mat("Wall", 0.5) + mat("Floor", 0.2) + mat("Desk", 0.4) + "}\n\n"
s += quad("Floor", [(0,0,0),(0,0,D),(W,0,D),(W,0,0)], "Floor")
s += quad("Ceiling", [(0,H,0),(W,H,0),(W,H,D),(0,H,D)], "Ceiling")
s += quad("WallN", [(0,0,0),(W,0,0),(W,H,0),(0,H,0)], "Wall")
s += quad("WallS", [(0,0,D),(0,H,D),(W,H,D),(W,0,D)], "Wall")
s += quad("WallW", [(0,0,0),(0,H,0),(0,H,D),(0,0,D)], "Wall")
s += quad("WallE", [(W,0,0),(W,0,D),(W,H,D),(W,H,0)], "Wall")
s += box("Desk", (3.8, 0.0, 0.6), (5.4, 0.75, 1.4), "Desk")
for i, (x, z) in enumerate([(1.5, 1.0), (4.5, 1.0), (1.5, 3.0), (4.5, 3.0)]):
    s += f'''def RectLight "Lamp{i}"
{{
    float inputs:width = 0.6
    float inputs:height = 0.6
    float spectral:luminousFlux = 3000
    double3 xformOp:translate = ({x}, {H - 0.01}, {z})
    float xformOp:rotateX = -90
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateX"]
}}
'''
open(sys.argv[1], "w").write(s)
EOF
fi

# 10 × 10 cell centres of the work-plane rectangle.
mapfile -t ats < <(awk -v o="$origin" -v u="$u" -v v="$v" 'BEGIN {
    split(o, O, ","); split(u, U, ","); split(v, V, ",")
    for (j = 0; j < 10; j++) for (i = 0; i < 10; i++) {
        a = (i + 0.5) / 10; b = (j + 0.5) / 10
        printf "%.6g,%.6g,%.6g\n", O[1] + a*U[1] + b*V[1], O[2] + a*U[2] + b*V[2], O[3] + a*U[3] + b*V[3]
    }
}')
args=()
for p in "${ats[@]}"; do args+=(--at "$p" --normal "$normal"); done

start=$(date +%s.%N)
# shellcheck disable=SC2086
"$bin" meter "$stage" "${args[@]}" --rel-error 0.005 --json ${METER_ARGS:-} >"$tmp/out.json"
end=$(date +%s.%N)
awk -v t0="$start" -v t1="$end" -F'"samples":' '
    NF > 1 { split($2, a, /[,}]/); n += a[1]; k++; if ($0 ~ /"converged":false/) bad++ }
    END { printf "%d readings, %d samples in total, %d not converged, %.2f s wall\n", k, n, bad, t1 - t0 }
' "$tmp/out.json"
grep -o '"value":[^,]*' "$tmp/out.json" | cut -d: -f2 |
    awk '{ s += $1; if (NR == 1 || $1 < mn) mn = $1; if ($1 > mx) mx = $1 } END { printf "E on the work plane: min %.1f, mean %.1f, max %.1f lx\n", mn, s / NR, mx }'
