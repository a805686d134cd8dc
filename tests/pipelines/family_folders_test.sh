#!/usr/bin/env bash
# A pipeline family is its folder (docs/pipelines.md, "Adding a pipeline"):
# every family pipelines.def names has its folder server/pipelines/<family>/,
# every folder there but stages/ is such a family, and outside tests/, bench/
# and docs/ no file names a family's folder but the family's own files, and
# no shader or C++ outside it reads the parameter groups it defines (its
# parameters.def and pass-local rows), so adding one touches its folder, its
# tests and the one registry line.
#   family_folders_test.sh <source root>
set -euo pipefail
cd "$1"
fail=0
families=$(sed -n 's/^DN_PIPELINE(\([a-z0-9_]*\), *[a-z0-9_]*).*/\1/p' server/pipelines/pipelines.def | sort -u)
[ -n "$families" ] || { echo "no DN_PIPELINE rows in server/pipelines/pipelines.def"; exit 1; }
for family in $families; do
  if [ ! -d "server/pipelines/$family" ]; then
    echo "pipelines.def names family $family, but server/pipelines/$family/ does not exist"
    fail=1
    continue
  fi
  # server/pipelines/<family>/ or an include path pipelines/<family>/; tests/pipelines/<family>/ is the tests'.
  outside=$(grep -rlP "(?<!tests/)pipelines/$family/" CMakeLists.txt server shaders protocol client python examples scripts \
              2>/dev/null | grep -v "^server/pipelines/$family/" || true)
  if [ -n "$outside" ]; then
    echo "family $family's folder is named outside it:"
    echo "$outside" | sed 's/^/  /'
    fail=1
  fi
  groups=$(find "server/pipelines/$family" -maxdepth 1 \( -name parameters.def -o -name '*.pass' \) \
             -exec sed -n 's/^DN_PARAM(\([a-z0-9_]*\),.*/\1/p' {} + | sort -u)
  for group in $groups; do
    # DN_PARAM_VALUE(group, name) in GLSL, parameters.<group>_<name> in C++.
    readers=$(grep -rlE "DN_PARAM_VALUE\($group,|[.>]${group}_[a-z]" server shaders 2>/dev/null |
                grep -v "^server/pipelines/$family/" || true)
    if [ -n "$readers" ]; then
      echo "family $family's parameter group $group is read outside its folder:"
      echo "$readers" | sed 's/^/  /'
      fail=1
    fi
  done
done
for dir in server/pipelines/*/; do
  name=$(basename "$dir")
  [ "$name" = stages ] && continue
  if ! grep -qx "$name" <<<"$families"; then
    echo "server/pipelines/$name/ is no family of pipelines.def"
    fail=1
  fi
done
exit $fail
