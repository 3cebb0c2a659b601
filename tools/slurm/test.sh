#!/usr/bin/env bash
# The Slurm recipe (render.sbatch, meter.sbatch) tested against a real Slurm on this machine:
#   1. installs Debian's slurm-wlm and munge if they are missing (apt-get: needs root; CI runs
#      as root, elsewhere run it with sudo);
#   2. starts munged, slurmctld and slurmd on loopback only, from a temporary slurm.conf with
#      one node (this machine's CPUs), every file in a temporary directory;
#   3. submits the Cornell box at 4 parts and a 16-point meter grid at 4 parts, each an array
#      job with a dependent merge (the README's two commands), polls with a bound, and checks
#      that the merged outputs equal single-machine runs bit for bit (the EXR byte for byte
#      but its wall-clock attribute; the map's CSV, JSON and PNG byte for byte);
#   4. stops everything it started, by PID, also on failure (trap), and checks that none of
#      it is left running.
# Usage: tools/slurm/test.sh [path/to/spectral-render] (default: target/release's, built if
# missing). Exit 0 and a last line "slurm: 2 passed, 0 failed" when all is well.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
bin=${1:-$repo/target/release/spectral-render}
poll_limit_s=${SLURM_TEST_TIMEOUT:-600}

if [[ $(id -u) != 0 ]]; then
    echo "slurm test: needs root (apt-get, and daemons that run jobs as root): sudo $0" >&2
    exit 1
fi
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v munged >/dev/null || ! command -v sbatch >/dev/null; then
    echo "== installing slurm-wlm and munge (Debian)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
if [[ ! -x $bin ]]; then
    (cd "$repo" && cargo build --release --bin spectral-render)
fi
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")

work=$(mktemp -d /tmp/spectral-slurm.XXXXXX)
chmod 711 "$work"
pids=()
# slurmstepd processes that are running (not zombies waiting to be reaped).
steps() { ps -C slurmstepd -o stat= | grep -vc '^Z' || true; }
steps_before=$(steps)
export SLURM_CONF=$work/slurm.conf

teardown() {
    local status=$?
    set +e
    if [[ -f $SLURM_CONF ]] && ((${#pids[@]} > 0)); then
        scancel --full --quiet --user=root 2>/dev/null
        for _ in $(seq 50); do
            [[ -z $(squeue -h 2>/dev/null) ]] && break
            sleep 0.2
        done
    fi
    # Daemons in reverse order of starting: slurmd, slurmctld, munged.
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        kill -TERM "${pids[i]}" 2>/dev/null
        for _ in $(seq 100); do
            kill -0 "${pids[i]}" 2>/dev/null || break
            sleep 0.1
        done
        kill -KILL "${pids[i]}" 2>/dev/null
        wait "${pids[i]}" 2>/dev/null
    done
    local left=0
    for p in "${pids[@]}"; do
        if kill -0 "$p" 2>/dev/null; then
            echo "slurm test: process $p still running" >&2
            left=1
        fi
    done
    local steps_after
    for _ in $(seq 100); do
        steps_after=$(steps)
        [[ $steps_after == "$steps_before" ]] && break
        sleep 0.1
    done
    if [[ $steps_after != "$steps_before" ]]; then
        echo "slurm test: slurmstepd processes: $steps_before before, $steps_after after" >&2
        left=1
    fi
    if ((status != 0)); then
        for f in "$work"/*.log "$work"/*.out "$work"/logs/*; do
            [[ -f $f ]] && { echo "--- $f"; tail -n 20 "$f"; } >&2
        done
    fi
    rm -rf "$work"
    if ((left)); then
        echo "slurm: 1 passed, 1 failed (processes left running)"
        exit 1
    fi
    exit "$status"
}
trap teardown EXIT
trap 'exit 130' INT TERM

# Two free ports on loopback, chosen per run.
port=$((20000 + (RANDOM % 2000) * 2))
cpus=$(nproc)
host=$(hostname -s)
mkdir -p "$work/state" "$work/spool" "$work/logs" "$work/munge"
chmod 711 "$work/munge"
head -c 1024 /dev/urandom >"$work/munge/munge.key"
chmod 400 "$work/munge/munge.key"
cat >"$SLURM_CONF" <<CONF
ClusterName=spectraltest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
LaunchParameters=use_interactive_step
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
DependencyParameters=kill_invalid_depend
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

echo "== starting munged, slurmctld, slurmd ($SLURM_CONF, ports $port-$((port + 1)))"
munged --foreground --force --socket="$work/munge/munge.socket" \
    --key-file="$work/munge/munge.key" --pid-file="$work/munge/munged.pid" \
    --log-file="$work/munged.log" --seed-file="$work/munge/munged.seed" \
    >>"$work/munged.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ -S $work/munge/munge.socket ]] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >>"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >>"$work/slurmd.out" 2>&1 &
pids+=($!)
up=0
for _ in $(seq 150); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qx idle; then up=1; break; fi
    sleep 0.2
done
((up)) || { echo "slurm test: the node never became idle" >&2; sinfo >&2 || true; exit 1; }
sinfo

cd "$work"
stage=$repo/scenes/cornell-box.usda
render_opts=(--resolution 64x48 --spp 24 --integrator bdpt --seed 11)
meter_opts=(--grid=-0.9,-0.999,-0.9 --u 1.8,0,0 --v 0,0,1.8 --n 4,4 --normal 0,1,0
    --spp 2048 --integrator path)
export SPECTRAL_RENDER=$bin

echo "== submitting (the README's commands)"
jid=$(sbatch --parsable --array=0-3 --output="$work/logs/render-%a.log" \
    "$here/render.sbatch" render-out 4 "$stage" "${render_opts[@]}")
merge_jid=$(sbatch --parsable --dependency=afterok:"$jid" --output="$work/logs/render-merge.log" \
    "$here/render.sbatch" --merge render-out 4)
mjid=$(sbatch --parsable --array=0-3 --output="$work/logs/meter-%a.log" \
    "$here/meter.sbatch" meter-out 4 "$stage" "${meter_opts[@]}")
mmerge_jid=$(sbatch --parsable --dependency=afterok:"$mjid" --output="$work/logs/meter-merge.log" \
    "$here/meter.sbatch" --merge meter-out 4)
echo "render array $jid, merge $merge_jid; meter array $mjid, merge $mmerge_jid"

echo "== single-machine runs while Slurm works"
"$bin" "$stage" "${render_opts[@]}" -o single.exr 2>single-render.log
"$bin" meter "$stage" "${meter_opts[@]}" -o single-map 2>single-meter.log >/dev/null

start=$SECONDS
while [[ -n $(squeue -h) ]]; do
    if ((SECONDS - start > poll_limit_s)); then
        echo "slurm test: jobs still queued after ${poll_limit_s} s" >&2
        squeue >&2
        exit 1
    fi
    sleep 1
done
echo "jobs done after $((SECONDS - start)) s of polling"
for j in "$merge_jid" "$mmerge_jid"; do
    state=$(scontrol show job "$j" | grep -o 'JobState=[A-Z_]*' || true)
    [[ $state == JobState=COMPLETED ]] || { echo "slurm test: job $j: $state" >&2; exit 1; }
done

passed=0 failed=0
# The EXRs are equal: every header attribute (name, type, value bytes) but
# spectralRender:wallTime, and every byte after the header (offsets and pixel chunks). The
# attributes' order in the header is the EXR library's and may differ between processes.
if python3 - single.exr render-out/merged.exr <<'PY'; then
import struct, sys
def split(path):
    data = open(path, "rb").read()
    at, attributes = 8, {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        (size,) = struct.unpack_from("<i", data, type_end + 1)
        value = data[type_end + 5:type_end + 5 + size]
        attributes[data[at:name_end]] = (data[name_end + 1:type_end], value)
        at = type_end + 5 + size
    attributes.pop(b"spectralRender:wallTime")
    return attributes, data[at + 1:]
(a_attr, a_body), (b_attr, b_body) = (split(p) for p in sys.argv[1:])
same = a_attr == b_attr and a_body == b_body
print(f"render: merged EXR {'equals' if same else 'DIFFERS from'} the single render "
      f"({len(a_attr)} attributes, {len(a_body)} bytes of offsets and pixels; wall time aside)")
sys.exit(0 if same else 1)
PY
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi
same=1
for ext in csv json png; do
    cmp -s "single-map.$ext" "meter-out/merged.$ext" || { echo "meter: map .$ext differs"; same=0; }
done
if ((same)); then
    echo "meter: merged map (csv, json, png) equals the single run byte for byte"
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi
echo "slurm: $passed passed, $failed failed"
((failed == 0))
