#!/usr/bin/env bash
# stat's convergence (paper 003 Fig. 5 and property (d)):
# one still frame of a dnrender scene rendered with its sample statistics at
# 4, 8, ... spp (doubling, dnrender --stats, seed 3), denoised by `stat`
# (defaults) and by its base filter alone (membership 0) through `dn denoise`
# exactly as a user would, against two independent high-spp references.
# Per spp: RMSE of the input, the base filter and stat against reference 1,
# and the noise-corrected MSE (mean of (x - r1)(x - r2), unbiased for the
# error against the true image, docs/results.md) of each. Writes
# OUT/convergence.tsv and OUT/stat_convergence.png; --docs also copies the
# plot to docs/images/stat_convergence.png. --param NAME=VALUE (repeatable)
# sets a stat parameter for both the base filter and stat (e.g. radius=6);
# --demodulated renders the statistics over demodulated samples (dnrender
# --stats-demodulated: dn denoise then sets demodulated = 1 for both);
# --seed S renders the noisy frames with another seed (default 3; not 1,
# reference 1's, whose samples the frames would share).
# Environment: DN_BUILD_DIR (default build) holds the binaries; DN_SKIP_SETUP=1
# skips scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh

scenes="1 3"
size=128x72
max_spp=512
ref_spp=4096
out=out/stat_convergence
cache=out/cache
docs=0
stat_params=()
stats_flag=--stats
seed=3
usage() {
  cat <<USAGE
usage: bench/stat_convergence.sh [--scenes "1 3"] [--size WxH] [--max-spp N] [--ref-spp S] [--param NAME=VALUE]...
                                 [--demodulated] [--seed S] [--out DIR] [--cache DIR] [--docs]
defaults: --scenes "$scenes" --size $size --max-spp $max_spp --ref-spp $ref_spp --out $out
USAGE
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --max-spp) max_spp=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --param) stat_params+=(--param "$2"); shift 2 ;;
    --demodulated) stats_flag=--stats-demodulated; shift ;;
    --seed) seed=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "stat_convergence: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
[ "$seed" != 1 ] || { echo "stat_convergence: --seed 1 is reference 1's seed" >&2; exit 2; }
width=${size%x*}
height=${size#*x}
[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dnrender=$bin/examples/renderer/dnrender
dn=$bin/client/dn
mkdir -p "$out"
start_bench_server stat_convergence "$bin" "$dn" "$out/dnserver.log"

tsv="$out/convergence.tsv"
printf 'scene\tspp\tmethod\trmse\tnc_mse\n' > "$tsv"
for s in $scenes; do
  dir="$out/scene$s"
  echo "stat_convergence: scene $s: references at $ref_spp spp (cached)"
  "$dnrender" --scene "$s" --frames 1 --width "$width" --height "$height" --out "$dir/refs" \
    --reference "$ref_spp" --reference2 --cache "$cache" --quiet
  spp=4
  while [ "$spp" -le "$max_spp" ]; do
    "$dnrender" --scene "$s" --frames 1 --width "$width" --height "$height" --spp "$spp" "$stats_flag" --seed "$seed" \
      --out "$dir/spp$spp" --quiet
    for row in "noisy passthrough" "base stat membership=0" "stat stat"; do
      read -r label pipeline params <<< "$row"
      param_args=()
      for p in $params; do param_args+=(--param "$p"); done
      [ "$pipeline" != stat ] || param_args+=(${stat_params[@]+"${stat_params[@]}"})
      "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset dnrender \
        --input "$dir/spp$spp/frame_%04d.exr" --start 0 --end 0 --output "$dir/spp$spp/$label/frame_%04d.exr" \
        -r "$dir/refs/ref_%04d.exr" --reference2 "$dir/refs/ref2_%04d.exr" --summary "$dir/spp$spp/$label.tsv"
      printf '%s\t%s\t%s\t%s\t%s\n' "$s" "$spp" "$label" "$(column "$dir/spp$spp/$label.tsv" rmse)" \
        "$(column "$dir/spp$spp/$label.tsv" nc_mse)" >> "$tsv"
    done
    echo "stat_convergence: scene $s: $spp spp done"
    spp=$((spp * 2))
  done
done

# The title names what differs from stat's defaults.
title_extra=""
for a in ${stat_params[@]+"${stat_params[@]}"}; do [ "$a" = --param ] || title_extra+=", $a"; done
[ "$stats_flag" = --stats ] || title_extra+=", demodulated"

# RMSE from the noise-corrected MSE (clamped at 1e-12: it can come out
# slightly negative within the references' noise), against spp, log-log.
plots=""
for s in $scenes; do
  for m in noisy base stat; do
    awk -F'\t' -v s="$s" -v m="$m" 'NR > 1 && $1 == s && $3 == m { print $2, sqrt($5 > 1e-12 ? $5 : 1e-12) }' "$tsv" \
      > "$out/scene${s}_$m.dat"
    [ -z "$plots" ] || plots+=", "
    plots+="'$out/scene${s}_$m.dat' with linespoints title 'scene $s $m'"
  done
done
gnuplot <<GP
set terminal png size 800,500 font ",11" noenhanced
set output '$out/stat_convergence.png'
set title 'stat against spp ($size, dnrender$title_extra)'
set logscale xy
set grid
set key outside right
set xlabel 'samples per pixel'
set ylabel 'noise-corrected RMSE'
plot $plots
GP
echo "stat_convergence: $tsv, $out/stat_convergence.png"
if [ "$docs" = 1 ]; then cp "$out/stat_convergence.png" docs/images/stat_convergence.png; fi
