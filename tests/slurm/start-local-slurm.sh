#!/usr/bin/env bash
# Start a single-node SLURM cluster on this machine (Debian's slurm-wlm and
# munge; installed if missing): controller and compute daemon on localhost,
# one partition `debug` with every CPU. Needs root (or sudo). Idempotent:
# daemons already running are kept. Exit status 0 once `sinfo` shows the
# node up; non-zero, with the reason on stderr, otherwise.
set -euo pipefail
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo -n "$@"; fi; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  as_root apt-get install -y -q slurm-wlm munge >/dev/null 2>&1 \
    || { as_root apt-get update -q >/dev/null && as_root apt-get install -y -q slurm-wlm munge >/dev/null; }
fi

host=$(hostname -s)
as_root mkdir -p /etc/munge /run/munge /var/log/munge /var/lib/munge \
  /var/spool/slurmd /var/spool/slurmctld /var/log/slurm /etc/slurm
if ! as_root test -s /etc/munge/munge.key; then
  as_root dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
as_root chown -R munge:munge /etc/munge /run/munge /var/log/munge /var/lib/munge
as_root chmod 700 /etc/munge
as_root chmod 400 /etc/munge/munge.key
pgrep -x munged >/dev/null || as_root su -s /bin/sh munge -c /usr/sbin/munged

as_root tee /etc/slurm/slurm.conf >/dev/null <<CONF
# Written by tests/slurm/start-local-slurm.sh (irtp): one node, localhost.
ClusterName=irtp-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SlurmdSpoolDir=/var/spool/slurmd
StateSaveLocation=/var/spool/slurmctld
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
ReturnToService=2
MaxArraySize=1001
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
CONF

pgrep -x slurmctld >/dev/null || as_root slurmctld
pgrep -x slurmd >/dev/null || as_root slurmd
for _ in $(seq 1 60); do
  if sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then
    sinfo
    exit 0
  fi
  sleep 1
done
echo "start-local-slurm: the node did not come up; sinfo says:" >&2
sinfo >&2 || true
tail -n 20 /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log >&2 || true
exit 1
