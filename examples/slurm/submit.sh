#!/bin/bash
# Submit a sharded vrpt render to Slurm: a job array of N shards (render-array.sbatch),
# then the merge (merge.sbatch), which starts only when every shard has succeeded.
#
#   VRPT=$PWD/target/release/vrpt SCENE=scenes/cornell-box SPP=1024 N=8 OUT=$PWD/out \
#       examples/slurm/submit.sh [SBATCH OPTIONS...]
#
# SBATCH OPTIONS (e.g. --partition=cpu --account=me --cpus-per-task=8) go to both sbatch
# calls. The other variables are those of render-array.sbatch (VRPT, SCENE, SPP, SEED,
# WIDTH, HEIGHT, MAX_DEPTH, PASS_SPP, VRPT_ARGS); N defaults to 4, OUT to ./vrpt-out.
# OUT must be on a filesystem every node sees; the jobs' logs go there too.
#
# Prints the two job ids, the last two lines as `array_job=ID` and `merge_job=ID`.
# Follow them with `squeue -u $USER`; the result is $OUT/merged.exr.

set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
N=${N:-4}
OUT=${OUT:-vrpt-out}
if ! [[ $N =~ ^[1-9][0-9]*$ ]]; then
    echo "submit.sh: N must be a positive integer, not '$N'" >&2
    exit 2
fi
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
export N OUT

# Stale shards of an earlier run would be merged with the new ones (vrpt merge would
# refuse a mismatch, but better not to start from them).
rm -f "$OUT"/shard-*.exr "$OUT/merged.exr"

array_job=$(sbatch --parsable --array="0-$((N - 1))" --output="$OUT/slurm-%A_%a.out" \
    "$@" "$here/render-array.sbatch")
array_job=${array_job%%;*}  # "id;cluster" on a multi-cluster setup
merge_job=$(sbatch --parsable --dependency="afterok:$array_job" --output="$OUT/slurm-%j-merge.out" \
    "$@" "$here/merge.sbatch")
merge_job=${merge_job%%;*}

echo "submitted $N shards as array job $array_job, merge as job $merge_job (after $array_job succeeds)"
echo "result: $OUT/merged.exr; logs: $OUT/slurm-*.out"
echo "array_job=$array_job"
echo "merge_job=$merge_job"
