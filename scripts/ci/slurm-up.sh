#!/usr/bin/env bash
# Starts a single-node Slurm cluster on this host for the tests of `twopass slurm`
# (crates/twopass/tests/slurm.rs): munged, `slurmctld -D` and `slurmd -D` with a slurm.conf
# generated for this host (its short hostname, CPUs=2, RealMemory from /proc/meminfo). Installs
# nothing: Debian's slurmctld, slurmd, slurm-client and munge must be installed (.ci/run does).
# Runs as root (the daemons and the test jobs run as root). Idempotent: a cluster already up is
# left as it is. State, logs and the PID files go to $TWOPASS_SLURM_STATE
# (default /tmp/twopass-slurm); the configuration to $SLURM_CONF (default
# /etc/slurm/slurm.conf, where the client commands look for it).
set -euo pipefail

state=${TWOPASS_SLURM_STATE:-/tmp/twopass-slurm}
conf=${SLURM_CONF:-/etc/slurm/slurm.conf}
export SLURM_CONF="${conf}"

for tool in munged slurmctld slurmd sinfo sbatch; do
  if ! command -v "${tool}" >/dev/null; then
    echo "slurm-up: ${tool} not found; install slurmctld slurmd slurm-client munge" >&2
    exit 1
  fi
done

if sinfo -h -o %T 2>/dev/null | grep -Eq '^(idle|mixed|allocated)'; then
  echo "slurm-up: a cluster is already up (${conf})"
  exit 0
fi

host=$(hostname -s)
mem_mib=$(awk '/^MemTotal:/ { print int($2 / 1024) }' /proc/meminfo)
mkdir -p "${state}/ctld" "${state}/d" "$(dirname "${conf}")"

# Process tracking by /proc and no task plugin: a container has no cgroup hierarchy for
# Slurm. config_overrides: the node is what this file says (2 CPUs), whatever the hardware.
cat >"${conf}" <<CONF
ClusterName=twopass
SlurmctldHost=${host}
AuthType=auth/munge
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
StateSaveLocation=${state}/ctld
SlurmdSpoolDir=${state}/d
SlurmctldPidFile=${state}/slurmctld.pid
SlurmdPidFile=${state}/slurmd.pid
SlurmctldLogFile=${state}/slurmctld.log
SlurmdLogFile=${state}/slurmd.log
SlurmctldTimeout=30
SlurmdTimeout=30
MinJobAge=600
NodeName=${host} CPUs=2 RealMemory=${mem_mib} State=UNKNOWN
PartitionName=debug Nodes=${host} Default=YES MaxTime=INFINITE State=UP
CONF

# munged: its key comes with Debian's package; it runs as the munge user.
if ! pgrep -x munged >/dev/null; then
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  if [[ ! -s /etc/munge/munge.key ]]; then
    mungekey --create --keyfile=/etc/munge/munge.key
    chown munge:munge /etc/munge/munge.key
  fi
  runuser -u munge -- munged
fi

# The daemons in the foreground (-D), detached from this shell, logging into the state folder.
nohup slurmctld -D -f "${conf}" >"${state}/slurmctld.out" 2>&1 &
echo $! >"${state}/slurmctld.launcher.pid"
nohup slurmd -D -f "${conf}" >"${state}/slurmd.out" 2>&1 &
echo $! >"${state}/slurmd.launcher.pid"

# Up when the node takes jobs: at most 60 s.
for _ in $(seq 60); do
  if sinfo -h -o %T 2>/dev/null | grep -Eq '^(idle|mixed|allocated)'; then
    echo "slurm-up: ${host} up with 2 CPUs and ${mem_mib} MiB (${conf}, logs in ${state})"
    exit 0
  fi
  sinfo -h -o %T 2>/dev/null | grep -Eq '^(down|drain)' &&
    scontrol update nodename="${host}" state=resume 2>/dev/null || true
  sleep 1
done
echo "slurm-up: the node did not come up in 60 s; see ${state}/*.log" >&2
sinfo >&2 || true
tail -n 20 "${state}"/slurmctld.log "${state}"/slurmd.log >&2 || true
exit 1
