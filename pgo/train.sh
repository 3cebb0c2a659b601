#!/usr/bin/env bash
# Writes pgo/spectral-render.profdata, the profile that release builds of this crate are
# optimised with, and pgo/METADATA, the build hashes it fits (pgo/rustc-wrapper; docs/design.md
# §8, "Profile-guided optimisation"). It instruments the crate, renders the training scenes
# below, and merges their counters. Run it after work on the rendering code (functions changed
# since the profile was written build as without it), and when a build says the profile does
# not fit it (another compiler, dependencies, features or profile settings). Needs the rustup
# component llvm-tools for llvm-profdata (installed here if missing). Instrumented build and
# counters go to target/pgo; the renders' log to target/pgo/train.log.
set -euo pipefail
cd "$(dirname "$0")/.."
work="$PWD/target/pgo"
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
profdata="$sysroot/lib/rustlib/$host/bin/llvm-profdata"

[ -x "$profdata" ] || rustup component add llvm-tools
rm -rf "$work/raw"
mkdir -p "$work/raw"
# Only this wrapper instruments; the crate is rebuilt so that it records the build's hash.
unset RUSTC_WRAPPER CARGO_BUILD_RUSTC_WRAPPER
cargo clean --release -p spectral-render --target-dir "$work/gen" 2>/dev/null || true
SPECTRAL_RENDER_PGO="generate:$work/raw" CARGO_TARGET_DIR="$work/gen" \
    cargo build --release --bin spectral-render
bin="$work/gen/release/spectral-render"
out="$work/out"
log="$work/train.log"
mkdir -p "$out"
: >"$log"
# The training renders, about 10 s instrumented; their images are thrown away. The box of the
# benchmarks leads (tools/bench_equal_error.sh's scene, with the path tracer as it measures it
# and with the defaults); the others carry the rest of what users run at a smaller weight: a
# function's counts decide how it is laid out, and the heaviest workload's hot paths come first.
run() {
    echo "== $*" >>"$log"
    LLVM_PROFILE_FILE="$work/raw/train_%m.profraw" "$bin" "$@" -o "$out/train.exr" >>"$log" 2>&1 || {
        echo "pgo/train.sh: training render failed (see $log): $*" >&2
        exit 1
    }
}
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
shopt -s nullglob
raw=("$work"/raw/*.profraw)
if [ ${#raw[@]} -eq 0 ] || [ ! -s "$work/raw/METADATA" ]; then
    echo "pgo/train.sh: the instrumented build wrote no counters or no build hash" >&2
    exit 1
fi
"$profdata" merge --sparse -o "$work/spectral-render.profdata" "${raw[@]}"
sort -u "$work/raw/METADATA" >"$work/METADATA"
mv "$work/spectral-render.profdata" pgo/spectral-render.profdata
mv "$work/METADATA" pgo/METADATA
echo "wrote pgo/spectral-render.profdata ($(du -h pgo/spectral-render.profdata | cut -f1)) for the builds pgo/METADATA lists"
