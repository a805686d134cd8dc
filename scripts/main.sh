#!/usr/bin/env bash
# The main job: starts dnserver on the default device (lavapipe without a GPU),
# renders a short sequence, streams it through every available pipeline with
# the dn client, and writes denoised images plus a metrics table to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh

out=out
frames=${DN_FRAMES:-16}
width=${DN_WIDTH:-320}
height=${DN_HEIGHT:-180}
mkdir -p "$out"
socket="/tmp/dnserver-main-$$.sock"

echo "main: rendering $frames frames of ${width}x${height}"
build/examples/synthetic/dnsynth --out "$out/input" --frames "$frames" --width "$width" --height "$height"

build/server/dnserver --listen "unix://$socket" --log-level warn 2> "$out/dnserver.log" &
server=$!
trap 'kill -TERM $server 2>/dev/null || true; wait $server 2>/dev/null || true' EXIT
for _ in $(seq 1 300); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { echo "main: dnserver did not start:"; cat "$out/dnserver.log"; exit 1; }

table="$out/metrics.md"
{
  echo "# Metrics: ${frames} frames, ${width}x${height}, dnsynth scene"
  echo
  echo "Device: $(build/client/dn ping --server "unix://$socket" --count 1 | sed -n '1s/.* on //p')"
  echo
  echo "Means over all frames against the noise-free reference; SSIM on ACES-tone-mapped luma."
  echo "End-to-end: submit to result through the socket, 3 frames in flight. Server: upload + device passes + download."
  echo
  echo "| pipeline | RMSE | relMSE | SSIM | end-to-end ms/frame | server ms/frame |"
  echo "|---|---|---|---|---|---|"
} > "$table"

# Every pipeline the server offers, as WELCOME lists them.
pipelines=$(build/client/dn ping --server "unix://$socket" --count 1 | awk '$1 == "pipeline" { print $2 }')
for pipeline in $pipelines; do
  mkdir -p "$out/$pipeline"
  build/client/dn denoise -q --server "unix://$socket" --pipeline "$pipeline" --preset dnrender \
    --input "$out/input/frame_%04d.exr" --start 0 --end $((frames - 1)) \
    --output "$out/$pipeline/frame_%04d.exr" --png "$out/$pipeline/frame_%04d.png" \
    -r "$out/input/ref_%04d.exr" --summary "$out/$pipeline/summary.tsv"
  # summary.tsv: one header line, one line of means.
  tail -n 1 "$out/$pipeline/summary.tsv" |
    awk -F'\t' -v p="$pipeline" '{ printf "| %s | %.5f | %.5f | %.4f | %.1f | %.2f |\n", p, $1, $2, $3, $4, $5 }' >> "$table"
done

echo
cat "$table"
echo
echo "main: denoised frames in $out/<pipeline>/, metrics in $table"
