#!/usr/bin/env bash
# A still view converges, on a real renderer's frames. Renders one of the
# project's Cycles scenes (bench/cycles.sh's room or window) with the camera
# held (cycles_*.py --still: the frames differ only in noise) at 1 spp per
# frame, for each pass variant (--variants: preset = Blender's defaults, no
# Denoising Data; denoising = + Denoising Data; all = + the Roughness /
# SpecularF0 AOVs), and streams each through the plain running mean of the
# inputs (accumulate with alpha_min 0 and max_history 1024) and every
# pipeline the server offers, with `dn denoise --preset cycles` as a user
# would. Output frame n (the result after n frames) is measured against two
# independent --ref-spp renders of the same still frame (seeds 1 and 2):
# RMSE, relMSE and ꟻLIP HDR against the first, and the noise-corrected
# relMSE over both (dn denoise --reference2), which takes out the
# references' own noise.
# Writes OUT/still.tsv (every frame) and OUT/still.md: per variant and
# method, RMSE / nc relMSE / ꟻLIP HDR after 1, 2, 4, ... frames, at how many
# of those counts the method is above the running mean (by each),
# and at how many it rises from the previous count (nc relMSE). A pipeline
# that fails (e.g. svgf-fb without the F0 AOV) is reported in the table.
# Environment: BLENDER, DN_BUILD_DIR (default build), DN_SKIP_SETUP=1 as
# bench/cycles.sh. Without Blender: exit 77 (skipped).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh
. bench/lib/blender_render.sh
bench=cycles_still

scene=room
variants=preset,denoising,all
frames=64
size=320x180
ref_spp=1024
threads=0
out=""
usage() {
  cat <<EOF
usage: bench/cycles_still.sh [--scene room|window] [--variants LIST] [--frames N] [--size WxH]
                             [--ref-spp S] [--threads N] [--out DIR]
defaults: --scene $scene --variants $variants --frames $frames --size $size --ref-spp $ref_spp
          --out out/cycles_still/SCENE (threads 0: all cores)
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --variants) variants=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "$bench: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
blender_options
blender_scene "$scene" || { echo "$bench: unknown scene '$scene' (room, window)" >&2; exit 2; }
out=${out:-out/cycles_still/$scene}
find_blender

[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dn=$bin/client/dn
mkdir -p "$out"
render_times="$out/render_times.tsv"
printf 'what\tspp\tseed\tpasses\tframes\tseconds\tseconds_per_frame\n' > "$render_times"
for v in "${vars[@]}"; do blender_render "input-$v" "$frames" 1 0 "$v" --still; done
blender_render ref 1 "$ref_spp" 1 all --still
blender_render ref2 1 "$ref_spp" 2 all --still

# dn denoise reads a reference per frame: every frame's is the one still render.
for r in ref ref2; do
  rm -rf "$out/$r-frames"
  mkdir -p "$out/$r-frames"
  for f in $(seq 0 $((frames - 1))); do ln -s "../render/$r/frame_0000.exr" "$out/$r-frames/$(printf 'frame_%04d.exr' "$f")"; done
done

start_bench_server "$bench-$scene" "$bin" "$dn" "$out/dnserver.log"
rows=("mean accumulate alpha_min=0 max_history=1024")
for p in $("$dn" ping --server "$server_url" --count 1 | awk '$1 == "pipeline" && $2 != "passthrough" && $2 != "accumulate" { print $2 }'); do
  rows+=("$p $p")
done

tsv="$out/still.tsv"
printf 'variant\tmethod\tframes\trmse\trelmse\tnc_relmse\tflip_hdr\n' > "$tsv"
failures="$out/failures.tsv"
: > "$failures"
for v in "${vars[@]}"; do
  for row in "${rows[@]}"; do
    read -r label pipeline params <<< "$row"
    param_args=()
    for p in $params; do param_args+=(--param "$p"); done
    echo "$bench: $scene $v: $label"
    log="$out/$v-$label.log"
    # dn's per-frame lines: "frame N ... rmse X relmse Y ... nc_relmse Z ..." and "frame N flip_ldr A flip_hdr B".
    if "$dn" denoise --server "$server_url" --pipeline "$pipeline" --preset cycles "${param_args[@]}" \
        --input "$out/render/input-$v/frame_%04d.exr" --start 0 --end $((frames - 1)) \
        -r "$out/ref-frames/frame_%04d.exr" --reference2 "$out/ref2-frames/frame_%04d.exr" > "$log" 2>&1; then
      awk -v OFS='\t' -v v="$v" -v m="$label" '
        $1 == "frame" { f = $2 + 1; if (!(f in seen)) { seen[f] = 1; order[++n] = f }
                        for (i = 3; i < NF; ++i) if ($i ~ /^(rmse|relmse|nc_relmse|flip_hdr)$/) val[f, $i] = $(i + 1) }
        END { for (k = 1; k <= n; ++k) { f = order[k]
                print v, m, f, val[f, "rmse"], val[f, "relmse"], val[f, "nc_relmse"], val[f, "flip_hdr"] } }' "$log" >> "$tsv"
    else
      printf '%s\t%s\t%s\n' "$v" "$label" "$(grep -v '^[[:space:]]*$' "$log" | tail -1 | tr '\t|' '  ' |
      sed -E "s/.*(requires channel '[a-z0-9_]+').*/\1/" | cut -c1-200)" >> "$failures"
    fi
  done
done

# The table: per variant and method, RMSE / nc relMSE / FLIP HDR at 1, 2, 4,
# ... frames, at how many counts above the running mean, and rises.
awk -F'\t' -v frames="$frames" -v failures="$failures" '
  NR == 1 { next }
  { key = $1 SUBSEP $2; rmse[key, $3] = $4; rel[key, $3] = $6; flip[key, $3] = $7
    if (!(key in seen)) { seen[key] = 1; order[++n] = key } }
  END {
    line = "| variant | method |"; sep = "|---|---|"
    for (f = 1; f <= frames; f *= 2) { line = line " " f " |"; sep = sep "---|" }
    print line " above the mean (RMSE / nc relMSE / ꟻLIP) | rises (nc relMSE) |"; print sep "---|---|"
    for (i = 1; i <= n; ++i) {
      split(order[i], k, SUBSEP); mean = k[1] SUBSEP "mean"
      line = "| " k[1] " | " k[2] " |"; a = 0; b = 0; d = 0; c = 0; r = 0; prev = ""
      for (f = 1; f <= frames; f *= 2) {
        line = line sprintf(" %.4f / %.4f / %.4f |", rmse[order[i], f], rel[order[i], f], flip[order[i], f]); ++c
        if (rmse[order[i], f] > rmse[mean, f]) ++a
        if (rel[order[i], f] > rel[mean, f]) ++b
        if (flip[order[i], f] > flip[mean, f]) ++d
        if (prev != "" && rel[order[i], f] > prev) ++r
        prev = rel[order[i], f]
      }
      print line " " a " / " b " / " d " of " c " | " r " |"
    }
    while ((getline l < failures) > 0) { split(l, fl, "\t"); print "| " fl[1] " | " fl[2] " | failed: " fl[3] " |" }
  }' "$tsv" > "$out/still.md"
echo "$bench: table $out/still.md (RMSE / nc relMSE / FLIP HDR against the $ref_spp-spp references)"
cat "$out/still.md"
