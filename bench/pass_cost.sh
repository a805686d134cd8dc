#!/usr/bin/env bash
# Per-pass cost (what reflect adds over svgf-fb, per pass). Streams the speed-error bench's moving-camera frames of one dnrender
# scene (--input, default out/bench/scene<N>/input, rendered by
# bench/speed_error.sh; rendered here with dnrender when missing) through each pipeline with `dn denoise`,
# and prints one markdown table: the median device time of every pass over
# the frames after the warm-up of --repeat sessions, per pipeline, and the
# sum of those medians. Timestamps come from the server (the timings a RESULT carries).
# Environment: DN_BUILD_DIR (default build) holds the binaries.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/lib/bench_server.sh

scene=1
pipelines="svgf-fb reflect"
frames=12
warmup=2
repeat=3
size=320x180
out=out/pass_cost
input=
usage() {
  echo "usage: bench/pass_cost.sh [--scene N] [--pipelines \"svgf-fb reflect\"] [--frames N] [--warmup N] [--repeat R] [--size WxH] [--input DIR] [--out DIR]"
}
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --pipelines) pipelines=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --warmup) warmup=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --input) input=$2; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "pass_cost: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
[ "$frames" -gt "$warmup" ] || { echo "pass_cost: --frames must exceed --warmup" >&2; exit 2; }
bin=${DN_BUILD_DIR:-build}
dn=$bin/client/dn
mkdir -p "$out"

[ -n "$input" ] || input=out/bench/scene$scene/input
if [ ! -f "$input/frame_$(printf %04d $((frames - 1))).exr" ]; then
  input=$out/scene$scene
  mkdir -p "$input"
  "$bin/examples/renderer/dnrender" --scene "$scene" --size "$size" --frames "$frames" --out "$input" > /dev/null
fi

start_bench_server pass_cost "$bin" "$dn" "$out/dnserver.log"

# One line per pass and frame after the warm-up, from dn's per-frame line
# "frame N  e2e ... server ... [pass ms, pass ms, ...]"; --repeat sessions
# per pipeline, interleaved, so that machine load falls on all alike.
for _ in $(seq 1 "$repeat"); do
  for p in $pipelines; do
    "$dn" denoise --server "$server_url" --pipeline "$p" --preset dnrender --input "$input/frame_%04d.exr" \
      --start 0 --end $((frames - 1)) 2>&1 |
      awk -v warm="$warmup" -v p="$p" '/^frame / { if (n++ < warm) next; sub(/.*\[/, ""); sub(/\].*/, "");
        k = split($0, parts, ", "); for (i = 1; i <= k; ++i) { split(parts[i], f, " "); print p, f[1], f[2] } }'
  done
done > "$out/passes.txt"

echo "Per-pass device time, ms: median over frames $warmup..$((frames - 1)) of scene $scene ($size) in $repeat sessions per pipeline, on $device"
echo
awk -v pipelines="$pipelines" '
  { key = $1 SUBSEP $2; v[key, ++n[key]] = $3; if (!($2 in seen)) { seen[$2] = 1; order[++passes] = $2 } }
  function median(key,   m, i, j, t, a) {
    m = n[key]; if (m == 0) return "";
    for (i = 1; i <= m; ++i) a[i] = v[key, i];
    for (i = 2; i <= m; ++i) { t = a[i]; for (j = i - 1; j >= 1 && a[j] > t; --j) a[j + 1] = a[j]; a[j + 1] = t }
    return m % 2 ? a[(m + 1) / 2] : (a[m / 2] + a[m / 2 + 1]) / 2 }
  END {
    np = split(pipelines, names, " ");
    header = "| pass |"; rule = "|---|";
    for (k = 1; k <= np; ++k) { header = header " " names[k] " |"; rule = rule "---:|" }
    print header; print rule;
    for (i = 1; i <= passes; ++i) {
      row = "| " order[i] " |";
      for (k = 1; k <= np; ++k) { m = median(names[k] SUBSEP order[i]); row = row " " (m == "" ? "" : sprintf("%.2f", m)) " |"; total[k] += m }
      print row }
    row = "| **sum of medians** |";
    for (k = 1; k <= np; ++k) row = row " **" sprintf("%.1f", total[k]) "** |";
    print row }' "$out/passes.txt" | tee "$out/passes.md"
