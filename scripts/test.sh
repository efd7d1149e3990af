#!/usr/bin/env bash
# Runs every gearsim test, installing what is missing first (scripts/setup.sh):
#   1. the C core in double and float precision (cmocka under CTest), and
#      consumers of the installed CMake package and pkg-config file;
#   2. firmware: Cortex-M4F build, QEMU run bit-exact with the host, size,
#      symbol and stack checks (scripts/firmware_check.sh);
#   3. hardening: sanitizers, valgrind, bounded libFuzzer runs, edge
#      parameters, cppcheck/MISRA, clang-tidy (scripts/hardening.sh);
#   4. the Python package, analysis and HIL bridge (pytest tests/python);
#   5. the FMUs with FMPy (scripts/build_fmu.sh --test).
# Stops at the first failing stage.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
started=$SECONDS
stage() { printf '\n== %s (%ds)\n' "$1" $((SECONDS - started)) >&2; }

jobs=$(nproc 2>/dev/null || echo 2)
for precision in double float; do
  stage "C core, $precision precision"
  dir=build/test-$precision
  single=OFF; [ "$precision" = float ] && single=ON
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGEARSIM_SINGLE_PRECISION=$single >/dev/null
  cmake --build "$dir" -j "$jobs" >/dev/null
  ctest --test-dir "$dir" --output-on-failure -j "$jobs"
done

stage "CMake package and pkg-config consumers"
scripts/package_check.sh

stage "firmware (Cortex-M4F under QEMU)"
scripts/firmware_check.sh

stage "hardening"
scripts/hardening.sh

stage "FMUs"
scripts/build_fmu.sh --test

stage "Python package, analysis, HIL"
.venv/bin/python -m pytest -q tests/python
stage "all stages passed"
