#!/usr/bin/env bash
# Submits a study to Slurm or PBS: one job per run still to compute, each with its own ranks and its own
# continuation at the time limit, started only after the run whose stages it reuses; then one last job that
# writes the summaries and the robustness page. Run by `divcoll study STUDY --out DIR --submit slurm|pbs`
# (which validates the study, writes DIR's manifest and DIR/jobs/runs.tsv, then hands over to this script):
#   study-submit.sh slurm|pbs --study FILE --out DIR --runs RUNS.tsv --of N --name NAME --bin DIVCOLL
#                   --ranks-per-run R --max-parallel K [--dry-run] [-- scheduler options...]
# RUNS.tsv: jobs/lib/study-job.sh. --dry-run prints the commands and the dependencies and submits nothing.
#
# Slurm: one array whose task K is run K (jobs/slurm/study-run.sbatch), --array=<runs>%K, submitted held; each
# run that reuses another run's stages gets `scontrol update JobId=<array>_K Dependency=afterok:<array>_B`
# (Slurm splits that task off the array, and the %K limit still counts it), then the array is released. A
# task that fails makes its dependants' dependency impossible; --kill-on-invalid-dep=yes cancels them, so that
# the report job (afterany on the whole array) still runs and lists what failed.
# PBS (PBS Pro / OpenPBS): no dependency on one subjob, so the runs go in levels: level 0 computes from scratch,
# level L reuses a run of level L-1. One array per level (-J 1-M%K, subjob i runs the i-th run of
# DIR/jobs/level-L.runs; a level of one run is a plain job), level L after level L-1 (depend=afterok). A
# subjob that reaches its walltime resubmits itself as a plain job; a run of the next level that then finds
# its base not complete (divcoll exit 3) resubmits itself after the base's continuation job.
set -euo pipefail

die() {
  echo "study-submit: error: $*" >&2
  exit 2
}
sched=${1:-}
shift || true
[ "$sched" = slurm ] || [ "$sched" = pbs ] || die "first argument: slurm or pbs"
study='' dir='' runs='' of='' name='' bin='' ranks=1 maxp=0 dry=0
while [ $# -gt 0 ]; do
  case $1 in
    --study) study=$2; shift 2 ;;
    --out) dir=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --of) of=$2; shift 2 ;;
    --name) name=$2; shift 2 ;;
    --bin) bin=$2; shift 2 ;;
    --ranks-per-run) ranks=$2; shift 2 ;;
    --max-parallel) maxp=$2; shift 2 ;;
    --dry-run) dry=1; shift ;;
    --) shift; break ;;
    *) die "unknown argument $1" ;;
  esac
done
extra=("$@")
{ [ -n "$study" ] && [ -n "$dir" ] && [ -f "$runs" ] && [ -n "$bin" ]; } || die "--study, --out, --runs and --bin are required"
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export DIVCOLL_STUDY_DIR=$dir
# shellcheck source=jobs/lib/study-job.sh
source "$root/jobs/lib/study-job.sh"

mapfile -t nums < <(cut -f1 "$runs")
declare -A path dep stages reuses
for k in "${nums[@]}"; do
  path[$k]=$(study_field "$k" 2 "$runs")
  dep[$k]=$(study_field "$k" 3 "$runs")
  stages[$k]=$(study_field "$k" 4 "$runs")
  reuses[$k]=$(study_field "$k" 5 "$runs")
done
if [ "$dry" = 1 ]; then rm -f "$runs"; fi
env_vars="DIVCOLL_ROOT=$root,DIVCOLL_BIN=$bin,DIVCOLL_STUDY=$study,DIVCOLL_STUDY_DIR=$dir"
scheduler=$([ "$sched" = slurm ] && echo Slurm || echo PBS)
echo "study $name: $of runs, ${#nums[@]} to compute ($((of - ${#nums[@]})) complete), $ranks rank(s) each," \
  "$([ "$maxp" -gt 0 ] && echo "at most $maxp at once" || echo "no limit on how many at once"); ${scheduler}$([ "$dry" = 1 ] && echo ", dry run: nothing is submitted")"

# a run whose job is still queued or running is not submitted twice
if [ "$dry" = 0 ]; then
  for k in "${nums[@]}"; do
    j=$(study_recorded "${path[$k]}" job)
    s=$(study_recorded "${path[$k]}" state)
    case $s in queued | running | requeued | resubmitted) ;; *) continue ;; esac
    if [ "$sched" = slurm ]; then
      [ -n "$(squeue -h -j "$j" -o %i 2> /dev/null)" ] || continue
    else
      qstat "$j" > /dev/null 2>&1 || continue
    fi
    die "run $k (${path[$k]}) still has job $j in the queue: wait for it to end, or cancel it, then submit again"
  done
fi

# runs a command, or prints it for a dry run; prints its output (a job id)
exec 3>&1
submit() {
  if [ "$dry" = 1 ]; then
    local a line='  $'
    for a in "$@"; do
      case $a in *[[:space:]]*) line+=" '$a'" ;; *) line+=" $a" ;; esac
    done
    echo "$line" >&3
    echo "${dry_id:-<job>}"
  else
    "$@"
  fi
}

if [ "$sched" = slurm ]; then
  script=$root/jobs/slurm/study-run.sbatch
  common=(--parsable --open-mode=append)
  report=()
  if [ ${#nums[@]} -gt 0 ]; then
    spec=$(IFS=,; echo "${nums[*]}")
    [ "$maxp" -gt 0 ] && spec+="%$maxp"
    hold=()
    for k in "${nums[@]}"; do [ "${dep[$k]}" != 0 ] && hold=(--hold); done
    [ "$dry" = 1 ] && echo "commands:"
    dry_id='<A>'
    a=$(submit sbatch "${common[@]}" --export="ALL,$env_vars" "${hold[@]}" --array="$spec" --ntasks="$ranks" --job-name="divcoll-$name" \
      --output="$dir/jobs/%x-%A_%a.out" --kill-on-invalid-dep=yes "${extra[@]}" "$script")
    a=${a%%;*}
    for k in "${nums[@]}"; do
      if [ "${dep[$k]}" != 0 ]; then
        submit scontrol update JobId="${a}_$k" Dependency="afterok:${a}_${dep[$k]}" > /dev/null ||
          { scancel "$a"; die "could not make run $k wait for run ${dep[$k]}; the array $a is cancelled"; }
      fi
    done
    if [ ${#hold[@]} -gt 0 ]; then submit scontrol release "$a" > /dev/null; fi
    report=(--dependency="afterany:$a")
    for k in "${nums[@]}"; do
      if [ "$dry" = 0 ]; then
        study_record "${path[$k]}" scheduler=slurm "job=${a}_$k" "log=$dir/jobs/divcoll-$name-${a}_$k.out" state=queued
      fi
    done
  fi
  dry_id='<R>'
  r=$(submit sbatch "${common[@]}" "${report[@]}" --ntasks=1 --job-name="divcoll-$name-report" \
    --output="$dir/jobs/%x-%j.out" "${extra[@]}" --export="ALL,$env_vars,DIVCOLL_STUDY_REPORT=1" "$script")
  r=${r%%;*}
  echo "jobs:"
  for k in "${nums[@]}"; do
    after=
    [ "${dep[$k]}" != 0 ] && after=" after ${a}_${dep[$k]} (reuses ${reuses[$k]})"
    [ "${dep[$k]}" = 0 ] && [ "${reuses[$k]}" != - ] && after=" (reuses ${reuses[$k]}, complete)"
    printf '  %-10s run %s %s: %s%s\n' "${a}_$k" "$k" "${path[$k]}" "${stages[$k]}" "$after"
  done
  printf '  %-10s divcoll report %s%s\n' "$r" "$dir" "$([ ${#nums[@]} -gt 0 ] && echo " after every task of $a (afterany)")"
else
  script=$root/jobs/pbs/study-run.pbs
  # levels: a run waits for a run of the level before it
  declare -A level
  top=0
  for k in "${nums[@]}"; do
    if [ "${dep[$k]}" = 0 ]; then level[$k]=0; else level[$k]=$((${level[${dep[$k]}]} + 1)); fi
    [ "${level[$k]}" -gt "$top" ] && top=${level[$k]}
  done
  [ "$dry" = 1 ] && echo "commands:"
  ids=() prev=
  if [ ${#nums[@]} -gt 0 ]; then
    for l in $(seq 0 "$top"); do
      list=$dir/jobs/level-$l.runs
      members=()
      for k in "${nums[@]}"; do [ "${level[$k]}" = "$l" ] && members+=("$k"); done
      [ "$dry" = 0 ] && printf '%s\n' "${members[@]}" > "$list"
      args=(-N "divcoll-$name" -l "select=1:ncpus=$ranks:mpiprocs=$ranks" -j oe -o "$dir/jobs/")
      if [ ${#members[@]} -gt 1 ]; then
        args+=(-J "1-${#members[@]}$([ "$maxp" -gt 0 ] && echo "%$maxp")" -v "$env_vars,DIVCOLL_STUDY_LEVEL_FILE=$list")
      else
        args+=(-v "$env_vars,DIVCOLL_STUDY_RUN=${members[0]}")
      fi
      [ -n "$prev" ] && args+=(-W "depend=afterok:$prev")
      dry_id="<L$l>"
      id=$(submit qsub "${args[@]}" "${extra[@]}" "$script")
      ids+=("$id")
      prev=$id
      for k in "${members[@]}"; do
        [ "$dry" = 0 ] && study_record "${path[$k]}" scheduler=pbs "job=$id" state=queued
        printf '  level %s %-10s run %s %s: %s%s\n' "$l" "$id" "$k" "${path[$k]}" "${stages[$k]}" \
          "$([ "${dep[$k]}" != 0 ] && echo " after level $((l - 1)) (reuses ${reuses[$k]})")"
      done
    done
  fi
  dry_id='<R>'
  dep_all=$(IFS=:; echo "${ids[*]}")
  rargs=(-N "divcoll-$name-report" -l select=1:ncpus=1:mpiprocs=1 -j oe -o "$dir/jobs/" -v "$env_vars,DIVCOLL_STUDY_REPORT=1")
  [ -n "$dep_all" ] && rargs+=(-W "depend=afterany:$dep_all")
  r=$(submit qsub "${rargs[@]}" "${extra[@]}" "$script")
  echo "  report   $r divcoll report $dir$([ -n "$dep_all" ] && echo " after every level (afterany)")"
fi
echo "follow it: $bin study $dir --status"
