# Shared by the Blender benchmark scripts (sourced, not run): one cached
# Cycles render of a project scene script.
#
# blender_options: checks the options both scripts take (size, frames,
# ref_spp, threads, variants) and sets width, height and the array vars.
blender_options() {
  width=${size%x*}
  height=${size#*x}
  case "$size" in [0-9]*x[0-9]*) ;; *) echo "$bench: --size wants WxH and the counts integers" >&2; exit 2 ;; esac
  local value
  for value in "$width" "$height" "$frames" "$ref_spp" "$threads"; do
    case "$value" in *[!0-9]* | "") echo "$bench: --size wants WxH and the counts integers" >&2; exit 2 ;; esac
  done
  [ "$frames" -ge 2 ] || { echo "$bench: need --frames >= 2" >&2; exit 2; }
  IFS=, read -r -a vars <<< "$variants"
  for v in "${vars[@]}"; do case "$v" in preset | denoising | all) ;; *) echo "$bench: unknown variant '$v' (preset, denoising, all)" >&2; exit 2 ;; esac; done
}

# blender_render NAME FRAMES SPP SEED PASSES [SCRIPT-OPTION ...]: renders
# FRAMES frames of $script into $out/render/NAME (frame_%04d.exr) unless a
# render with the same settings, the same scene scripts ($depends) and the
# same Blender is there; appends a line to $render_times. Reads blender,
# blender_version, script, depends, scene, width, height, threads, out,
# render_times and the caller's name in $bench (for messages).
blender_render() {
  local name=$1 n=$2 spp=$3 seed=$4 passes=$5
  shift 5
  local dir="$out/render/$name" lastf
  lastf=$(printf '%04d' $((n - 1)))
  local sum
  sum=$(cat "${depends[@]}" | sha1sum | cut -c1-12)
  local stamp="$name $scene ${width}x$height frames=$n spp=$spp seed=$seed passes=$passes${*:+ $*} script=$sum blender=$blender_version"
  if [ -f "$dir/stamp" ] && [ "$(head -1 "$dir/stamp")" = "$stamp" ] && [ -f "$dir/frame_$lastf.exr" ]; then
    echo "$bench: $name: cached ($dir)"
  else
    rm -rf "$dir"
    mkdir -p "$dir"
    echo "$bench: rendering $name: $scene, $n frames at ${width}x$height, $spp spp, seed $seed, passes $passes${*:+ $*} (Blender $blender_version)"
    local t0 t1
    t0=$(date +%s.%N)
    "$blender" -b --factory-startup --python "$script" -- --out "$dir" --width "$width" --height "$height" \
      --frames "$n" --spp "$spp" --seed "$seed" --passes "$passes" --threads "$threads" "$@" > "$dir/blender.log" 2>&1 ||
      { echo "$bench: Blender failed rendering $name; the end of $dir/blender.log:" >&2; tail -20 "$dir/blender.log" >&2; exit 1; }
    t1=$(date +%s.%N)
    [ -f "$dir/frame_$lastf.exr" ] || { echo "$bench: Blender wrote no $dir/frame_$lastf.exr" >&2; exit 1; }
    printf '%s\n%s\n' "$stamp" "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')" > "$dir/stamp"
  fi
  local s
  s=$(sed -n 2p "$dir/stamp")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$spp" "$seed" "$passes" "$n" "$s" \
    "$(awk -v s="$s" -v n="$n" 'BEGIN { printf "%.2f", s / n }')" >> "$render_times"
}

# blender_scene SCENE: sets script, depends (the scripts its renders depend
# on) for the project's Cycles scene SCENE (room, window); 1 if unknown.
blender_scene() {
  case "$1" in
    room) script=examples/blender/cycles_room.py; depends=("$script") ;;
    window) script=examples/blender/cycles_window.py; depends=("$script" examples/blender/cycles_room.py) ;;
    *) return 1 ;;
  esac
}

# find_blender: sets blender and blender_version, or says why this script is
# skipped and exits 77 (Blender is not a build or CI dependency).
find_blender() {
  blender=${BLENDER:-blender}
  if ! command -v "$blender" > /dev/null 2>&1; then
    echo "$bench: SKIPPED: Blender not found ('$blender' is not on PATH; set BLENDER=/path/to/blender or install" >&2
    echo "$bench: it, e.g. apt-get install blender). Blender is not a build or CI dependency; nothing was run." >&2
    exit 77
  fi
  blender_version=$("$blender" --version 2>/dev/null | awk 'NR == 1 { print $2 }')
}
