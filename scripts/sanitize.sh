#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run of the end-to-end and
# pipeline tests, leak detection on (docs/server.md, "Sanitizers").
#   scripts/sanitize.sh                # build build-asan/, run ctest -L "e2e|pipelines"
#   scripts/sanitize.sh -R HostilePeer # extra arguments go to ctest
# Leaks reported from third-party libraries only (the Vulkan loader and
# driver, LLVM under lavapipe) are suppressed by scripts/sanitize/lsan.supp;
# a leak with a frame of ours is never suppressed. UBSan stops at the first
# error. Installs what it needs (as scripts/setup.sh) and builds incrementally.
set -euo pipefail
cd "$(dirname "$0")/.."
DN_SKIP_BUILD=1 ./scripts/setup.sh  # packages only
dir=build-asan
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
if [ ! -f "$dir/build.ninja" ]; then
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDN_BUILD_BENCH=OFF \
    -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined"
fi
cmake --build "$dir" -j "$(nproc)"
supp="$PWD/scripts/sanitize/lsan.supp"
# The Vulkan loader unloads the driver and the layers (the GPU tests enable
# the validation layer) at vkDestroyInstance; a leak they left then shows as
# "<unknown module>", which no suppression can name. Preloaded, they stay
# mapped and their leaks are attributed (and suppressed) by name; ASan then
# does not come first in the library list, hence verify_asan_link_order=0.
preload=""
for lib in libvulkan_lvp.so libVkLayer_khronos_validation.so libVkLayer_MESA_device_select.so; do
  path=$(ls /usr/lib/*/"$lib" 2>/dev/null | head -n 1 || true)
  [ -z "$path" ] || preload="${preload:+$preload:}$path"
done
[ -z "$preload" ] || export LD_PRELOAD="$preload"
export ASAN_OPTIONS="detect_leaks=1:verify_asan_link_order=0:strict_string_checks=1:detect_stack_use_after_return=1"
export LSAN_OPTIONS="suppressions=$supp:print_suppressions=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
if [ $# -eq 0 ]; then set -- -L "e2e|pipelines"; fi
ctest --test-dir "$dir" --output-on-failure -j 2 --timeout 900 "$@"
