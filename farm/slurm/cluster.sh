#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for trying and testing glint's
# job array (farm/slurm/render.sbatch) without a real cluster:
#
#   farm/slurm/cluster.sh start    # install (Debian's slurm-wlm and munge) and start; idempotent
#   export SLURM_CONF=/tmp/glint-slurm/slurm.conf
#   sinfo                          # the node "localhost", idle
#   farm/slurm/cluster.sh stop
#
# Everything it writes (configuration, munge key and socket, state, logs) lies
# in one folder, $GLINT_SLURM_DIR (default /tmp/glint-slurm); it needs root (or
# sudo) for its packages and daemons, as Slurm's daemons do. No systemd needed.
# Arrays may have up to 100,001 tasks here (MaxArraySize; Slurm's default is 1,001).
set -euo pipefail

dir=${GLINT_SLURM_DIR:-/tmp/glint-slurm}
export SLURM_CONF=$dir/slurm.conf
as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

install() {
  local missing=()
  for p in slurm-wlm munge; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  if [ ${#missing[@]} -gt 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    as_root apt-get update -qq
    as_root apt-get install -y -qq "${missing[@]}" >/dev/null
  fi
}

configure() {
  mkdir -p "$dir/state" "$dir/spool" "$dir/log"
  chmod 700 "$dir"
  [ -f "$dir/munge.key" ] || { head -c 1024 /dev/urandom > "$dir/munge.key"; chmod 400 "$dir/munge.key"; }
  local cpus memory
  cpus=$(nproc)
  # Leave 2 GiB of the machine to everything else.
  memory=$(awk '/MemTotal/ { m = int($2 / 1024) - 2048; print (m > 1024 ? m : 1024) }' /proc/meminfo)
  cat > "$SLURM_CONF" <<CONF
ClusterName=glint
SlurmctldHost=localhost
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldPort=${GLINT_SLURM_PORT:-6817}
SlurmdPort=$(( ${GLINT_SLURM_PORT:-6817} + 1 ))
MinJobAge=600
MaxArraySize=100001
NodeName=localhost CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
}

# Whether the daemon of pid file $1 (named $2) runs.
alive() { [ -f "$1" ] && [ "$(ps -p "$(cat "$1" 2>/dev/null)" -o comm= 2>/dev/null)" = "$2" ]; }

# Whether its controller runs and answers (scontrol alone waits a minute
# where no configuration or controller exists yet).
running() {
  alive "$dir/slurmctld.pid" slurmctld && scontrol ping 2>/dev/null | grep -q "is UP"
}

start() {
  install
  if running; then
    echo "slurm: already running ($SLURM_CONF)"
    return
  fi
  configure
  # Each daemon not already running (after a start cut short) is started.
  alive "$dir/munged.pid" munged ||
    as_root munged --key-file="$dir/munge.key" --socket="$dir/munge.socket" --pid-file="$dir/munged.pid" \
      --log-file="$dir/log/munged.log" --seed-file="$dir/munged.seed" --force
  alive "$dir/slurmctld.pid" slurmctld || as_root slurmctld -f "$SLURM_CONF"
  alive "$dir/slurmd.pid" slurmd || as_root slurmd -f "$SLURM_CONF"
  # Up within a few seconds; the node idle once slurmd has registered.
  for _ in $(seq 1 60); do
    if running && sinfo -h -o %t 2>/dev/null | grep -q idle; then
      echo "slurm: up ($SLURM_CONF): $(sinfo -h -o '%P %D node, %c CPUs, %t')"
      return
    fi
    sleep 0.5
  done
  echo "slurm: did not come up; logs in $dir/log" >&2
  tail -n 20 "$dir"/log/*.log >&2 || true
  return 1
}

daemons=(slurmd slurmctld munged)

stop() {
  if running; then as_root scontrol shutdown >/dev/null 2>&1 || true; fi
  # Only a pid file's own daemon is stopped (a stale file's number may be another process's now).
  for name in "${daemons[@]}"; do
    if alive "$dir/$name.pid" "$name"; then as_root kill "$(cat "$dir/$name.pid" 2>/dev/null)" 2>/dev/null || true; fi
  done
  # All gone within a few seconds (so a start right after finds munge's socket free); the folder keeps the logs.
  for _ in $(seq 1 40); do
    local left=0
    for name in "${daemons[@]}"; do alive "$dir/$name.pid" "$name" && left=1; done
    if [ "$left" = 0 ]; then
      echo "slurm: stopped"
      return
    fi
    sleep 0.25
  done
  echo "slurm: a daemon is still running after stop (pid files in $dir)" >&2
  return 1
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) if running; then sinfo; else echo "slurm: not running"; exit 1; fi ;;
  *) echo "usage: $0 start|stop|status" >&2; exit 2 ;;
esac
