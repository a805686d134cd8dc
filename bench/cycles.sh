#!/usr/bin/env bash
# A real client: Blender Cycles. Renders the project's Cycles scene
# (examples/blender/cycles_room.py: mirror sphere, gold sphere, floor with
# checker-mapped roughness, small area light, moving camera) three times —
# the noisy input (--spp, seed 0) and two independent references (--ref-spp,
# seeds 1 and 2) — then streams the input through every pipeline a dnserver
# offers with `dn denoise --preset cycles`, exactly as a user would, and
# writes to OUT: results.tsv, results.md (the table), section.md (the docs
# section) and cycles.png (side by side: the whole frame and crops of the
# mirror sphere and the floor). A pipeline that fails is reported in the
# table and the run goes on.
#
# The error columns: RMSE, relMSE and SSIM against reference 1, and the
# noise-corrected MSE and relMSE. With a dn that has `dn denoise --reference2`
# they are its nc_mse / nc_relmse (mean of (x - r1)(x - r2), unbiased);
# otherwise the approximation MSE(x, r1) - MSE(r2, r1)/2 (E[(x - r1)^2] =
# (x - truth)^2 + var(r), E[(r2 - r1)^2] = 2 var(r)), from the means of the
# per-frame values, marked "approx." in the table.
#
# --docs also copies the picture to docs/images/cycles.png and puts the
# section into docs/results.md between its cycles markers.
# Environment: BLENDER (default blender), DN_BUILD_DIR (default build) holds
# the binaries; DN_SKIP_SETUP=1 skips scripts/setup.sh. Renders are cached in
# OUT/render and reused while the scene script and the settings are unchanged.
# Blender is not a dependency of the build or of CI: without it this script
# says so and exits with status 77 (skipped).
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh

frames=8
size=320x180
spp=1
ref_spp=256
out=out/cycles
docs=0
threads=0
usage() {
  cat <<EOF
usage: bench/cycles.sh [--frames N] [--size WxH] [--spp S] [--ref-spp S] [--threads N] [--out DIR] [--docs]
defaults: --frames $frames --size $size --spp $spp --ref-spp $ref_spp --out $out (threads 0: all cores)
Blender: \$BLENDER or 'blender' on PATH (Debian: apt-get install blender).
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "cycles: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
width=${size%x*}
height=${size#*x}
case "$width$height$frames$spp$ref_spp$threads" in *[!0-9]* | "") echo "cycles: --size wants WxH and the counts integers" >&2; exit 2 ;; esac
[ "$frames" -ge 2 ] || { echo "cycles: need --frames >= 2" >&2; exit 2; }

blender=${BLENDER:-blender}
if ! command -v "$blender" > /dev/null 2>&1; then
  echo "cycles: SKIPPED: Blender not found ('$blender' is not on PATH; set BLENDER=/path/to/blender or install" >&2
  echo "cycles: it, e.g. apt-get install blender). Blender is not a build or CI dependency; nothing was run." >&2
  exit 77
fi
blender_version=$("$blender" --version 2>/dev/null | awk 'NR == 1 { print $2 }')

[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
bin=${DN_BUILD_DIR:-build}
dn=$bin/client/dn
for b in "$dn" "$bin/server/dnserver" "$bin/bench/side_by_side"; do
  [ -x "$b" ] || { echo "cycles: $b is missing (build first, or set DN_BUILD_DIR)" >&2; exit 1; }
done
mkdir -p "$out"
last=$((frames - 1))
lastf=$(printf '%04d' "$last")

# --- render (cached) -------------------------------------------------------
script=examples/blender/cycles_room.py
script_sum=$(sha1sum "$script" | cut -c1-12)
render_times="$out/render_times.tsv"
printf 'what\tspp\tseed\tframes\tseconds\tseconds_per_frame\n' > "$render_times"
render() {  # name spp seed
  local dir="$out/render/$1" stamp="$1 ${width}x$height frames=$frames spp=$2 seed=$3 script=$script_sum blender=$blender_version"
  if [ -f "$dir/stamp" ] && [ "$(head -1 "$dir/stamp")" = "$stamp" ] && [ -f "$dir/frame_$lastf.exr" ]; then
    echo "cycles: $1: cached ($dir)"
  else
    rm -rf "$dir"
    mkdir -p "$dir"
    echo "cycles: rendering $1: $frames frames at ${width}x$height, $2 spp, seed $3 (Blender $blender_version)"
    local t0 t1
    t0=$(date +%s.%N)
    "$blender" -b --factory-startup --python "$script" -- --out "$dir" --width "$width" --height "$height" \
      --frames "$frames" --spp "$2" --seed "$3" --threads "$threads" > "$dir/blender.log" 2>&1 ||
      { echo "cycles: Blender failed rendering $1; the end of $dir/blender.log:" >&2; tail -20 "$dir/blender.log" >&2; exit 1; }
    t1=$(date +%s.%N)
    [ -f "$dir/frame_$lastf.exr" ] || { echo "cycles: Blender wrote no $dir/frame_$lastf.exr" >&2; exit 1; }
    printf '%s\n%s\n' "$stamp" "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')" > "$dir/stamp"
  fi
  local s
  s=$(sed -n 2p "$dir/stamp")
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$frames" "$s" "$(awk -v s="$s" -v n="$frames" 'BEGIN { printf "%.2f", s / n }')" >> "$render_times"
}
render input "$spp" 0
render ref "$ref_spp" 1
render ref2 "$ref_spp" 2
input="$out/render/input/frame_%04d.exr"
ref="$out/render/ref/frame_%04d.exr"
ref2="$out/render/ref2/frame_%04d.exr"

# --- server ----------------------------------------------------------------
start_bench_server cycles "$bin" "$dn" "$out/dnserver.log"

# Rows: "label pipeline [NAME=VALUE | channels=LIST ...]": the noisy input,
# every pipeline the server offers (new ones are picked up without changes),
# then svgf on the split lighting (DiffDir+DiffInd over DiffCol, GlossDir+GlossInd
# over GlossCol: the lighting forms, docs/protocol.md §7.4).
rows=("noisy passthrough")
for p in $("$dn" ping --server "$server_url" --count 1 | awk '$1 == "pipeline" { print $2 }'); do
  case "$p" in passthrough) ;; *) rows+=("$p $p") ;; esac
done
rows+=("svgf-split svgf channels=diffuse_lighting,specular_lighting,specular_albedo,albedo,normal,depth,motion,emission,roughness")


# Why dn failed, on one line: its last non-empty output line (dn's error), or its exit status.
failure() {  # log status
  local why
  why=$(grep -v '^[[:space:]]*$' "$1" | tail -1 | tr '\t|' '  ' | cut -c1-300)
  case "$2" in 1 | 2) ;; *) why="dn exited with status $2$([ "$2" -gt 128 ] && echo " (signal $(($2 - 128)))")${why:+; last line: $why}" ;; esac
  echo "${why:-dn exited with status $2}"
}

# Reference 2 against reference 1: the references' own noise.
echo "cycles: reference 2 against reference 1"
rm -f "$out/refs.tsv"
status=0
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

results="$out/results.tsv"
printf 'method\tstatus\trmse\trelmse\tssim\tnc_mse\tnc_relmse\tdevice_ms\tframe_ms\n' > "$results"
panels=()
panel_labels=()
labels=""
for row in "${rows[@]}"; do
  read -r label pipeline params <<< "$row"
  param_args=()
  for p in $params; do
    case "$p" in channels=*) param_args+=(--channels "${p#channels=}") ;; *) param_args+=(--param "$p") ;; esac
  done
  dir="$out/$label"
  rm -rf "$dir"
  mkdir -p "$dir"
  echo "cycles: $label"
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
    elif [ -n "${ref_failed:-}" ]; then
      nc_mse=nan
      nc_relmse=nan
    else
      nc_mse=$(awk -v a="$rmse" -v r="$ref_rmse" 'BEGIN { print a * a - r * r / 2 }')
      nc_relmse=$(awk -v a="$relmse" -v r="$ref_relmse" 'BEGIN { print a - r / 2 }')
    fi
    printf '%s\tok\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$rmse" "$relmse" "$(column "$m" ssim)" \
      "$nc_mse" "$nc_relmse" "$(column "$m" device_ms)" \
      "$(awk -v fps="$(column "$m" fps)" 'BEGIN { print (fps > 0 ? 1000 / fps : "nan") }')" >> "$results"
    panels+=("$dir/frame_$lastf.exr")
    panel_labels+=(--label "$label")
    labels+="$label | "
  else
    why=$(failure "$dir/dn.log" "$status")
    echo "cycles: $label FAILED: $why" >&2
    printf '%s\tfailed: %s\t\t\t\t\t\t\t\n' "$label" "$why" >> "$results"
  fi
done

# Side by side: the last frame of every pipeline that ran, then reference 1;
# crops: the mirror sphere (with the light's highlight) and the floor under the gold sphere.
"$bin/bench/side_by_side" --out "$out/cycles.png" --crop 0.24,0.28,0.3,0.5 --crop 0.5,0.62,0.3,0.38 \
  "${panel_labels[@]}" --label reference "${panels[@]}" "$out/render/ref/frame_$lastf.exr" || echo "cycles: side_by_side failed (the table is still written)" >&2

{
  echo "| method | RMSE | relMSE | SSIM | nc MSE ($nc_kind) | nc relMSE ($nc_kind) | device ms/frame | end-to-end ms/frame |"
  echo "|---|---|---|---|---|---|---|---|"
  awk -F'\t' 'NR > 1 {
    if ($2 == "ok") printf "| %s | %.4f | %.4f | %.4f | %.4g | %.4g | %.1f | %.1f |\n", $1, $3, $4, $5, $6, $7, $8, $9
    else printf "| %s | %s | | | | | | |\n", $1, $2 }' "$results"
} > "$out/results.md"

cpu=$(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo)
{
  echo "Machine: $(nproc) cores of ${cpu:-unknown CPU}, device \`$device\`; Blender $blender_version; $(date -u +%Y-%m-%d)."
  echo "Command: \`bench/cycles.sh --frames $frames --size $size --spp $spp --ref-spp $ref_spp\`:"
  echo "examples/blender/cycles_room.py rendered at ${width}×${height}, $frames frames of a moving camera; input $spp spp"
  echo "(seed 0), reference 1 and reference 2 at $ref_spp spp (seeds 1 and 2); every row is"
  echo "\`dn denoise --preset cycles --pipeline P --input ... -r ref1\` (means over the $frames frames)."
  if [ -z "${ref_failed:-}" ]; then
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
  echo
  cat "$out/results.md"
  echo
  echo "Cycles render times (CPU, Blender start-up included):"
  awk -F'\t' 'NR > 1 { printf "%s%s %s spp %.1f s (%.2f s/frame)", (NR > 2 ? "; " : ""), $1, $2, $5, $6 } END { print "." }' "$render_times"
  echo
  echo "Last frame and crops (mirror sphere, floor): ${labels}reference 1"
  echo
  echo "![cycles](images/cycles.png)"
} > "$out/section.md"

if [ "$docs" = 1 ]; then
  grep -q '<!-- cycles:begin -->' docs/results.md || { echo "cycles: docs/results.md has no cycles markers" >&2; exit 1; }
  mkdir -p docs/images
  cp "$out/cycles.png" docs/images/cycles.png
  awk -v section="$out/section.md" '
    /<!-- cycles:begin -->/ { print; while ((getline line < section) > 0) print line; skip = 1; next }
    /<!-- cycles:end -->/ { skip = 0 }
    !skip { print }' docs/results.md > "$out/results.md.new"
  mv "$out/results.md.new" docs/results.md
  echo "cycles: docs/results.md and docs/images/cycles.png updated"
fi

echo
cat "$out/section.md"
echo
echo "cycles: table $out/results.md, side by side $out/cycles.png (${labels}reference 1)"
