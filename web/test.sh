#!/usr/bin/env bash
# The web page's browser test: build web/dist when it is older than the sources,
# serve it, and drive Debian's Chromium (headless, SwiftShader's WebGL2 and
# WebGPU) through web/test.mjs, which prints "N passed, M failed". Installs
# what it needs (idempotent): chromium, node's playwright-core (no browser
# download: it drives the system one).
set -euo pipefail
cd "$(dirname "$0")/.."

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }
missing=()
dpkg -s chromium >/dev/null 2>&1 || missing+=(chromium)
command -v npm >/dev/null || missing+=(nodejs npm)
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  as_root apt-get update -qq
  as_root apt-get install -y -qq "${missing[@]}"
fi
(cd web && npm ci --no-audit --no-fund --silent)

stale=$(find crates/glint/src crates/glint-web web/index.html web/build.sh scenes assets Cargo.lock \
  -newer web/dist/glint_web_webgpu_bg.wasm 2>/dev/null | head -1 || true)
if [ ! -f web/dist/glint_web_webgpu_bg.wasm ] || [ -n "$stale" ]; then
  bash web/build.sh
fi
# The page's size budgets: gzipped bytes a browser downloads (its module's
# wasm and js, and the html; build.sh prints them). A change that grows the
# page past one fails here. Lowered as the page shrinks; the WebGL2 one was its
# target (issue 33, 1,300,000), the WebGPU one 2% over its size when set. Both
# were raised by 45 KB and 60 KB for levels of detail (issue 47): meshoptimizer's
# simplifier, which the page runs to make its shapes' levels, is about 51 KB
# gzipped in each module. Both grew by 12 KB for glTF's MSFT_lod (the same
# crate's surface-distance measurement of each given level, and its reader),
# and by 11 KB for the school drawn in place from the GPU (issue 48: its
# step, sort and placing shaders and their Rust, which World now reaches; the
# WebGL2 module carries them unused, as it does the GPU particles), and by
# 13 KB for the cloth solved on the GPU and drawn in place (issue 48: its
# Vertex Block Descent and placing shaders, its colouring and buffers), and
# by 6 KB for light clusters (issue 49: the binning, the cluster array and
# the forward shader's CLUSTERED text, in each module), and by 6.5 KB for the
# GPU's binning passes, the heat map and lit particles' shader variants
# (issue 49 again), and by 6 KB for accumulated stills and soft shadows
# (issue 51: the fold and copy passes and their shader, the soft-shadow
# shader text, the samples-per-pixel and sun-size controls), and by 8 KB for
# SMAA (issue 51: its three passes' shader text, about 4 KB gzipped, the
# area texture's generator, the stencil pipelines and the anti-aliasing
# control; the 25 KB area texture itself is computed, not shipped), and by
# 9 KB (WebGL2) and 10 KB (WebGPU) for order-independent transparency
# (issue 51: the weighted and exact twins, their targets, composites and
# shader text, the particles' twins and the transparency control; each module
# carries the exact path unused, as browsers cannot keep its lists).
for budget in webgl2:1418000 webgpu:791000; do
  module=${budget%%:*} budget=${budget#*:}
  page=0
  for f in "web/dist/glint_web_${module}_bg.wasm" "web/dist/glint_web_$module.js" web/dist/index.html; do
    page=$((page + $(gzip -9 < "$f" | wc -c)))
  done
  echo "the $module page: $page bytes gzipped (budget $budget)"
  if [ "$page" -gt "$budget" ]; then
    echo "FAIL the $module page is $page bytes gzipped, over its budget of $budget" >&2
    exit 1
  fi
done
# A broken scene the page must report (line 3: a camera origin of two numbers).
printf '{\n"classname" "camera"\n"origin" "0 1"\n}\n' > web/dist/scenes/broken.scn
# A sign stored sideways in a JPEG whose EXIF orientation turns it upright: the
# page's browser turns it as it decodes it, and glint's own decoder must too.
cat > web/dist/scenes/turned.scn <<'EOF'
{ "classname" "world"
"ambient" "1 1 1" }
{ "classname" "camera"
"origin" "0 0 2.2"
"target" "0 0 0" }
{ "classname" "material"
"name" "sign"
"diffuse_map" "../assets/textures/turned.jpg" }
{ "classname" "entity"
"mesh" "cube"
"material" "sign"
"scale" "2 1 0.05" }
EOF
# The small school of the native tests (400 fish and a shark), each fish an
# untextured cube: the page's rasterizer and glint's sample a texture this
# small on screen differently, which the comparison is not about.
sed -e 's#"mesh" "\.\./\.\./assets/underwater/fish\.obj"#"mesh" "cube"\n"material" "fish"#' -e '/"mtl\.fish\./d' \
  -e 's#\.\./\.\./assets/#../assets/#' tests/scenes/school.scn > web/dist/scenes/school.scn
printf '{ "classname" "material"\n"name" "fish"\n"base_color" "0.9 0.6 0.2" }\n' >> web/dist/scenes/school.scn
# Two small cloths the native tests solve on the GPU (a pinned sheet swinging,
# a free one dropped on the floor).
cp tests/scenes/cloth_gpu.scn web/dist/scenes/cloth_gpu.scn
# Soft shadows from a sun and a spot light with a size.
cp tests/scenes/soft_shadows.scn web/dist/scenes/soft_shadows.scn
# SMAA after tonemapping.
cp tests/scenes/smaa.scn web/dist/scenes/smaa.scn
# Crossing glass: weighted transparency (exact, the scene's own, is native
# only: the page must say so).
sed 's/"transparency" "exact"/"transparency" "weighted"/' tests/scenes/transparency.scn > web/dist/scenes/transparency.scn
cp tests/scenes/transparency.scn web/dist/scenes/transparency_exact.scn

cargo build -q -p glint-cli
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
python3 -m http.server "$port" --bind 127.0.0.1 -d web/dist >/dev/null 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$port/index.html" >/dev/null && break; sleep 0.1; done
node web/test.mjs "http://127.0.0.1:$port" "$PWD/target/debug/glint" "$PWD/web/output"
