#!/bin/sh
# End to end: dnrender streams three frames through a real dnserver (svgf on
# the default device) and writes what comes back.
# usage: stream_test.sh DNSERVER DNRENDER WORKDIR
# Exits 77 (skipped) when the server binary has not been built.
set -eu
server=$1
render=$2
dir=$3
if [ ! -x "$server" ]; then
  echo "stream_test: $server not built, skipped"
  exit 77
fi
rm -rf "$dir"
mkdir -p "$dir"
sock="$dir/dn.sock"
"$server" --listen "unix://$sock" --log-level warn >"$dir/server.log" 2>&1 &
pid=$!
trap 'kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true' EXIT
i=0
while [ ! -S "$sock" ] && [ "$i" -lt 300 ]; do
  sleep 0.1
  i=$((i + 1))
done
"$render" --scene 2 --frames 3 --width 64 --height 36 --server "unix://$sock" --pipeline svgf --out "$dir/out" --quiet
for f in 0000 0001 0002; do
  test -s "$dir/out/frame_$f.exr"
  test -s "$dir/out/denoised_$f.exr"
done
# Guide rays (--extra-samples): the session declares the extra samples' planes.
"$render" --scene 2 --frames 2 --width 64 --height 36 --extra-samples 2 --server "unix://$sock" --pipeline svgf \
  --out "$dir/guide" --quiet
for f in 0000 0001; do
  test -s "$dir/guide/denoised_$f.exr"
done
echo "stream_test: 3 frames denoised, 2 with extra samples"
