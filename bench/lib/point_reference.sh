# Shared by the still-camera benchmark scripts (sourced, not run): the point
# references, what a still camera's 1-spp frames converge to (dnrender's
# sample 0 goes through the pixel centre in every frame).
#
# point_reference SCENE INDEX: the mean of point_frames 1-spp still frames
# (seed 10 + INDEX; with jitter=1 rendered with jitter_arg, --jitter),
# cached under cache; prints its path. Reads cache, width, height,
# point_frames, dnrender, metrics (bench/progressive_metrics) and, if set,
# jitter and jitter_arg.
point_reference() {
  local s=$1 index=$2
  local dir="$cache/progressive_point_${s}_${width}x${height}_n$point_frames"
  [ "${jitter:-0}" = 0 ] || dir+="_jitter"  # the held camera's jitter moves sample 0: another image
  local file="$dir/ref$index.exr"
  if [ ! -f "$file" ]; then
    local tmp="$dir/frames$index.$$"
    "$dnrender" --scene "$s" --frames "$point_frames" --hold-camera 0 --width "$width" --height "$height" \
      --seed $((10 + index)) ${jitter_arg[@]+"${jitter_arg[@]}"} --out "$tmp" --quiet 2> /dev/null
    "$metrics" --average "$tmp/frame_%04d.exr" --frames "$point_frames" --write "$file.tmp.exr"
    mv "$file.tmp.exr" "$file"
    rm -rf "$tmp"
  fi
  echo "$file"
}
