#!/usr/bin/env bash
# Runs deploy/slurm/mltfarm.sbatch on a one-node Slurm cluster started here (slurmctld + slurmd from
# Debian's slurm-wlm, munge authentication; see /work/shared/design/slurm-local.md), and checks that the
# image it produces is byte-identical to `mltfarm render` through the local farm with the same settings.
#   tests/farm/slurm_local_test.sh BUILD_TOOLS_DIR
# Exit 0: passed; 77: skipped (the daemons cannot run here, with the reason); anything else: failed.
set -euo pipefail
TOOLS=$(cd "${1:?usage: $0 BUILD/tools}" && pwd)
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
skip() { echo "SKIP: $*" >&2; exit 77; }

# --- setup: packages, munge ---------------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  [ "$(id -u)" = 0 ] || command -v sudo >/dev/null || skip "slurm-wlm/munge not installed and no root to install them"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
  export DEBIAN_FRONTEND=noninteractive
  ($SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends slurm-wlm munge) >/dev/null 2>&1 ||
    skip "apt-get install slurm-wlm munge failed (no package mirror reachable?)"
fi
[ "$(id -u)" = 0 ] || skip "the local Slurm daemons run as root (SlurmUser=root) and this is not root"

WORK=$(mktemp -d /tmp/mltfarm-slurm-XXXXXX)
CONF=$WORK/slurm.conf
export SLURM_CONF=$CONF
cleanup() {
  for pidfile in "$WORK/slurmd.pid" "$WORK/slurmctld.pid"; do
    [ -f "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null || true
  done
  # munged only if this script started it (by its pid file).
  [ "${STARTED_MUNGE:-0}" = 1 ] && [ -f /run/munge/munged.pid ] && kill "$(cat /run/munge/munged.pid)" 2>/dev/null || true
  sleep 1
  if [ "${KEEP:-0}" = 0 ]; then rm -rf "$WORK"; else echo "kept $WORK" >&2; fi
}
trap cleanup EXIT

if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  [ -f /etc/munge/munge.key ] || { mungekey -c 2>/dev/null || create-munge-key 2>/dev/null || true; }
  mkdir -p /run/munge && chown munge:munge /run/munge 2>/dev/null || true
  chown munge:munge /etc/munge/munge.key 2>/dev/null || true
  STARTED_MUNGE=1
  su -s /bin/sh munge -c "munged --force" 2>"$WORK/munged.err" || munged --force 2>>"$WORK/munged.err" || true
  for _ in $(seq 1 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.1; done
  munge -n | unmunge >/dev/null 2>&1 || skip "munged does not start: $(cat "$WORK/munged.err")"
fi

# --- a one-node cluster ---------------------------------------------------------------------------
HOST=$(hostname -s)
CPUS=$(nproc)
MEM=$(( $(free -m | awk '/^Mem:/{print $2}') * 9 / 10 ))
mkdir -p "$WORK/state" "$WORK/spool"
cat >"$CONF" <<CONF
ClusterName=mltfarmtest
SlurmctldHost=$HOST
AuthType=auth/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$HOST CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -f "$CONF" || skip "slurmctld does not start: $(tail -3 "$WORK/slurmctld.log" 2>/dev/null)"
slurmd -f "$CONF" || skip "slurmd does not start: $(tail -3 "$WORK/slurmd.log" 2>/dev/null)"
for _ in $(seq 1 100); do
  sinfo -h -o %t 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o %t | grep -q idle || skip "the node never became idle: $(sinfo 2>&1 | tail -2)"

# --- the farm under Slurm -------------------------------------------------------------------------
SETTINGS=(--method pssmlt --width 32 --height 32 --mutations-per-pixel 8 --chains 16 --bootstrap 4000
          --seed 11 --max-depth 4 --spp 8)
cd "$WORK"
MLTFARM_BIN=$TOOLS MLTFARM_PORT=$((20000 + RANDOM % 20000)) \
  sbatch --wait --ntasks=2 --cpus-per-task=1 --output="$WORK/job.out" \
  "$ROOT/deploy/slurm/mltfarm.sbatch" "$ROOT/scenes/cornell-box.xml" "$WORK/slurm.exr" "${SETTINGS[@]}" ||
  { cat "$WORK/job.out" >&2; cat "$WORK"/mltfarm-state-*/coordinator.log >&2 || true; exit 1; }
cat "$WORK/job.out"
[ -s "$WORK/slurm.exr" ] && [ -s "$WORK/slurm.png" ] || { echo "FAIL: no image from the Slurm job" >&2; exit 1; }
grep -q "event=uploaded" "$WORK"/mltfarm-state-*/workers.log || { echo "FAIL: no worker uploaded" >&2; exit 1; }

# The same job on the local farm gives the same bytes.
"$TOOLS/mltfarm" render "$ROOT/scenes/cornell-box.xml" "${SETTINGS[@]}" --workers 1 -q -o "$WORK/local.exr"
cmp "$WORK/slurm.exr" "$WORK/local.exr" || { echo "FAIL: Slurm and local farm images differ" >&2; exit 1; }
echo "PASS: Slurm batch job (coordinator + srun worker steps) rendered the byte-identical image"
