#!/usr/bin/env bash
# A real single-node Slurm cluster on this machine, from Debian's packages, for tests and
# trials: munged, slurmctld and slurmd, without systemd, everything under one folder.
#
#   scripts/slurm/local-cluster.sh start   # installs the packages if missing, prints
#                                          # the line to export: SLURM_CONF=...
#   scripts/slurm/local-cluster.sh stop    # stops the daemons it started, by PID
#
# Needs root (the packages, and munged runs as the munge user). The folder is
# $P3TRACE_SLURM_DIR (default /tmp/p3trace-slurm); its slurm.conf is what clients need
# (SLURM_CONF). The ports are $P3TRACE_SLURM_PORT and the next one (default 6817, 6818).
set -euo pipefail

dir=${P3TRACE_SLURM_DIR:-/tmp/p3trace-slurm}
port=${P3TRACE_SLURM_PORT:-6817}
conf=$dir/etc/slurm.conf
say() { echo "local-cluster: $*" >&2; }
die() { say "$*"; exit 1; }

# The daemons started, as name:pid-file; stop kills exactly these PIDs.
pid_files=("slurmd:$dir/run/slurmd.pid" "slurmctld:$dir/run/slurmctld.pid" "munged:$dir/munge/munged.pid")

install_packages() {
  local missing=()
  command -v munged >/dev/null || missing+=(munge)
  command -v slurmctld >/dev/null || missing+=(slurmctld)
  command -v slurmd >/dev/null || missing+=(slurmd)
  command -v sbatch >/dev/null || missing+=(slurm-client)
  [ ${#missing[@]} -eq 0 ] && return
  command -v apt-get >/dev/null || die "no apt-get to install ${missing[*]}"
  say "installing ${missing[*]}"
  apt-get update -qq
  # policy-rc.d-free: nothing starts a daemon here (no systemd); we start our own.
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
}

running() { # running PID-FILE: true when the file names a live process
  [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null
}

start() {
  [ "$(id -u)" -eq 0 ] || die "must run as root (packages, munge user)"
  for entry in "${pid_files[@]}"; do
    running "${entry#*:}" && die "${entry%%:*} already runs from $dir: stop first"
  done
  install_packages
  # Only what an earlier start made: the folder may be anywhere.
  rm -rf "${dir:?}"/{etc,run,log,state,spool,munge}
  mkdir -p "$dir"/{etc,run,log,state,spool,munge}
  chmod 755 "$dir"
  # munged refuses to run as root with its key: it runs as munge, in its own folder.
  if [ ! -s /etc/munge/munge.key ]; then
    if command -v mungekey >/dev/null; then mungekey --create --force;
    else dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none; fi
  fi
  chown munge:munge /etc/munge/munge.key "$dir/munge"
  chmod 400 /etc/munge/munge.key
  chmod 755 "$dir/munge"
  runuser -u munge -- munged --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed"
  local host node
  host=$(hostname -s)
  # The node as slurmd sees it (CPUs, sockets, cores, memory), reachable on loopback.
  node=$(slurmd -C | head -1)
  cat > "$conf" <<CONF
ClusterName=p3trace
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
MaxArraySize=4097
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$conf
  slurmctld -f "$conf" -c   # -c: a clean start, no state from an earlier cluster
  slurmd -f "$conf"
  # Up when the node is idle; then one probe job, since the first job after slurmctld
  # starts waits for its first scheduling pass.
  local i state
  for i in $(seq 1 100); do
    state=$(sinfo -h -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.2
  done
  [ "$state" = idle ] || die "the node did not come up (state '$state'); see $dir/log"
  local probe
  probe=$(sbatch --parsable -o /dev/null --wrap true)
  for i in $(seq 1 300); do
    squeue -h -j "$probe" 2>/dev/null | grep -q . || break
    sleep 0.2
  done
  say "up: $host, $(sinfo -h -o '%c CPUs') in partition main"
  echo "export SLURM_CONF=$conf"
}

stop() {
  local entry name file pid
  # The cluster's jobs first, so that no job step outlives its slurmd.
  if running "$dir/run/slurmctld.pid"; then
    export SLURM_CONF=$conf
    scancel --quiet --user=root 2>/dev/null || true
    for _ in $(seq 1 100); do
      squeue -h 2>/dev/null | grep -q . || break
      sleep 0.1
    done
  fi
  for entry in "${pid_files[@]}"; do
    name=${entry%%:*} file=${entry#*:}
    running "$file" || continue
    pid=$(cat "$file")
    kill "$pid"
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then kill -9 "$pid"; fi
    say "stopped $name ($pid)"
  done
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  *) echo "usage: $0 start|stop" >&2; exit 2 ;;
esac
