#!/usr/bin/env bash
# Runs every gearsim benchmark and prints the figures (docs/performance.md):
#   1. the C core, Release build: ns per step and steps per second of every
#      configuration, one call at a time and batched (bench/gearsim_bench.c);
#   2. instructions per step with valgrind's callgrind (bench/instructions.py);
#   3. the Cortex-M4F float build: code size, and instructions per step on
#      QEMU mps2-an386 (bench/m4_bench.py; skipped without arm-none-eabi-gcc /
#      qemu-system-arm);
#   4. Python: Rig.run and Rig.step through the bindings, and the Python,
#      numpy and scipy alternatives (bench/python_bench.py);
#   5. the table and the target check (bench/report.py).
# Results go to build/bench/results/ (JSON per part and results.md).
# No benchmark asserts a time: targets are reported as met or missed.
#
# Usage: scripts/bench.sh [--quick] [--update-docs]
#   --quick        fewer runs and samples (a smoke run of the whole chain, ~1 min)
#   --update-docs  also rewrite the results section of docs/performance.md
# Environment: GEARSIM_PYTHON  the Python with gearsim installed (default: the
#              project's .venv, set up by scripts/setup.sh as for the tests).
set -euo pipefail
cd "$(dirname "$0")/.."

quick=0
update_docs=0
for arg in "$@"; do
  case "$arg" in
    --quick) quick=1 ;;
    --update-docs) update_docs=1 ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown argument $arg" >&2; exit 2 ;;
  esac
done

if [ -n "${GEARSIM_PYTHON:-}" ]; then
  py=$GEARSIM_PYTHON
  command -v valgrind >/dev/null 2>&1 || echo "bench.sh: valgrind not found (apt-get install valgrind); no instruction counts" >&2
elif [ -f pyproject.toml ]; then
  scripts/setup.sh valgrind   # the tests' environment, plus valgrind for the counts
  py=.venv/bin/python
else
  py=python3
fi

out=build/bench/results
mkdir -p "$out"
jobs=$(nproc 2>/dev/null || echo 2)

echo "== Build (Release)" >&2
cmake -S bench -B build/bench -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/bench -j "$jobs" >/dev/null
bin=build/bench/gearsim_bench

if [ "$quick" = 1 ]; then
  runs=5; steps=50000; count_steps=4000; pyflags=(--quick)
else
  runs=15; steps=200000; count_steps=8000; pyflags=()
fi

echo "== C core: time per step ($runs runs x $steps steps)" >&2
"$bin" --runs "$runs" --steps "$steps" --json "$out/c.json"

echo "== C core: instructions per step (callgrind)" >&2
python3 bench/instructions.py "$bin" --steps "$count_steps" --json "$out/instructions.json"

echo "== Cortex-M4F float build" >&2
python3 bench/m4_bench.py --json "$out/m4.json"

echo "== Python ($py)" >&2
if "$py" -c "import gearsim; gearsim.Model" >/dev/null 2>&1; then
  if ! "$py" -c "import scipy" >/dev/null 2>&1; then
    # the bench extra's pins from pyproject.toml, without `pip install .[bench]`:
    # that would rebuild and replace the gearsim installed in that environment
    echo "bench.sh: installing the bench extra (scipy) into $py's environment for the solve_ivp comparison" >&2
    mapfile -t bench_reqs < <("$py" -c 'import tomllib
with open("pyproject.toml", "rb") as f:
    print("\n".join(tomllib.load(f)["project"]["optional-dependencies"]["bench"]))')
    "$py" -m pip install -q "${bench_reqs[@]}" >/dev/null 2>&1 || echo "bench.sh: could not install scipy; solve_ivp skipped" >&2
  fi
  "$py" bench/python_bench.py "${pyflags[@]}" --json "$out/python.json"
else
  echo "bench.sh: gearsim is not importable with $py; Python figures skipped" >&2
  echo '{"available": false, "reason": "gearsim not importable"}' > "$out/python.json"
fi

report_args=("$out")
[ "$update_docs" = 1 ] && report_args+=(--update-docs docs/performance.md)
python3 bench/report.py "${report_args[@]}"
