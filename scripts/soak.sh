#!/usr/bin/env bash
# Soak benchmark: 2,000 frames of the showcase on Vulkan and on GL, and the process's
# resident memory after measured frame 100 and at the end (glint bench's
# resident_mib_frame_100 / resident_mib_end). Growth past the warm-up is a leak:
# glint's, or a driver's (examples/bare_cubes.rs draws with wgpu alone to tell).
# Usage (from the project root):  scripts/soak.sh [FRAMES] [SIZE]
set -eu
F=${1:-2000}; S=${2:-640x360}
cargo build --release -q --bin glint
for backend in vulkan gl; do
  WGPU_BACKEND=$backend target/release/glint bench scenes/showcase.scn --mode optimized --json \
      --frames "$F" --size "$S" 2>/dev/null | python3 -c '
import json, sys
backend, frames = sys.argv[1], sys.argv[2]
m = json.loads(sys.stdin.read().splitlines()[-1])["modes"]["optimized"]
a, b = m["resident_mib_frame_100"], m["resident_mib_end"]
print(f"{backend:>6}: {frames} frames, {m['"'"'frame_ms_median'"'"']:.2f} ms median; resident {a:.1f} MiB after frame 100, {b:.1f} MiB at the end ({b - a:+.1f} MiB)")' "$backend" "$F"
done
