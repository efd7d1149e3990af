#!/usr/bin/env bash
# Builds the FMI 2.0 co-simulation FMUs of the gearsim rigs (docs/fmu.md):
#   build/fmu/gearsim_gear_rig.fmu and build/fmu/gearsim_rack_rig.fmu
# plus build/fmu/reference/libgearsim.so (the same C core, for tests/fmu).
#
# The FMI 2.0 headers come from the FMPy wheel: the fmu extra's requirements
# (fmpy, as pyproject.toml pins it) are installed into the project venv (.venv,
# or $GEARSIM_VENV) when missing.
#
# Usage: scripts/build_fmu.sh [--test]     (--test also runs pytest tests/fmu)
# Environment: GEARSIM_VENV (default .venv), GEARSIM_FMU_BUILD_DIR (default build/fmu)
set -euo pipefail
cd "$(dirname "$0")/.."

run_tests=0
for arg in "$@"; do
  case "$arg" in
    --test) run_tests=1 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "build_fmu: unknown argument '$arg'" >&2; exit 2 ;;
  esac
done

venv=${GEARSIM_VENV:-.venv}
build=${GEARSIM_FMU_BUILD_DIR:-build/fmu}

if [ ! -x "$venv/bin/python" ]; then
  echo "build_fmu: creating $venv" >&2
  python3 -m venv "$venv"
fi
py="$venv/bin/python"

need=()
if ! "$py" -c "import fmpy" 2>/dev/null; then
  # the fmu extra's pins, without `pip install .[fmu]`: that would rebuild the
  # C extension and replace the venv's (editable) gearsim for nothing
  mapfile -t fmu_reqs < <("$py" -c 'import tomllib
with open("pyproject.toml", "rb") as f:
    print("\n".join(tomllib.load(f)["project"]["optional-dependencies"]["fmu"]))')
  need+=("${fmu_reqs[@]}")
fi
if ((run_tests)); then
  for mod in pytest numpy cffi; do
    "$py" -c "import $mod" 2>/dev/null || need+=("$mod")
  done
fi
if ((${#need[@]})); then
  echo "build_fmu: installing into $venv: ${need[*]}" >&2
  "$py" -m pip install -q "${need[@]}"
fi

fmi2_dir=$("$py" -c "import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), 'c-code'))")
if [ ! -f "$fmi2_dir/fmi2Functions.h" ]; then
  echo "build_fmu: fmpy at $fmi2_dir ships no fmi2Functions.h" >&2
  exit 1
fi

cmake_bin=$(command -v cmake || true)
[ -n "$cmake_bin" ] || cmake_bin="$venv/bin/cmake"   # fmpy's dependencies bring a cmake wheel
if [ ! -x "$cmake_bin" ]; then
  echo "build_fmu: cmake not found (apt-get install cmake, or scripts/setup.sh)" >&2
  exit 1
fi
"$cmake_bin" -S fmu -B "$build" -DCMAKE_BUILD_TYPE=Release -DGEARSIM_FMI2_INCLUDE_DIR="$fmi2_dir" >/dev/null
"$cmake_bin" --build "$build" -j "$(nproc 2>/dev/null || echo 2)"

echo "build_fmu: FMUs:" >&2
ls -1 "$build"/gearsim_gear_rig.fmu "$build"/gearsim_rack_rig.fmu

if ((run_tests)); then
  GEARSIM_FMU_DIR="$build" "$py" -m pytest -q tests/fmu
fi
