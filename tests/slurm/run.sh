#!/bin/bash
# A real Slurm test of docs/how-to/slurm.md: install Slurm and MUNGE from
# Debian's packages if they are missing, start a one-node cluster on this
# machine (as root: slurmctld + slurmd, proctrack/linuxproc, task/none, a
# MUNGE key of its own), submit experiments/slurm/jam-array.sbatch as a 4-task
# array on a small experiment, wait for it, gather the tables with a plain
# run, and check them against one plain run (bit for bit, timing aside).
# Stops its daemons on exit. Needs root; run from the repository root:
#
#   bash tests/slurm/run.sh [path/to/jamkit]
#
# .ci/run calls it. Exit status 0 only if the array ran and the tables
# agree.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
JAMKIT=${1:-$ROOT/target/release/jamkit}
[ -x "$JAMKIT" ] || { echo "slurm test: no jamkit binary at $JAMKIT (build it first)" >&2; exit 1; }
[ "$(id -u)" = 0 ] || { echo "slurm test: needs root (it starts slurmctld and slurmd)" >&2; exit 1; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "slurm test: installing slurm-wlm and munge from Debian's packages"
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

WORK=$(mktemp -d /tmp/jamkit-slurm.XXXXXX)
chmod 755 "$WORK"
MUNGE_SOCKET=$WORK/munge/munge.socket
cleanup() {
    set +e
    [ -f "$WORK/slurmd.pid" ] && kill "$(cat "$WORK/slurmd.pid")" 2>/dev/null
    [ -f "$WORK/slurmctld.pid" ] && kill "$(cat "$WORK/slurmctld.pid")" 2>/dev/null
    [ -f "$WORK/munge/munged.pid" ] && kill "$(cat "$WORK/munge/munged.pid")" 2>/dev/null
    sleep 1
    if [ "${KEEP:-0}" = 1 ]; then echo "slurm test: kept $WORK"; else rm -rf "$WORK"; fi
}
trap cleanup EXIT

# MUNGE with a key and a socket of its own.
mkdir -p "$WORK/munge"
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$WORK/munge/munge.key"
munged --force --key-file="$WORK/munge/munge.key" --socket="$MUNGE_SOCKET" \
    --pid-file="$WORK/munge/munged.pid" --log-file="$WORK/munge/munged.log" \
    --seed-file="$WORK/munge/munged.seed"

HOST=$(hostname -s)
CONF=$WORK/slurm.conf
mkdir -p "$WORK/spool" "$WORK/state"
cat > "$CONF" <<EOF
ClusterName=jamkit-test
SlurmctldHost=$HOST
AuthType=auth/munge
AuthInfo=socket=$MUNGE_SOCKET
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SlurmctldPort=16817
SlurmdPort=16818
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmdSpoolDir=$WORK/spool
StateSaveLocation=$WORK/state
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
NodeName=$HOST CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$HOST Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
EOF
export SLURM_CONF=$CONF
slurmctld -f "$CONF"
slurmd -f "$CONF"

# Wait (bounded) for the node to take jobs.
for _ in $(seq 60); do
    state=$(sinfo -h -N -o %t 2>/dev/null | head -1 || true)
    case "$state" in idle|mix|alloc) break ;; esac
    sleep 1
done
[ "${state:-}" = idle ] || [ "${state:-}" = mix ] || {
    echo "slurm test: the node never became idle (state '${state:-none}')" >&2
    tail -20 "$WORK/slurmctld.log" "$WORK/slurmd.log" >&2
    exit 1
}

# The array: 4 parts of a small experiment into one shared directory.
OUT=$WORK/run
EXPERIMENT=$ROOT/experiments/quickstart.ron
ARGS="--set particles=64 --set samples=8"
start=$(date +%s)
JOB=$(EXPERIMENT=$EXPERIMENT OUT=$OUT JAMKIT=$JAMKIT JAMKIT_ARGS=$ARGS \
    sbatch --parsable --array=1-4 --cpus-per-task=1 --chdir="$WORK" \
    --output="$WORK/jamkit-%A_%a.log" "$ROOT/experiments/slurm/jam-array.sbatch")
JOB=${JOB%%;*}
echo "slurm test: submitted array job $JOB"
for _ in $(seq 240); do
    left=$(squeue -h -j "$JOB" 2>/dev/null | wc -l)
    [ "$left" = 0 ] && break
    sleep 1
done
[ "$left" = 0 ] || { echo "slurm test: the array did not finish within 240 s" >&2; squeue >&2; exit 1; }
for t in 1 2 3 4; do
    log=$WORK/jamkit-${JOB}_$t.log
    grep -q "shard $t/4" "$log" || { echo "slurm test: task $t did not finish its part" >&2; cat "$log" >&2; exit 1; }
done
echo "slurm test: the array ran in $(( $(date +%s) - start )) s"

# Gather with a plain run, and compare with one plain run elsewhere.
# shellcheck disable=SC2086
"$JAMKIT" run "$EXPERIMENT" --out "$OUT" $ARGS --quiet > "$WORK/gather.txt"
grep -q "8 packings (8 reused" "$WORK/gather.txt" || { echo "slurm test: the gathering run did not reuse all 8 packings" >&2; cat "$WORK/gather.txt" >&2; exit 1; }
# shellcheck disable=SC2086
"$JAMKIT" run "$EXPERIMENT" --out "$WORK/single" $ARGS --quiet --jobs 1 > /dev/null
strip() { python3 - "$1" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
w = rows[0].index("wall_s")
for r in rows:
    del r[w]
    print(",".join(r))
PY
}
if ! diff <(strip "$OUT/results.csv") <(strip "$WORK/single/results.csv") > "$WORK/diff.txt"; then
    echo "slurm test: the array's results differ from one plain run:" >&2
    cat "$WORK/diff.txt" >&2
    exit 1
fi
echo "slurm test: 4 array tasks gathered = one plain run (8 packings, timing aside)"
