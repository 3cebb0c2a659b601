#!/usr/bin/env bash
# Writes pgo/spectral-render.profdata, the profile that release builds of this crate
# are optimised with (pgo/rustc-wrapper; docs/design.md §8, "Profile-guided optimisation").
# It instruments the crate (pgo/rustc-wrapper), renders the training scenes below, and merges
# their counters. Run it after changes to the rendering code: a profile older than the code
# still builds and renders the same bits, but the functions that changed lose its guidance; and
# after a change of compiler, dependencies or features, which the wrapper says it cannot apply
# the profile to. Needs the rustup component llvm-tools (installed here if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
work=${PGO_WORK:-target/pgo}
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
profdata="$sysroot/lib/rustlib/$host/bin/llvm-profdata"

[ -x "$profdata" ] || rustup component add llvm-tools
rm -rf "$work/raw"
mkdir -p "$work/raw"
SPECTRAL_RENDER_PGO="generate:$(cd "$work/raw" && pwd)" CARGO_TARGET_DIR="$work/gen" \
    cargo build --release --bin spectral-render
bin="$work/gen/release/spectral-render"
out="$work/out"
mkdir -p "$out"
# The training renders, about 10 s instrumented; their images are thrown away. The box of the
# benchmarks leads (tools/bench_equal_error.sh's scene, with the path tracer as it measures it
# and with the defaults); the others carry the rest of what users run at a smaller weight: a
# function's counts decide how it is laid out, and the heaviest workload's hot paths come first.
run() { "$bin" "$@" -o "$out/train.exr" >/dev/null 2>&1 || {
    echo "pgo/train.sh: training render failed: $*" >&2
    exit 1
}; }
box=tests/data/usd/cbox.usda
run $box --resolution 128x128 --spp 32 --max-depth 7 --integrator path --sampler independent --split 1 --rr-depth 2
run $box --resolution 128x128 --spp 16 --max-depth 7
run scenes/cornell-box.usda --resolution 96x72 --spp 16
run scenes/room.usda --resolution 96x72 --spp 16
run scenes/materials.usda --resolution 96x72 --spp 16
run scenes/cornell-box.usda --resolution 96x72 --spp 8 --integrator bdpt
run scenes/cornell-box.usda --resolution 96x72 --spp 8 --integrator vcm
run scenes/open-office.usda --resolution 96x72 --spp 4
run scenes/caustic.usda --resolution 96x72 --spp 8
run scenes/cornell-box.usda --resolution 96x72 --spp 4 --integrator light
"$profdata" merge --sparse -o pgo/spectral-render.profdata "$work/raw"/*.profraw
sort -u "$work/raw/METADATA" > pgo/METADATA
echo "wrote pgo/spectral-render.profdata ($(du -h pgo/spectral-render.profdata | cut -f1)) for the builds pgo/METADATA lists"
