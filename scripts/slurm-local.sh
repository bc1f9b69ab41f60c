#!/usr/bin/env bash
# A single-node Slurm cluster on this machine (localhost), for CI and for trying the
# SLURM profile (workflow/profiles/slurm) without a real cluster.
#
#   scripts/slurm-local.sh [start]   install (Debian slurm-wlm, munge) if missing, configure,
#                                    start munged, slurmctld, slurmd; wait for an idle node
#   scripts/slurm-local.sh stop      stop the three daemons started here
#   scripts/slurm-local.sh status    print sinfo / squeue
#   scripts/slurm-local.sh down      exit 0 when this script's cluster is configured here but
#                                    its controller is not running (after a reboot, a stop)
#
# Idempotent: when the cluster already answers, `start` returns in well under a second.
# Needs root (it installs packages, writes /etc/slurm/slurm.conf and runs the daemons).
# The cluster: controller and the only node are this host (NodeAddr 127.0.0.1), CPUs and
# RealMemory from nproc and /proc/meminfo, one partition "local", no accounting storage (so
# no sacct: the profile queries job states with squeue), no cgroups (proctrack/linuxproc).
# Exit status != 0 with an ERROR line when the cluster does not start. Under CI=true the
# Makefile's `test` target and tests/test_slurm.py fail the run on it (outside CI the Slurm
# tests skip, naming the reason). Cost on a fresh Debian 12 (bookworm) machine: installing
# the 8 packages (3.5 MB) and starting took 8 s (apt lists already fetched by
# scripts/setup.sh; an apt-get update on empty lists adds ~6 s).
set -euo pipefail

PARTITION="${SSW_SLURM_PARTITION:-local}"
CONF_DIR=/etc/slurm
CONF="$CONF_DIR/slurm.conf"
STATE=/var/spool/slurmctld
SPOOL=/var/spool/slurmd
LOGDIR=/var/log/slurm
RUNDIR=/run/slurm
WAIT_S="${SSW_SLURM_WAIT_S:-60}"

say() { echo "[slurm-local] $*"; }
die() { echo "[slurm-local] ERROR: $*" >&2; exit 1; }

need_root() {
    if [ "$(id -u)" -ne 0 ]; then
        die "must run as root (it installs slurm-wlm/munge, writes $CONF and starts the daemons); \
try: sudo $0 ${1:-start}"
    fi
}

node_name() { hostname -s; }

# 0 when sinfo shows this host's node in a usable state (idle, mixed, allocated).
node_ready() {
    command -v sinfo >/dev/null 2>&1 || return 1
    local st
    st=$(timeout 5 sinfo -h -n "$(node_name)" -o '%T' 2>/dev/null | head -n1) || return 1
    case "$st" in
        idle*|mix*|alloc*|completing*) return 0 ;;
        *) return 1 ;;
    esac
}

install_packages() {
    local missing=()
    command -v slurmctld >/dev/null 2>&1 || missing+=(slurm-wlm)
    command -v munged >/dev/null 2>&1 || missing+=(munge)
    [ ${#missing[@]} -eq 0 ] && return 0
    say "installing ${missing[*]} from Debian"
    local t0=$SECONDS
    export DEBIAN_FRONTEND=noninteractive
    if ! apt-get install -y --no-install-recommends "${missing[@]}" >/tmp/slurm-local-apt.log 2>&1; then
        say "apt-get install failed; running apt-get update first"
        apt-get update >>/tmp/slurm-local-apt.log 2>&1 || die "apt-get update failed (see /tmp/slurm-local-apt.log)"
        apt-get install -y --no-install-recommends "${missing[@]}" >>/tmp/slurm-local-apt.log 2>&1 \
            || die "apt-get install ${missing[*]} failed (see /tmp/slurm-local-apt.log)"
    fi
    say "installed in $((SECONDS - t0)) s"
}

write_conf() {
    local node cpus mem
    node=$(node_name)
    # the CPUs this host gives processes; not OMP_NUM_THREADS / OMP_THREAD_LIMIT, which GNU
    # nproc honours (the test suite sets OMP_NUM_THREADS=1: a 1-CPU node would leave every
    # 2-rank MPI job pending)
    cpus=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
    # RealMemory (MiB): 90 % of the total, leaving room for the daemons and the OS. From
    # /proc/meminfo (kB): `free` is procps, which a minimal Debian image does not have.
    mem=$(awk '/^MemTotal:/ {printf "%d", $2 / 1024 * 0.9}' /proc/meminfo)
    [ -n "$mem" ] && [ "$mem" -gt 0 ] || die "cannot read MemTotal from /proc/meminfo"
    mkdir -p "$CONF_DIR" "$STATE" "$SPOOL" "$LOGDIR" "$RUNDIR"
    local tmp
    tmp=$(mktemp "$CONF_DIR/.slurm.conf.XXXXXX")
    cat >"$tmp" <<EOF
# Written by ssw scripts/slurm-local.sh: a single-node cluster on localhost.
ClusterName=ssw-local
SlurmctldHost=${node}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=${STATE}
SlurmdSpoolDir=${SPOOL}
SlurmctldPidFile=${RUNDIR}/slurmctld.pid
SlurmdPidFile=${RUNDIR}/slurmd.pid
SlurmctldLogFile=${LOGDIR}/slurmctld.log
SlurmdLogFile=${LOGDIR}/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
# No accounting storage: there is no sacct; query job states with squeue.
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
# Fast turnaround for tests.
SchedulerParameters=sched_interval=2
MessageTimeout=20
KillWait=5
MinJobAge=300
InactiveLimit=0
SlurmctldTimeout=30
SlurmdTimeout=60
DefMemPerCPU=1024
NodeName=${node} NodeAddr=127.0.0.1 CPUs=${cpus} RealMemory=${mem} State=UNKNOWN
PartitionName=${PARTITION} Nodes=${node} Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
    if [ -f "$CONF" ] && cmp -s "$tmp" "$CONF"; then
        rm -f "$tmp"
        return 1
    fi
    mv -f "$tmp" "$CONF"
    chmod 644 "$CONF"
    say "wrote $CONF (node ${node}: CPUs=${cpus}, RealMemory=${mem} MiB, partition ${PARTITION})"
    return 0
}

start_munge() {
    if [ ! -s /etc/munge/munge.key ]; then
        say "creating munge key"
        mkdir -p /etc/munge
        dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
    fi
    chown munge:munge /etc/munge /etc/munge/munge.key 2>/dev/null || true
    chmod 700 /etc/munge
    chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge 2>/dev/null || true
    if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        return 0
    fi
    say "starting munged"
    if id munge >/dev/null 2>&1; then
        runuser -u munge -- /usr/sbin/munged || /usr/sbin/munged --force
    else
        /usr/sbin/munged --force
    fi
    for _ in $(seq 1 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
        sleep 0.1
    done
    die "munged does not answer (munge -n | unmunge fails); see /var/log/munge/munged.log"
}

daemon_running() {  # $1: pid file
    [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null
}

start() {
    need_root start
    if [ -f "$CONF" ] && node_ready; then
        say "already running: $(sinfo -h -o '%P %D %T %C' | head -n1)"
        return 0
    fi
    install_packages
    local changed=0
    write_conf && changed=1
    start_munge
    if [ "$changed" = 1 ]; then
        stop_daemons quiet
    fi
    if ! daemon_running "$RUNDIR/slurmctld.pid"; then
        say "starting slurmctld"
        # -c: clear the saved state (jobs, node state) of an earlier run of this test cluster.
        /usr/sbin/slurmctld -c || die "slurmctld failed to start; see $LOGDIR/slurmctld.log"
    fi
    if ! daemon_running "$RUNDIR/slurmd.pid"; then
        say "starting slurmd"
        /usr/sbin/slurmd || die "slurmd failed to start; see $LOGDIR/slurmd.log"
    fi
    local t0=$SECONDS
    while ! node_ready; do
        if [ $((SECONDS - t0)) -ge "$WAIT_S" ]; then
            sinfo 2>&1 || true
            tail -n 20 "$LOGDIR/slurmctld.log" "$LOGDIR/slurmd.log" 2>/dev/null || true
            die "node $(node_name) not idle after ${WAIT_S} s"
        fi
        # A node left DOWN/DRAINED by an earlier run: resume it.
        scontrol update nodename="$(node_name)" state=resume >/dev/null 2>&1 || true
        sleep 0.5
    done
    say "ready: $(sinfo -h -o '%P %D %T %C' | head -n1) (partition/nodes/state/CPUs A/I/O/T)"
}

stop_one() {  # $1: name, $2: pid file
    local pidf=$2
    if daemon_running "$pidf"; then
        local pid
        pid=$(cat "$pidf")
        kill "$pid" 2>/dev/null || true
        for _ in $(seq 1 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        [ "${3:-}" = quiet ] || say "stopped $1 (pid $pid)"
    fi
}

stop_daemons() {
    stop_one slurmd "$RUNDIR/slurmd.pid" "${1:-}"
    stop_one slurmctld "$RUNDIR/slurmctld.pid" "${1:-}"
}

stop() {
    need_root stop
    stop_daemons
    if [ -f /run/munge/munged.pid ]; then
        stop_one munged /run/munge/munged.pid
    fi
}

# The cluster written by this script is installed and its controller is not running. Then
# every Snakemake start waits 10 s: its Slurm executor plugin asks `scontrol show config` on
# import, and scontrol retries the absent controller until the plugin's timeout. The Makefile
# points its Snakemake calls at an empty Slurm configuration then, which fails at once.
down() {
    [ -f "$CONF" ] && head -n1 "$CONF" | grep -q "Written by ssw scripts/slurm-local.sh" \
        && ! daemon_running "$RUNDIR/slurmctld.pid"
}

status() {
    command -v sinfo >/dev/null 2>&1 || die "Slurm is not installed (run: $0 start)"
    sinfo
    squeue
}

case "${1:-start}" in
    start) start ;;
    stop) stop ;;
    status) status ;;
    down) down ;;
    *) die "unknown subcommand '$1' (allowed: start, stop, status, down)" ;;
esac
