#!/usr/bin/env bash
# A real client: Blender Cycles. Renders one of the project's Cycles scenes
# (--scene room: examples/blender/cycles_room.py, mirror sphere, gold sphere,
# floor with checker-mapped roughness, small area light; --scene window:
# examples/blender/cycles_window.py, a room lit through a window, glass and
# glossy objects, textured walls; both with a moving camera), then streams
# the noisy renders through every pipeline a dnserver offers with
# `dn denoise --preset cycles`, exactly as a user would.
#
# Inputs: each pass variant (--variants; cycles_*.py --passes: preset = only
# what the preset reads without Denoising Data, as a user with Blender's
# defaults has; denoising = + Denoising Data; all = + Denoising Data and the
# Roughness / SpecularF0 AOVs) at each sample count (--spp-list), seed 0, each
# rendered on its own as a user would. References: two independent renders
# (--ref-spp, seeds 1 and 2, --passes all). One table per variant and sample
# count; rows: the noisy input and every pipeline (a pipeline that fails is
# reported in the table and the run goes on), then svgf on the split
# lighting.
#
# The error columns: RMSE, relMSE and SSIM against reference 1; the
# noise-corrected MSE and relMSE (with a dn that has `dn denoise --reference2`
# its nc_mse / nc_relmse, the mean of (x - r1)(x - r2), unbiased; otherwise
# MSE(x, r1) - MSE(r2, r1)/2 from the means of the per-frame values, marked
# "approx."); the frames worse than the noisy input by RMSE / relMSE and
# ꟻLIP LDR / HDR, read from dn's --summary columns worse_rmse, worse_relmse,
# flip_ldr and flip_hdr where this dn writes them ("—" otherwise).
#
# OUT (default out/cycles/SCENE) gets render/ (the cached renders),
# VARIANT-sSPP/ (per table: results.tsv, results.md, side.png: the last frame
# of every pipeline that ran and reference 1, whole and cropped, and a folder
# per row), section.md (the docs section of this scene) and render_times.tsv.
# --docs also copies the first table's picture to docs/images/ (cycles.png for
# the room, cycles_window.png) and puts the section into docs/results.md
# between the scene's markers inside the cycles markers, keeping the other
# scene's section.
# Environment: BLENDER (default blender), DN_BUILD_DIR (default build) holds
# the binaries; DN_SKIP_SETUP=1 skips scripts/setup.sh. Renders are cached in
# OUT/render and reused while the scene scripts (sha1), the settings, the
# passes and the Blender version are unchanged.
# Blender is not a dependency of the build or of CI: without it this script
# says so and exits with status 77 (skipped).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh
. bench/lib/blender_render.sh
bench=cycles

scene=room
frames=8
size=320x180
spp_list=1,4,16
variants=preset,denoising,all
ref_spp=256
out=""
docs=0
render_only=0
threads=0
usage() {
  cat <<EOF
usage: bench/cycles.sh [--scene room|window] [--variants LIST] [--spp-list LIST] [--spp S] [--ref-spp S]
                       [--frames N] [--size WxH] [--threads N] [--out DIR] [--docs | --render-only]
defaults: --scene $scene --variants $variants --spp-list $spp_list --ref-spp $ref_spp --frames $frames
          --size $size --out out/cycles/SCENE (threads 0: all cores); --spp S is --spp-list S
variants: preset (no Denoising Data, no AOVs), denoising (+ Denoising Data), all (+ Roughness/SpecularF0 AOVs)
--render-only: render (or find cached) the inputs and references, then stop (no dnserver needed)
Blender: \$BLENDER or 'blender' on PATH (Debian: apt-get install blender).
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --variants) variants=$2; shift 2 ;;
    --spp-list | --spp) spp_list=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    --render-only) render_only=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "cycles: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
blender_options
IFS=, read -r -a spps <<< "$spp_list"
for s in "${spps[@]}"; do case "$s" in "" | *[!0-9]* | 0) echo "cycles: --spp-list wants positive integers, got '$spp_list'" >&2; exit 2 ;; esac; done
[ ${#spps[@]} -gt 0 ] && [ ${#vars[@]} -gt 0 ] || { echo "cycles: empty --variants or --spp-list" >&2; exit 2; }

# Per scene (its scripts: bench/lib/blender_render.sh): the side-by-side crops
# (X,Y,W,H fractions) and what they show, the picture's name in docs/images.
blender_scene "$scene" || { echo "$bench: unknown scene '$scene' (room, window)" >&2; exit 2; }
case "$scene" in
  room)
    crops=(--crop 0.24,0.28,0.3,0.5 --crop 0.5,0.62,0.3,0.38)
    crop_what="mirror sphere, floor"
    picture=cycles.png
    ;;
  window)
    crops=(--crop 0.3,0.35,0.3,0.45 --crop 0.0,0.1,0.35,0.5)
    crop_what="glass and glossy objects, the window wall"
    picture=cycles_window.png
    ;;
esac
out=${out:-out/cycles/$scene}

find_blender

bin=${DN_BUILD_DIR:-build}
dn=$bin/client/dn
if [ "$render_only" = 0 ]; then
  [ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
  for b in "$dn" "$bin/server/dnserver" "$bin/bench/side_by_side"; do
    [ -x "$b" ] || { echo "cycles: $b is missing (build first, or set DN_BUILD_DIR)" >&2; exit 1; }
  done
fi
mkdir -p "$out"
last=$((frames - 1))
lastf=$(printf '%04d' "$last")

# --- render (cached) -------------------------------------------------------
render_times="$out/render_times.tsv"
printf 'what\tspp\tseed\tpasses\tframes\tseconds\tseconds_per_frame\n' > "$render_times"
for v in "${vars[@]}"; do
  for s in "${spps[@]}"; do blender_render "input-$v-s$s" "$frames" "$s" 0 "$v"; done
done
blender_render ref "$frames" "$ref_spp" 1 all
blender_render ref2 "$frames" "$ref_spp" 2 all
ref="$out/render/ref/frame_%04d.exr"
ref2="$out/render/ref2/frame_%04d.exr"
[ "$render_only" = 0 ] || { echo "cycles: renders in $out/render"; exit 0; }

# --- server ----------------------------------------------------------------
start_bench_server "cycles-$scene" "$bin" "$dn" "$out/dnserver.log"
pipelines=$("$dn" ping --server "$server_url" --count 1 | awk '$1 == "pipeline" && $2 != "passthrough" { print $2 }')

# Why dn failed, on one line: its last non-empty output line (dn's error), or its exit status.
failure() {  # log status
  local why
  why=$(grep -v '^[[:space:]]*$' "$1" | tail -1 | tr '\t|' '  ' | cut -c1-300)
  case "$2" in 1 | 2) ;; *) why="dn exited with status $2$([ "$2" -gt 128 ] && echo " (signal $(($2 - 128)))")${why:+; last line: $why}" ;; esac
  echo "${why:-dn exited with status $2}"
}
# A --summary column this dn may not write yet: its value, or nothing.
optional_column() {  # file name
  awk -F'\t' -v name="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == name) c = i } NR == 2 && c { print $c }' "$1"
}

# Reference 2 against reference 1: the references' own noise.
echo "cycles: reference 2 against reference 1"
rm -f "$out/refs.tsv"
status=0
ref_failed=""
"$dn" denoise -q --server "$server_url" --pipeline passthrough --preset cycles --input "$ref2" --start 0 --end "$last" \
  -r "$ref" --summary "$out/refs.tsv" > "$out/refs.log" 2>&1 || status=$?
if [ "$status" = 0 ]; then
  ref_rmse=$(column "$out/refs.tsv" rmse)
  ref_relmse=$(column "$out/refs.tsv" relmse)
else
  ref_failed=$(failure "$out/refs.log" "$status")
  echo "cycles: comparing the references FAILED: $ref_failed" >&2
  ref_rmse=nan
  ref_relmse=nan
fi
nc_args=()
nc_kind="approx."
if "$dn" denoise --help 2>&1 | grep -q -- '--reference2'; then nc_args=(--reference2 "$ref2"); nc_kind="--reference2"; fi

# One table: every row on one input variant and sample count.
run_table() {  # variant spp
  local variant=$1 spp=$2 dir_t="$out/$1-s$2"
  local input="$out/render/input-$variant-s$spp/frame_%04d.exr"
  # Rows: "label pipeline [NAME=VALUE | channels=LIST ...]": the noisy input,
  # every pipeline the server offers (new ones are picked up without changes),
  # then svgf on the split lighting (DiffDir+DiffInd over DiffCol, GlossDir+GlossInd
  # over GlossCol: the lighting forms, docs/protocol.md §7.4; roughness where the file has the AOV).
  local split=diffuse_lighting,specular_lighting,specular_albedo,albedo,normal,depth,motion,emission
  [ "$variant" = all ] && split+=,roughness
  local rows=("noisy passthrough") p
  for p in $pipelines; do rows+=("$p $p"); done
  rows+=("svgf-split svgf channels=$split")

  rm -rf "$dir_t"
  mkdir -p "$dir_t"
  local results="$dir_t/results.tsv"
  printf 'method\tstatus\trmse\trelmse\tssim\tnc_mse\tnc_relmse\tworse_rmse\tworse_relmse\tflip_ldr\tflip_hdr\tdevice_ms\tframe_ms\n' > "$results"
  local panels=() panel_labels=() row label pipeline params param_args dir status m rmse relmse nc_mse nc_relmse why
  local labels=""
  for row in "${rows[@]}"; do
    read -r label pipeline params <<< "$row"
    param_args=()
    for p in $params; do
      case "$p" in channels=*) param_args+=(--channels "${p#channels=}") ;; *) param_args+=(--param "$p") ;; esac
    done
    dir="$dir_t/$label"
    mkdir -p "$dir"
    echo "cycles: $scene $variant ${spp} spp: $label"
    # One untimed frame in a session of its own first, as bench/speed_error.sh
    # does: llvmpipe compiles a kernel at its first dispatch, inside that frame's
    # device time, and the server keeps compiled kernels for later sessions. A
    # pipeline that cannot run fails here too; the measured run reports why.
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset cycles \
      --input "$input" --start 0 --end 0 > /dev/null 2>&1 || true
    status=0
    "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" "${param_args[@]}" --preset cycles \
      --input "$input" --start 0 --end "$last" --output "$dir/frame_%04d.exr" -r "$ref" "${nc_args[@]}" \
      --summary "$dir/summary.tsv" > "$dir/dn.log" 2>&1 || status=$?
    if [ "$status" = 0 ]; then
      m="$dir/summary.tsv"
      rmse=$(column "$m" rmse)
      relmse=$(column "$m" relmse)
      if [ ${#nc_args[@]} -gt 0 ]; then
        nc_mse=$(column "$m" nc_mse)
        nc_relmse=$(column "$m" nc_relmse)
      elif [ -n "$ref_failed" ]; then
        nc_mse=nan
        nc_relmse=nan
      else
        nc_mse=$(awk -v a="$rmse" -v r="$ref_rmse" 'BEGIN { print a * a - r * r / 2 }')
        nc_relmse=$(awk -v a="$relmse" -v r="$ref_relmse" 'BEGIN { print a - r / 2 }')
      fi
      printf '%s\tok\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$rmse" "$relmse" "$(column "$m" ssim)" \
        "$nc_mse" "$nc_relmse" "$(optional_column "$m" worse_rmse)" "$(optional_column "$m" worse_relmse)" \
        "$(optional_column "$m" flip_ldr)" "$(optional_column "$m" flip_hdr)" "$(column "$m" device_ms)" \
        "$(awk -v fps="$(column "$m" fps)" 'BEGIN { print (fps > 0 ? 1000 / fps : "nan") }')" >> "$results"
      panels+=("$dir/frame_$lastf.exr")
      panel_labels+=(--label "$label")
      labels+="$label | "
    else
      why=$(failure "$dir/dn.log" "$status")
      echo "cycles: $label FAILED: $why" >&2
      printf '%s\tfailed: %s\t\t\t\t\t\t\t\t\t\t\t\n' "$label" "$why" >> "$results"
    fi
  done

  # Side by side: the last frame of every row that ran, then reference 1, and the scene's crops.
  "$bin/bench/side_by_side" --out "$dir_t/side.png" "${crops[@]}" "${panel_labels[@]}" --label reference \
    "${panels[@]}" "$out/render/ref/frame_$lastf.exr" > /dev/null ||
    echo "cycles: side_by_side failed (the table is still written)" >&2
  echo "${labels}reference 1" > "$dir_t/side.txt"

  # "—" where this dn does not write the column; worse: frames out of $frames.
  awk -F'\t' -v nc="$nc_kind" -v n="$frames" '
    function num(x, f) { return x == "" ? "—" : sprintf(f, x) }
    function worse(a, b) { return a == "" && b == "" ? "—" : sprintf("%s / %s", a == "" ? "—" : a, b == "" ? "—" : b) }
    NR == 1 {
      printf "| method | RMSE | relMSE | SSIM | nc MSE (%s) | nc relMSE (%s) | frames worse than input of %d (RMSE / relMSE) | ꟻLIP LDR | ꟻLIP HDR | device ms/frame | end-to-end ms/frame |\n", nc, nc, n
      print "|---|---|---|---|---|---|---|---|---|---|---|"
      next
    }
    $2 == "ok" { printf "| %s | %.4f | %.4f | %.4f | %.4g | %.4g | %s | %s | %s | %.1f | %.1f |\n", $1, $3, $4, $5, $6, $7,
                 worse($8, $9), num($10, "%.4f"), num($11, "%.4f"), $12, $13; next }
    { why = $2  # the table keeps the gist of the usual refusal; results.tsv and dn.log have it all
      sub(/dn denoise: error: /, "", why)
      if (match(why, /requires channel [^,]*, but /)) why = substr(why, 1, RSTART + RLENGTH - 7) " (not in the file)"
      printf "| %s | %s | | | | | | | | | |\n", $1, why }' "$results" > "$dir_t/results.md"
}

for v in "${vars[@]}"; do
  for s in "${spps[@]}"; do run_table "$v" "$s"; done
done
first="$out/${vars[0]}-s${spps[0]}"

# --- the docs section --------------------------------------------------------
cpu=$(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo)
variant_text() {
  case "$1" in
    preset) echo "\`--passes preset\`: only the passes \`--preset cycles\` reads without Denoising Data (no Denoising Data, no AOVs: Blender's defaults otherwise)" ;;
    denoising) echo "\`--passes denoising\`: + Denoising Data" ;;
    all) echo "\`--passes all\`: + Denoising Data and the Roughness / SpecularF0 AOVs" ;;
  esac
}
{
  echo "<!-- cycles-$scene:begin -->"
  echo "#### Scene \`$scene\` ($script)"
  echo
  echo "Machine: $(nproc) cores of ${cpu:-unknown CPU}, device \`$device\`; Blender $blender_version; $(date -u +%Y-%m-%d)."
  echo "Command: \`bench/cycles.sh --scene $scene --variants $variants --spp-list $spp_list --ref-spp $ref_spp --frames $frames --size $size\`:"
  echo "rendered at ${width}×${height}, $frames frames of a moving camera; inputs seed 0, each pass variant rendered on its own;"
  echo "reference 1 and reference 2 at $ref_spp spp (seeds 1 and 2, \`--passes all\`); every row is"
  echo "\`dn denoise --preset cycles --pipeline P --input ... -r ref1\` (means over the $frames frames)."
  if [ -z "$ref_failed" ]; then
    echo "Reference 2 against reference 1: RMSE $(printf '%.4f' "$ref_rmse"), relMSE $(printf '%.4f' "$ref_relmse")"
    echo "(so one reference's own noise adds about $(awk -v r="$ref_rmse" 'BEGIN { printf "%.3g", r * r / 2 }') to every MSE against it)."
  else
    echo "Reference 2 against reference 1 (\`dn denoise --pipeline passthrough --input ref2 -r ref1\`) FAILED: $ref_failed"
  fi
  if [ ${#nc_args[@]} -gt 0 ]; then
    echo "nc MSE, nc relMSE: \`dn denoise --reference2 ref2\` (mean of (x − r1)(x − r2): the MSE against the noise-free image, unbiased)."
  else
    echo "nc MSE, nc relMSE (approx.): MSE(x, ref1) − MSE(ref2, ref1)/2 from the means of the per-frame values (this dn has no --reference2)."
  fi
  echo "Frames worse than input, ꟻLIP: dn's summary columns; \"—\" where the dn that ran does not write them."
  for v in "${vars[@]}"; do
    for s in "${spps[@]}"; do
      echo
      echo "##### \`$scene\`, input $s spp, $(variant_text "$v")"
      echo
      cat "$out/$v-s$s/results.md"
    done
  done
  echo
  echo "Cycles render times (CPU, Blender start-up included):"
  awk -F'\t' 'NR > 1 { printf "%s%s %s spp %.1f s (%.2f s/frame)", (NR > 2 ? "; " : ""), $1, $2, $6, $7 } END { print "." }' "$render_times"
  echo
  echo "Last frame and crops ($crop_what), input $(variant_text "${vars[0]}" | cut -d: -f1) at ${spps[0]} spp: $(cat "$first/side.txt")"
  echo
  echo "![cycles $scene](images/$picture)"
  echo "<!-- cycles-$scene:end -->"
} > "$out/section.md"

if [ "$docs" = 1 ]; then
  grep -q '<!-- cycles:begin -->' docs/results.md || { echo "cycles: docs/results.md has no cycles markers" >&2; exit 1; }
  mkdir -p docs/images
  cp "$first/side.png" "docs/images/$picture"
  # Inside the cycles markers: one block per scene, in the order room, window;
  # this run's scene replaced, the other kept as it is.
  for s in room window; do
    if [ "$s" = "$scene" ]; then
      cp "$out/section.md" "$out/block-$s.md"
    else
      awk -v b="<!-- cycles-$s:begin -->" -v e="<!-- cycles-$s:end -->" \
        '$0 == b { on = 1 } on { print } $0 == e { on = 0 }' docs/results.md > "$out/block-$s.md"
    fi
  done
  awk -v a="$out/block-room.md" -v b="$out/block-window.md" '
    function emit(f, first, line) { first = 1; while ((getline line < f) > 0) { if (first && printed) print ""; print line; first = 0; printed = 1 } }
    /<!-- cycles:begin -->/ { print; emit(a); emit(b); skip = 1; next }
    /<!-- cycles:end -->/ { skip = 0 }
    !skip { print }' docs/results.md > "$out/results.md.new"
  mv "$out/results.md.new" docs/results.md
  rm -f "$out/block-room.md" "$out/block-window.md"
  echo "cycles: docs/results.md and docs/images/$picture updated"
fi

echo
cat "$out/section.md"
echo
echo "cycles: tables $out/*-s*/results.md, side by side $out/*-s*/side.png"
