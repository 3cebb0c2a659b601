#!/usr/bin/env bash
# Instructions per path-traced sample on the peers' Cornell box, by callgrind (deterministic,
# for comparing builds on a noisy machine; issue 18, docs/design.md §8):
#
#   tools/instructions_per_sample.sh BINARY [SAMPLER [STAGE]]
#
# (total instructions at --spp 12 − total at --spp 4) / (128² · 8): 128², depth 7, seed 1,
# one thread, `--integrator path --sampler SAMPLER` (default zsobol), STAGE default
# ../shared/peers/cbox.usda. The whole program is counted, so the progress display's passes
# move it by up to ±2 % between runs of one binary; the count inside
# `PathEstimator::image_sample` (tools/callgrind_calls.py) is steadier. EXTRA_ARGS
# (environment) is added to both renders, e.g. EXTRA_ARGS="--rr-depth 2". Needs valgrind.
set -euo pipefail
BIN=$1
SAMPLER=${2:-zsobol}
STAGE=${3:-$(dirname "$0")/../../shared/peers/cbox.usda}
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
total() {
    valgrind --tool=callgrind --callgrind-out-file="$DIR/cg.$1" "$BIN" "$STAGE" -o "$DIR/$1.exr" \
        --resolution 128x128 --spp "$1" --max-depth 7 --seed 1 --threads 1 --integrator path \
        --sampler "$SAMPLER" ${EXTRA_ARGS:-} >/dev/null 2>&1
    awk '/^(summary|totals):/ {print $2; exit}' "$DIR/cg.$1"
}
A=$(total 4)
B=$(total 12)
echo "$(( (B - A) / (128 * 128 * 8) )) instructions per sample ($SAMPLER)"
