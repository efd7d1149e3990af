#!/usr/bin/env bash
# HIL loop timing and replay throughput: the C runner gearsim-hil (default
# scheduling and SCHED_FIFO where permitted) and the Python bridge side by
# side (bench/hil_bench.py; docs/hil-runner.md, docs/performance.md "HIL").
# Builds the runner in Release first (build/hil-bench). Run it on an idle
# machine: the figures are the machine's scheduling as much as the code's.
#
# Usage: scripts/hil_bench.sh [--seconds 60] [--rates 1000,10000] [--spin-us US]
#                             [--fifo 50] [--loads idle,other,same] [--cpu 0]
#                             [--replay-seconds 60] [--no-python] [--out FILE.json]
#   loads: idle; a CPU hog on the other core; one on the loop's core (--cpu), with
#   the loop pinned there (C runner --cpu, and --mlockall with --fifo)
#   (options go to bench/hil_bench.py; --seconds 5 is a smoke run)
# Environment: GEARSIM_PYTHON  the Python with gearsim installed (default: .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) sed -n '2,14p' "$0"; exit 0 ;; esac

py=${GEARSIM_PYTHON:-.venv/bin/python}
if [ ! -x "$py" ]; then
  scripts/setup.sh
  py=.venv/bin/python
fi
py_abs=$(cd "$(dirname "$py")" && pwd)/$(basename "$py")  # GEARSIM_PYTHON may be relative or absolute
dir=build/hil-bench
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF -DGEARSIM_BUILD_EXAMPLES=OFF \
  -DGEARSIM_BUILD_BENCH=OFF -DGEARSIM_BUILD_HIL=ON -DGEARSIM_HIL_PYTHON="$py_abs" >/dev/null
cmake --build "$dir" --target gearsim-hil -j "$(nproc 2>/dev/null || echo 2)" >/dev/null
GEARSIM_HIL_RUNNER="$PWD/$dir/hil/gearsim-hil" exec "$py_abs" bench/hil_bench.py "$@"
