#!/usr/bin/env bash
# A real Slurm cluster of one node on this machine, for the farm tests and for trying the
# templates of tools/farm/ by hand: Debian's slurmctld, slurmd and munge, without systemd.
#
#   tools/farm/local-slurm.sh start   # installs the packages if missing, starts munged,
#                                     # slurmctld and slurmd, waits until the node is idle,
#                                     # prints `export SLURM_CONF=...`
#   tools/farm/local-slurm.sh stop    # stops exactly the daemons `start` started
#   tools/farm/local-slurm.sh status
#
# Everything lives in one folder (APERTURE_SLURM_DIR, default /tmp/aperture-slurm-$UID): a
# private munge key and socket, slurm.conf, spool and state folders, logs, and `pids`, the
# process ids this script started. `stop` signals only those, and only while they still run
# the program they were started as. Nothing outside the folder is touched (no /etc, no
# system munged), so a machine's own Slurm, if it has one, is left alone.
#
# Why each setting: ProctrackType=proctrack/linuxproc and TaskPlugin=task/none need no
# cgroups (containers rarely delegate them); SchedulerParameters=batch_sched_delay=0 starts
# jobs without the default batching delay; DependencyParameters=kill_invalid_depend cancels a
# job whose afterok dependency can never be met (under SchedulerParameters it is silently
# ignored, and the merge of a failed array would stay pending forever).
set -euo pipefail

dir=${APERTURE_SLURM_DIR:-/tmp/aperture-slurm-$(id -u)}
ctld_port=${APERTURE_SLURMCTLD_PORT:-6817}
slurmd_port=${APERTURE_SLURMD_PORT:-6818}
conf=$dir/slurm.conf

log() { echo "local-slurm: $*" >&2; }

install_packages() {
    local missing=()
    for tool in slurmctld slurmd sbatch munged; do
        command -v "$tool" >/dev/null 2>&1 || PATH=$PATH:/usr/sbin command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    log "installing slurmctld slurmd slurm-client munge (missing: ${missing[*]})"
    if [ "$(id -u)" -ne 0 ]; then
        log "not root: install them with apt-get install slurmctld slurmd slurm-client munge"
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurmctld slurmd slurm-client munge >/dev/null
}

# Is process $1 alive and running program $2?
runs() {
    [ -n "$1" ] && [ -r "/proc/$1/comm" ] && [ "$(cat "/proc/$1/comm")" = "$2" ]
}

# The pid recorded for program $1, if any.
recorded() {
    [ -f "$dir/pids" ] && awk -v p="$1" '$1 == p { print $2 }' "$dir/pids" | tail -n 1
}

stop() {
    [ -f "$dir/pids" ] || { log "nothing recorded in $dir/pids: nothing to stop"; return 0; }
    # slurmd first (it may be running jobs), then the controller, then munge.
    for prog in slurmd slurmctld munged; do
        local pid
        pid=$(recorded "$prog")
        if runs "$pid" "$prog"; then
            kill -TERM "$pid"
            for _ in $(seq 50); do runs "$pid" "$prog" || break; sleep 0.1; done
            if runs "$pid" "$prog"; then
                log "$prog ($pid) ignored TERM for 5 s: KILL"
                kill -KILL "$pid"
            fi
            log "stopped $prog ($pid)"
        fi
    done
    rm -f "$dir/pids"
}

write_conf() {
    local cpus
    cpus=$(nproc)
    cat >"$conf" <<EOF
# Written by tools/farm/local-slurm.sh: one node, this machine, no systemd, no cgroups.
ClusterName=aperture
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=farm Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
}

start() {
    install_packages
    export PATH=$PATH:/usr/sbin
    if [ -f "$dir/pids" ] && runs "$(recorded slurmctld)" slurmctld; then
        log "already running (see $dir/pids)"
        echo "export SLURM_CONF=$conf"
        return 0
    fi
    mkdir -p "$dir"
    chmod 700 "$dir"
    rm -rf "$dir/state" "$dir/spool" "$dir/munge"
    mkdir -p "$dir/state" "$dir/spool" "$dir/log" "$dir/munge"
    chmod 700 "$dir/munge"
    : >"$dir/pids"
    # On any failure below, stop what was started so far.
    trap 'log "start failed; logs in $dir/log"; stop' ERR

    dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$dir/munge/munge.key"
    munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" \
        --seed-file="$dir/munge/munged.seed"
    echo "munged $(cat "$dir/munge/munged.pid")" >>"$dir/pids"

    write_conf
    export SLURM_CONF=$conf
    slurmctld -i -f "$conf"
    wait_for_file "$dir/slurmctld.pid" slurmctld
    echo "slurmctld $(cat "$dir/slurmctld.pid")" >>"$dir/pids"
    slurmd -N localhost -f "$conf"
    wait_for_file "$dir/slurmd.pid" slurmd
    echo "slurmd $(cat "$dir/slurmd.pid")" >>"$dir/pids"

    local t0=$SECONDS
    until sinfo -h -N -o '%t' 2>/dev/null | grep -qx idle; do
        if [ $((SECONDS - t0)) -ge 60 ]; then
            log "the node is not idle after 60 s: $(sinfo -h -N -o '%t %E' 2>&1)"
            false
        fi
        sleep 0.2
    done
    trap - ERR
    log "idle after $((SECONDS - t0)) s; daemons: $(tr '\n' ' ' <"$dir/pids")"
    echo "export SLURM_CONF=$conf"
}

# Waits up to 10 s for the pid file $1 of program $2.
wait_for_file() {
    for _ in $(seq 100); do
        [ -s "$1" ] && runs "$(cat "$1")" "$2" && return 0
        sleep 0.1
    done
    log "$2 did not start: $(tail -n 5 "$dir/log/$2.log" 2>/dev/null)"
    return 1
}

status() {
    if [ -f "$dir/pids" ]; then
        while read -r prog pid; do
            if runs "$pid" "$prog"; then echo "$prog $pid running"; else echo "$prog $pid gone"; fi
        done <"$dir/pids"
        SLURM_CONF=$conf sinfo -N 2>&1 || true
    else
        echo "not started (no $dir/pids)"
    fi
}

case "${1:-}" in
start) start ;;
stop) stop ;;
status) status ;;
*)
    echo "usage: $0 start|stop|status" >&2
    exit 2
    ;;
esac
