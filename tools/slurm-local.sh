#!/bin/bash
# A single-host Slurm cluster for penumbra's farm tests and measurements:
# controller and compute node on 127.0.0.1, with munge, started as root
# without systemd (Debian 12: slurmctld slurmd slurm-client munge, installed
# by tools/setup.sh --tests).
#
#   tools/slurm-local.sh up      start munged, slurmctld, slurmd; wait for the node
#   tools/slurm-local.sh down    stop the daemons this script started (by PID)
#   tools/slurm-local.sh status  which daemons run, and sinfo
#
# What the set-up needs (found on Debian 12, Slurm 22.05): munged --force as
# the munge user with /run/munge owned by munge; proctrack/linuxproc and
# task/none (no cgroups), no accounting; select/cons_tres with CR_Core
# (CR_Core_Memory gives a job without --mem the whole node);
# batch_sched_delay=0 (the 3 s default spaces the waves of an array);
# kill_invalid_depend (a merge whose array failed is cancelled, not left
# pending); MailProg=/bin/true; the node line exactly as `slurmd -C` prints
# it. Killed daemons linger as zombies for a while, so a zombie counts as
# dead, and every munge client call has a timeout.
set -euo pipefail

state=/run/penumbra-slurm          # PIDs of the daemons this script started
conf=/etc/slurm/slurm.conf
marker="# written by penumbra tools/slurm-local.sh"

die() { echo "slurm-local.sh: $*" >&2; exit 1; }

# A PID is alive when /proc has it in a state other than Z (zombie) or X.
alive() {
  local pid=$1 st
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  st=$(sed 's/.*) //' "/proc/$pid/stat" 2>/dev/null | cut -d' ' -f1) || return 1
  [[ -n $st && $st != Z && $st != X ]]
}

pid_of() { [[ -r $1 ]] && cat "$1" 2>/dev/null || true; }

munge_ok() { timeout 5 munge -n 2>/dev/null | timeout 5 unmunge >/dev/null 2>&1; }

write_conf() {
  if [[ -e $conf ]] && ! grep -qF "$marker" "$conf"; then
    die "$conf exists and was not written by this script: not touching it"
  fi
  local node
  node=$(slurmd -C | head -n1)
  [[ $node == NodeName=* ]] || die "slurmd -C printed no node line: $node"
  mkdir -p "$(dirname "$conf")"
  cat > "$conf" <<CONF
$marker
ClusterName=penumbra-local
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmUser=slurm
AuthType=auth/munge
SlurmctldPidFile=/run/slurm/slurmctld.pid
SlurmdPidFile=/run/slurm/slurmd.pid
StateSaveLocation=/var/lib/slurm/slurmctld
SlurmdSpoolDir=/var/lib/slurm/slurmd
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
MailProg=/bin/true
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
$node NodeAddr=127.0.0.1
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
}

up() {
  [[ $(id -u) == 0 ]] || die "run as root"
  for c in munged munge unmunge slurmctld slurmd sinfo; do
    command -v "$c" >/dev/null || die "$c not found: run tools/setup.sh --tests"
  done
  mkdir -p "$state"
  # munge: a key, /run/munge owned by munge, munged --force as munge.
  if ! munge_ok; then
    if [[ ! -s /etc/munge/munge.key ]]; then
      mkdir -p /etc/munge
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
    chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    runuser -u munge -- munged --force
    for _ in $(seq 50); do munge_ok && break; sleep 0.1; done
    munge_ok || die "munged did not come up (see /var/log/munge/munged.log)"
    pid_of /run/munge/munged.pid > "$state/munged.pid"
  fi
  write_conf
  mkdir -p /run/slurm /var/log/slurm /var/lib/slurm/slurmctld /var/lib/slurm/slurmd
  chown slurm:slurm /run/slurm /var/log/slurm /var/lib/slurm/slurmctld
  if ! alive "$(pid_of /run/slurm/slurmctld.pid)"; then
    slurmctld
    for _ in $(seq 50); do alive "$(pid_of /run/slurm/slurmctld.pid)" && break; sleep 0.1; done
    pid_of /run/slurm/slurmctld.pid > "$state/slurmctld.pid"
  fi
  if ! alive "$(pid_of /run/slurm/slurmd.pid)"; then
    slurmd
    for _ in $(seq 50); do alive "$(pid_of /run/slurm/slurmd.pid)" && break; sleep 0.1; done
    pid_of /run/slurm/slurmd.pid > "$state/slurmd.pid"
  fi
  # Ready when the node is idle (or mixed/allocated by earlier jobs).
  for _ in $(seq 200); do
    case $(timeout 5 sinfo -h -o %T 2>/dev/null | head -n1) in
      idle*|mix*|alloc*) status; return 0 ;;
    esac
    sleep 0.1
  done
  status
  die "the node did not become idle (see /var/log/slurm/)"
}

down() {
  local d pid
  for d in slurmd slurmctld munged; do
    pid=$(pid_of "$state/$d.pid")
    if alive "$pid" && [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$d" ]]; then
      kill "$pid"
      for _ in $(seq 100); do alive "$pid" || break; sleep 0.1; done
      alive "$pid" && kill -9 "$pid"
      echo "stopped $d ($pid)"
    fi
    rm -f "$state/$d.pid"
  done
}

status() {
  local d f pid
  for d in munged slurmctld slurmd; do
    case $d in munged) f=/run/munge/munged.pid ;; *) f=/run/slurm/$d.pid ;; esac
    pid=$(pid_of "$f")
    if alive "$pid"; then echo "$d: running ($pid)"; else echo "$d: not running"; fi
  done
  timeout 5 sinfo 2>/dev/null || echo "sinfo: no controller"
}

case ${1:-} in
  up) up ;;
  down) down ;;
  status) status ;;
  *) echo "usage: tools/slurm-local.sh up|down|status" >&2; exit 2 ;;
esac
