#!/usr/bin/env bash
# A sharded `patchwork check` of a corpus as a Slurm job array, and the merge after it.
#
#   cd CORPUS && SHARDS=8 bash /path/to/deploy/slurm-array.sh submit
#
# `submit` (on the login node) submits `slurm-array.sh shard` as an array of SHARDS tasks
# (--array=0-(SHARDS-1)) and `slurm-array.sh merge` as one job that waits for the whole array
# (--dependency=afterany: it runs even when a task failed, and then names the missing shard).
# Every task runs `patchwork check --shard auto`: Slurm's SLURM_ARRAY_TASK_ID, _MIN and _COUNT
# say which shard it is, and the task writes RESULTS/shard-ID.json. A task whose shard file
# is written ends with 0 even when its cases cracked: those are results, and `merge` prints
# the unsharded run's summary and exits with its code (0 passed, 1 a crack, 2 an error or a
# missing / duplicated shard) into RESULTS/merge.log.
#
# Settings (environment, read at submission; sbatch exports them to the jobs):
#   SHARDS       number of array tasks (8)
#   CORPUS_LIST  the model files, one path per line, relative to the folder submitted from
#                (files.txt): case ids then do not depend on where the corpus is mounted
#   CHECK_ARGS   flags of `patchwork check` shared by every shard ("--views 50")
#   RESULTS      folder for the shard files, failure images (named by case id), logs (results)
#   PATCHWORK    the patchwork binary (patchwork on the PATH)
#   SBATCH_ARGS  more sbatch flags for both jobs: partition, time, account ("")
set -euo pipefail

: "${SHARDS:=8}"
: "${CORPUS_LIST:=files.txt}"
: "${CHECK_ARGS:=--views 50}"
: "${RESULTS:=results}"
: "${PATCHWORK:=patchwork}"
: "${SBATCH_ARGS:=}"

case "${1:-}" in
submit)
  mkdir -p "$RESULTS"
  # shellcheck disable=SC2086 # SBATCH_ARGS holds several flags
  array=$(sbatch --parsable $SBATCH_ARGS --job-name=patchwork-check \
    --array="0-$((SHARDS - 1))" --output="$RESULTS/slurm-%A_%a.log" "$0" shard)
  array=${array%%;*} # --parsable prints JOBID[;CLUSTER]
  # shellcheck disable=SC2086
  merge=$(sbatch --parsable $SBATCH_ARGS --job-name=patchwork-merge \
    --dependency="afterany:$array" --output="$RESULTS/merge.log" "$0" merge)
  echo "array job $array ($SHARDS shards), merge job ${merge%%;*}: see $RESULTS/merge.log"
  ;;
shard)
  # lavapipe (Mesa's software Vulkan) wants a private runtime folder.
  if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "$XDG_RUNTIME_DIR" ]; then
    XDG_RUNTIME_DIR=$(mktemp -d)
    export XDG_RUNTIME_DIR
  fi
  out="$RESULTS/shard-${SLURM_ARRAY_TASK_ID:?not in a Slurm array task}.json"
  rm -f "$out" # a rerun never leaves an earlier result in its place
  set +e
  # shellcheck disable=SC2086 # CHECK_ARGS holds several flags
  "$PATCHWORK" check --files-from "$CORPUS_LIST" $CHECK_ARGS --shard auto \
    --out "$out" --save-failures "$RESULTS/failures"
  status=$?
  set -e
  if [ -f "$out" ]; then
    exit 0 # the shard ran: its verdict is the merge's
  fi
  exit "$status"
  ;;
merge)
  exec "$PATCHWORK" merge "$RESULTS"/shard-*.json
  ;;
*)
  echo "usage: $0 submit|shard|merge (see the comment at the top)" >&2
  exit 2
  ;;
esac
