#!/bin/sh
# bench/still_convergence.sh at 48x27 on scene 1, 8 frames: every method has
# a row per frame with finite numbers, the table has a row per method, and
# the running mean's noise-corrected relMSE falls from frame 1 to frame 8
# (the point references are what the still frames converge to).
# usage: still_convergence_test.sh SOURCE_DIR BUILD_DIR WORKDIR
set -eu
src=$1
build=$2
dir=$3
rm -rf "$dir"
mkdir -p "$dir"
DN_SKIP_SETUP=1 DN_BUILD_DIR="$build" "$src/bench/still_convergence.sh" --scenes 1 --frames 8 --size 48x27 \
  --point-ref-frames 16 --out "$dir/out" --cache "$dir/cache" > "$dir/log" 2>&1 || { cat "$dir/log"; exit 1; }
tsv="$dir/out/still.tsv"
for method in mean svgf svgf-fb reflect progressive svgf-no-converge; do
  [ "$(awk -F'\t' -v m="$method" '$2 == m' "$tsv" | wc -l)" -eq 8 ] || { echo "not 8 rows for $method"; cat "$tsv"; exit 1; }
  grep -q "^| 1 | $method |" "$dir/out/still.md" || { echo "no table row for $method"; cat "$dir/out/still.md"; exit 1; }
done
awk -F'\t' 'NR > 1 { for (i = 4; i <= NF; ++i) if ($i !~ /^-?[0-9.]+(e[-+]?[0-9]+)?$/) { print "row " NR " field " i ": " $i; bad = 1 } }
            END { exit bad }' "$tsv"
awk -F'\t' '$2 == "mean" && $3 == 1 { a = $6 } $2 == "mean" && $3 == 8 { b = $6 }
            END { if (!(b < a)) { print "running mean nc relMSE: frame 1 " a ", frame 8 " b; exit 1 } }' "$tsv"
echo "still_convergence smoke: ok"
