#!/usr/bin/env bash
# The almost empty frame: glint drawing the peers' scene with one cube
# (scenes/bench/peer_cubes_1.scn) beside three-d 0.19 drawing the same, in turn,
# three rounds, and glint's whole frame over three-d's (below 1: glint is faster).
# Usage (from the project root):  scripts/empty_frame.sh [FRAMES]
# Needs three-d's program, built by ../shared/peers/run.sh (or its first lines).
set -eu
F=${1:-200}
TD=target/peers/release/peer-three-d
[[ -x $TD ]] || { echo "no $TD: run ../shared/peers/run.sh once to build it"; exit 1; }
cargo build --release -q --bin glint
median() { python3 -c 'import json,sys
for line in reversed(sys.stdin.read().splitlines()):
    try: d=json.loads(line); break
    except Exception: pass
for k in sys.argv[1].split("."): d=d[k]
print(d)' "$1"; }
for round in 1 2 3; do
  g=$(target/release/glint bench scenes/bench/peer_cubes_1.scn --mode optimized --json --frames "$F" --size 640x360 --msaa 1 2>/dev/null | median modes.optimized.frame_ms_median)
  t=$("$TD" --n 1 --frames "$F" --warmup 5 2>/dev/null | median ms_median)
  python3 -c "import sys; g,t=map(float,sys.argv[1:3]); print(f'one cube round {sys.argv[3]}: glint {g:.3f} ms  three-d {t:.3f} ms  glint/three-d {g/t:.2f}')" "$g" "$t" "$round"
done
