#!/usr/bin/env bash
# One finished frame, denoised: each dnrender scene rendered once at 1, 4,
# 16 and 64 samples per pixel (seed 3) against a reference (seed 1,
# --ref-spp), through the image pipeline with the guides a renderer may have
# (colour alone; + albedo and normal; + depth), svgf's first frame (the full
# G-buffer and motion; what the a-trous baseline of bench/speed_error.sh is
# every frame) and OpenCV's non-local means on the tone-mapped frame
# (bench/lib/nlm_baseline.py, strength chosen per frame by the reference).
# Linear HDR RMSE and relMSE, HDR-ꟻLIP, device ms (the server's, steady
# state: the warm-up has compiled every kernel). Writes OUT/results.tsv and
# OUT/results.md; --docs puts the table into docs/results.md between its
# image-quality markers.
# Environment: DN_BUILD_DIR (default build); DN_SKIP_SETUP=1 skips scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh

scenes="1 2 3 4 5 6"
spps="1 4 16 64"
size=320x180
ref_spp=1024
out=out/image_quality
cache=out/cache
docs=0
usage() {
  echo "usage: bench/image_quality.sh [--scenes \"1 2\"] [--spp \"1 4\"] [--size WxH] [--ref-spp S] [--out DIR] [--docs]"
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --spp) spps=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "image_quality: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
width=${size%x*}
height=${size#*x}

[ "${DN_SKIP_SETUP:-0}" = 1 ] || ./scripts/setup.sh
# Debian's OpenCV binding is for Debian's Python (another python3 may come first in PATH).
py=/usr/bin/python3
"$py" -c "import cv2" 2>/dev/null || {
  echo "image_quality: installing python3-opencv (the non-local means baseline)"
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3-opencv > /dev/null
}
bin=${DN_BUILD_DIR:-build}
dnrender=$bin/examples/renderer/dnrender
dn=$bin/client/dn
mkdir -p "$out"
start_bench_server image_quality "$bin" "$dn" "$out/dnserver.log"

# Rows: "label pipeline channels [NAME=VALUE,...]". *-decorrelated: image with noise_estimate=1 (the
# decorrelated mean of the residuals, not their median), capped at 64 times the frame's gain, no harm
# guard: heavy-tailed noise is no longer underestimated; small bright features are spread.
rows=("input passthrough radiance" "image-colour image radiance" "image-albedo-normal image radiance,albedo,normal"
      "image-all image radiance,albedo,normal,depth"
      "image-colour-decorrelated image radiance noise_estimate=1,noise_cap=64,harm_guard=0"
      "image-all-decorrelated image radiance,albedo,normal,depth noise_estimate=1,noise_cap=64,harm_guard=0"
      "svgf-first-frame svgf radiance,albedo,normal,depth,motion")
results="$out/results.tsv"
printf 'scene\tspp\tmethod\trmse\trelmse\tflip_hdr\tdevice_ms\n' > "$results"
for s in $scenes; do
  dir="$out/scene$s"
  "$dnrender" --scene "$s" --width "$width" --height "$height" --out "$dir/refs" --reference "$ref_spp" \
    --cache "$cache" --quiet
  # The reference as plain RGB, for the baseline's choice of strength.
  "$dn" denoise -q --server "$server_url" --pipeline passthrough --channels radiance --preset dnrender \
    --input "$dir/refs/ref_%04d.exr" --start 0 --end 0 --exr-float --output "$dir/refs/rgb_%04d.exr"
  for spp in $spps; do
    echo "image_quality: scene $s, $spp spp"
    "$dnrender" --scene "$s" --width "$width" --height "$height" --spp "$spp" --seed 3 --out "$dir/spp$spp" --quiet
    for row in "${rows[@]}"; do
      read -r label pipeline channels params <<< "$row"
      param_args=()
      for p in ${params//,/ }; do param_args+=(--param "$p"); done
      summary="$dir/spp$spp/$label.tsv"
      "$dn" denoise -q --server "$server_url" --pipeline "$pipeline" --channels "$channels" "${param_args[@]}" --preset dnrender \
        --input "$dir/spp$spp/frame_%04d.exr" --start 0 --end 0 --exr-float --output "$dir/spp$spp/$label/frame_%04d.exr" \
        -r "$dir/refs/ref_%04d.exr" --summary "$summary"
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$s" "$spp" "$label" "$(column "$summary" rmse)" "$(column "$summary" relmse)" \
        "$(column "$summary" flip_hdr)" "$(column "$summary" device_ms)" >> "$results"
    done
    # Non-local means on the input's plain RGB (passthrough's output above).
    mkdir -p "$dir/spp$spp/nlm"
    h=$("$py" bench/lib/nlm_baseline.py "$dir/spp$spp/input/frame_0000.exr" "$dir/refs/rgb_0000.exr" \
          "$dir/spp$spp/nlm/frame_0000.exr")
    summary="$dir/spp$spp/nlm.tsv"
    "$dn" denoise -q --server "$server_url" --pipeline passthrough --channels radiance --preset dnrender \
      --input "$dir/spp$spp/nlm/frame_%04d.exr" --start 0 --end 0 -r "$dir/refs/ref_%04d.exr" --summary "$summary"
    printf '%s\t%s\tnlm-h%s\t%s\t%s\t%s\tnan\n' "$s" "$spp" "$h" "$(column "$summary" rmse)" "$(column "$summary" relmse)" \
      "$(column "$summary" flip_hdr)" >> "$results"
  done
done

{
  echo "| scene | spp | method | RMSE | relMSE | HDR-ꟻLIP | device ms |"
  echo "|---|---|---|---|---|---|---|"
  awk -F'\t' 'NR > 1 { printf "| %s | %s | %s | %.4f | %.4f | %.4f | %s |\n", $1, $2, $3, $4, $5, $6, ($7 == "nan" ? "–" : sprintf("%.1f", $7)) }' "$results"
  echo
  # Per spp and method: in how many scenes it is below the input, and its geometric-mean ratios to the input.
  echo "| spp | method | scenes below the input (RMSE / relMSE / ꟻLIP) | RMSE ÷ input | relMSE ÷ input | HDR-ꟻLIP ÷ input |"
  echo "|---|---|---|---|---|---|"
  awk -F'\t' 'NR > 1 { m = $3; sub(/-h[0-9]+$/, "", m); if (m == "input") { ir[$1, $2] = $4; il[$1, $2] = $5; if_[$1, $2] = $6 } rows[NR] = $0 }
    END {
      for (r in rows) { split(rows[r], f, "\t"); m = f[3]; sub(/-h[0-9]+$/, "", m); if (m == "input") continue
        k = f[2] "|" m; n[k]++; a = f[4] / ir[f[1], f[2]]; b = f[5] / il[f[1], f[2]]; c = f[6] / if_[f[1], f[2]]
        lr[k] += log(a); ll[k] += log(b); lf[k] += log(c); if (a < 1) wr[k]++; if (b < 1) wl[k]++; if (c < 1) wf[k]++ }
      for (k in n) { split(k, p, "|"); printf "| %s | %s | %d / %d / %d of %d | %.3f | %.3f | %.3f |\n", p[1], p[2], wr[k], wl[k], wf[k], n[k], exp(lr[k] / n[k]), exp(ll[k] / n[k]), exp(lf[k] / n[k]) }
    }' "$results" | sort -t'|' -k2,2n -k3,3
} > "$out/results.md"
cat "$out/results.md"

if [ "$docs" = 1 ]; then
  python3 - "$out/results.md" "$device" "$size" "$ref_spp" <<'PY'
import sys, datetime
table, device, size, ref = open(sys.argv[1]).read(), sys.argv[2], sys.argv[3], sys.argv[4]
doc = open("docs/results.md").read()
begin, end = "<!-- image-quality:begin -->", "<!-- image-quality:end -->"
body = (f"{begin}\n`bench/image_quality.sh --docs` on {device}, {datetime.date.today()}, {size}, references at {ref} spp.\n\n"
        f"{table}{end}")
i, j = doc.index(begin), doc.index(end) + len(end)
open("docs/results.md", "w").write(doc[:i] + body + doc[j:])
PY
fi
