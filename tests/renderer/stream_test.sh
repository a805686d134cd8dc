#!/bin/sh
# End to end: dnrender streams three frames through a real dnserver (svgf on
# the default device) and writes what comes back; then extra samples (svgf)
# and the sample statistics (stat).
# Demodulated statistics: dnrender's session and dn denoise on its files
# (whose dn.stat_samples sets the parameter) give the same output.
# usage: stream_test.sh DNSERVER DNRENDER WORKDIR DN
# Exits 77 (skipped) when the server binary has not been built.
set -eu
server=$1
render=$2
dir=$3
dn=$4
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
# Fewer than one sample per pixel: progressive takes sample_count, so dnrender streams it.
"$render" --scene 2 --frames 4 --width 64 --height 36 --spp 0.25 --server "unix://$sock" --pipeline progressive \
  --out "$dir/progressive" 2>"$dir/progressive.log"
grep -q "channels:.* sample_count" "$dir/progressive.log"
# ... and says how to watch the session: a dn watch command given the session's key in its environment.
grep -q "watch it with: DN_WATCH_KEY=[0-9a-f]\{32\} dn watch --server unix://$sock --session [0-9]* --output" \
  "$dir/progressive.log"
for f in 0000 0003; do
  test -s "$dir/progressive/denoised_$f.exr"
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
# Demodulated statistics (--stats-demodulated): streamed to stat with demodulated = 1; dn denoise
# reads dn.stat_samples from the files and must open the same session: its output matches
# dnrender's up to the files' fp16 albedo, which the filter divides by (measured RMSE 1.7e-4,
# where statistics over radiance give 0.0196); a --param that contradicts the files is a usage
# error (exit 2).
"$render" --scene 1 --frames 2 --width 64 --height 36 --spp 4 --stats-demodulated --server "unix://$sock" \
  --pipeline stat --out "$dir/statd" --quiet
"$dn" denoise --server "unix://$sock" --pipeline stat --input "$dir/statd/frame_%04d.exr" --end 1 --quiet \
  --param radius=20 --reference "$dir/statd/denoised_%04d.exr" --summary "$dir/statd/summary.tsv"
rmse_d=$(awk -F'\t' 'NR == 2 { print $1 }' "$dir/statd/summary.tsv")
awk -v r="$rmse_d" 'BEGIN { exit !(r < 1e-3) }' ||
  { echo "stream_test: dn denoise differs from dnrender's session (RMSE $rmse_d)"; exit 1; }
# The same frames with statistics over radiance denoise differently: the comparison above can fail.
"$render" --scene 1 --frames 2 --width 64 --height 36 --spp 4 --stats --out "$dir/statr" --quiet
"$dn" denoise --server "unix://$sock" --pipeline stat --input "$dir/statr/frame_%04d.exr" --end 1 --quiet \
  --reference "$dir/statd/denoised_%04d.exr" --summary "$dir/statr/summary.tsv"
rmse_r=$(awk -F'\t' 'NR == 2 { print $1 }' "$dir/statr/summary.tsv")
awk -v r="$rmse_r" -v d="$rmse_d" 'BEGIN { exit !(r > 10 * d) }' ||
  { echo "stream_test: statistics over radiance give RMSE $rmse_r, not 10x the demodulated $rmse_d"; exit 1; }
status=0
"$dn" denoise --server "unix://$sock" --pipeline stat --input "$dir/statd/frame_%04d.exr" --end 1 --quiet \
  --param demodulated=0 2>"$dir/statd/contradiction.log" || status=$?
test "$status" = 2 || { echo "stream_test: a contradicting --param demodulated exited $status, not 2"; exit 1; }
grep -q "contradicts" "$dir/statd/contradiction.log"
echo "stream_test: 3 frames denoised, 2 with extra samples, 2 with sample statistics (stat), 2 demodulated"
