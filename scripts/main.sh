#!/usr/bin/env bash
# The main job: a short run of the speed-against-error benchmark
# (bench/speed_error.sh): dnserver on the default device (lavapipe without a
# GPU), dnrender scene 1 (the room) at a small size, streamed through every
# pipeline the server offers and the baselines. Writes the denoised frames,
# side-by-side images and the metrics table to out/, and ends by listing
# every output with what it is.
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the run below needs: the packages, and these targets (the
# programs bench/speed_error.sh calls), not the tests.
./scripts/setup.sh --targets "dnserver dn dnrender side_by_side region_metrics region_temporal"
DN_SKIP_SETUP=1 bench/speed_error.sh --scenes 1 --frames "${DN_FRAMES:-8}" --still 8 --size "${DN_SIZE:-256x144}" \
  --ref-spp "${DN_REF_SPP:-64}" --out out
cp out/results.md out/metrics.md

scripts/list_outputs.sh out
