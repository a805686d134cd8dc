#!/usr/bin/env bash
# progressive's convergence below one sample per pixel (paper 004, progressive SVGF). For each dnrender scene, a still camera
# (--hold-camera 0: the frames differ only in noise, one reference) and a
# moving one (the scene's camera path, a reference per frame), F frames each
# rendered at 1, 1/4 and 1/16 spp per frame (dnrender --spp, stratified
# schedule: every pixel sampled exactly once in every 4 / 16 frames; unsampled
# pixels have sample_count 0), noisy frames at seed 3, denoised through
# `dn denoise` from the files (the dnrender preset sends sample_count to a
# pipeline that takes it, as streaming from dnrender does):
#   progressive at 1, 1/4 and 1/16 spp per frame, and
#   svgf at 1 spp per frame, the baseline at the same total samples
#   (progressive at 1/4 spp after frame k, 1-based, has k/4 samples per pixel,
#   like svgf after frame k/4).
# Per output frame (bench/progressive_metrics):
#   rmse        against reference 1;
#   nc_mse      the noise-corrected MSE, mean of (x - r1)(x - r2) over two
#               independent references (unbiased for the error against the
#               true image, docs/results.md); nc_relmse the same relative
#               (/ (mean reference^2 + 0.01));
#   nc_mse_noemit  nc_mse over the pixels with no emission in their 3x3
#               neighbourhood (input emission channel): without the light
#               sources' edges, where one centre sample per pixel aliases;
#   point_*     still camera only: rmse, nc_mse and nc_relmse against two
#               "point" references, each the mean of --point-ref-frames 1-spp
#               still frames (seeds 11 and 12). dnrender's sample 0 goes
#               through the pixel centre in every frame (also with --jitter:
#               a held camera keeps frame 0's jitter), so a still camera's
#               noisy frames converge to that point-sampled image, not to the
#               box-filtered --reference; the difference, at HDR edges (a
#               light seen through scene 3's slit, its reflection in scene 1's
#               mirror sphere), is an error floor no denoiser removes (the
#               plain mean of the noisy frames converges to the point
#               references, not to --reference);
#   temporal    mean |Y_f - Y_{f-1}| of linear luminance between consecutive
#               output frames (dn denoise's `temporal`, per pair; meaningful
#               on the still camera);
#   holes       pixels exactly 0 in R, G and B where reference 1 has a
#               channel > 0 and the input's point-sampled depth is a surface
#               (not background: at scene 3's slit the centre sample sees the
#               black outside, the box-filtered reference some light; every
#               method outputs 0 there); zero_px all exact zeros; nonfinite NaN/inf
#               pixels; uncovered (still camera) pixels no input frame has
#               sampled yet.
# Writes OUT/progressive.tsv (one row per scene, camera, method, spp and
# frame), OUT/summary.md (equal total spp 1, 4, 16, 64; temporal error; first
# hole-free frame) and three plots against total samples per pixel, log-log, a
# panel per scene and camera: OUT/progressive_convergence.png (noise-corrected
# RMSE against the references), ..._relmse.png (noise-corrected relMSE) and
# ..._point.png (still: against the point references; moving: without the
# emitters' neighbourhoods). --docs copies them to docs/images/.
# References: the moving camera's at --ref-spp per frame, the still camera's
# (path frame 0) at --still-ref-spp, the point references; all cached under
# --cache (the point references as progressive_point_<scene>_<W>x<H>_n<N>[_jitter]/:
# delete them when the renderer changes).
# --param NAME=VALUE (repeatable) passes a parameter to the progressive
# sessions (dn denoise --param), to measure a variant; svgf keeps its defaults.
# --jitter renders the noisy frames (and the point references) with dnrender
# --jitter: per-frame Halton jitter for the moving camera; the still camera
# keeps frame 0's jitter (dnrender takes the held frame's), so its sample 0
# only moves once.
# Environment: DN_BUILD_DIR (default build) holds the binaries; DN_SKIP_SETUP=1
# skips scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh
. bench/lib/point_reference.sh

scenes="1 3"
size=128x72
frames=64
ref_spp=128
still_ref_spp=4096
point_frames=1024
seed=3
out=out/progressive_convergence
cache=out/cache
docs=0
jitter=0
params=()
usage() {
  cat <<USAGE
usage: bench/progressive_convergence.sh [--scenes "1 3"] [--size WxH] [--frames F] [--ref-spp S]
                                        [--still-ref-spp S] [--point-ref-frames N] [--seed S] [--jitter]
                                        [--param NAME=VALUE ...]
                                        [--out DIR] [--cache DIR] [--docs]
defaults: --scenes "$scenes" --size $size --frames $frames --ref-spp $ref_spp --still-ref-spp $still_ref_spp
          --point-ref-frames $point_frames --seed $seed --out $out
USAGE
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --still-ref-spp) still_ref_spp=$2; shift 2 ;;
    --point-ref-frames) point_frames=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --jitter) jitter=1; shift ;;
    --param) params+=(--param "$2"); shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "progressive_convergence: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
width=${size%x*}
height=${size#*x}
case "$width$height" in *[!0-9]* | "") echo "progressive_convergence: --size wants WxH, got '$size'" >&2; exit 2 ;; esac
case "$frames$point_frames" in *[!0-9]*) echo "progressive_convergence: --frames and --point-ref-frames want numbers" >&2; exit 2 ;; esac
[ "$frames" -ge 2 ] && [ "$point_frames" -ge 2 ] ||
  { echo "progressive_convergence: need --frames >= 2 and --point-ref-frames >= 2" >&2; exit 2; }
case "$seed" in
  1 | 11 | 12) echo "progressive_convergence: --seed $seed is a reference's seed (1: --reference, 11, 12: point references)" >&2
    exit 2 ;;
esac
[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dnrender=$bin/examples/renderer/dnrender
dn=$bin/client/dn
metrics=$bin/bench/progressive_metrics
[ -x "$metrics" ] || { echo "progressive_convergence: $metrics is not built (cmake --build $bin --target progressive_metrics)" >&2; exit 1; }
mkdir -p "$out"
start_bench_server progressive_convergence "$bin" "$dn" "$out/dnserver.log"
t_start=$(date +%s)
jitter_arg=()
[ "$jitter" = 0 ] || jitter_arg=(--jitter)


# Rows: "method pipeline spp-per-frame tag".
rows=("svgf svgf 1 spp1" "progressive progressive 1 spp1" "progressive progressive 0.25 spp1_4"
      "progressive progressive 0.0625 spp1_16")
tsv="$out/progressive.tsv"
printf 'scene\tcamera\tmethod\tspp\tframe\ttotal_spp\trmse\tnc_mse\tref_noise_mse\ttemporal\tholes\tzero_px\tnonfinite\tuncovered\tnc_relmse\tnc_mse_noemit\tnoemit_px\tpoint_rmse\tpoint_nc_mse\tpoint_nc_relmse\n' > "$tsv"
for s in $scenes; do
  dir="$out/scene$s"
  echo "progressive_convergence: scene $s: references ($frames moving at $ref_spp spp, still at $still_ref_spp spp," \
    "point references of $point_frames frames; cached)"
  # The references (seed 1, the second its own); dnrender also renders seed 1's
  # noisy frames beside them: not used.
  "$dnrender" --scene "$s" --frames "$frames" --width "$width" --height "$height" --out "$dir/moving/refs" \
    --reference "$ref_spp" --reference2 --cache "$cache" --quiet
  "$dnrender" --scene "$s" --frames 1 --width "$width" --height "$height" --out "$dir/still/refs" \
    --reference "$still_ref_spp" --reference2 --cache "$cache" --quiet
  rm -f "$dir"/moving/refs/frame_*.exr "$dir"/still/refs/frame_*.exr
  point1=$(point_reference "$s" 1)
  point2=$(point_reference "$s" 2)
  for camera in still moving; do
    hold=()
    if [ "$camera" = still ]; then
      hold=(--hold-camera 0)
      ref=(--reference "$dir/still/refs/ref_0000.exr" --reference2 "$dir/still/refs/ref2_0000.exr")
    else
      ref=(--reference "$dir/moving/refs/ref_%04d.exr" --reference2 "$dir/moving/refs/ref2_%04d.exr")
    fi
    for x in 1 0.25 0.0625; do
      case "$x" in 1) tag=spp1 ;; 0.25) tag=spp1_4 ;; 0.0625) tag=spp1_16 ;; esac
      "$dnrender" --scene "$s" --frames "$frames" ${hold[@]+"${hold[@]}"} --width "$width" --height "$height" \
        --spp "$x" --seed "$seed" ${jitter_arg[@]+"${jitter_arg[@]}"} --out "$dir/$camera/input_$tag" --quiet
    done
    for row in "${rows[@]}"; do
      read -r method pipeline x tag <<< "$row"
      res="$dir/$camera/${method}_$tag"
      input="$dir/$camera/input_$tag/frame_%04d.exr"
      pipeline_params=()
      [ "$pipeline" != progressive ] || pipeline_params=(${params[@]+"${params[@]}"})
      "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" --preset dnrender \
        ${pipeline_params[@]+"${pipeline_params[@]}"} --input "$input" --start 0 --end $((frames - 1)) \
        --output "$res/frame_%04d.exr" --exr-float --summary "$res.summary.tsv"
      "$metrics" --output "$res/frame_%04d.exr" "${ref[@]}" --input "$input" --frames "$frames" | cut -f1-12 > "$res.tsv"
      if [ "$camera" = still ]; then
        "$metrics" --output "$res/frame_%04d.exr" --reference "$point1" --reference2 "$point2" --frames "$frames" |
          cut -f2,3,10 > "$res.point.tsv"
      else
        # No point references; no "uncovered" (a moving camera's pixels change places).
        awk -F'\t' -v OFS='\t' 'NR > 1 { $9 = "nan" } 1' "$res.tsv" > "$res.tsv.new" && mv "$res.tsv.new" "$res.tsv"
        awk 'BEGIN { print "rmse\tnc_mse\tnc_relmse" } NR > 1 { print "nan\tnan\tnan" }' "$res.tsv" > "$res.point.tsv"
      fi
      paste "$res.tsv" "$res.point.tsv" |
        awk -F'\t' -v OFS='\t' -v s="$s" -v c="$camera" -v m="$method" -v x="$x" \
          'NR > 1 { t = ($1 + 1) * x; $1 = $1 OFS t; print s, c, m, x, $0 }' >> "$tsv"
      echo "progressive_convergence: scene $s $camera: $method at $x spp/frame done"
    done
  done
done
t_end=$(date +%s)

# Equal total samples per pixel, the temporal error and the first hole-free frame.
{
  echo "Command: \`bench/progressive_convergence.sh --scenes \"$scenes\" --size $size --frames $frames --ref-spp $ref_spp --still-ref-spp $still_ref_spp --point-ref-frames $point_frames --seed $seed$([ "$jitter" = 0 ] || echo " --jitter")\`; device \`$device\`; $((t_end - t_start)) s after the server started."
  echo
  echo "Error at equal total samples per pixel (frame: the 1-based frame at which the method reaches them). nc = noise-corrected; \"no emitters\": over pixels without emission in their 3x3 neighbourhood; \"point\": still camera, against the mean of $point_frames 1-spp still frames (what the noisy frames converge to):"
  echo
  echo "| scene | camera | method | spp/frame | total spp | frame | nc MSE | RMSE | nc relMSE | nc MSE, no emitters | nc MSE, point | nc relMSE, point |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
  for s in $scenes; do
    for camera in still moving; do
      for total in 1 4 16 64; do
        awk -F'\t' -v s="$s" -v c="$camera" -v t="$total" 'NR > 1 && $1 == s && $2 == c && $6 == t {
          printf "| %s | %s | %s | %s | %s | %d | %.4g | %.4g | %.4g | %.4g | %.4g | %.4g |\n",
            $1, $2, $3, $4, $6, $5 + 1, $8, $7, $15, $16, $19, $20 }' "$tsv"
      done
    done
  done
  echo
  echo "Temporal error (mean |Y_f - Y_{f-1}|, linear luminance) at the last frame and its mean over the second half of the frames; the first 1-based frame with no hole (output 0 in R, G, B where reference 1 > 0 and the input depth is a surface), the last with one, and the most holes in a frame; the first frame at which every pixel has had a sample (still camera); NaN or infinite output pixels over all frames:"
  echo
  echo "| scene | camera | method | spp/frame | temporal, last frame | temporal, frames $((frames / 2 + 1))-$frames | first hole-free frame | last frame with holes | max holes | every pixel sampled from frame | non-finite pixels |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
  awk -F'\t' -v F="$frames" '
    NR > 1 {
      k = $1 "|" $2 "|" $3 "|" $4
      if (!(k in seen)) { seen[k] = 1; order[++n] = k; first[k] = "never"; last[k] = "none"; maxh[k] = 0; cov[k] = "-" }
      if ($5 == F - 1) tlast[k] = $10
      if ($5 >= F / 2) { tsum[k] += $10; tn[k]++ }
      if ($11 == 0 && first[k] == "never") first[k] = $5 + 1
      if ($11 > 0) last[k] = $5 + 1
      if ($11 > maxh[k]) maxh[k] = $11
      if ($14 != "nan" && $14 == 0 && cov[k] == "-") cov[k] = $5 + 1
      nonfin[k] += $13
    }
    END {
      for (i = 1; i <= n; ++i) {
        k = order[i]; split(k, p, "|")
        printf "| %s | %s | %s | %s | %.4g | %.4g | %s | %s | %d | %s | %d |\n", p[1], p[2], p[3], p[4], tlast[k],
          tsum[k] / tn[k], first[k], last[k], maxh[k], cov[k], nonfin[k]
      }
    }' "$tsv"
} > "$out/summary.md"

# The plots, against total samples per pixel, log-log, a panel per scene and
# camera. Values are clamped at 1e-12 (a noise-corrected MSE can come out
# slightly negative within the references' noise); RMSE = sqrt(MSE).
nscenes=$(echo $scenes | wc -w)
title_extra=""
[ "$jitter" = 0 ] || title_extra=", --jitter"
# plot_error FILE YLABEL EXPR STILL_COLUMN MOVING_COLUMN STILL_TITLE MOVING_TITLE
# (EXPR an awk expression of v, the column's value).
plot_error() {
  local file=$1 ylabel=$2 expr=$3 still_col=$4 moving_col=$5 still_title=$6 moving_title=$7
  {
    echo "set terminal png size 1100,$((380 * nscenes)) font ',10' noenhanced"
    echo "set output '$out/$file'"
    echo "set multiplot layout $nscenes,2 title 'progressive (1, 1/4, 1/16 spp/frame) and svgf (1 spp/frame) against total samples ($size, dnrender$title_extra)'"
    echo "set logscale xy"
    echo "set grid"
    echo "set key bottom left"
    echo "set xlabel 'total samples per pixel'"
    echo "set ylabel '$ylabel'"
    for s in $scenes; do
      for camera in still moving; do
        local col=$still_col title=$still_title
        [ "$camera" = still ] || { col=$moving_col; title=$moving_title; }
        local plots=""
        for row in "${rows[@]}"; do
          read -r method pipeline x tag <<< "$row"
          local dat="$out/plot/scene${s}_${camera}_${method}_${tag}_$col.dat"
          mkdir -p "$out/plot"
          awk -F'\t' -v s="$s" -v c="$camera" -v m="$method" -v x="$x" -v col="$col" \
            'NR > 1 && $1 == s && $2 == c && $3 == m && $4 == x { v = ($col > 1e-12 ? $col : 1e-12); print $6, '"$expr"' }' \
            "$tsv" > "$dat"
          [ -z "$plots" ] || plots+=", "
          plots+="'$dat' with linespoints pt 7 ps 0.4 title '$method $x spp/frame'"
        done
        echo "set title 'scene $s, $camera camera$title'"
        echo "plot $plots"
      done
    done
    echo "unset multiplot"
  } | gnuplot
}
plot_error progressive_convergence.png 'noise-corrected RMSE' 'sqrt(v)' 8 8 '' ''
plot_error progressive_convergence_relmse.png 'noise-corrected relMSE' 'v' 15 15 '' ''
plot_error progressive_convergence_point.png 'noise-corrected RMSE' 'sqrt(v)' 19 16 \
  ": vs mean of $point_frames 1-spp frames" ', no emission in 3x3'

echo
cat "$out/summary.md"
echo
echo "progressive_convergence: $tsv, $out/summary.md, $out/progressive_convergence{,_relmse,_point}.png"
if [ "$docs" = 1 ]; then
  mkdir -p docs/images
  cp "$out/progressive_convergence.png" "$out/progressive_convergence_relmse.png" \
    "$out/progressive_convergence_point.png" docs/images/
fi
