#!/bin/bash
# The study on a Slurm cluster: motions (here), the sweep as a job array of SHARDS tasks, then
# merge, tnew, fit and report in one job that starts when every shard has succeeded.
#   pipelines/slurm-submit.sh configs/paper.yaml out/paper 16
set -euo pipefail
CONFIG=${1:-configs/paper.yaml}
OUT=${2:-out/paper}
SHARDS=${3:-16}
SLIDESTACK=${SLIDESTACK:-target/release/slidestack}
[ -x "$SLIDESTACK" ] || cargo build --release
"$SLIDESTACK" motions "$CONFIG" --out "$OUT"
array=$(sbatch --parsable --array="1-$SHARDS" pipelines/sweep.slurm "$CONFIG" "$OUT")
sbatch --dependency="afterok:$array" --job-name=slidestack-finish --wrap \
  "$SLIDESTACK merge $CONFIG --out $OUT && $SLIDESTACK run $CONFIG --out $OUT"
echo "submitted sweep array $array ($SHARDS shards) and the finishing job"
