#!/usr/bin/env bash
# Builds the viewer: message code from proto/sportsim/v1 (protoc + protoc-gen-es) into web/gen/,
# then one bundle with esbuild. Usage: web/build.sh OUT_DIR   (default: web/dist)
# Needs node_modules (npm ci in web/) and protoc on PATH.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here/dist}
proto_root=$here/../proto
mkdir -p "$out" "$here/gen"
if [ ! -x "$here/node_modules/.bin/protoc-gen-es" ]; then
  echo "web/build.sh: run 'npm ci' in web/ first" >&2
  exit 1
fi
# Generate into a private directory, then copy over gen/: two build directories building at once
# write the same files.
tmp=$(mktemp -d "$here/gen.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
protoc -I "$proto_root" \
  --plugin=protoc-gen-es="$here/node_modules/.bin/protoc-gen-es" \
  --es_out="$tmp" --es_opt=target=js+dts,import_extension=js \
  "$proto_root"/sportsim/v1/*.proto
cp -R "$tmp/." "$here/gen/"
"$here/node_modules/.bin/esbuild" "$here/src/main.js" --bundle --format=iife --target=es2022 \
  --minify --sourcemap --legal-comments=none --log-level=warning --outfile="$out/app.js"
cp "$here/static/index.html" "$here/static/app.css" "$out/"
echo "web/build.sh: viewer in $out ($(wc -c < "$out/app.js") bytes of script)"
