#!/usr/bin/env bash
# The main job: a short run of the speed-against-error benchmark
# (bench/speed_error.sh): dnserver on the default device (lavapipe without a
# GPU), dnrender scene 1 (the room) at a small size, streamed through every
# pipeline the server offers and the baselines. Writes the denoised frames,
# side-by-side images and the metrics table to out/, and ends by listing
# every output with what it is.
set -euo pipefail
cd "$(dirname "$0")/.."
bench/speed_error.sh --scenes 1 --frames "${DN_FRAMES:-8}" --still 8 --size "${DN_SIZE:-256x144}" \
  --ref-spp "${DN_REF_SPP:-64}" --out out
cp out/results.md out/metrics.md

# Where each output is (only what this run wrote).
methods=""
for d in out/scene1/*/; do
  m=$(basename "$d")
  case "$m" in input | refs | still) ;; *) methods+="${methods:+, }$m" ;; esac
done
outputs=(
  "out/metrics.md|the metrics table (markdown): RMSE, relMSE, SSIM, temporal error, device and end-to-end ms per frame, device bytes per pixel of every method"
  "out/results.tsv|the same numbers as TSV, one row per method"
  "out/region.tsv|the error over regions of the frame only: glossy, highlights, disocclusions, roughness-mapped"
  "out/region_temporal.tsv|the still shot's temporal error over glossy surfaces"
  "out/scene1.png|side by side: the last frame of every method and the reference, each named in its label strip, with two enlarged crops"
  "out/speed_error.png|the plot: relMSE against device time per frame, one labelled point per method"
  "out/section.md|the above as the docs/results.md section (bench/speed_error.sh --docs puts it there)"
  "out/scene1/<method>/|the denoised frames (EXR, frame_%04d.exr; still/ the still-camera shot) of each method: $methods"
  "out/scene1/input/|the noisy input frames (dnrender, 1 spp, every channel)"
  "out/scene1/refs/|the references (ref_%04d.exr, ${DN_REF_SPP:-64} spp; ref2_ an independent second one)"
  "out/scene1/still/|the still-camera input frames"
  "out/dnserver.log|the server's log of the run"
)
echo
echo "main: outputs"
for o in "${outputs[@]}"; do
  path=${o%%|*}
  what=${o#*|}
  check=${path//<method>\//}
  [ -e "$check" ] || continue
  printf '  %-24s %s\n' "$path" "$what"
done
