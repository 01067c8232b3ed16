#!/bin/bash
# End-to-end test of the Slurm examples (examples/slurm) on one Debian machine.
#
#   cargo build --release          # first: this script does not build vrpt
#   sudo tools/slurm/e2e.sh        # as root; VRPT=/path/to/vrpt to test another binary
#
# It brings up a throwaway one-node Slurm cluster on this machine, all of it under
# $E2E_DIR (default /tmp/vrpt-slurm-e2e): installs Debian's slurm-wlm and munge if they are
# missing, writes a munge key and a slurm.conf there, starts munged, slurmctld and slurmd
# (in the foreground, as background processes of this script; no systemd needed, so it
# runs in a container), submits examples/slurm/submit.sh (an array of 4 shards of
# scenes/cornell-box at 64x64, 64 spp, and the dependent merge), waits for the jobs, renders
# the same image in one local run and checks with `vrpt diff` that the merged shards equal
# it to f32 rounding (max relative difference <= 1e-6). Prints PASS or FAIL and exits 0 or
# 1; it stops the daemons it started on exit. Re-runnable: each run starts from a clean
# $E2E_DIR (after stopping daemons a previous, killed run may have left there).
#
# The cluster listens on 127.0.0.1 only, on ports $E2E_PORT and $E2E_PORT+1 (default
# 16817/16818, not Slurm's 6817/6818, so a real Slurm on the machine is left alone); it
# does not touch /etc/slurm or the system's munged.
#
# Environment: VRPT (default target/release/vrpt), E2E_DIR, E2E_PORT, E2E_TIMEOUT
# (seconds to wait for the jobs, default 300), N (shards, default 4), SEED (default 7).

set -euo pipefail

t0=$(date +%s.%N)
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
D=${E2E_DIR:-/tmp/vrpt-slurm-e2e}
PORT=${E2E_PORT:-16817}
TIMEOUT=${E2E_TIMEOUT:-300}
N=${N:-4}
SEED=${SEED:-7}
SPP=64 WIDTH=64 HEIGHT=64
SCENE=$repo/scenes/cornell-box
VRPT=${VRPT:-$repo/target/release/vrpt}
# Settings of render-array.sbatch that the local render below does not repeat.
unset PASS_SPP MAX_DEPTH VRPT_ARGS

log() { echo "[e2e $(date +%T)] $*"; }
elapsed() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

result=FAIL
finish() {
    local rc=$?
    set +e
    stop_cluster
    [[ $result == PASS ]] || rc=1
    echo "$result ($(elapsed) s total)"
    exit "$rc"
}

fail() {
    echo "FAILED: $*" >&2
    exit 1
}

# --- preconditions -------------------------------------------------------------------
[[ $(id -u) == 0 ]] || { echo "e2e.sh: run as root (it installs packages and runs slurmd)" >&2; exit 2; }
[[ $VRPT == /* ]] || VRPT=$PWD/$VRPT
if [[ ! -x $VRPT ]]; then
    echo "e2e.sh: no vrpt binary at $VRPT: run 'cargo build --release' first, or set VRPT" >&2
    exit 2
fi
help=$("$VRPT" render --help)
if [[ $help != *--shard* ]]; then
    echo "e2e.sh: $VRPT has no 'render --shard': rebuild with 'cargo build --release'" >&2
    exit 2
fi

# --- packages ------------------------------------------------------------------------
need=()
command -v munged >/dev/null || need+=(munge)
command -v slurmctld >/dev/null || need+=(slurmctld)
command -v slurmd >/dev/null || need+=(slurmd)
command -v sbatch >/dev/null || need+=(slurm-client)
if ((${#need[@]})); then
    log "installing ${need[*]} (slurm-wlm, munge)"
    # No service may start during the install (a container has no init to stop them
    # again): policy-rc.d says so to Debian's maintainer scripts, unless one is there.
    policy_added=
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod +x /usr/sbin/policy-rc.d
        policy_added=1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >/dev/null
    apt-get install -y -q --no-install-recommends slurm-wlm munge >/dev/null
    [[ -n $policy_added ]] && rm -f /usr/sbin/policy-rc.d
fi
log "$(slurmctld -V), $(munged --version 2>&1 | head -n 1)"

# --- a clean state dir ---------------------------------------------------------------
# Stop what a previous run left running (killed before its trap ran): only processes whose
# pid files are in $D and whose command line names this run's files.
stop_pidfile() {
    local pidfile=$1 pid i
    [[ -f $pidfile ]] || return 0
    pid=$(<"$pidfile")
    if [[ $pid =~ ^[0-9]+$ ]] && [[ -r /proc/$pid/cmdline ]] &&
        tr '\0' ' ' <"/proc/$pid/cmdline" | grep -q -- "$D"; then
        kill -TERM "$pid" 2>/dev/null || true
        for ((i = 0; i < 50; i++)); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        kill -KILL "$pid" 2>/dev/null || true
    fi
    rm -f "$pidfile"
}
ctld_alive() {
    [[ -f $D/run/slurmctld.pid ]] && kill -0 "$(<"$D/run/slurmctld.pid")" 2>/dev/null
}
stop_cluster() {
    # Jobs first (those of a timed-out run, or all of a killed run's private cluster), so
    # that no slurmstepd outlives slurmd.
    if ctld_alive; then
        if [[ -n ${array_job:-} ]]; then
            SLURM_CONF=$D/slurm.conf timeout 10 scancel "$array_job" ${merge_job:+"$merge_job"} 2>/dev/null || true
        else
            SLURM_CONF=$D/slurm.conf timeout 10 scancel --user=root 2>/dev/null || true
        fi
        sleep 1
    fi
    # slurmd before slurmctld, munged last (both talk through it).
    local p
    for p in slurmd slurmctld munged; do
        if [[ -f $D/run/$p.pid ]]; then
            log "stopping $p (pid $(<"$D/run/$p.pid"))"
            stop_pidfile "$D/run/$p.pid"
        fi
    done
    return 0
}
case $D in /tmp/?* | /var/tmp/?* | "$repo"/target/?*) ;; *) fail "E2E_DIR=$D: refusing to rm -rf a folder outside /tmp, /var/tmp or target/" ;; esac
stop_cluster
rm -rf "$D"
mkdir -p "$D"/{run,log,munge,ctld,spool,out}
chmod 711 "$D/munge"  # the socket reachable, the key (0400) not
trap finish EXIT
trap 'exit 130' INT TERM

# --- munge ---------------------------------------------------------------------------
# A key and socket of our own; slurm.conf's AuthInfo points Slurm at the socket.
dd if=/dev/urandom of="$D/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$D/munge/munge.key"
MUNGE_SOCKET=$D/munge/munge.socket
munged --foreground --force --key-file="$D/munge/munge.key" --socket="$MUNGE_SOCKET" \
    --pid-file="$D/run/munged.pid.unused" --seed-file="$D/munge/munged.seed" >"$D/log/munged.out" 2>&1 &
echo $! >"$D/run/munged.pid"
for ((i = 0; i < 50; i++)); do
    [[ -S $MUNGE_SOCKET ]] && munge --socket="$MUNGE_SOCKET" -n </dev/null | unmunge --socket="$MUNGE_SOCKET" >/dev/null 2>&1 && break
    sleep 0.2
done
munge --socket="$MUNGE_SOCKET" -n </dev/null | unmunge --socket="$MUNGE_SOCKET" >/dev/null ||
    { cat "$D/log/munged.out" >&2; fail "munged did not start"; }
log "munged up (pid $(<"$D/run/munged.pid"))"

# --- slurm.conf ----------------------------------------------------------------------
host=$(hostname -s)
cpus=$(nproc)
cat >"$D/slurm.conf" <<CONF
# Throwaway one-node cluster of tools/slurm/e2e.sh; everything under $D.
ClusterName=vrpte2e
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
# Root runs the daemons in a throwaway container; a real cluster has a slurm user.
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$MUNGE_SOCKET
CredType=cred/munge
# No cgroups (a container rarely has a writable cgroup tree): processes tracked through
# /proc, no task binding or containment, no accounting.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# Finished jobs stay visible to scontrol for 10 minutes (there is no accounting database).
MinJobAge=600
ReturnToService=2
StateSaveLocation=$D/ctld
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/run/slurmctld.pid.unused
SlurmdPidFile=$D/run/slurmd.pid.unused
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1024 State=UNKNOWN
PartitionName=e2e Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$D/slurm.conf

# --- slurmctld, slurmd ---------------------------------------------------------------
slurm_logs() {
    local f
    for f in "$D"/log/*; do
        echo "----- $f (last 40 lines)"
        tail -n 40 "$f"
    done
}
slurmctld -D -i -f "$D/slurm.conf" >"$D/log/slurmctld.out" 2>&1 &
echo $! >"$D/run/slurmctld.pid"
slurmd -D -N "$host" -f "$D/slurm.conf" >"$D/log/slurmd.out" 2>&1 &
echo $! >"$D/run/slurmd.pid"

log "waiting for node $host to be idle"
state=
for ((i = 0; i < 120; i++)); do
    state=$(sinfo -h -N -n "$host" -o '%t' 2>/dev/null || true)
    [[ $state == idle ]] && break
    for p in slurmctld slurmd; do
        kill -0 "$(<"$D/run/$p.pid")" 2>/dev/null || { slurm_logs >&2; fail "$p exited"; }
    done
    sleep 0.5
done
[[ $state == idle ]] || { sinfo -N -l >&2; slurm_logs >&2; fail "node $host not idle after 60 s (state '$state')"; }
log "cluster up: $(sinfo -h -o '%P %a %D %t %c cpus')"

# --- the sharded render through the examples -----------------------------------------
OUT=$D/out
log "submitting $N shards + merge with examples/slurm/submit.sh"
sub=$(cd "$D" && VRPT=$VRPT SCENE=$SCENE SPP=$SPP SEED=$SEED WIDTH=$WIDTH HEIGHT=$HEIGHT \
    N=$N OUT=$OUT "$repo/examples/slurm/submit.sh" --cpus-per-task=1)
echo "$sub"
array_job=$(sed -n 's/^array_job=//p' <<<"$sub")
merge_job=$(sed -n 's/^merge_job=//p' <<<"$sub")
[[ -n $array_job && -n $merge_job ]] || fail "could not read the job ids from submit.sh"

# The state of every job of the array (one line per task once they are split) and of the
# merge.
job_states() { scontrol show job -o "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p'; }
show_jobs() {
    scontrol show job "$array_job"
    scontrol show job "$merge_job"
    local f
    for f in "$OUT"/slurm-*.out; do
        [[ -e $f ]] || continue
        echo "----- $f"
        cat "$f"
    done
}
log "waiting for array job $array_job and merge job $merge_job (timeout $TIMEOUT s)"
deadline=$((SECONDS + TIMEOUT))
last=
while :; do
    merge_state=$(job_states "$merge_job")
    array_states=$(job_states "$array_job" | sort | uniq -c | awk '{printf "%s%s x%s", sep, $2, $1; sep=", "}')
    now="array: ${array_states:-?}; merge: ${merge_state:-?}"
    [[ $now != "$last" ]] && log "$now"
    last=$now
    case $merge_state in
        COMPLETED) break ;;
        FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | PREEMPTED | BOOT_FAIL | DEADLINE)
            show_jobs >&2
            slurm_logs >&2
            fail "merge job $merge_job ended $merge_state"
            ;;
    esac
    if ((SECONDS >= deadline)); then
        show_jobs >&2
        slurm_logs >&2
        fail "jobs not done after $TIMEOUT s"
    fi
    sleep 1
done
bad=$(job_states "$array_job" | grep -vx COMPLETED || true)
[[ -z $bad ]] || { show_jobs >&2; fail "array tasks not COMPLETED: $bad"; }
for f in "$OUT"/slurm-*.out; do
    echo "----- $(basename "$f")"
    cat "$f"
done

# --- the same image in one local render ----------------------------------------------
log "rendering the same image locally in one run"
"$VRPT" render "$SCENE" --spp "$SPP" --seed "$SEED" --width "$WIDTH" --height "$HEIGHT" \
    -o "$OUT/local.exr" --quiet
log "vrpt diff merged.exr local.exr"
"$VRPT" diff "$OUT/merged.exr" "$OUT/local.exr" | tee "$OUT/diff.txt"
maxrel=$(awk '/^max relative difference/ { print $4; exit }' "$OUT/diff.txt")
[[ -n $maxrel ]] || fail "vrpt diff printed no 'max relative difference' line"

# Control: another seed must differ by far more, or the check above proves nothing.
"$VRPT" render "$SCENE" --spp "$SPP" --seed "$((SEED + 1))" --width "$WIDTH" --height "$HEIGHT" \
    -o "$OUT/other-seed.exr" --quiet
ctrl=$("$VRPT" diff "$OUT/merged.exr" "$OUT/other-seed.exr" | awk '/^max relative difference/ { print $4; exit }')
log "control: max relative difference to seed $((SEED + 1)): $ctrl (must be > 1e-3)"
awk -v c="$ctrl" 'BEGIN { exit !(c + 0 > 1e-3) }' || fail "the control render does not differ: the check is vacuous"

if awk -v m="$maxrel" 'BEGIN { exit !(m + 0 <= 1e-6) }'; then
    log "merged shards == single render: max relative difference $maxrel <= 1e-6"
    result=PASS
else
    fail "merged shards differ from the single render: max relative difference $maxrel > 1e-6"
fi
