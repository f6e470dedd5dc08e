#!/usr/bin/env bash
# A real scheduler: runs `rondo farm slurm` on a one-node Slurm cluster on localhost.
#
# Installs Debian's slurm-wlm and munge if missing, starts a private munged, slurmctld and slurmd
# (2 CPUs, ports 16817/16818, all state in a temporary directory), submits the script for a small
# scene in 4 array tasks, waits for the array and the merge, and checks that the merged image
# equals a single-process render exactly (with a non-default sampler, which every task must be
# given, and an output directory whose name has a space, a quote and `$(…)`). Then a task is
# made to fail: the report job must name it with the commands to rerun it, the direct command
# pasted into sh must render the task's samples, and rerunning it with sbatch must complete the
# merge. Stops the daemons and removes everything on exit. Usage: bash tests/slurm.sh (as root;
# a few minutes at most).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
RONDO=$ROOT/target/release/rondo
[ -x "$RONDO" ] || cargo build --release --quiet

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
  echo "installing slurm-wlm and munge"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

WORK=$(mktemp -d /tmp/rondo-slurm.XXXXXX)
chmod 700 "$WORK"
PIDS=()
cleanup() {
  set +e
  if [ -n "${SLURM_CONF:-}" ] && [ -e "$WORK/slurmctld.pid" ]; then
    scancel --quiet --user=root 2>/dev/null
  fi
  for pid in "${PIDS[@]}"; do
    kill "$pid" 2>/dev/null
  done
  for pid in "${PIDS[@]}"; do
    wait "$pid" 2>/dev/null
  done
  rm -rf "$WORK"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in "$WORK"/*.log "$OUT"/*.out; do
    [ -e "$f" ] && { echo "--- $f"; tail -n 20 "$f"; }
  done
  exit 1
}

# munge: a private key and socket, so a system munged (if any) is left alone.
OUT="$WORK/out dir 'q' \$(touch pwned)"
mkdir -p "$WORK/munge" "$WORK/state" "$WORK/spool" "$OUT"
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$WORK/munge/munge.key"
munged --force --foreground --key-file="$WORK/munge/munge.key" \
  --socket="$WORK/munge/munge.sock" --pid-file="$WORK/munge/munged.pid" \
  --seed-file="$WORK/munge/munge.seed" --log-file="$WORK/munged.log" >"$WORK/munged.stdout" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$WORK/munge/munge.sock" ] && break; sleep 0.1; done
[ -S "$WORK/munge/munge.sock" ] || fail "munged did not start"

HOST=$(hostname -s)
export SLURM_CONF=$WORK/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=rondotest
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$WORK/munge/munge.sock
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MinJobAge=600
NodeName=rondo1 NodeAddr=127.0.0.1 NodeHostname=$HOST CPUs=2 State=UNKNOWN
PartitionName=test Nodes=rondo1 Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -i -f "$SLURM_CONF" >"$WORK/slurmctld.stdout" 2>&1 &
PIDS+=($!)
slurmd -D -N rondo1 -f "$SLURM_CONF" >"$WORK/slurmd.stdout" 2>&1 &
PIDS+=($!)
for _ in $(seq 60); do
  state=$(sinfo -h -n rondo1 -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || fail "the node did not come up (state: ${state:-none})"
echo "slurm up: node rondo1, 2 CPUs"

# waits until no job of ours is queued or running (at most $1 seconds)
wait_idle() {
  for _ in $(seq "$1"); do
    [ -z "$(squeue -h -o %i 2>/dev/null)" ] && return 0
    sleep 1
  done
  squeue
  return 1
}

SIZE=(--width 40 --height 30 --sampler independent)
"$RONDO" farm slurm scenes/cornell.ron --spp 16 --tasks 4 "${SIZE[@]}" -o "$OUT/final.exr" \
  >"$WORK/render.sbatch"
grep -q -- '--array=0-3' "$WORK/render.sbatch" || fail "no --array=0-3 in the script"
cd "$OUT"
array=$(sbatch --parsable "$WORK/render.sbatch")
echo "submitted array job $array"
wait_idle 180 || fail "jobs still queued after 180 s"
[ -s final.exr ] || fail "no merged image"
ls "$OUT/final.parts" | grep -c '^part-.*\.exr$' | grep -qx 4 || fail "not 4 partials"

"$RONDO" render "$ROOT/scenes/cornell.ron" --spp 16 "${SIZE[@]}" -o "$WORK/single.exr" 2>/dev/null
"$RONDO" render "$ROOT/scenes/cornell.ron" --spp 16 "${SIZE[@]}" -o "$WORK/single.png" 2>/dev/null
"$RONDO" merge final.parts/part-*.exr -o "$WORK/merged.png" 2>/dev/null
cmp "$WORK/merged.png" "$WORK/single.png" || fail "merged PNG differs from the single render"
"$RONDO" diff final.exr "$WORK/single.exr" >"$WORK/diff.txt"
grep -Eq '^rmse +0(\.0+)?e0$' "$WORK/diff.txt" || fail "merged EXR differs: $(cat "$WORK/diff.txt")"
echo "ok: the Slurm merge equals the single-process render"

# A failing task: its partial's path is taken by a directory.
rm -rf final.parts final.exr ./*.out
mkdir -p final.parts/part-0002.exr
array=$(sbatch --parsable "$WORK/render.sbatch")
wait_idle 180 || fail "jobs still queued after 180 s (failure run)"
[ ! -e final.exr ] || fail "the merge ran although a task failed"
report=$(ls rondo-final-report-*.out 2>/dev/null | head -n 1)
[ -n "$report" ] || fail "no report job ran"
grep -q 'task 2 (samples 8..12) failed' "$report" || fail "report does not name task 2: $(cat "$report")"
all=$(grep -A1 '^or rerun them all' "$report" | tail -n 1)
[ "$(sh -c "sbatch() { printf '%s|' \"\$@\"; }; $all")" = "--array=2|$WORK/render.sbatch|" ] ||
  fail "report's sbatch command does not parse back: $all"
# The direct command, pasted into sh as printed: it renders the task's samples, and runs nothing
# the path holds.
direct=$(grep -A1 '^task 2 (samples 8..12) failed' "$report" | tail -n 1)
rmdir final.parts/part-0002.exr
sh -c "$direct" 2>/dev/null || fail "the report's direct command fails: $direct"
[ ! -e pwned ] && [ ! -e "$WORK/pwned" ] || fail "the report's direct command ran \$(touch pwned)"
"$RONDO" merge --allow-gaps final.parts/part-0002.exr -o "$WORK/part2.png" 2>/dev/null ||
  fail "the direct command wrote no partial"
rm final.parts/part-0002.exr
sbatch --parsable --array=2 "$WORK/render.sbatch" >/dev/null
wait_idle 180 || fail "jobs still queued after 180 s (rerun)"
[ -s final.exr ] || fail "no merged image after the rerun"
"$RONDO" diff final.exr "$WORK/single.exr" >"$WORK/diff.txt"
grep -Eq '^rmse +0(\.0+)?e0$' "$WORK/diff.txt" || fail "merged EXR after rerun differs"
echo "ok: a failed task is reported with its rerun command, and the rerun completes the merge"
echo "slurm: 2 passed, 0 failed"
