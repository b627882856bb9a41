#!/usr/bin/env bash
# Submit a glint sequence to Slurm as a job array of chunks:
#
#   farm/slurm/submit.sh SCENE FRAMES OUT [sbatch options...]
#
# with CHUNK (frames a task, 100), FPS, SIZE, SIM_CACHE, GLINT and GLINT_ARGS
# passed on to each task (see render.sbatch). Prints the job's id. A
# cluster's MaxArraySize (1,001 by default) bounds the tasks: pick CHUNK so that
# FRAMES / CHUNK fits.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE FRAMES OUT [sbatch options...]" >&2
  exit 2
fi
scene=$1 frames=$2 out=$3
shift 3
chunk=${CHUNK:-100}
if ! [[ $frames =~ ^[1-9][0-9]*$ && $chunk =~ ^[1-9][0-9]*$ ]]; then
  echo "$0: FRAMES ($frames) and CHUNK ($chunk) must be whole numbers above 0" >&2
  exit 2
fi
tasks=$(( (frames + chunk - 1) / chunk ))
here=$(cd "$(dirname "$0")" && pwd)
export SCENE=$scene FRAMES=$frames OUT=$out CHUNK=$chunk
exec sbatch --parsable --array="0-$((tasks - 1))" --export=ALL "$@" "$here/render.sbatch"
