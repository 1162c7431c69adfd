#!/usr/bin/env bash
# Starts a single-node Slurm on this machine (Debian slurm-wlm: munged, slurmctld and slurmd on
# localhost) so `tomodem run export slurm` scripts can be submitted for real, and the e2e test
# Slurm.SubmittedArrayAndGatherRunEachStepOnce runs instead of skipping. Needs root. Idempotent:
# does nothing when `sinfo` already answers. Stop with: kill $(cat /run/slurmd.pid /run/slurmctld.pid).
set -euo pipefail
if sinfo -h >/dev/null 2>&1; then sinfo; exit 0; fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
host=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
mkdir -p /var/lib/slurm/slurmctld /var/lib/slurm/slurmd /var/log/slurm /run/munge
chown munge:munge /run/munge
chown -R slurm:slurm /var/lib/slurm /var/log/slurm
# No cgroups (containers rarely delegate them): processes are tracked through /proc.
cat > /etc/slurm/slurm.conf <<CONF
ClusterName=tomodem
SlurmctldHost=${host}(127.0.0.1)
AuthType=auth/munge
SlurmUser=slurm
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
StateSaveLocation=/var/lib/slurm/slurmctld
SlurmdSpoolDir=/var/lib/slurm/slurmd
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=${host} NodeAddr=127.0.0.1 CPUs=${cpus} RealMemory=${mem} State=UNKNOWN
PartitionName=debug Nodes=${host} Default=YES MaxTime=INFINITE State=UP
CONF
pgrep -x munged >/dev/null || su -s /bin/sh munge -c /usr/sbin/munged
pgrep -x slurmctld >/dev/null || /usr/sbin/slurmctld
sleep 2
pgrep -x slurmd >/dev/null || /usr/sbin/slurmd
for _ in $(seq 20); do sinfo -h -o %T 2>/dev/null | grep -Eq '^(idle|mixed)' && break; sleep 1; done
sinfo
