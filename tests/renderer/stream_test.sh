#!/bin/sh
# End to end: dnrender streams three frames through a real dnserver (svgf on
# the default device) and writes what comes back; then extra samples (svgf)
# and the sample statistics (stat).
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
# Sample statistics (--stats, channels 51-54, fp32): streamed to stat, which requires them...
"$render" --scene 2 --frames 2 --width 64 --height 36 --spp 4 --stats --server "unix://$sock" --pipeline stat \
  --out "$dir/stat" 2>"$dir/stat.log"
grep -q "channels:.* stat_count stat_mean stat_m2 stat_m3" "$dir/stat.log"
for f in 0000 0001; do
  test -s "$dir/stat/denoised_$f.exr"
done
# ... and not to a pipeline that takes none (the server would refuse them): said on stderr.
"$render" --scene 2 --frames 1 --width 64 --height 36 --stats --server "unix://$sock" --pipeline svgf --quiet \
  2>"$dir/svgf_stats.log"
grep -q -- "--stats is ignored for streaming: pipeline svgf" "$dir/svgf_stats.log"
echo "stream_test: 3 frames denoised, 2 with extra samples, 2 with sample statistics (stat)"
