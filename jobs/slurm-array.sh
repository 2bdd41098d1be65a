#!/bin/sh
# A Slurm batch script for array jobs: each task renders its chunk of a raybundle job, and the
# tasks together write the same bits as one process rendering the whole range.
#
#   sbatch --array=0-3 jobs/slurm-array.sh                    # the demo in 4 chunks
#   RB_JOB=shot.yaml RB_ARGS="--frames 1-100 --out /farm/shot" sbatch --array=0-9 jobs/slurm-array.sh
#
# Environment (sbatch passes the submitting shell's environment to the tasks):
#   RB_JOB      the job file (default: jobs/demo.yaml, relative to the submit directory)
#   RAYBUNDLE   the raybundle binary (default: build/raybundle when the submit directory has
#               one, otherwise raybundle on PATH)
#   RB_ARGS     more options for `raybundle render`, split at spaces (default: none)
# Each task runs `raybundle render RB_JOB --chunk slurm --resume --progress=openjd RB_ARGS`:
# its chunk comes from SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT (so any --array=A-B or
# A-B:S works), a requeued or resubmitted task keeps the frames already written, and progress
# goes to the task's log as openjd_progress lines. Exit status 1 is worth a retry, 2 is not
# (see raybundle(1)).
#SBATCH --job-name=raybundle
#SBATCH --array=0-3
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --output=raybundle-%A_%a.log
set -eu
cd "${SLURM_SUBMIT_DIR:-.}"
job=${RB_JOB:-jobs/demo.yaml}
if [ -z "${RAYBUNDLE:-}" ]; then
    if [ -x build/raybundle ]; then RAYBUNDLE=build/raybundle; else RAYBUNDLE=raybundle; fi
fi
# shellcheck disable=SC2086 # RB_ARGS is a list of options
exec "$RAYBUNDLE" render "$job" --chunk slurm --resume --progress=openjd ${RB_ARGS:-}
