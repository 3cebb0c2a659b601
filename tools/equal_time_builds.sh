#!/usr/bin/env bash
# Before/after of a change meant to change an integrator's noise: examples/equal_time.rs from two
# builds against one reference, and per build the equal-time criterion of issue 17,
#   relRMSE(B) ≤ relRMSE(A) × √(time per sample of B / that of A) × 1.1,
# for A the first and B each further integrator of `--integrators`, with times in CPU seconds
# (fair on a shared machine: relRMSE(B) is scaled by √(CPU_B / CPU_A) to equal CPU time). The
# criterion holds when B's error per sample is at most 1.1 × A's.
#
# Usage: tools/equal_time_builds.sh OLD_EQUAL_TIME NEW_EQUAL_TIME REFERENCE.exr STAGE [ARGS…]
#   e.g. git worktree add /tmp/old <rev> && cargo build --release --example equal_time \
#          --manifest-path /tmp/old/Cargo.toml
#        tools/equal_time_builds.sh /tmp/old/target/release/examples/equal_time \
#          target/release/examples/equal_time /tmp/cm-ref.exr scenes/caustic-mirror.usda \
#          --resolution 160x120 --max-depth 10 --time 60 --reference-time 600 \
#          --reference-integrator path --integrators path,bdpt
# The reference is rendered once by the new build (or read, if REFERENCE.exr exists) and used
# by both. ARGS are equal_time's.
set -euo pipefail
OLD="$1"; NEW="$2"; REF="$3"; shift 3
criterion() {
  awk '/^ *(path|light|bdpt|vcm|auto) +[0-9.]+ +[0-9.]+ +[0-9]+ / {
         name = $1; cpu = $3; spp = $4; rel = $6
         if (!seen) { seen = 1; a = name; cpu0 = cpu; spp0 = spp; rel0 = rel; next }
         r = (rel / rel0) * sqrt(cpu / cpu0)   # relRMSE ratio at equal CPU time
         t = (cpu / spp) / (cpu0 / spp0)       # time-per-sample ratio
         printf "criterion %s vs %s: relRMSE ratio at equal CPU time %.3f <= sqrt(time per sample ratio %.3f) x 1.1 = %.3f? %s (per-sample error ratio %.3f)\n",
           name, a, r, t, sqrt(t) * 1.1, (r <= sqrt(t) * 1.1) ? "met" : "NOT met", r / sqrt(t)
       }'
}
for which in old new; do
  bin=$OLD; [ $which = new ] && bin=$NEW
  [ $which = old ] && [ ! -e "$REF" ] && "$NEW" "$@" --reference "$REF" --integrators path --time 1 >/dev/null
  echo "== $which build: $bin"
  out=$("$bin" "$@" --reference "$REF")
  echo "$out"
  echo "$out" | criterion
done
