#!/usr/bin/env bash
# Runs every gearsim test, installing what is missing first (scripts/setup.sh).
# The stages, in order (each name runs alone: scripts/test.sh STAGE [STAGE ...]):
#   lint       the style checks: ruff check and format, clang-format, mypy on
#              gearsim.analysis (scripts/lint.sh; --fix applies the formatters)
#   c          the C core in double and float precision (cmocka under CTest)
#   package    consumers of the installed CMake package and pkg-config file
#   firmware   Cortex-M4F build, QEMU run bit-exact with the host, size,
#              symbol and stack checks (scripts/firmware_check.sh)
#   hardening  sanitizers, valgrind, bounded libFuzzer runs, edge parameters,
#              cppcheck/MISRA, clang-tidy (scripts/hardening.sh)
#   fmu        the FMUs with FMPy (scripts/build_fmu.sh --test)
#   python     the Python package, analysis and HIL bridge (pytest tests/python;
#              PYTEST_ARGS adds options, e.g. PYTEST_ARGS='-m "not slow"')
# With no STAGE, all of them. Stops at the first failing stage.
# scripts/test.sh --list prints the stage names.
set -euo pipefail
cd "$(dirname "$0")/.."

all_stages=(lint c package firmware hardening fmu python)
if [ "${1:-}" = "--list" ]; then
  printf '%s\n' "${all_stages[@]}"
  exit 0
fi
stages=("$@")
((${#stages[@]})) || stages=("${all_stages[@]}")
for s in "${stages[@]}"; do
  case " ${all_stages[*]} " in
    *" $s "*) ;;
    *) echo "test.sh: no stage '$s' (stages: ${all_stages[*]})" >&2; exit 2 ;;
  esac
done

scripts/setup.sh
started=$SECONDS
stage() { printf '\n== %s (%ds)\n' "$1" $((SECONDS - started)) >&2; }
jobs=$(nproc 2>/dev/null || echo 2)

run_lint() { stage "style checks"; scripts/lint.sh; }
run_c() {
  local precision
  for precision in double float; do   # the presets of CMakePresets.json
    stage "C core, $precision precision"
    cmake --preset "$precision" >/dev/null
    cmake --build --preset "$precision" -j "$jobs" >/dev/null
    ctest --preset "$precision" -j "$jobs"
  done
}
run_package() { stage "CMake package and pkg-config consumers"; scripts/package_check.sh; }
run_firmware() { stage "firmware (Cortex-M4F under QEMU)"; scripts/firmware_check.sh; }
run_hardening() { stage "hardening"; scripts/hardening.sh; }
run_fmu() { stage "FMUs"; scripts/build_fmu.sh --test; }
run_python() {
  stage "Python package, analysis, HIL"
  # shellcheck disable=SC2086  # PYTEST_ARGS is a list of options
  eval ".venv/bin/python -m pytest -q tests/python ${PYTEST_ARGS:-}"
}

for s in "${stages[@]}"; do
  "run_$s"
done
stage "all stages passed: ${stages[*]}"
