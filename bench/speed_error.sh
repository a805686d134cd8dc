#!/usr/bin/env bash
# Speed against error. For each dnrender scene: a moving-camera sequence with
# high-sample references and a still shot (--hold-camera) are rendered once,
# then streamed through every pipeline the server offers and the baselines
# (the noisy input, plain temporal accumulation, and a non-temporal
# edge-avoiding a-trous filter). Writes to OUT: results.tsv, results.md (the
# table), region.tsv (error over glossy surfaces, highlights, disocclusions and
# roughness-mapped surfaces), region_temporal.tsv (the still shot's temporal
# error over glossy surfaces), speed_error.png (plot) and scene<N>.png (side by
# side with crops).
# Two independent references per frame (dnrender --reference2: the second has
# a seed of its own; the noisy inputs are rendered with seed 3, so they share
# random numbers with neither) give the noise-corrected MSE and the references'
# own noise (dn denoise --reference2, metrics.hpp); --no-reference2 skips the
# second one. Also per method: LDR- and HDR-FLIP (dn/image/flip.hpp; LDR on the
# ACES-tone-mapped frames) and in how many frames the output's RMSE / relMSE is
# above the noisy input's own (dn denoise -r: worse_rmse, worse_relmse).
# --docs also copies the images to docs/images/ and puts the section into
# docs/results.md between its speed-error markers.
# Environment: DN_BUILD_DIR (default build) holds the binaries; DN_SKIP_SETUP=1
# skips scripts/setup.sh (the tests run this on a build they just made).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh

scenes="1 2 3 4 5 6"
frames=12        # moving-camera frames per scene
still=16         # still-camera frames per scene (the second half is measured)
size=320x180
ref_spp=256
out=out/bench
cache=out/cache
docs=0
reference2=1
usage() {
  cat <<EOF
usage: bench/speed_error.sh [--scenes "1 2 3 4"] [--frames N] [--still N] [--size WxH]
                            [--ref-spp S] [--out DIR] [--cache DIR] [--no-reference2] [--docs]
defaults: --scenes "$scenes" --frames $frames --still $still --size $size --ref-spp $ref_spp --out $out
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --still) still=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    --no-reference2) reference2=0; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "speed_error: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
width=${size%x*}
height=${size#*x}
case "$width$height" in *[!0-9]* | "") echo "speed_error: --size wants WxH, got '$size'" >&2; exit 2 ;; esac
[ "$frames" -ge 2 ] && [ "$still" -ge 4 ] || { echo "speed_error: need --frames >= 2 and --still >= 4" >&2; exit 2; }

[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dnrender=$bin/examples/renderer/dnrender
dn=$bin/client/dn
mkdir -p "$out"

start_bench_server bench "$bin" "$dn" "$out/dnserver.log"

# Rows: "label pipeline [NAME=VALUE | channels=LIST ...]". The baselines
# first, then every other pipeline the server offers (new ones are picked up
# without changes), then svgf on the split lighting (diffuse + specular).
rows=("noisy passthrough" "accumulate accumulate" "atrous svgf max_history=1")
# stat is left out: it filters the frame's own sample statistics, and a
# 1-spp frame has n = 1 (no variance); its evidence is convergence against
# samples (bench/stat_convergence.sh). stat-temporal accumulates them across
# frames (the inputs carry dnrender --stats), also at the radius 6 of paper
# 003's fast setting.
for p in $("$dn" ping --server "$server_url" --count 1 | awk '$1 == "pipeline" { print $2 }'); do
  case "$p" in passthrough | accumulate | stat) ;; *) rows+=("$p $p") ;; esac
done
rows+=("svgf-split svgf channels=diffuse,specular,albedo,normal,depth,motion,emission")
case " ${rows[*]} " in *" stat-temporal stat-temporal "*) rows+=("stat-temporal-r6 stat-temporal radius=6 sigma_spatial=3") ;; esac
# reflect without specular history: the thesis's NoSpecReproj baseline
# (paper 001 §7.2) its temporal error is compared with.
case " ${rows[*]} " in *" reflect reflect "*) rows+=("reflect-nospec reflect specular_history=0") ;; esac

# Column NAME of a `dn denoise --summary` file.

# The roughness values of each scene's roughness-mapped surfaces (dnrender
# scenes.cpp); region_metrics adds glossy surfaces, highlights and
# disocclusions for every scene: error over those pixels only goes to region.tsv.
region_roughness() { case "$1" in 1) echo 0.04,0.35 ;; 5) echo 0.03,0.4 ;; esac; }
region="$out/region.tsv"
printf 'scene\tregion\tmethod\trmse\trelmse\tssim\tnc_mse\tnc_relmse\tref_noise_mse\tpixels\n' > "$region"
region_temporal="$out/region_temporal.tsv"
printf 'scene\tregion\tmethod\ttemporal\tpixels\n' > "$region_temporal"

results="$out/results.tsv"
printf 'scene\tmethod\trmse\trelmse\tssim\ttemporal\tdevice_ms\tframe_ms\tbytes_per_pixel\tnc_mse\tnc_relmse\tref_noise_mse\tflip_ldr\tflip_hdr\tworse_rmse\tworse_relmse\n' > "$results"
last=$(printf '%04d' $((frames - 1)))
for s in $scenes; do
  dir="$out/scene$s"
  echo "speed_error: scene $s: rendering $frames frames + $still still frames at ${width}x${height}, references at $ref_spp spp"
  # The references (seed 1, the second its own) into refs/ (dnrender also renders
  # that seed's noisy frames there: not used), the noisy inputs at seed 3.
  ref2_args=()
  [ "$reference2" = 0 ] || ref2_args=(--reference2)
  "$dnrender" --scene "$s" --frames "$frames" --width "$width" --height "$height" --out "$dir/refs" \
    --reference "$ref_spp" "${ref2_args[@]}" --cache "$cache" --quiet
  rm -f "$dir/refs"/frame_*.exr
  [ "$reference2" = 0 ] || ref2_args=(--reference2 "$dir/refs/ref2_%04d.exr")
  "$dnrender" --scene "$s" --frames "$frames" --width "$width" --height "$height" --out "$dir/input" --reflection \
    --stats --seed 3 --quiet
  "$dnrender" --scene "$s" --frames "$still" --hold-camera 0 --width "$width" --height "$height" \
    --out "$dir/still" --reflection --stats --seed 3 --quiet
  panels=()
  panel_labels=()
  for row in "${rows[@]}"; do
    read -r label pipeline params <<< "$row"
    param_args=()
    for p in $params; do
      case "$p" in channels=*) param_args+=(--channels "${p#channels=}") ;; *) param_args+=(--param "$p") ;; esac
    done
    echo "speed_error: scene $s: $label"
    # One untimed frame in a session of its own first: llvmpipe compiles a
    # kernel at its first dispatch (seconds with a cold Mesa cache, inside the
    # frame's device time), and the server keeps compiled kernels for later
    # sessions, so the measured runs below are steady state.
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset dnrender \
      --input "$dir/input/frame_%04d.exr" --start 0 --end 0 > /dev/null
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset dnrender \
      --input "$dir/input/frame_%04d.exr" --start 0 --end $((frames - 1)) \
      --output "$dir/$label/frame_%04d.exr" -r "$dir/refs/ref_%04d.exr" "${ref2_args[@]}" \
      --summary "$dir/$label/moving.tsv"
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset dnrender \
      --input "$dir/still/frame_%04d.exr" --start 0 --end $((still - 1)) --warmup $((still / 2)) \
      --output "$dir/$label/still/frame_%04d.exr" --summary "$dir/$label/still.tsv"
    # The same still-shot pairs as dn's temporal column (both frames past the
    # warm-up), over glossy surfaces only.
    "$bin/bench/region_temporal" --output "$dir/$label/still/frame_%04d.exr" --input "$dir/still/frame_%04d.exr" \
      --first $((still / 2 + 1)) --frames $((still - still / 2 - 1)) --method "$label" --region glossy |
      awk -v s="$s" 'NR > 1 { print s "\t" $0 }' >> "$region_temporal"
    m="$dir/$label/moving.tsv"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$s" "$label" "$(column "$m" rmse)" \
      "$(column "$m" relmse)" "$(column "$m" ssim)" "$(column "$dir/$label/still.tsv" temporal)" \
      "$(column "$m" device_ms)" "$(awk -v fps="$(column "$m" fps)" 'BEGIN { print (fps > 0 ? 1000 / fps : "nan") }')" \
      "$(column "$m" device_bytes_per_pixel)" "$(column "$m" nc_mse)" "$(column "$m" nc_relmse)" \
      "$(column "$m" ref_noise_mse)" "$(column "$m" flip_ldr)" "$(column "$m" flip_hdr)" \
      "$(column "$m" worse_rmse)" "$(column "$m" worse_relmse)" >> "$results"
    panels+=("$dir/$label/frame_$last.exr")
    panel_labels+=(--label "$label")
    region_args=(--region glossy,highlights,disocclusion)
    [ -z "$(region_roughness "$s")" ] ||
      region_args=(--roughness "$(region_roughness "$s")" --region roughness-mapped,glossy,highlights,disocclusion)
    [ "$reference2" = 0 ] || region_args+=(--reference2 "$dir/refs/ref2_%04d.exr")
    "$bin/bench/region_metrics" --output "$dir/$label/frame_%04d.exr" --reference "$dir/refs/ref_%04d.exr" \
      --input "$dir/input/frame_%04d.exr" --frames "$frames" --method "$label" "${region_args[@]}" |
      awk -v s="$s" 'NR > 1 { print s "\t" $0 }' >> "$region"
  done
  # Detail areas (fractions of the frame) per scene.
  case "$s" in
    1) crops=(--crop 0.30,0.62,0.25,0.25 --crop 0.55,0.35,0.2,0.2) ;;
    2) crops=(--crop 0.05,0.3,0.3,0.3 --crop 0.55,0.5,0.3,0.3) ;;
    3) crops=(--crop 0.1,0.5,0.3,0.3 --crop 0.5,0.3,0.3,0.3) ;;
    4) crops=(--crop 0.35,0.55,0.3,0.3 --crop 0.6,0.3,0.25,0.25) ;;
    *) crops=(--crop 0.3,0.2,0.25,0.3 --crop 0.35,0.7,0.3,0.3) ;;
  esac
  "$bin/bench/side_by_side" --out "$out/scene$s.png" "${crops[@]}" "${panel_labels[@]}" --label reference \
    "${panels[@]}" "$dir/refs/ref_$last.exr"
done

# The table, grouped by scene.
labels=""
for row in "${rows[@]}"; do labels+="${row%% *} "; done
{
  echo "| scene | method | RMSE | relMSE | SSIM | ꟻLIP LDR | ꟻLIP HDR | nc MSE | nc relMSE | reference noise MSE | frames worse than input (RMSE / relMSE) | temporal | device ms/frame | end-to-end ms/frame | device B/pixel |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  awk -F'\t' -v n="$frames" 'NR > 1 { printf "| %s | %s | %.4f | %.4f | %.4f | %.4f | %.4f | %.5f | %.4f | %.5f | %s / %s of %s | %.5f | %.1f | %.1f | %.0f |\n", $1, $2, $3, $4, $5, $13, $14, $10, $11, $12, $15, $16, n, $6, $7, $8, $9 }' "$results"
} > "$out/results.md"

# The plot: relMSE against device time, one colour per scene, each point
# labelled with its method. Methods of similar speed and error sit close
# together, so the labels are placed (bench/lib/place_labels.awk) where they
# overlap neither each other nor a point, farther out with a leader line where
# the nearer places are taken; that needs the plot area in pixels: fixed
# margins and axis ranges.
plot_files=""
for s in $scenes; do
  awk -F'\t' -v s="$s" 'NR > 1 && $1 == s { print $2, ($7 > 0.01 ? $7 : 0.01), $4 }' "$results" > "$out/plot_scene$s.dat"
  plot_files+="$s "
done
for s in $scenes; do awk -v s="$s" '{ print s, $1, $2, $3 }' "$out/plot_scene$s.dat"; done > "$out/plot_points.dat"
# The data's range, a fifth of a decade wider on each side.
read -r xmin xmax ymin ymax < <(awk '
  $3 > 0 && (x0 == "" || $3 < x0) { x0 = $3 } $3 > 0 && (x1 == "" || $3 > x1) { x1 = $3 }
  $4 > 0 && (y0 == "" || $4 < y0) { y0 = $4 } $4 > 0 && (y1 == "" || $4 > y1) { y1 = $4 }
  END {
    if (x0 == "") { x0 = 0.1; x1 = 1 }
    if (y0 == "") { y0 = 0.1; y1 = 1 }
    f = 10 ^ 0.2
    printf "%.6g %.6g %.6g %.6g\n", x0 / f, x1 * f, y0 / f, y1 * f
  }' "$out/plot_points.dat")
plot_w=960 plot_h=600
[ "$(wc -l < "$out/plot_points.dat")" -le 20 ] || { plot_w=1280 plot_h=800; }
lm=0.09 rm=0.84 bm=0.11 tm=0.92
awk -v W=$plot_w -v H=$plot_h -v lm=$lm -v rm=$rm -v bm=$bm -v tm=$tm -v xmin="$xmin" -v xmax="$xmax" \
  -v ymin="$ymin" -v ymax="$ymax" -v cw=6.5 -v ch=13 -f bench/lib/place_labels.awk "$out/plot_points.dat" \
  > "$out/plot_labels.dat"
leaders=""
if awk '$5 != "-" { found = 1 } END { exit !found }' "$out/plot_labels.dat"; then
  leaders=", '$out/plot_labels.dat' using 5:6:(\$7-\$5):(\$8-\$6) with vectors nohead lc rgb 'gray40' notitle"
fi
gnuplot <<EOF
set terminal png size $plot_w,$plot_h font ",11"
set output '$out/speed_error.png'
set lmargin at screen $lm
set rmargin at screen $rm
set bmargin at screen $bm
set tmargin at screen $tm
set logscale xy
set xrange [$xmin:$xmax]
set yrange [$ymin:$ymax]
set grid
set key outside right top title 'scene'
set xlabel 'device time per frame, ms (${width}x${height}, $device)'
set ylabel 'relMSE against the ${ref_spp}-spp reference (mean over $frames frames)'
set title 'Speed against error'
files = '$plot_files'
plot for [s in files] '$out/plot_scene'.s.'.dat' using 2:3 with points pt 7 ps 1.5 title s, \
     '$out/plot_labels.dat' using 3:4:2 with labels left font ",9" notitle$leaders
EOF

cpu=$(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo)
{
  echo "Machine: $(nproc) cores of ${cpu:-unknown CPU}, device \`$device\`; $(date -u +%Y-%m-%d)."
  echo "Command: \`bench/speed_error.sh --scenes \"$scenes\" --frames $frames --still $still --size $size --ref-spp $ref_spp\`."
  echo
  cat "$out/results.md"
  if [ "$(wc -l < "$region")" -gt 1 ]; then
    echo
    echo "Over regions of the frame only (bench/region_metrics: roughness-mapped = pixels whose roughness is one of the map's values, scene 1 floor, scene 5 floor and back panel; glossy = roughness below 0.3; highlights = reference luminance above 20 × the frame's median, dilated 1 px; disocclusion = no matching previous-frame depth where the motion points, from the second frame on):"
    echo
    echo "| scene | region | method | RMSE | relMSE | SSIM | nc MSE | nc relMSE | reference noise MSE | pixels/frame |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    awk -F'\t' 'NR > 1 { printf "| %s | %s | %s | %.4f | %.4f | %.4f | %.5f | %.4f | %.5f | %.0f |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9, $10 }' "$region"
  fi
  if [ "$(wc -l < "$region_temporal")" -gt 1 ]; then
    echo
    echo "Still-camera temporal error over glossy surfaces only (bench/region_temporal: roughness below 0.3 in the still shot's input, the same frame pairs as the temporal column above):"
    echo
    echo "| scene | method | temporal, glossy | pixels/frame |"
    echo "|---|---|---|---|"
    awk -F'\t' 'NR > 1 && $4 != "nan" { printf "| %s | %s | %.5f | %.0f |\n", $1, $3, $4, $5 }' "$region_temporal"
  fi
  echo
  echo "![speed against error](images/speed_error.png)"
  for s in $scenes; do
    echo
    echo "Scene $s, last moving frame: $labels| reference"
    echo
    echo "![scene $s](images/scene$s.png)"
  done
} > "$out/section.md"

if [ "$docs" = 1 ]; then
  mkdir -p docs/images
  cp "$out/speed_error.png" docs/images/speed_error.png
  for s in $scenes; do cp "$out/scene$s.png" "docs/images/scene$s.png"; done
  awk -v section="$out/section.md" '
    /<!-- speed-error:begin -->/ { print; while ((getline line < section) > 0) print line; skip = 1; next }
    /<!-- speed-error:end -->/ { skip = 0 }
    !skip { print }' docs/results.md > "$out/results.md.new"
  grep -q '<!-- speed-error:begin -->' docs/results.md || { echo "speed_error: docs/results.md has no speed-error markers" >&2; exit 1; }
  mv "$out/results.md.new" docs/results.md
  echo "speed_error: docs/results.md and docs/images/ updated"
fi

echo
cat "$out/section.md"
echo
echo "speed_error: table $out/results.md, plot $out/speed_error.png, side by side $out/scene<N>.png ($labels| reference)"
