#!/usr/bin/env bash
# glint on real schedulers: a single-node Slurm cluster started here renders a
# sequence as a job array of chunks (with and without a simulation cache, and
# a failed task run again), and the Open Job Description template is checked
# and run with the reference CLI; every frame must equal the whole run's, byte
# for byte. Ends with "N passed, M failed" (exit 1 if any failed).
#
#   bash farm/test.sh
#
# FARM_SCENE, FARM_FRAMES (a multiple of 4), FARM_SIZE and FARM_FPS pick the
# sequence (tests/scenes/school.scn, 24 frames of 64x48 at 30 fps); GLINT the
# binary (else target/debug/glint, built if missing). Installs Debian's
# slurm-wlm and munge and a virtual environment with openjd-cli where missing.
set -uo pipefail
cd "$(dirname "$0")/.."
root=$PWD

scene=${FARM_SCENE:-tests/scenes/school.scn}
frames=${FARM_FRAMES:-24}
size=${FARM_SIZE:-64x48}
fps=${FARM_FPS:-30}
chunk=$((frames / 4))
openjd_version=0.8.0
export NODEVICE_SELECT=1

if [ -z "${GLINT:-}" ]; then
  cargo build -q -p glint-cli || exit 1
  GLINT=$root/target/debug/glint
fi
venv=$root/target/farm-venv
if ! "$venv/bin/openjd" --version 2>/dev/null | grep -q "$openjd_version"; then
  rm -rf "$venv"
  if ! python3 -m venv "$venv" 2>/dev/null; then
    # Debian's python3 makes virtual environments with python3-venv only.
    if [ "$(id -u)" = 0 ]; then apt-get install -y -qq python3-venv >/dev/null; else sudo apt-get install -y -qq python3-venv >/dev/null; fi
    rm -rf "$venv"
    python3 -m venv "$venv" || exit 1
  fi
  "$venv/bin/pip" install -q "openjd-cli==$openjd_version" || exit 1
fi

work=$(mktemp -d)
export GLINT_SLURM_DIR=$work/slurm SLURM_CONF=$work/slurm/slurm.conf
cleanup() { farm/slurm/cluster.sh stop >/dev/null 2>&1; rm -rf "$work"; }
trap cleanup EXIT

passed=0 failed=0
pass() { echo "ok: $1"; passed=$((passed + 1)); }
fail() { echo "FAILED: $1"; failed=$((failed + 1)); }
now() { date +%s.%N; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }

# "" when every frame in folder $1 equals the whole run's, else what differs.
differs() {
  local k name out=""
  for ((k = 0; k < frames; k++)); do
    name=$(printf '%04d.png' "$k")
    if [ ! -f "$1/$name" ]; then out+=" $name missing"; elif ! cmp -s "$work/whole/$name" "$1/$name"; then out+=" $name differs"; fi
  done
  echo "$out"
}

# Wait for Slurm job $1 (at most FARM_TIMEOUT seconds, 600, then it is
# cancelled); "" when every task completed with exit code 0.
wait_job() {
  local deadline=$((SECONDS + ${FARM_TIMEOUT:-600}))
  while [ -n "$(squeue -h -j "$1" 2>/dev/null)" ]; do
    if [ "$SECONDS" -ge "$deadline" ]; then
      scancel "$1"
      echo "timed out after ${FARM_TIMEOUT:-600} s: $(squeue -h -j "$1" -o '%i %T %r' | head -3)"
      return
    fi
    sleep 0.1
  done
  scontrol show job "$1" | grep -o 'JobState=[A-Z_]*\|ExitCode=[0-9:]*' | grep -v 'JobState=COMPLETED\|ExitCode=0:0' | sort | uniq -c
}

# The reference: the whole sequence in one run.
started=$(now)
if ! "$GLINT" render "$scene" --frames "$frames" --fps "$fps" --size "$size" -o "$work/whole/%04d.png" 2>"$work/whole.log"; then
  cat "$work/whole.log"
  fail "the whole run of $scene"
  echo "$passed passed, $failed failed"
  exit 1
fi
whole=$(seconds "$started" "$(now)")
echo "whole run: $frames frames of $scene in $whole s"

# Slurm: the array of 4 chunks, as a cluster user submits it.
if farm/slurm/cluster.sh start; then
  pass "a single-node Slurm cluster starts (and says so when started again: $(farm/slurm/cluster.sh start))"
  submit() { # OUT SIM_CACHE [sbatch options]: the job's id. Submitted from
    # the project's folder (the tasks' working directory, so the scene's assets
    # lie inside it), with each task's log at OUT-TASK.log.
    local out=$1 cache=$2
    shift 2
    CHUNK=$chunk SIZE=$size FPS=$fps GLINT=$GLINT SIM_CACHE=$cache \
      farm/slurm/submit.sh "$scene" "$frames" "$out/%04d.png" --output="$out-%a.log" "$@"
  }
  started=$(now)
  job=$(submit "$work/slurm" "")
  bad=$(wait_job "$job")
  array=$(seconds "$started" "$(now)")
  wrong=$(differs "$work/slurm")
  if [ -z "$bad" ] && [ -z "$wrong" ]; then
    pass "a Slurm array of 4 chunks draws the whole run's $frames frames ($array s, the whole run $whole s)"
  else
    fail "the Slurm array:$bad$wrong"
  fi
  if grep -q "^frame $chunk: time" "$work/slurm-1.log"; then
    pass "each task's log has a line a frame"
  else
    fail "task 1's log: $(head -3 "$work/slurm-1.log")"
  fi

  # From a simulation cache: each chunk starts at its first frame.
  if "$GLINT" bake "$scene" --frames "$frames" --fps "$fps" --every "$chunk" -o "$work/cache" 2>"$work/bake.log"; then
    started=$(now)
    job=$(submit "$work/cached" "$work/cache")
    bad=$(wait_job "$job")
    cached=$(seconds "$started" "$(now)")
    wrong=$(differs "$work/cached")
    if [ -z "$bad" ] && [ -z "$wrong" ] && grep -q "resumed from frame $((3 * chunk))" "$work/cached-3.log"; then
      pass "the array from a simulation cache draws the same frames ($cached s)"
    else
      fail "the array from a cache:$bad$wrong $(head -2 "$work/cached-3.log")"
    fi
  else
    fail "glint bake: $(tail -3 "$work/bake.log")"
  fi

  # A failed task run again draws only its missing frames.
  rm -f "$work/slurm/$(printf '%04d' "$((chunk + 1))").png" "$work/slurm/$(printf '%04d' "$((chunk + 2))").png"
  job=$(submit "$work/slurm" "" --array=1)
  bad=$(wait_job "$job")
  drawn=$(grep -c "^frame" "$work/slurm-1.log")
  wrong=$(differs "$work/slurm")
  if [ -z "$bad" ] && [ -z "$wrong" ] && [ "$drawn" = 2 ]; then
    pass "a task run again (--skip-existing) draws only its 2 missing frames"
  else
    fail "the rerun task:$bad$wrong, $drawn frames drawn"
  fi
  farm/slurm/cluster.sh stop >/dev/null && pass "the cluster stops"
else
  fail "the Slurm cluster did not start"
fi

# Open Job Description: the template passes the reference checker, a broken
# one does not, and a local run of it (bake, then the chunks) draws the frames.
openjd=$venv/bin/openjd
if "$openjd" check farm/glint.openjd.yaml >/dev/null; then
  pass "openjd check farm/glint.openjd.yaml"
else
  fail "openjd check: $("$openjd" check farm/glint.openjd.yaml 2>&1 | tail -3)"
fi
sed '/^- TASK_CHUNKING/d' farm/glint.openjd.yaml > "$work/broken.yaml"
if ! "$openjd" check "$work/broken.yaml" >/dev/null 2>&1; then
  pass "openjd check refuses the template without its TASK_CHUNKING extension"
else
  fail "openjd check passed a template with chunks but no TASK_CHUNKING extension"
fi
started=$(now)
# Its tasks run in a session folder of their own: the project's folder is
# named as an asset root.
if "$openjd" run farm/glint.openjd.yaml --step Render --run-dependencies \
  -p Scene="$root/$scene" -p Frames="$frames" -p Fps="$fps" -p ChunkSize="$chunk" -p Size="$size" \
  -p Output="$work/openjd" -p Glint="$GLINT" -p ExtraArgs="--asset-root $root" >"$work/openjd.log" 2>&1; then
  ran=$(seconds "$started" "$(now)")
  wrong=$(differs "$work/openjd")
  if [ -z "$wrong" ] && grep -q "Chunks run: 5" "$work/openjd.log"; then
    pass "openjd run: a bake and 4 chunks draw the whole run's frames ($ran s)"
  else
    fail "openjd run:$wrong $(grep 'Chunks run' "$work/openjd.log")"
  fi
else
  fail "openjd run: $(tail -5 "$work/openjd.log")"
fi

echo "$passed passed, $failed failed"
[ "$failed" = 0 ]
