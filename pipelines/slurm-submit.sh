#!/usr/bin/env bash
# Submits a slidestack study to Slurm from a login node, without computing anything there:
#   1. `motions` as one job (only when motions.h5 is not up to date),
#   2. the sweep as a job array, task K computing shard K of N (`sweep --shard K/N`), and with an
#      `ida:` section the IDA as a second array beside it (`ida --shard K/N`, N at most the IDA's
#      work units), both after motions,
#   3. one finishing job, started when every task has ended (`afterany`), that checks every work
#      unit of the sweep is there, merges them and runs the later stages the config configures
#      (tnew, fit, ida with an `ida:` section: it traces what an IDA task left out and assembles
#      ida.h5, floors with a `floor_spectra:` section, report).
# In a building study `tnew` has work units too (the attached fractions'): the finishing job is
# then split in a merge job (after the sweep array: checks and merges the sweep) and the rest,
# and between them runs a `tnew` array (`tnew --shard K/N`, N at most its work units) that the
# rest waits for (the finishing job's `tnew` computes what a task left out and assembles tnew.h5).
# A config without a grid but with an `ida:` section (configs/ida-quick.yaml) gets the motions job,
# the IDA array (N defaults to its work units, one per task) and the finishing job.
# Each part is left out when its file is already up to date (`slidestack status`), so submitting
# a finished study submits nothing. Run with --help for the options; pipelines/README.md has the
# walk-through.
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(dirname "$HERE")
PROG=pipelines/slurm-submit.sh

# A sweep unit's cost per record sample of its work bound comes from `slidestack status`
# (SWEEP_NS_PER_SAMPLE, src/study/cost.rs): on one storey 188 ns per simulated sample per thread,
# measured by the paper study on 2 threads (docs/performance.md "The paper's study"), a bound; in
# a building study the mean over its frames of a cost measured per storey count
# (scripts/storey-cost), an estimate. SLIDESTACK_NS_PER_SAMPLE overrides it. The time limit adds a
# factor 2 and 5 minutes on top.
# A building study's tnew array: its CPU time over the sweep's, as measured on the costliest
# frame of configs/mdof-research.yaml (20 storeys, the stack on the roof: 363.2 against 159.8
# CPU-s, pipelines/README.md "A research-sized building study").
TNEW_PER_SWEEP=2.3
# Before the motions job has run, `slidestack status` cannot know the motions' length: the sizing
# then assumes this many record samples per motion (the built-in stochastic motion has 4001, the
# eleven FEMA P695 records of tests/fixtures 1800 to 7991).
ASSUMED_SAMPLES_PER_MOTION=${SLIDESTACK_SAMPLES_PER_MOTION:-8000}
# Default sizing aims at tasks of at most this many seconds (on the bound) and at most this many
# CPUs per task (small tasks start sooner on a shared cluster).
TARGET_TASK_S=1800
MAX_DEFAULT_CPUS=4

usage() {
  cat <<EOF
usage: $PROG [options] CONFIG OUT [-- SBATCH_OPTION...]

Submits the study CONFIG (e.g. configs/paper.yaml) into the output directory OUT (on a file
system the compute nodes share). Relative paths are taken from the current directory.

options (defaults in brackets; "sized" = from the grid's work units and their measured cost):
  -A, --account NAME        charge the jobs to this account [the site's default]
  -p, --partition NAME      submit to this partition [the site's default]
  -n, --shards N            sweep array tasks [sized]; 1 <= N <= work units, N < MaxArraySize
  -c, --cpus-per-task C     CPUs (threads) of every job [sized, at most $MAX_DEFAULT_CPUS]
  -t, --time TIME           time limit of each sweep task, any sbatch form [sized]
      --tnew-time TIME      time limit of each tnew task of a building study [sized; --time
                            when that is given]
      --stage-time TIME     time limit of the motions job and the finishing job [30:00]
      --mem SIZE            memory of every job, e.g. 2G [the site's default]
      --array LIST          submit only these shard indices, e.g. 3 or 2,5-7: to rerun failed
                            tasks; N is that of the last submission into OUT unless --shards
      --max-running M       at most M sweep tasks at a time (sbatch --array=...%M)
      --force               recompute every stage even when up to date (slidestack --force)
      --dry-run             check everything and print the sbatch commands, submit nothing
  -h, --help                this text
  -- SBATCH_OPTION...       passed to every sbatch call (e.g. -- --qos=short --mail-type=END)

environment:
  SLIDESTACK                the binary [$ROOT/target/release/slidestack]; this script never
                            builds it. SBATCH_* variables are honoured by sbatch as usual.

Logs: OUT/slurm/logs/. Watch: squeue --me. The finishing job's log says what to resubmit if a
sweep task failed.
EOF
}

die() {
  echo "$PROG: $*" >&2
  exit 1
}
note() { echo "$PROG: $*"; }
is_uint() { [[ $1 =~ ^[0-9]+$ ]]; }

CONFIG="" OUT="" SHARDS="" CPUS="" TIME="" TNEW_TIME="" STAGE_TIME="" MEM="" ACCOUNT="" PARTITION=""
ARRAY="" MAX_RUNNING="" DRY_RUN=0 FORCE=0
EXTRA=()
POSITIONAL=()
need_value() { [ "$2" -ge 2 ] || die "$1 needs a value (see --help)"; }
while [ $# -gt 0 ]; do
  case $1 in
  -h | --help)
    usage
    exit 0
    ;;
  -A | --account) need_value "$1" $#; ACCOUNT=$2; shift 2 ;;
  -p | --partition) need_value "$1" $#; PARTITION=$2; shift 2 ;;
  -n | --shards) need_value "$1" $#; SHARDS=$2; shift 2 ;;
  -c | --cpus-per-task) need_value "$1" $#; CPUS=$2; shift 2 ;;
  -t | --time) need_value "$1" $#; TIME=$2; shift 2 ;;
  --tnew-time) need_value "$1" $#; TNEW_TIME=$2; shift 2 ;;
  --stage-time) need_value "$1" $#; STAGE_TIME=$2; shift 2 ;;
  --mem) need_value "$1" $#; MEM=$2; shift 2 ;;
  --array) need_value "$1" $#; ARRAY=$2; shift 2 ;;
  --max-running) need_value "$1" $#; MAX_RUNNING=$2; shift 2 ;;
  --account=* | --partition=* | --shards=* | --cpus-per-task=* | --time=* | --tnew-time=* | \
    --stage-time=* | --mem=* | --array=* | --max-running=*)
    opt=${1%%=*}
    set -- "$opt" "${1#*=}" "${@:2}"
    ;;
  --dry-run) DRY_RUN=1; shift ;;
  --force) FORCE=1; shift ;;
  --)
    shift
    EXTRA=("$@")
    break
    ;;
  -*) die "unknown option $1 (see --help; sbatch options go after --)" ;;
  *) POSITIONAL+=("$1"); shift ;;
  esac
done
[ ${#POSITIONAL[@]} -eq 2 ] || {
  usage >&2
  exit 2
}
for v in SHARDS CPUS MAX_RUNNING; do
  val=${!v}
  if [ -n "$val" ] && { ! is_uint "$val" || [ "$val" -lt 1 ]; }; then
    die "$(tr '[:upper:]_' '[:lower:]-' <<<"$v") must be a whole number >= 1, not '$val'"
  fi
done

CONFIG=$(realpath -e -- "${POSITIONAL[0]}" 2>/dev/null) || die "no config file ${POSITIONAL[0]}"
OUT=$(realpath -m -- "${POSITIONAL[1]}")
SLURM_DIR=$OUT/slurm

# --- The binary: never built here. ---------------------------------------------------------
SLIDESTACK=${SLIDESTACK:-$ROOT/target/release/slidestack}
if [ ! -x "$SLIDESTACK" ]; then
  cat >&2 <<EOF
$PROG: no slidestack binary at $SLIDESTACK.
This script does not build it: a release build takes minutes of CPU, which a login node is not
for. Build it once where your site allows builds (it needs cargo and the HDF5 C library, e.g.
'module load hdf5' or Debian's libhdf5-dev), for example on a compute node:
  srun --cpus-per-task=4 --time=30:00 bash -c 'cd $ROOT && cargo build --release'
(on Debian/Ubuntu with root: cd $ROOT && scripts/install-deps.sh && cargo build --release),
then run this command again; or point SLIDESTACK at an existing binary:
  SLIDESTACK=/path/to/slidestack $PROG ...
EOF
  exit 1
fi
SLIDESTACK=$(realpath -e -- "$SLIDESTACK")
version=$("$SLIDESTACK" --version 2>&1) ||
  die "$SLIDESTACK does not run on this node: $version
(built on another system? It needs the HDF5 library it was built with on this node and on the
compute nodes; build it on a compute node as described in pipelines/README.md)"

case $OUT in
/tmp/* | /dev/shm/* | /var/tmp/*)
  note "warning: $OUT is under a node-local directory on most clusters; compute nodes must see it" ;;
esac

# --- What is up to date (`slidestack status`, no computing). ---------------------------------
"$SLIDESTACK" status --help >/dev/null 2>&1 ||
  die "$SLIDESTACK has no 'status' command: it is older than these scripts; build the current
sources (see pipelines/README.md, \"Building\")"
status=$("$SLIDESTACK" status "$CONFIG" --out "$OUT" --format env) ||
  die "slidestack status failed on $CONFIG (message above); nothing was submitted"
# shellcheck disable=SC2034 # TNEW, FIT, IDA and REPORT are read through ${!v} below
MOTIONS="" SWEEP="" TNEW="" FIT="" IDA="" REPORT="" SWEEP_UNITS="" SWEEP_UNITS_DONE=""
SWEEP_CASES_PER_UNIT="" SWEEP_SAMPLES_PER_MOTION="" SWEEP_SAMPLES_PER_UNIT="" STAGES=""
SWEEP_NS_PER_SAMPLE=""
IDA_UNITS="" IDA_UNITS_DONE="" TNEW_UNITS="" TNEW_UNITS_DONE=""
# KEY=VALUE lines; the keys used here are checked below, others are left alone. A stage the
# config does not configure has no line (STAGES lists the configured ones).
while IFS= read -r line; do
  [[ $line =~ ^([A-Z_]+)=(.*)$ ]] || continue
  case ${BASH_REMATCH[1]} in
  MOTIONS | SWEEP | TNEW | FIT | IDA | REPORT | SWEEP_UNITS | SWEEP_UNITS_DONE | \
    SWEEP_CASES_PER_UNIT | SWEEP_SAMPLES_PER_MOTION | SWEEP_SAMPLES_PER_UNIT | STAGES | \
    SWEEP_NS_PER_SAMPLE | \
    IDA_UNITS | IDA_UNITS_DONE | TNEW_UNITS | TNEW_UNITS_DONE)
    printf -v "${BASH_REMATCH[1]}" '%s' "${BASH_REMATCH[2]}" ;;
  esac
done <<<"$status"
[ -n "$STAGES" ] || die "slidestack status gave no STAGES line: $SLIDESTACK is older than these
scripts; build the current sources (see pipelines/README.md, \"Building\")"
# Without a grid the IDA is the only array; without either there is nothing to spread.
HAS_SWEEP=1
[ -n "$SWEEP" ] || HAS_SWEEP=0
if [ $HAS_SWEEP = 0 ] && [[ ,$STAGES, != *,ida,* ]]; then
  die "$CONFIG has neither a grid nor an ida: section, so there is nothing to run as an array; its
stages ($STAGES) run on one machine: $SLIDESTACK run $CONFIG --out $OUT"
fi
IFS=, read -ra stages <<<"$STAGES"
all_done=1 states=""
for stage in "${stages[@]}"; do
  v=${stage^^}
  case ${!v} in up_to_date | stale | missing | damaged) ;; *) die "slidestack status gave $v='${!v}'" ;; esac
  [ "${!v}" = up_to_date ] || all_done=0
  states="$states${states:+, }$stage ${!v}"
done
for v in SWEEP_UNITS SWEEP_UNITS_DONE SWEEP_CASES_PER_UNIT SWEEP_SAMPLES_PER_MOTION SWEEP_SAMPLES_PER_UNIT \
  SWEEP_NS_PER_SAMPLE IDA_UNITS IDA_UNITS_DONE TNEW_UNITS TNEW_UNITS_DONE; do
  is_uint "${!v}" || die "slidestack status gave $v='${!v}'"
done
NS_PER_SAMPLE=${SLIDESTACK_NS_PER_SAMPLE:-$SWEEP_NS_PER_SAMPLE}
is_uint "$NS_PER_SAMPLE" || die "SLIDESTACK_NS_PER_SAMPLE must be a whole number of nanoseconds"
if [ -n "${SLIDESTACK_NS_PER_SAMPLE:-}" ]; then
  ns_from="SLIDESTACK_NS_PER_SAMPLE"
elif [ "$TNEW_UNITS" -gt 0 ]; then
  ns_from="the building study's frames' estimate, src/study/cost.rs"
else
  ns_from="the one-storey bound, src/study/cost.rs"
fi
units=()
[ $HAS_SWEEP = 0 ] || units+=("$SWEEP_UNITS_DONE of $SWEEP_UNITS sweep units")
[ "$TNEW_UNITS" = 0 ] || units+=("$TNEW_UNITS_DONE of $TNEW_UNITS tnew units")
[ "$IDA_UNITS" = 0 ] || units+=("$IDA_UNITS_DONE of $IDA_UNITS ida units")
stored=$(IFS=,; echo "${units[*]}")
note "status: $states (${stored//,/, } stored)"
if [ $FORCE = 0 ] && [ $all_done = 1 ]; then
  note "the study in $OUT is up to date: nothing to submit ($OUT/report/index.html; --force recomputes it)"
  exit 0
fi
# What is submitted: the motions job when motions.h5 is not up to date, the sweep array when
# sweep.h5 is not, the finishing job always. --force submits all three (without the motions job
# when only some shards are resubmitted with --array) and passes --force to every stage.
NEED_MOTIONS=1 NEED_SWEEP=$HAS_SWEEP
[ "$MOTIONS" != up_to_date ] || NEED_MOTIONS=0
[ "$SWEEP" != up_to_date ] || NEED_SWEEP=0
if [ $FORCE = 1 ]; then
  NEED_SWEEP=$HAS_SWEEP
  if [ -z "$ARRAY" ]; then NEED_MOTIONS=1; fi
fi
# The IDA array (a config with an `ida:` section whose ida.h5 is not up to date, or --force), not
# when only some sweep shards are resubmitted (--array): the finishing job's `ida` traces what
# is left. Its N is the sweep's, at most the IDA's work units.
NEED_IDA=0
if [[ ,$STAGES, == *,ida,* ]] && [ -z "$ARRAY" ] && { [ "$IDA" != up_to_date ] || [ $FORCE = 1 ]; }; then
  NEED_IDA=1
fi

# The tnew array (a building study, whose attached fractions are tnew's work units, when tnew.h5
# is not up to date or --force), also when only some sweep shards are resubmitted (--array): the
# first submission's tnew array was cancelled with its failed merge, and its units are the
# costly part. Its N is the sweep's, at most tnew's work units, and its time limit the sweep
# task's (its units cost about as much as the sweep's); with the sweep to run, a merge job goes
# between the two arrays. A tnew task skips the units already stored.
NEED_TNEW=0
if [ "$TNEW_UNITS" -gt 0 ] && { [ "$TNEW" != up_to_date ] || [ $FORCE = 1 ]; }; then
  NEED_TNEW=1
fi

# --- What the cluster allows. ----------------------------------------------------------------
HAVE_SLURM=1 why=""
if ! command -v sbatch >/dev/null 2>&1 || ! command -v sinfo >/dev/null 2>&1 ||
  ! command -v scontrol >/dev/null 2>&1; then
  HAVE_SLURM=0 why="sbatch, sinfo or scontrol not found: run this on a Slurm login node"
elif ! partitions=$(sinfo -h -o '%P' 2>&1); then
  HAVE_SLURM=0 why="cannot reach the Slurm controller (sinfo: $(head -n1 <<<"$partitions"))"
fi
if [ $HAVE_SLURM = 0 ]; then
  [ $DRY_RUN = 1 ] || die "$why"
  note "$why; --dry-run goes on without the cluster's limits"
fi
MAX_ARRAY="" NODE_CPUS="" PART_LIMIT="" part=""
if [ $HAVE_SLURM = 1 ]; then
  MAX_ARRAY=$(scontrol show config 2>/dev/null | awk '$1 == "MaxArraySize" {print $3}') || true
  part=$PARTITION
  [ -n "$part" ] || part=$(sed -n 's/\*$//p' <<<"$partitions" | head -n1)
  if [ -n "$part" ]; then
    NODE_CPUS=$(sinfo -h -N -p "$part" -o '%c' 2>/dev/null | sort -n | tail -n1) || true
    PART_LIMIT=$(sinfo -h -p "$part" -o '%l' 2>/dev/null | head -n1) || true
    [ -n "$NODE_CPUS" ] || die "partition '$part' has no nodes (sinfo -p $part); choose one with -p (sinfo lists them)"
  fi
fi

# Minutes of a Slurm time string (MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS); empty if none.
minutes() {
  local t=$1 d=0 h=0 m=0 s=0
  case $t in infinite | UNLIMITED | "") return 0 ;; esac
  if [[ $t =~ ^([0-9]+)-(.*)$ ]]; then
    d=${BASH_REMATCH[1]}
    t=${BASH_REMATCH[2]}
    IFS=: read -r h m s <<<"$t"
  else
    local f
    IFS=: read -ra f <<<"$t"
    case ${#f[@]} in
    1) m=${f[0]} ;;
    2) m=${f[0]} s=${f[1]} ;;
    3) h=${f[0]} m=${f[1]} s=${f[2]} ;;
    *) return 1 ;;
    esac
  fi
  for x in "$d" "${h:-0}" "${m:-0}" "${s:-0}"; do is_uint "$x" || return 1; done
  echo $(((10#$d * 24 + 10#${h:-0}) * 60 + 10#${m:-0} + (10#${s:-0} + 59) / 60))
}

# --- Shards: N from the options, the last submission, or the grid. ---------------------------
LAST=$SLURM_DIR/submission.env
if [ -n "$ARRAY" ] && [ -z "$SHARDS" ]; then
  [ -r "$LAST" ] || die "--array needs the N of the original submission: give --shards N"
  SHARDS=$(sed -n 's/^SHARDS=\([0-9]*\)$/\1/p' "$LAST")
  is_uint "$SHARDS" || die "cannot read SHARDS from $LAST: give --shards N"
  note "--array: N = $SHARDS, from the last submission ($LAST)"
fi
if [ -n "$ARRAY" ] && [ $HAS_SWEEP = 0 ]; then
  die "--array resubmits sweep shards, and $CONFIG has no grid: submit again without it (the IDA's
units already stored are not traced again)"
fi
if [ -n "$ARRAY" ] && [ $NEED_MOTIONS = 1 ]; then
  die "motions.h5 is $MOTIONS, so every shard must run again: submit without --array"
fi

cpu_cap=$MAX_DEFAULT_CPUS
if is_uint "${NODE_CPUS:-x}" && [ "$NODE_CPUS" -lt "$cpu_cap" ]; then cpu_cap=$NODE_CPUS; fi
array_cap=""
if is_uint "${MAX_ARRAY:-x}"; then array_cap=$((MAX_ARRAY - 1)); fi
given="" sized=""
for v in SHARDS CPUS TIME; do
  if [ -n "${!v}" ]; then given="$given ${v,,}"; else sized="$sized ${v,,}"; fi
done
# The work bound of a unit: at most three simulations per case, each over the motion's samples
# (status: SWEEP_SAMPLES_PER_UNIT = 3 x cases per unit x mean samples per motion).
if [ "$SWEEP_SAMPLES_PER_MOTION" -gt 0 ]; then
  SAMPLES_PER_UNIT=$SWEEP_SAMPLES_PER_UNIT
  samples_from="$SWEEP_SAMPLES_PER_MOTION samples per motion, from motions.h5"
else
  is_uint "$ASSUMED_SAMPLES_PER_MOTION" || die "SLIDESTACK_SAMPLES_PER_MOTION must be a whole number"
  SAMPLES_PER_UNIT=$((3 * SWEEP_CASES_PER_UNIT * ASSUMED_SAMPLES_PER_MOTION))
  samples_from="$ASSUMED_SAMPLES_PER_MOTION samples per motion assumed, as motions.h5 is $MOTIONS"
fi
if [ $HAS_SWEEP = 0 ]; then
  # No measured cost of an IDA unit to size from: one unit per task, as many tasks as the
  # array allows.
  if [ -z "$SHARDS" ]; then
    SHARDS=$IDA_UNITS
    if [ -n "$array_cap" ] && [ "$SHARDS" -gt "$array_cap" ]; then SHARDS=$array_cap; fi
  fi
  # No sweep task, so no sweep time limit: the IDA's tasks take the stage time.
  TIME=${TIME:-30:00}
  note "sizing: no grid, so no sweep; the IDA's $IDA_UNITS work units in $SHARDS array tasks"
elif [ "$SAMPLES_PER_UNIT" -gt 0 ] && [ "$SWEEP_UNITS" -gt 0 ]; then
  # U: bound of one unit's CPU seconds; W: of all units. CPUs: enough for tasks of
  # TARGET_TASK_S with the shards given (1 if not), at most cpu_cap and no more than a shard's
  # units. Shards: enough for tasks of TARGET_TASK_S, at most the units and the array limit. Time
  # limit: twice the bound of a task's wall time (its units, CPUs at a time) plus 5 minutes, at
  # least 10 minutes.
  read -r UNIT_S W CPUS SHARDS EST TMIN < <(awk -v s="$SAMPLES_PER_UNIT" -v ns="$NS_PER_SAMPLE" \
    -v units="$SWEEP_UNITS" -v c="${CPUS:-0}" -v n="${SHARDS:-0}" -v target=$TARGET_TASK_S \
    -v ccap="$cpu_cap" -v acap="${array_cap:-0}" '
    function ceil(x) { return (x == int(x)) ? x : int(x) + 1 }
    BEGIN {
      u = s * ns * 1e-9; w = units * u
      sized_c = (c == 0)
      if (sized_c) { c = ceil(w / ((n > 0 ? n : 1) * target)); if (c > ccap) c = ccap; if (c < 1) c = 1 }
      if (n == 0) {
        n = ceil(w / (c * target)); if (n > units) n = units; if (acap > 0 && n > acap) n = acap
        if (n < 1) n = 1
      }
      per = ceil(units / n)
      if (sized_c && c > per) c = per
      est = ceil(per / c) * u
      t = ceil((2 * est + 300) / 60); if (t < 10) t = 10
      printf "%.3f %.1f %d %d %.0f %d\n", u, w, c, n, est, t
    }')
  [ -n "$TIME" ] || TIME=$TMIN
  if [ "$TNEW_UNITS" -gt 0 ] && [ -z "${SLIDESTACK_NS_PER_SAMPLE:-}" ]; then
    note "sizing: $SWEEP_UNITS work units of $SWEEP_CASES_PER_UNIT cases, each about $UNIT_S CPU-s ($SAMPLES_PER_UNIT record samples of the work bound x $NS_PER_SAMPLE ns, $ns_from; $samples_from); $W CPU-s in all, about $EST s per task"
  else
    note "sizing: $SWEEP_UNITS work units of $SWEEP_CASES_PER_UNIT cases, each at most $UNIT_S CPU-s (at most $SAMPLES_PER_UNIT simulated record samples x $NS_PER_SAMPLE ns, $ns_from; $samples_from); $W CPU-s in all, at most $EST s per task"
  fi
elif [ -n "$sized" ]; then
  note "warning: the grid has no work to size from: default 1 shard, 1 CPU, 4 hours where not given"
fi
CPUS=${CPUS:-1}
SHARDS=${SHARDS:-1}
TIME=${TIME:-4:00:00}
show_time() { if is_uint "$1"; then echo "$1 min"; else echo "$1"; fi; }
plim=$(minutes "$PART_LIMIT") || plim=""
if [[ $sized == *time* ]] && [ -n "$plim" ] && [ "$(minutes "$TIME")" -gt "$plim" ]; then
  note "warning: the default time limit, $(show_time "$TIME"), is above the limit of partition '$part' ($PART_LIMIT): using $PART_LIMIT (give more --shards if tasks time out)"
  TIME=$PART_LIMIT
fi
if [ -z "$STAGE_TIME" ]; then
  STAGE_TIME=30:00
  if [ -n "$plim" ] && [ "$plim" -lt 30 ]; then STAGE_TIME=$PART_LIMIT; fi
fi
if [ $HAS_SWEEP = 1 ]; then
  note "jobs: shards $SHARDS, CPUs per job $CPUS, time limits $(show_time "$TIME") per sweep task and $(show_time "$STAGE_TIME") for motions and finishing${given:+ (given:$given)}"
else
  note "jobs: IDA shards $SHARDS, CPUs per job $CPUS, time limit $(show_time "$STAGE_TIME") per job${given:+ (given:$given)}"
fi

# --- Checks before any work. ------------------------------------------------------------------
if [ $HAS_SWEEP = 0 ] && [ "$SHARDS" -gt "$IDA_UNITS" ]; then
  die "--shards $SHARDS is more than the IDA's $IDA_UNITS work units: give at most $IDA_UNITS"
fi
if [ $HAS_SWEEP = 1 ] && [ "$SHARDS" -gt "$SWEEP_UNITS" ]; then
  die "--shards $SHARDS is more than the $SWEEP_UNITS work units of the grid: give at most $SWEEP_UNITS"
fi
if [ -n "$array_cap" ] && [ "$SHARDS" -gt "$array_cap" ]; then
  die "--shards $SHARDS: this cluster's MaxArraySize is $MAX_ARRAY, so array indices stop at $array_cap; give --shards $array_cap or fewer (and more --cpus-per-task)"
fi
if [ -n "$NODE_CPUS" ] && is_uint "$NODE_CPUS" && [ "$CPUS" -gt "$NODE_CPUS" ]; then
  die "--cpus-per-task $CPUS: the largest node of partition '$part' has $NODE_CPUS CPUs, so the jobs would never start; give at most $NODE_CPUS"
fi
for v in TIME STAGE_TIME TNEW_TIME; do
  [ -n "${!v}" ] || continue
  opt=--$(tr _ - <<<"${v,,}")
  m=$(minutes "${!v}") || die "$opt '${!v}' is not a Slurm time (MM, HH:MM:SS, D-HH:MM:SS, ...)"
  if [ -n "$plim" ] && [ -n "$m" ] && [ "$m" -gt "$plim" ]; then
    die "$opt ${!v}: partition '$part' allows at most $PART_LIMIT, so the jobs would never start"
  fi
done
INDICES=()
if [ -n "$ARRAY" ]; then
  IFS=, read -ra items <<<"$ARRAY"
  for it in "${items[@]}"; do
    if [[ $it =~ ^([0-9]+)$ ]]; then
      a=${BASH_REMATCH[1]} b=$a step=1
    elif [[ $it =~ ^([0-9]+)-([0-9]+)(:([0-9]+))?$ ]]; then
      a=${BASH_REMATCH[1]} b=${BASH_REMATCH[2]} step=${BASH_REMATCH[4]:-1}
    else
      die "--array '$ARRAY': expected indices and ranges such as 3 or 2,5-7"
    fi
    a=$((10#$a)) b=$((10#$b)) step=$((10#$step))
    if [ "$a" -lt 1 ] || [ "$b" -gt "$SHARDS" ] || [ "$a" -gt "$b" ] || [ "$step" -lt 1 ]; then
      die "--array '$ARRAY': shard indices go from 1 to N = $SHARDS"
    fi
    for ((k = a; k <= b; k += step)); do INDICES+=("$k"); done
  done
  ARRAY_SPEC=$ARRAY
else
  for ((k = 1; k <= SHARDS; k++)); do INDICES+=("$k"); done
  ARRAY_SPEC="1-$SHARDS"
fi
[ -z "$MAX_RUNNING" ] || ARRAY_SPEC="$ARRAY_SPEC%$MAX_RUNNING"

# Jobs of an earlier submission into OUT (their working directory) still queued or running: a
# second submission would run the same shards twice at the same time.
if [ $HAVE_SLURM = 1 ]; then
  active=$(squeue -h -u "$(id -un)" -o '%i %j %Z' 2>/dev/null |
    awk -v d="$OUT" '$2 ~ /^slidestack-/ && $3 == d {print $1}' | tr '\n' ' ')
  if [ -n "$active" ]; then
    die "jobs of an earlier submission into $OUT are still queued or running (${active% }):
wait for them to end (squeue -u $(id -un)) or cancel them (scancel ${active% }), then submit again"
  fi
fi

# --- The jobs. --------------------------------------------------------------------------------
LOGS=$SLURM_DIR/logs
common=(--parsable --chdir="$OUT" --open-mode=append --cpus-per-task="$CPUS")
[ -z "$ACCOUNT" ] || common+=(--account="$ACCOUNT")
[ -z "$PARTITION" ] || common+=(--partition="$PARTITION")
[ -z "$MEM" ] || common+=(--mem="$MEM")

# The binary the jobs run: a copy named by its SHA-256, so rebuilding while jobs wait changes
# nothing for them.
sha=$(sha256sum "$SLIDESTACK" | cut -c1-16)
JOB_BIN=$SLURM_DIR/bin/slidestack-$sha

# --force goes first to each batch script, which passes it to every slidestack stage it runs.
FORCE_ARG=()
[ $FORCE = 0 ] || FORCE_ARG=(--force)
motions_cmd=(sbatch "${common[@]}" --job-name=slidestack-motions --time="$STAGE_TIME"
  --output="$LOGS/motions-%j.out" "${EXTRA[@]}" "$HERE/motions.slurm" "${FORCE_ARG[@]}" "$JOB_BIN" "$CONFIG" "$OUT")
sweep_cmd=(sbatch "${common[@]}" --job-name=slidestack-sweep --time="$TIME" --array="$ARRAY_SPEC"
  --output="$LOGS/sweep-%A_%a.out" "${EXTRA[@]}" "$HERE/sweep.slurm" "${FORCE_ARG[@]}" "$JOB_BIN" "$CONFIG" "$OUT"
  "$SHARDS")
IDA_SHARDS=$SHARDS
if [ "$IDA_UNITS" -lt "$IDA_SHARDS" ]; then IDA_SHARDS=$IDA_UNITS; fi
[ "$IDA_SHARDS" -ge 1 ] || NEED_IDA=0
IDA_SPEC="1-$IDA_SHARDS"
[ -z "$MAX_RUNNING" ] || IDA_SPEC="$IDA_SPEC%$MAX_RUNNING"
ida_cmd=(sbatch "${common[@]}" --job-name=slidestack-ida --time="$STAGE_TIME" --array="$IDA_SPEC"
  --output="$LOGS/ida-%A_%a.out" "${EXTRA[@]}" "$HERE/shard.slurm" "${FORCE_ARG[@]}" ida "$JOB_BIN" "$CONFIG"
  "$OUT" "$IDA_SHARDS")
TNEW_SHARDS=$SHARDS
if [ "$TNEW_UNITS" -lt "$TNEW_SHARDS" ]; then TNEW_SHARDS=$TNEW_UNITS; fi
# A tnew task's time limit: --tnew-time, else the sweep's when given, else from the sweep's
# estimated CPU time (W) times TNEW_PER_SWEEP over the tnew tasks, sized as the sweep's (twice
# plus 5 minutes, at least 10 minutes, at most the partition's limit).
if [ -n "$TNEW_TIME" ]; then
  :
elif [ $NEED_TNEW = 1 ] && [[ $given != *time* ]] && [ -n "${W:-}" ] && [ "$TNEW_SHARDS" -ge 1 ]; then
  read -r TNEW_W TNEW_EST TNEW_TIME < <(awk -v w="$W" -v r="$TNEW_PER_SWEEP" -v n="$TNEW_SHARDS" -v c="$CPUS" '
    function ceil(x) { return (x == int(x)) ? x : int(x) + 1 }
    BEGIN {
      tw = r * w; est = ceil(tw / (n * c)); t = ceil((2 * est + 300) / 60); if (t < 10) t = 10
      printf "%.1f %d %d\n", tw, est, t
    }')
  if [ -n "$plim" ] && [ "$TNEW_TIME" -gt "$plim" ]; then TNEW_TIME=$PART_LIMIT; fi
  note "sizing: tnew's $TNEW_UNITS work units, about $TNEW_W CPU-s in all ($TNEW_PER_SWEEP × the sweep's), about $TNEW_EST s per task: a limit of $(show_time "$TNEW_TIME") per tnew task"
else
  TNEW_TIME=$TIME
fi
TNEW_SPEC="1-$TNEW_SHARDS"
[ -z "$MAX_RUNNING" ] || TNEW_SPEC="$TNEW_SPEC%$MAX_RUNNING"
tnew_cmd=(sbatch "${common[@]}" --job-name=slidestack-tnew --time="$TNEW_TIME" --array="$TNEW_SPEC"
  --output="$LOGS/tnew-%A_%a.out" "${EXTRA[@]}" "$HERE/shard.slurm" "${FORCE_ARG[@]}" tnew "$JOB_BIN" "$CONFIG"
  "$OUT" "$TNEW_SHARDS")
# The command that resubmits failed shards of this submission with the same binary, N and sizes;
# the finishing job prints it with --array LIST added.
RESUBMIT_CMD="SLIDESTACK=$(printf '%q' "$JOB_BIN") $(printf '%q' "$HERE/slurm-submit.sh")"
resubmit=(--shards "$SHARDS" --cpus-per-task "$CPUS" --time "$TIME" --stage-time "$STAGE_TIME")
[ "$TNEW_UNITS" = 0 ] || resubmit+=(--tnew-time "$TNEW_TIME")
[ -z "$ACCOUNT" ] || resubmit+=(--account "$ACCOUNT")
[ -z "$PARTITION" ] || resubmit+=(--partition "$PARTITION")
[ -z "$MEM" ] || resubmit+=(--mem "$MEM")
[ -z "$MAX_RUNNING" ] || resubmit+=(--max-running "$MAX_RUNNING")
[ $FORCE = 0 ] || resubmit+=(--force)
resubmit+=("$CONFIG" "$OUT")
[ ${#EXTRA[@]} -eq 0 ] || resubmit+=(-- "${EXTRA[@]}")
RESUBMIT_ARGS=$(printf '%q ' "${resubmit[@]}")
RESUBMIT_ARGS=${RESUBMIT_ARGS% }

# With the sweep and tnew both as arrays, the finishing job is split: the merge job between them
# and the rest after tnew's.
NEED_MERGE=0 FINISH_PART=()
if [ $NEED_TNEW = 1 ] && [ $NEED_SWEEP = 1 ]; then NEED_MERGE=1 FINISH_PART=(--after-merge); fi
merge_cmd=(sbatch "${common[@]}" --job-name=slidestack-merge --time="$STAGE_TIME"
  --output="$LOGS/merge-%j.out" "${EXTRA[@]}" "$HERE/finish.slurm" "${FORCE_ARG[@]}" --sweep-only "$JOB_BIN"
  "$CONFIG" "$OUT" "$SHARDS" "$RESUBMIT_CMD" "$RESUBMIT_ARGS")
finish_cmd=(sbatch "${common[@]}" --job-name=slidestack-finish --time="$STAGE_TIME"
  --output="$LOGS/finish-%j.out" "${EXTRA[@]}" "$HERE/finish.slurm" "${FORCE_ARG[@]}" "${FINISH_PART[@]}"
  "$JOB_BIN" "$CONFIG" "$OUT" "$SHARDS" "$RESUBMIT_CMD" "$RESUBMIT_ARGS")

parts="finishing job"
[ $NEED_IDA = 0 ] || parts="ida array ($IDA_SHARDS shards of $IDA_UNITS units, $(show_time "$STAGE_TIME") each), $parts"
[ $NEED_TNEW = 0 ] || parts="tnew array ($TNEW_SHARDS shards of $TNEW_UNITS units, $(show_time "$TNEW_TIME") each), $parts"
[ $NEED_MERGE = 0 ] || parts="merge job, $parts"
[ $NEED_SWEEP = 0 ] || parts="sweep array (tasks $ARRAY_SPEC of N = $SHARDS shards, $CPUS CPUs and $(show_time "$TIME") each), $parts"
[ $NEED_MOTIONS = 0 ] || parts="motions job, $parts"
note "submitting: $parts"

# sbatch --test-only checks each request against the cluster (partition, account, limits)
# without submitting anything.
test_only() {
  local what=$1 out
  shift
  if ! out=$("$1" --test-only "${@:2}" 2>&1); then
    die "sbatch refused the $what job, so nothing was submitted:
$out"
  fi
}
if [ $HAVE_SLURM = 1 ]; then
  [ $NEED_MOTIONS = 0 ] || test_only motions "${motions_cmd[@]}"
  [ $NEED_SWEEP = 0 ] || test_only sweep "${sweep_cmd[@]}"
  [ $NEED_MERGE = 0 ] || test_only merge "${merge_cmd[@]}"
  [ $NEED_TNEW = 0 ] || test_only tnew "${tnew_cmd[@]}"
  [ $NEED_IDA = 0 ] || test_only ida "${ida_cmd[@]}"
  test_only finishing "${finish_cmd[@]}"
fi

if [ $DRY_RUN = 1 ]; then
  note "dry run; would submit (each with its --dependency):"
  if [ $NEED_MOTIONS = 1 ]; then printf ' %q' "${motions_cmd[@]}"; echo; fi
  if [ $NEED_SWEEP = 1 ]; then printf ' %q' "${sweep_cmd[@]}"; echo; fi
  if [ $NEED_MERGE = 1 ]; then printf ' %q' "${merge_cmd[@]}"; echo; fi
  if [ $NEED_TNEW = 1 ]; then printf ' %q' "${tnew_cmd[@]}"; echo; fi
  if [ $NEED_IDA = 1 ]; then printf ' %q' "${ida_cmd[@]}"; echo; fi
  printf ' %q' "${finish_cmd[@]}"
  echo
  exit 0
fi

mkdir -p "$LOGS" "$SLURM_DIR/bin" "$SLURM_DIR/done"
if [ ! -x "$JOB_BIN" ]; then
  tmp=$(mktemp "$SLURM_DIR/bin/.slidestack.XXXXXX")
  cp "$SLIDESTACK" "$tmp"
  chmod 755 "$tmp"
  mv -f "$tmp" "$JOB_BIN"
fi
# Success markers of the shards about to run are stale now.
if [ -z "$ARRAY" ]; then
  rm -f "$SLURM_DIR/done/shard-"*
else
  for k in "${INDICES[@]}"; do rm -f "$SLURM_DIR/done/shard-$k-of-$SHARDS"; done
fi
tmp=$(mktemp "$SLURM_DIR/.submission.XXXXXX")
{
  echo "SHARDS=$SHARDS"
  echo "CONFIG=$(printf '%q' "$CONFIG")"
  echo "BINARY=$(printf '%q' "$JOB_BIN")"
  echo "SUBMITTED=$(date -u +%Y-%m-%dT%H:%M:%SZ)"
} >"$tmp"
mv -f "$tmp" "$LAST"

deps=()
if [ $NEED_MOTIONS = 1 ]; then
  motions_job=$("${motions_cmd[@]}")
  motions_job=${motions_job%%;*}
  note "motions job $motions_job"
  # The array waits for motions and is cancelled if motions fails, instead of pending forever.
  sweep_cmd=("${sweep_cmd[0]}" --dependency="afterok:$motions_job" --kill-on-invalid-dep=yes "${sweep_cmd[@]:1}")
  ida_cmd=("${ida_cmd[0]}" --dependency="afterok:$motions_job" --kill-on-invalid-dep=yes "${ida_cmd[@]:1}")
  deps+=("$motions_job")
fi
if [ $NEED_SWEEP = 1 ]; then
  array_job=$("${sweep_cmd[@]}")
  array_job=${array_job%%;*}
  note "sweep array $array_job: tasks $ARRAY_SPEC, shard K of N = $SHARDS in task K"
  deps=("$array_job")
fi
if [ $NEED_TNEW = 1 ]; then
  if [ $NEED_MERGE = 1 ]; then
    merge_cmd=("${merge_cmd[0]}" --dependency="afterany:$array_job" "${merge_cmd[@]:1}")
    merge_job=$("${merge_cmd[@]}")
    merge_job=${merge_job%%;*}
    note "merge job $merge_job: checks and merges the sweep's units"
    # The tnew array needs sweep.h5: cancelled if the merge fails, instead of pending forever.
    tnew_cmd=("${tnew_cmd[0]}" --dependency="afterok:$merge_job" --kill-on-invalid-dep=yes "${tnew_cmd[@]:1}")
  fi
  tnew_job=$("${tnew_cmd[@]}")
  tnew_job=${tnew_job%%;*}
  note "tnew array $tnew_job: tasks $TNEW_SPEC, tnew shard K of N = $TNEW_SHARDS in task K"
  deps=("$tnew_job")
fi
if [ $NEED_IDA = 1 ]; then
  ida_job=$("${ida_cmd[@]}")
  ida_job=${ida_job%%;*}
  note "ida array $ida_job: tasks $IDA_SPEC, IDA shard K of N = $IDA_SHARDS in task K"
  # The finishing job waits for the sweep array (or motions) and for the IDA array.
  if [ $NEED_SWEEP = 0 ] && [ $NEED_TNEW = 0 ]; then deps=(); fi
  deps+=("$ida_job")
fi
if [ ${#deps[@]} -gt 0 ]; then
  # afterany: starts however the tasks end, then checks that every unit is there.
  finish_cmd=("${finish_cmd[0]}" --dependency="afterany:$(
    IFS=:
    echo "${deps[*]}"
  )" "${finish_cmd[@]:1}")
fi
finish_job=$("${finish_cmd[@]}")
finish_job=${finish_job%%;*}
note "finishing job $finish_job"
note "logs in $LOGS; watch with: squeue --me; the report will be $OUT/report/index.html"
checker="the finishing job's log ($LOGS/finish-$finish_job.out)"
[ $NEED_MERGE = 0 ] || checker="the merge job's log ($LOGS/merge-$merge_job.out)"
[ $HAS_SWEEP = 0 ] || note "if a sweep task fails, $checker gives the command that resubmits only the failed shards"
