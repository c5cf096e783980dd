#!/usr/bin/env bash
# A real Slurm test of `cogeo batch` (run by tests/batch.rs): installs Debian's slurm-wlm and munge
# when missing, starts a single-node cluster on this machine (its own ports, state and spool under a
# temporary folder), submits deploy/slurm/cogeo-array.sbatch as a job array over a manifest of
# three tiny `cogeo synth` scenes, cancels one task in the middle of its removal step with scancel
# and requeues it, waits for all three, and checks that every entry finished, that the requeued
# task skipped the steps it had done, and that `cogeo batch report` lists all three.
#   usage: scripts/slurm_test.sh PATH/TO/cogeo
# Prints "slurm test skipped: <why>" and exits 0 where Slurm cannot be installed or started.
set -euo pipefail
cogeo="$(realpath "${1:?usage: scripts/slurm_test.sh PATH/TO/cogeo}")"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
skip() { echo "slurm test skipped: $*"; exit 0; }
say() { echo "slurm test: $*" >&2; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  [ "$(id -u)" -eq 0 ] || skip "slurm-wlm and munge are not installed and this is not root"
  say "installing slurm-wlm and munge"
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      slurm-wlm munge; } >/dev/null 2>&1 || skip "apt-get could not install slurm-wlm and munge"
fi

work="$(mktemp -d /tmp/cogeo-slurm.XXXXXX)"
started_munged=0
passed=0
cleanup() {
  [ -n "${SLURM_CONF:-}" ] && scontrol shutdown >/dev/null 2>&1 || true
  sleep 1
  [ -f "$work/slurmd.pid" ] && kill "$(cat "$work/slurmd.pid")" 2>/dev/null || true
  [ -f "$work/slurmctld.pid" ] && kill "$(cat "$work/slurmctld.pid")" 2>/dev/null || true
  [ "$started_munged" = 1 ] && pkill -x munged 2>/dev/null || true
  [ "$passed" = 1 ] && rm -rf "$work" || true
}
trap cleanup EXIT

# munge: a key and a running daemon (the one already serving, when there is one)
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  [ -f /etc/munge/munge.key ] || { mkdir -p /etc/munge; dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null; }
  chown munge:munge /etc/munge/munge.key 2>/dev/null || true
  chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge 2>/dev/null || true
  runuser -u munge -- /usr/sbin/munged 2>/dev/null || /usr/sbin/munged --force || skip "munged does not start"
  started_munged=1
  for _ in $(seq 20); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.2; done
fi
munge -n 2>/dev/null | unmunge >/dev/null 2>&1 || skip "munge does not work here"

host="$(hostname -s)"
port=$((20000 + $$ % 20000))
mkdir -p "$work/state" "$work/spool"
cat > "$work/slurm.conf" <<EOF
ClusterName=cogeotest
SlurmctldHost=$host
SlurmUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
JobRequeue=1
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
NodeName=$host CPUs=$(nproc) RealMemory=2000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$work/slurm.conf"
slurmctld -c || skip "slurmctld does not start (see $work/slurmctld.log)"
slurmd || skip "slurmd does not start (see $work/slurmd.log)"
for _ in $(seq 30); do sinfo -h -o %t 2>/dev/null | grep -q idle && break; sleep 1; done
sinfo -h -o %t | grep -q idle || skip "the node does not come up (see $work/slurmd.log)"
say "cluster up on $host:$port"

# three tiny scenes, a manifest
for i in 0 1 2; do
  "$cogeo" synth --out "$work/scenes/s$i" --width 32 --height 24 --views 8 --objects 2 --seed $((i + 1)) \
    --gt-without 1 2>/dev/null
done
cat > "$work/manifest.json" <<EOF
{
  "output_root": "out",
  "defaults": {
    "train": ["--iters", "120", "--sh-degree", "0", "--checkpoint-every", "40"],
    "tag": ["--method", "vote"],
    "remove": ["--refine-iters", "150"]
  },
  "scenes": [
    {"name": "s0", "data": "scenes/s0", "masks": "object_mask", "labels": [1],
     "ground_truth": {"images": "scenes/s0/without_1/images", "masks": "scenes/s0/object_mask", "synth": true}},
    {"name": "s1", "data": "scenes/s1", "masks": "object_mask", "labels": [1],
     "ground_truth": {"images": "scenes/s1/without_1/images", "masks": "scenes/s1/object_mask", "synth": true}},
    {"name": "s2", "data": "scenes/s2", "masks": "object_mask", "labels": [1, 2]}
  ]
}
EOF
n="$("$cogeo" batch plan "$work/manifest.json" --count)"
[ "$n" = 3 ] || { echo "slurm test: plan says $n tasks, expected 3" >&2; exit 1; }

cd "$work"
job="$(COGEO="$cogeo" sbatch --parsable --array=0-$((n - 1)) --gres=none --cpus-per-task=1 --mem=500 \
  --output="$work/task-%a.log" "$root/deploy/slurm/cogeo-array.sbatch" "$work/manifest.json")"
say "submitted job array $job"

# cancel task 1 once its tag step is done (inside its removal), then requeue it
for _ in $(seq 600); do [ -f "$work/out/s1/.batch/tag.json" ] && break; sleep 0.2; done
[ -f "$work/out/s1/.batch/tag.json" ] || { echo "slurm test: task 1 never finished tagging" >&2; cat "$work"/task-1.log >&2; exit 1; }
if [ -f "$work/out/s1/.batch/remove.json" ]; then
  echo "slurm test: task 1 finished its removal before it could be cancelled" >&2; exit 1
fi
scancel "${job}_1"
for _ in $(seq 100); do squeue -h -j "${job}_1" -t R,CG 2>/dev/null | grep -q . || break; sleep 0.2; done
say "cancelled ${job}_1 during its removal; requeueing it"
scontrol requeue "${job}_1"
scontrol update jobid="${job}_1" StartTime=now >/dev/null 2>&1 || true

for _ in $(seq 900); do squeue -h -j "$job" 2>/dev/null | grep -q . || break; sleep 0.5; done
if squeue -h -j "$job" | grep -q .; then
  echo "slurm test: the array did not finish in 450 s" >&2; squeue >&2; exit 1
fi

fail=0
for i in 0 1 2; do
  want="train tag remove eval"; [ "$i" = 2 ] && want="train tag remove"
  for s in $want; do
    [ -f "$work/out/s$i/.batch/$s.json" ] || { echo "slurm test: s$i has no $s marker" >&2; fail=1; }
  done
  [ -f "$work/out/s$i/removal/scene.ply" ] || { echo "slurm test: s$i has no removal/scene.ply" >&2; fail=1; }
done
grep -q "restart 1" "$work/task-1.log" || { echo "slurm test: task 1 shows no restart" >&2; fail=1; }
grep -q "batch: skip train" "$work/task-1.log" || { echo "slurm test: the requeued task did not skip train" >&2; fail=1; }
grep -q "batch: skip tag" "$work/task-1.log" || { echo "slurm test: the requeued task did not skip tag" >&2; fail=1; }
"$cogeo" batch report "$work/manifest.json" > "$work/report.md"
[ "$(grep -c '| done |' "$work/report.md")" = 3 ] || { echo "slurm test: the report does not list 3 done entries" >&2; fail=1; }
if [ "$fail" != 0 ]; then
  for i in 0 1 2; do echo "--- task $i log" >&2; cat "$work/task-$i.log" >&2; done
  exit 1
fi
echo "--- requeued task log (task 1)"
grep -E "^cogeo-array|^batch:" "$work/task-1.log"
echo "--- report"
cat "$work/report.md"
echo "slurm test: passed"
passed=1
