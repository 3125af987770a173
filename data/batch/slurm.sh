#!/bin/bash
# A tryon batch as a Slurm array job: array task I runs part I of N of the manifest
# (`--shard I/N`; job k of the manifest is in part k mod N), each on one node's cores. The output
# folder must be on a file system every node sees. See docs/scale.md.
#
#   sbatch data/batch/slurm.sh                        # the 4 parts
#   sbatch --dependency=afterany:<array job id> --wrap \
#       "tryon batch data/batch/makehuman-cross.toml --summary"   # the summary of all parts
#
# Preempted or failed tasks: submit the same array again; jobs already done are skipped and
# interrupted ones go on from their checkpoints.
#SBATCH --job-name=tryon-batch
#SBATCH --array=0-3
#SBATCH --cpus-per-task=8
#SBATCH --mem=16G
#SBATCH --time=04:00:00
#SBATCH --output=tryon-batch-%A_%a.log
set -euo pipefail

MANIFEST=${MANIFEST:-data/batch/makehuman-cross.toml}
export TRYON_DATA=${TRYON_DATA:-$HOME/tryon-data}

srun tryon batch "$MANIFEST" \
    --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}" \
    --jobs "${SLURM_CPUS_PER_TASK}"
