#!/usr/bin/env bash
# Start a single-node SLURM cluster on this machine (Debian's slurm-wlm and
# munge; installed if missing): controller and compute daemon on localhost,
# one partition `debug` with every CPU. Needs root (or sudo).
#
# The cluster keeps its state in directories of its own
# (/var/spool/irtp-slurm, logs in /var/log/irtp-slurm), emptied at each fresh
# start, so state left by another SLURM setup on the machine (a different
# ClusterName makes slurmctld refuse to start) cannot get in the way. A
# cluster of ours already up is kept; any other running slurmctld or slurmd
# is stopped first.
#
# MaxArraySize is set low (IRTP_SLURM_MAX_ARRAY, default 11) so that the
# sweep test's plans need several arrays, as a plan larger than a real
# cluster's MaxArraySize does.
#
# Exit status 0 once `sinfo` shows the node up; non-zero otherwise, with the
# failing step and the daemons' logs on stderr (the daemons themselves log
# only to their files).
set -euo pipefail
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo -n "$@"; fi; }
cluster=irtp-local
spool=/var/spool/irtp-slurm
logs=/var/log/irtp-slurm
max_array=${IRTP_SLURM_MAX_ARRAY:-11}

diagnose() {
  echo "start-local-slurm: failed at line $1: $2" >&2
  echo "start-local-slurm: uid $(id -u), host $(hostname 2>/dev/null || echo '?')" >&2
  as_root tail -n 20 "$logs/slurmctld.log" "$logs/slurmd.log" >&2 2>/dev/null || true
}
trap 'diagnose $LINENO "$BASH_COMMAND"' ERR

node_up() { sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; }
ours_up() {
  pgrep -x slurmctld >/dev/null && pgrep -x slurmd >/dev/null \
    && scontrol show config 2>/dev/null | grep -qE "^ClusterName += $cluster\$" \
    && scontrol show config 2>/dev/null | grep -qE "^MaxArraySize += $max_array\$" && node_up
}

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  as_root apt-get install -y -q slurm-wlm munge >/dev/null 2>&1 \
    || { as_root apt-get update -q >/dev/null && as_root apt-get install -y -q slurm-wlm munge >/dev/null; }
fi

as_root mkdir -p /etc/munge /run/munge /var/log/munge /var/lib/munge /etc/slurm
if ! as_root test -s /etc/munge/munge.key; then
  as_root dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
as_root chown -R munge:munge /etc/munge /run/munge /var/log/munge /var/lib/munge
as_root chmod 700 /etc/munge
as_root chmod 400 /etc/munge/munge.key
pgrep -x munged >/dev/null || as_root su -s /bin/sh munge -c /usr/sbin/munged

if ours_up; then
  sinfo
  exit 0
fi

# Not ours, or not up: stop whatever runs and start clean.
as_root pkill -x slurmctld || true
as_root pkill -x slurmd || true
for _ in $(seq 1 50); do
  pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null || break
  sleep 0.1
done
as_root rm -rf "$spool" "$logs"
as_root mkdir -p "$spool/ctld" "$spool/d" "$logs"

host=$(hostname -s)
as_root tee /etc/slurm/slurm.conf >/dev/null <<CONF
# Written by tests/slurm/start-local-slurm.sh (irtp): one node, localhost.
ClusterName=$cluster
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SlurmdSpoolDir=$spool/d
StateSaveLocation=$spool/ctld
SlurmctldLogFile=$logs/slurmctld.log
SlurmdLogFile=$logs/slurmd.log
SlurmctldPidFile=$spool/slurmctld.pid
SlurmdPidFile=$spool/slurmd.pid
ReturnToService=2
MaxArraySize=$max_array
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
CONF

as_root slurmctld
as_root slurmd
for _ in $(seq 1 60); do
  if node_up; then
    sinfo
    exit 0
  fi
  sleep 1
done
echo "start-local-slurm: the node did not come up in 60 s; sinfo says:" >&2
sinfo >&2 || true
as_root tail -n 20 "$logs/slurmctld.log" "$logs/slurmd.log" >&2 || true
exit 1
