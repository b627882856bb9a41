#!/usr/bin/env bash
# What a simulation cache saves a chunk far into a long sequence: the
# tablecloth's 600 frames at 30 fps, its chunk 580..600 rendered without a
# cache (its cloth stepped from time 0: 1,933 steps before its first frame) and
# from one (stepped from frame 580), RUNS times each, alternating, in one run;
# then the medians, their ratio, the bake's time and the cache's bytes. Both
# chunks' frames are checked equal.
#
#   bash farm/bench_cache.sh            # SIZE=1280x720 RUNS=3 SCENE=scenes/tablecloth.scn
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${SCENE:-scenes/tablecloth.scn}
size=${SIZE:-1280x720}
runs=${RUNS:-3}
cargo build -q --release -p glint-cli
glint=$PWD/target/release/glint
export NODEVICE_SELECT=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }

started=$(now)
"$glint" bake "$scene" --frames 600 --fps 30 -o "$work/cache" 2>/dev/null
baked=$(awk -v a="$started" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }')
bytes=$(du -sb "$work/cache" | cut -f1)
files=$(find "$work/cache" -type f | wc -l)

chunk() { # FOLDER [options]: seconds
  local out=$1 t0
  shift
  rm -rf "$out"
  t0=$(now)
  "$glint" render "$scene" --size "$size" --frames 600 --fps 30 --frame-range 580..600 -o "$out/%04d.png" "$@" 2>/dev/null
  awk -v a="$t0" -v b="$(now)" 'BEGIN { printf "%.3f\n", b - a }'
}
without=() with=()
for ((r = 0; r < runs; r++)); do
  without+=("$(chunk "$work/without")")
  with+=("$(chunk "$work/with" --sim-cache "$work/cache")")
done
for f in "$work"/without/*.png; do
  cmp -s "$f" "$work/with/$(basename "$f")" || { echo "frame $(basename "$f") differs from the cache" >&2; exit 1; }
done
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
a=$(median "${without[@]}") b=$(median "${with[@]}")
echo "$scene, frames 580..600 of 600 at 30 fps, $size, $runs runs each (median; all: without ${without[*]}, with ${with[*]})"
echo "  without a cache: $a s"
echo "  from the cache:  $b s  ($(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.1f", a / b }')x faster; the 20 frames are the same bytes)"
echo "  bake of the 600 frames: $baked s; cache: $bytes bytes in $files files"
