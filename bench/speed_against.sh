#!/usr/bin/env bash
# Speed against an earlier commit: builds pipeline_bench at BASE in a git
# worktree (OUT/base, kept between runs: incremental), then runs the base
# and the current binary alternately per pipeline, ROUNDS rounds, so both
# see the same load. Prints a Markdown table of the median device ms and the
# per-round ratios (current / base), and writes every pipeline_bench row to
# OUT/rows/. Run from a built tree (scripts/setup.sh). --base-bin takes an
# already built pipeline_bench instead of building one.
# Environment: DN_BUILD_DIR (default build) holds the current pipeline_bench.
set -euo pipefail
cd "$(dirname "$0")/.."

base=
base_bin=
rounds=3
size=640x360
frames=8
out=out/speed_against
configs=("svgf" "svgf-fb" "reflect" "progressive" "progressive --spp-period 4" "accumulate")
usage() {
  cat <<EOF
usage: bench/speed_against.sh --base COMMIT | --base-bin PATH [--rounds N] [--size WxH] [--frames N] [--out DIR]
                              [--pipeline "NAME [pipeline_bench options]"]...
defaults: --rounds $rounds --size $size --frames $frames --out $out, pipelines: ${configs[*]}
EOF
}
custom=()
while [ $# -gt 0 ]; do
  case "$1" in
    --base) base=$2; shift 2 ;;
    --base-bin) base_bin=$2; shift 2 ;;
    --rounds) rounds=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --pipeline) custom+=("$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "speed_against.sh: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
[ -n "$base" ] || [ -n "$base_bin" ] || { echo "speed_against.sh: --base COMMIT or --base-bin PATH is required" >&2; usage >&2; exit 2; }
[ ${#custom[@]} -eq 0 ] || configs=("${custom[@]}")
current=${DN_BUILD_DIR:-build}/bench/pipeline_bench
[ -x "$current" ] || { echo "speed_against.sh: $current not built (scripts/setup.sh)" >&2; exit 1; }

if [ -z "$base_bin" ]; then
  base_label=$(git rev-parse --short "$base^{commit}")
  tree=$out/base
  if [ ! -d "$tree" ]; then
    mkdir -p "$out"
    git worktree add --detach "$tree" "$base_label" >/dev/null
  else
    git -C "$tree" checkout --quiet --detach "$base_label"
  fi
  [ -f "$tree/build/build.ninja" ] || cmake -S "$tree" -B "$tree/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
  ninja -C "$tree/build" pipeline_bench >/dev/null
  base_bin=$tree/build/bench/pipeline_bench
else
  base_label=$base_bin
fi

# The device ms column of the pipeline's row (column 7 of the Markdown table).
device_ms() { awk -F'|' -v p=" $1 " '$2 == p { print $7 + 0 }' "$2"; }

rows=$out/rows
rm -rf "$rows"
mkdir -p "$rows"
for r in $(seq "$rounds"); do
  for config in "${configs[@]}"; do
    name=${config// /_}
    for which in base current; do
      bin=$base_bin
      [ "$which" = current ] && bin=$current
      # shellcheck disable=SC2086 # config holds the pipeline and its options
      "$bin" --pipeline $config --size "$size" --frames "$frames" --warmup 2 >"$rows/$name.$which.$r" 2>/dev/null
    done
  done
done

current_label=$(git describe --always --dirty=+)
echo "| pipeline | base $base_label (ms) | $current_label (ms) | current / base, per round | median ratio |"
echo "|---|---|---|---|---|"
for config in "${configs[@]}"; do
  name=${config// /_}
  pipeline=${config%% *}
  for r in $(seq "$rounds"); do
    echo "$(device_ms "$pipeline" "$rows/$name.base.$r") $(device_ms "$pipeline" "$rows/$name.current.$r")"
  done | python3 -c '
import statistics, sys
name = sys.argv[1]
pairs = [tuple(map(float, line.split())) for line in sys.stdin if line.strip()]
base = [b for b, _ in pairs]
now = [c for _, c in pairs]
ratios = [c / b for b, c in pairs]
def ms(x): return f"{x:.0f}" if x >= 100 else f"{x:.3g}"
per_round = ", ".join(f"{x:.2f}" for x in ratios)
print(f"| {name} | {ms(statistics.median(base))} | {ms(statistics.median(now))} | {per_round} | "
      f"{statistics.median(ratios):.2f} |")' "$config"
done
