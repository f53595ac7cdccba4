#!/usr/bin/env bash
# Slurm smoke test for `regolith sweep --plan`: brings up a one-node Slurm cluster on this
# machine from Debian's packages (munge, slurmctld, slurmd), submits a plan's slurm.sbatch
# as written, waits for the array, collects it, and compares every run's state_hash with
# the same sweep run locally by `regolith sweep --jobs 2`. Needs root (it installs the
# packages and starts the daemons) and leaves nothing running.
#
#   cargo build --release && bash scripts/slurm-smoke.sh [SWEEP.ron]
#
# Output of the recorded run: docs/data/slurm-smoke.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$PWD
sweep=${1:-sweeps/slope_speed_coarse.ron}
regolith=${REGOLITH:-$top/target/release/regolith}
[ -x "$regolith" ] || { echo "build first: cargo build --release (no $regolith)" >&2; exit 2; }
started=$(date +%s)

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v munged >/dev/null || ! command -v sbatch >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurmctld slurmd slurm-client munge
fi

work=$(mktemp -d /tmp/slurm-smoke.XXXXXX)
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    wait 2>/dev/null || true
}
trap cleanup EXIT

# munge: a key of our own and a daemon on private sockets.
mkdir -p "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 700 "$work/munge"
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
    --seed-file="$work/munge/seed"
pids+=("$(cat "$work/munge/munged.pid")")

host=$(hostname -s)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool"
cat > "$work/slurm.conf" <<EOF
ClusterName=smoke
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=smoke Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
slurmctld -D -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 60); do
    sinfo -h -o %T 2>/dev/null | grep -q idle && break
    sleep 1
done
sinfo -h -o %T | grep -q idle || {
    echo "the node did not come up; logs in $work" >&2
    tail -n 20 "$work"/slurm*.log "$work"/slurm*.out >&2 || true
    exit 1
}
echo "slurm: node $host with $cpus CPUs up after $(( $(date +%s) - started )) s"

export PATH=$(dirname "$regolith"):$PATH
"$regolith" sweep "$sweep" --plan "$work/plan"
(cd "$work/plan" && sbatch --wait slurm.sbatch)
"$regolith" sweep --collect "$work/plan"
"$regolith" sweep "$sweep" --out "$work/local" --jobs 2 >/dev/null

# The last column of both tables: every body's state_hash, run by run.
a=$(tail -n +2 "$work/plan/sweep.csv" | awk -F, '{print $NF}')
b=$(tail -n +2 "$work/local/sweep.csv" | awk -F, '{print $NF}')
echo "state_hash per run (Slurm | local):"
paste -d'|' <(echo "$a") <(echo "$b")
if [ "$a" != "$b" ]; then
    echo "FAILED: the Slurm array's runs differ from the local sweep's" >&2
    exit 1
fi
echo "passed: $(echo "$a" | wc -l) runs bitwise equal; $(( $(date +%s) - started )) s in all"
rm -rf "$work"
