#!/usr/bin/env bash
# Build the web page into web/dist: glint-web for wasm32, its JavaScript glue
# (wasm-bindgen at the version in Cargo.lock), size-optimised with wasm-opt,
# beside index.html and the demo scenes and assets. Installs what it needs (idempotent). Serve web/dist with any static
# server, e.g. `python3 -m http.server -d web/dist`.
set -euo pipefail
cd "$(dirname "$0")/.."

rustup target list --installed | grep -qx wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' Cargo.lock)
if ! wasm-bindgen --version 2>/dev/null | grep -q " $version\$"; then
  cargo install wasm-bindgen-cli --version "$version"
fi
# wasm-opt from npm's binaryen (the version in web/package-lock.json): Debian's
# is too old for the reference types rustc now emits, and breaks the module.
(cd web && npm ci --no-audit --no-fund --silent)

rm -rf web/dist
mkdir -p web/dist
# Two modules: glint_web_webgl2 (glint-web's feature `webgl`) and
# glint_web_webgpu (`webgpu`: no wgpu-core and no naga, since glint's shaders
# are WGSL made when glint is built). index.html loads the one the browser can use.
for module in webgl2 webgpu; do
  feature=webgpu
  [ "$module" = webgl2 ] && feature=webgl
  cargo build --profile web --locked --target wasm32-unknown-unknown -p glint-web --no-default-features --features "$feature"
  wasm-bindgen --target web --no-typescript --out-dir web/dist --out-name "glint_web_$module" \
    target/wasm32-unknown-unknown/web/glint_web.wasm
  web/node_modules/.bin/wasm-opt -Oz --enable-reference-types --enable-bulk-memory --enable-nontrapping-float-to-int \
    --enable-sign-ext --enable-mutable-globals --enable-multivalue --strip-debug --strip-producers \
    "web/dist/glint_web_${module}_bg.wasm" -o "web/dist/glint_web_${module}_bg.wasm"
done
cp web/index.html web/dist/
mkdir -p web/dist/scenes
cp scenes/*.scn web/dist/scenes/
cp -r assets web/dist/assets
rm -rf web/dist/assets/fonts
# Gzipped bytes of files served one by one.
gz() { local sum=0 f; for f in "$@"; do sum=$((sum + $(gzip -9 < "$f" | wc -c))); done; echo "$sum"; }
for file in glint_web_webgl2_bg.wasm glint_web_webgl2.js glint_web_webgpu_bg.wasm glint_web_webgpu.js index.html; do
  echo "web/dist/$file: $(wc -c < "web/dist/$file") bytes, gzipped $(gz "web/dist/$file") bytes"
done
# What a browser downloads: one module, its glue and the page.
for module in webgl2 webgpu; do
  files=("web/dist/glint_web_${module}_bg.wasm" "web/dist/glint_web_$module.js" web/dist/index.html)
  echo "the $module page (wasm + js + html): $(cat "${files[@]}" | wc -c) bytes, gzipped $(gz "${files[@]}") bytes"
done
