#!/usr/bin/env bash
# Lists what scripts/main.sh wrote under OUT (default out), one line per
# output with what it is; only what exists is listed.
#
#   scripts/list_outputs.sh [OUT]
set -euo pipefail
out=${1:-out}
methods=""
for d in "$out"/scene1/*/; do
  [ -d "$d" ] || continue
  m=$(basename "$d")
  case "$m" in input | refs | still) ;; *) methods+="${methods:+, }$m" ;; esac
done
outputs=(
  "metrics.md|the metrics table (markdown): RMSE, relMSE, SSIM, FLIP (LDR, HDR), frames worse than the noisy input, temporal error, device and end-to-end ms per frame, device bytes per pixel of every method"
  "results.tsv|the same numbers as TSV, one row per method"
  "region.tsv|the error over regions of the frame only: glossy, highlights, disocclusions, roughness-mapped"
  "region_temporal.tsv|the still shot's temporal error over glossy surfaces"
  "scene1.png|side by side: the last frame of every method and the reference, each named in its label strip, with two enlarged crops"
  "speed_error.png|the plot: relMSE against device time per frame, one labelled point per method"
  "section.md|the above as the docs/results.md section (bench/speed_error.sh --docs puts it there)"
  "scene1/<method>/|the denoised frames (EXR, frame_%04d.exr; still/ the still-camera shot) of each method: $methods"
  "scene1/input/|the noisy input frames (dnrender, 1 spp, every channel)"
  "scene1/refs/|the references (ref_%04d.exr, ${DN_REF_SPP:-64} spp; ref2_ an independent second one)"
  "scene1/still/|the still-camera input frames"
  "dnserver.log|the server's log of the run"
)
echo
echo "main: outputs"
for o in "${outputs[@]}"; do
  path=$out/${o%%|*}
  what=${o#*|}
  if [[ $path == *"<method>/" ]]; then
    [ -n "$methods" ] || continue
  else
    [ -e "$path" ] || continue
  fi
  printf '  %-24s %s\n' "$path" "$what"
done
