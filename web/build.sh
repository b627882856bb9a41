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

cargo build --profile web --locked --target wasm32-unknown-unknown -p glint-web
rm -rf web/dist
mkdir -p web/dist
wasm-bindgen --target web --no-typescript --out-dir web/dist target/wasm32-unknown-unknown/web/glint_web.wasm
web/node_modules/.bin/wasm-opt -Oz --enable-reference-types --enable-bulk-memory --enable-nontrapping-float-to-int \
  --enable-sign-ext --enable-mutable-globals --enable-multivalue --strip-debug --strip-producers \
  web/dist/glint_web_bg.wasm -o web/dist/glint_web_bg.wasm
cp web/index.html web/dist/
mkdir -p web/dist/scenes
cp scenes/*.scn web/dist/scenes/
cp -r assets web/dist/assets
rm -rf web/dist/assets/fonts
for file in glint_web_bg.wasm glint_web.js index.html; do
  echo "web/dist/$file: $(wc -c < "web/dist/$file") bytes, gzipped $(gzip -9 < "web/dist/$file" | wc -c) bytes"
done
echo "web/dist: $(du -sh web/dist | cut -f1); page (wasm + js + html): $(cat web/dist/glint_web_bg.wasm web/dist/glint_web.js web/dist/index.html | wc -c) bytes, gzipped $(cat web/dist/glint_web_bg.wasm web/dist/glint_web.js web/dist/index.html | gzip -9 | wc -c) bytes"
