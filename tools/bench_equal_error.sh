#!/usr/bin/env bash
# Time to equal error on the Cornell box (issue 18): ours (path with --sampler zsobol and
# independent, and zsobol with --adaptive) against Mitsuba 3 llvm_ad_spectral and
# scalar_spectral, interleaved in one run: samples/s, relRMSE at 64, 256 and 1024 spp, time to
# relRMSE 5 % with the visible light masked, and the ratios (tools/equal_error.py says how each
# is measured; `tools/equal_error.py --from-log LOG` reprints the table of a run from what it
# printed to stderr).
#
#   tools/bench_equal_error.sh [--rounds N] [--spp 64 256 1024] [--rr-depth N…] [--split N…]
#   [--no-adaptive] [--unsplit-independent] [--baseline OTHER_BUILD]
#   (equal_error.py; --baseline adds a row of another build of ours, e.g. the commit issue 18
#   was measured on, c5d7459, for its samples/s in the same run)
#
# Needs the peers' venv (../shared/peers/README.md; PEERS_VENV, default ~/peers/venv) and
# DRJIT_LIBLLVM_PATH for the llvm variant. The reference is Mitsuba llvm_ad_spectral at
# REF_SPP samples per pixel (default 16384), kept outside the repository in PEERS_OUT
# (default ~/peers/out); it is rendered once, by ../shared/peers/mitsuba_reference.py, when
# missing (about 5 min on an idle 2-core machine at 16384 spp). Its noise over the masked
# pixels, from its checkpoint at a quarter of REF_SPP, is subtracted (equal_error.py).
set -euo pipefail
# --baseline's path as given from the caller's directory, before the cd below.
args=()
while [[ $# -gt 0 ]]; do
    if [[ $1 == --baseline && $# -gt 1 ]]; then
        args+=("$1" "$(realpath "$2")"); shift 2
    else
        args+=("$1"); shift
    fi
done
set -- "${args[@]+"${args[@]}"}"
cd "$(dirname "$0")/.."
VENV="${PEERS_VENV:-$HOME/peers/venv}"
OUT="${PEERS_OUT:-$HOME/peers/out}"
REF_SPP="${REF_SPP:-16384}"
export DRJIT_LIBLLVM_PATH="${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}"
REF="$OUT/ref_mitsuba_llvm_ad_spectral_256_${REF_SPP}spp.exr"
if [[ ! -f "$REF" ]]; then
    echo "rendering the reference ($REF_SPP spp) into $OUT" >&2
    PEERS_OUT="$OUT" "$VENV/bin/python" ../shared/peers/mitsuba_reference.py \
        --variant llvm_ad_spectral --total "$REF_SPP"
fi
cargo build --release --quiet
PEERS_OUT="$OUT" "$VENV/bin/python" tools/equal_error.py --reference "$REF" "$@"
