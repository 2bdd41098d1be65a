#!/bin/sh
# make check-farm: jobs/slurm-array.sh on a real Slurm cluster. Installs Debian's slurm-wlm and
# munge when missing (scripts/install-deps.sh --farm), starts a one-node cluster on this machine
# (munged, slurmctld, slurmd, a generated slurm.conf, everything in a temporary directory, as
# root), submits the demo as an array of 4 chunks, waits with a bounded timeout, and checks the
# frames are bit-identical to one process rendering them. It stops exactly the processes it
# started, by the PIDs recorded when it started them, also when it fails, and then checks that
# none of them (nor a job step) is left.
#
# Environment: RB_FARM_SIZE (default 160x90), RB_FARM_FRAMES (0-7), RB_FARM_TASKS (4),
# RB_FARM_TIMEOUT (seconds for the array job, 300), RB_FARM_PORTS ("CTLD SLURMD", the daemons'
# ports; by default two that tests/tools/freeport finds free when the cluster starts, chosen
# again when a daemon finds its port taken after all). The wall times of both renders are
# printed as "# wall" lines (make bench reads them).
. tests/integration/lib.sh

size=${RB_FARM_SIZE:-160x90}
frames=${RB_FARM_FRAMES:-0-7}
tasks=${RB_FARM_TASKS:-4}
limit=${RB_FARM_TIMEOUT:-300}
FREEPORT="$BUILD/tests/tools/freeport"

if [ "$(id -u)" != 0 ]; then
    skip "a Slurm array job renders the demo" "the cluster's daemons run as root; run as root"
    done_testing
fi
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
    ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    if ! scripts/install-deps.sh --farm >"$T/install.log" 2>&1; then
        skip "a Slurm array job renders the demo" \
            "cannot install slurm-wlm and munge: $(tail -n 1 "$T/install.log")"
        done_testing
    fi
fi

# The cluster: its files, and the processes started (PIDs recorded as each starts). Every
# process of the cluster carries RB_FARM_CLUSTER in its environment (the daemons, the step
# daemons slurmd forks, the tasks through sbatch's exported environment), which this shell
# does not: the final check finds any that outlived the stop.
# In /tmp rather than $T: munged wants every directory above its socket searchable by everyone
# (clients of any user connect), and a test run's TMPDIR is private.
D=$(mktemp -d /tmp/raybundle-farm.XXXXXX) || fail_all "a directory for the cluster"
chmod 0755 "$D"
mkdir -m 0700 "$D/state" "$D/spool"
pids=""
job=""

# stop: cancels the job, stops the daemons by PID (TERM, then KILL after 10 s); idempotent.
stop() {
    if [ -n "$job" ]; then
        scancel "$job" 2>/dev/null
        i=0
        while [ -n "$(squeue -h -j "$job" 2>/dev/null)" ] && [ $i -lt 100 ]; do
            sleep 0.2
            i=$((i + 1))
        done
        job=""
    fi
    for pid in $pids; do
        kill -TERM "$pid" 2>/dev/null
    done
    for pid in $pids; do
        i=0
        while kill -0 "$pid" 2>/dev/null && [ $i -lt 50 ]; do
            sleep 0.2
            i=$((i + 1))
        done
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    pids=""
}

# leftovers: the PIDs of processes that carry this cluster's mark.
leftovers() {
    for p in /proc/[0-9]*; do
        if tr '\0' '\n' 2>/dev/null <"$p/environ" | grep -qxF "RB_FARM_CLUSTER=$D"; then
            echo "${p#/proc/}"
        fi
    done
}

cleanup() {
    stop
    for pid in $(leftovers); do
        kill -KILL "$pid" 2>/dev/null
    done
    rm -rf "$T" "$D"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

# start NAME COMMAND...: runs a daemon in the foreground of a background job and records it.
start() {
    name=$1
    shift
    RB_FARM_CLUSTER="$D" "$@" >"$D/$name.out" 2>&1 &
    pids="$! $pids" # stopped in reverse order of starting
}

# wait_for SECONDS COMMAND...: polls COMMAND until it succeeds, or fails once SECONDS passed.
wait_for() {
    deadline=$(($(date +%s) + $1))
    shift
    while ! "$@" 2>/dev/null; do
        [ "$(date +%s)" -lt "$deadline" ] || return 1
        sleep 0.2
    done
}

# logs: the end of the cluster's logs, as TAP comments, to say why it failed.
logs() {
    for f in munged.out slurmctld.log slurmctld.out slurmd.log slurmd.out; do
        [ -s "$D/$f" ] && tail -n 15 "$D/$f" | sed "s/^/# $f: /"
    done
}

host=$(uname -n | cut -d. -f1)
cpus=$(nproc)
mem_mb=$(($(sed -n 's/^MemTotal: *\([0-9]*\) kB/\1/p' /proc/meminfo) / 1024 / 2))
export SLURM_CONF="$D/slurm.conf"

# configure CTLD_PORT SLURMD_PORT: writes slurm.conf. SlurmctldHost names this machine
# (slurmctld refuses to run on a host the file does not name) at 127.0.0.1; no cgroups
# (containers rarely delegate them), no accounting.
configure() {
    cat >"$SLURM_CONF" <<EOF
ClusterName=raybundle
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$1
SlurmdPort=$2
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$D/munge.sock
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/slurmctld.log
SlurmdLogFile=$D/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

# munged with its own key, socket, seed, log and PID file.
dd if=/dev/urandom of="$D/munge.key" bs=1024 count=1 2>/dev/null
chmod 0400 "$D/munge.key"
start munged munged --foreground --socket="$D/munge.sock" --key-file="$D/munge.key" \
    --seed-file="$D/munge.seed" --log-file="$D/munged.log" --pid-file="$D/munged.pid"
if ! wait_for 20 test -S "$D/munge.sock"; then
    logs
    fail_all "munged starts"
fi
ok "munged starts"

# The daemons' ports: free when freeport chose them, but another program may bind one before
# its daemon does. A daemon that finds its port taken says so in its log and exits; then the
# other is stopped too (by PID, TERM then KILL) and both start again on new ports, three tries
# in all.
idle() { sinfo -h -n "$host" -o %T | grep -qx idle; }
port_taken() { grep -qi 'address already in use' "$D/slurmctld.log" "$D/slurmd.log" 2>/dev/null; }
idle_or_taken() { idle || port_taken; }
munged_pids=$pids
try=1
while :; do
    ports=${RB_FARM_PORTS:-$("$FREEPORT" 2 | tr '\n' ' ')}
    set -- $ports
    [ $# -eq 2 ] || fail_all "two free ports for slurmctld and slurmd (${ports:-none found})"
    configure "$1" "$2"
    start slurmctld slurmctld -D -f "$SLURM_CONF"
    start slurmd slurmd -D -f "$SLURM_CONF"
    wait_for 60 idle_or_taken
    idle 2>/dev/null && break
    if ! port_taken || [ -n "${RB_FARM_PORTS:-}" ] || [ $try -ge 3 ]; then
        logs
        fail_all "the node $host comes up idle (ports $1 and $2)"
    fi
    echo "# ports $1 and $2: one was taken before its daemon bound it; trying new ones"
    daemons=${pids%"$munged_pids"}
    pids=$daemons
    stop
    pids=$munged_pids
    rm -rf "$D/slurmctld.log" "$D/slurmd.log" "$D/state"/* "$D/spool"/*
    try=$((try + 1))
done
ok "the node $host comes up idle (slurmctld on port $1, slurmd on port $2)"
check "slurmctld listens on its port, $1" grep -q "^ *[0-9]*: [0-9A-F]*:$(printf '%04X' "$1") " \
    /proc/net/tcp

# One process renders the frames; then the array job renders them in chunks.
t0=$(date +%s.%N)
rb render jobs/demo.yaml --size "$size" --frames "$frames" --out "$T/single" -q
t1=$(date +%s.%N)
expect_exit 0 "one process renders frames $frames at $size"

case $RB in
/*) raybundle=$RB ;;
*) raybundle=$(pwd)/$RB ;;
esac
RB_FARM_CLUSTER="$D" RB_JOB=jobs/demo.yaml RAYBUNDLE="$raybundle" \
    RB_ARGS="--size $size --frames $frames --out $T/farm" \
    sbatch --parsable --array=0-$((tasks - 1)) --output="$D/task-%a.log" \
    jobs/slurm-array.sh >"$T/sbatch" 2>&1
status=$?
job=$(cut -d';' -f1 "$T/sbatch")
check "sbatch accepts jobs/slurm-array.sh as an array of $tasks ($(head -c 200 "$T/sbatch"))" \
    test "$status" -eq 0
done_job() { [ -z "$(squeue -h -j "$job")" ]; }
check "the array job finishes within $limit s" wait_for "$limit" done_job
t2=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" -v n="$tasks" -v s="$size" -v f="$frames" 'BEGIN {
    printf "# wall single %.2f s, slurm %.2f s (%d tasks), slurm / single %.2f: frames %s at %s\n",
        b - a, c - b, n, (c - b) / (b - a), f, s }'

# Each task ran its chunk, reporting progress the OpenJD way, and succeeded.
i=0
while [ $i -lt "$tasks" ]; do
    log="$D/task-$i.log"
    check "task $i reached openjd_progress: 100" grep -qx "openjd_progress: 100" "$log"
    check "task $i rendered chunk $i/$tasks" grep -q ", chunk $i/$tasks) in " "$log"
    grep -qx "openjd_progress: 100" "$log" 2>/dev/null || tail -n 5 "$log" | sed "s/^/# task $i: /"
    i=$((i + 1))
done
want=$(cd "$T/single" && ls)
have=$(cd "$T/farm" 2>/dev/null && ls)
check "the array job wrote the same files as one process" test "$want" = "$have"
for exr in "$T"/single/*.exr; do
    name=$(basename "$exr")
    check "$name from the array job is identical to one process's" \
        cmp -s "$exr" "$T/farm/$name"
done

# The final check sees what it must: each daemon started carries the mark.
marked=" $(leftovers | tr '\n' ' ')"
for pid in $pids; do
    check "process $pid of the cluster is found by its mark" \
        sh -c "case '$marked' in *' $pid '*) exit 0 ;; esac; exit 1"
done
stop
left=$(leftovers | tr '\n' ' ')
check "no process of the cluster is left (${left:-none})" test -z "$left"
done_testing
