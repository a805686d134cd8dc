#!/usr/bin/env bash
# A still view converges. For each dnrender scene, a still camera
# (--hold-camera 0: the frames differ only in noise, seed 3) at 1 spp per
# frame, denoised through `dn denoise` by every svgf-family pipeline, by
# stat-temporal from the radiance alone (the frames carry no statistics), and by
# the plain running mean of the inputs (accumulate with alpha_min 0 and
# max_history 1024). Each output frame n is measured against two "point"
# references, each the mean of --point-ref-frames 1-spp still frames (seeds
# 11 and 12; dnrender's sample 0 goes through the pixel centre in every
# frame, so the noisy frames converge to that image, not to a box-filtered
# render: bench/progressive_convergence.sh, whose cached references these
# are): rmse against the first, and the noise-corrected MSE and relMSE over
# both (bench/progressive_metrics), which take out the references' own noise,
# and the HDR-FLIP against the first.
# Writes OUT/still.tsv (every frame) and OUT/still.md: per scene and method
# RMSE / nc relMSE / HDR-FLIP after 1, 2, 4, ... frames, and at how many of
# those frame counts the method is above the running mean (by each).
# Environment: DN_BUILD_DIR (default build) holds the binaries; DN_SKIP_SETUP=1
# skips scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh
. bench/lib/point_reference.sh

scenes="1 2 3 4 5 6"
frames=64
size=128x72
point_frames=1024
out=out/still
cache=out/cache
usage() {
  cat <<EOF
usage: bench/still_convergence.sh [--scenes "1 2"] [--frames N] [--size WxH] [--point-ref-frames N]
                                  [--out DIR] [--cache DIR]
defaults: --scenes "$scenes" --frames $frames --size $size --point-ref-frames $point_frames --out $out
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --point-ref-frames) point_frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "still_convergence: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
width=${size%x*}
height=${size#*x}
case "$width$height$frames$point_frames" in *[!0-9]* | "") echo "still_convergence: bad --size, --frames or --point-ref-frames" >&2; exit 2 ;; esac
[ "$frames" -ge 2 ] || { echo "still_convergence: need --frames >= 2" >&2; exit 2; }

[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dnrender=$bin/examples/renderer/dnrender
dn=$bin/client/dn
metrics=$bin/bench/progressive_metrics
mkdir -p "$out"
start_bench_server still "$bin" "$dn" "$out/dnserver.log"


# Rows: "label pipeline [NAME=VALUE ...]"; the running mean first.
rows=("mean accumulate alpha_min=0 max_history=1024" "svgf svgf" "svgf-fb svgf-fb" "reflect reflect"
      "progressive progressive" "stat-temporal stat-temporal" "svgf-no-converge svgf converge_still=0")
tsv="$out/still.tsv"
printf 'scene\tmethod\tframes\trmse\tnc_mse\tnc_relmse\tflip_hdr\n' > "$tsv"
for s in $scenes; do
  dir="$out/scene$s"
  echo "still_convergence: scene $s: $frames still frames at ${width}x${height}, point references of $point_frames frames (cached)"
  point1=$(point_reference "$s" 1)
  point2=$(point_reference "$s" 2)
  "$dnrender" --scene "$s" --frames "$frames" --hold-camera 0 --width "$width" --height "$height" --reflection \
    --seed 3 --out "$dir/input" --quiet
  for row in "${rows[@]}"; do
    read -r label pipeline params <<< "$row"
    param_args=()
    for p in $params; do param_args+=(--param "$p"); done
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" --preset dnrender "${param_args[@]}" \
      --input "$dir/input/frame_%04d.exr" --start 0 --end $((frames - 1)) --output "$dir/$label/frame_%04d.exr" \
      --exr-float > /dev/null
    "$metrics" --output "$dir/$label/frame_%04d.exr" --reference "$point1" --reference2 "$point2" --frames "$frames" |
      awk -F'\t' -v OFS='\t' -v s="$s" -v m="$label" 'NR > 1 { print s, m, $1 + 1, $2, $3, $10, $13 }' >> "$tsv"
  done
done

# The table: per scene and method, RMSE / nc relMSE / HDR-FLIP at 1, 2, 4,
# ... frames, at how many of those the method is above the running mean, and
# at how many it is above its own value at the count before (rises).
awk -F'\t' -v frames="$frames" '
  NR == 1 { next }
  { key = $1 SUBSEP $2; rmse[key, $3] = $4; rel[key, $3] = $6; flip[key, $3] = $7
    if (!(key in seen)) { seen[key] = 1; order[++n] = key } }
  END {
    line = "| scene | method |"; sep = "|---|---|"
    for (f = 1; f <= frames; f *= 2) { line = line " " f " |"; sep = sep "---|" }
    print line " above the mean (RMSE / nc relMSE / ꟻLIP) | rises |"; print sep "---|---|"
    for (i = 1; i <= n; ++i) {
      split(order[i], k, SUBSEP); mean = k[1] SUBSEP "mean"
      line = "| " k[1] " | " k[2] " |"; a = 0; b = 0; d = 0; c = 0; ra = 0; rb = 0; rd = 0
      for (f = 1; f <= frames; f *= 2) {
        line = line sprintf(" %.4f / %.4f / %.4f |", rmse[order[i], f], rel[order[i], f], flip[order[i], f]); ++c
        if (rmse[order[i], f] > rmse[mean, f]) ++a
        if (rel[order[i], f] > rel[mean, f]) ++b
        if (flip[order[i], f] > flip[mean, f]) ++d
        if (f > 1 && rmse[order[i], f] > rmse[order[i], f / 2]) ++ra
        if (f > 1 && rel[order[i], f] > rel[order[i], f / 2]) ++rb
        if (f > 1 && flip[order[i], f] > flip[order[i], f / 2]) ++rd
      }
      print line " " a " / " b " / " d " of " c " | " ra " / " rb " / " rd " |"
    }
  }' "$tsv" > "$out/still.md"
echo "still_convergence: table $out/still.md (RMSE against the first point reference / noise-corrected relMSE / HDR-FLIP)"
cat "$out/still.md"
