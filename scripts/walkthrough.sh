#!/usr/bin/env bash
# The main job: sets up gearsim (scripts/setup.sh), then runs the compare ->
# diagnose -> fit walkthrough on the bundled demo measurement (and on the EMPS
# data when DATA_EMPS.mat is present: README, Real data) and writes report/report.html.
# Extra arguments go to examples/walkthrough.py (e.g. --no-emps, --out DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
.venv/bin/python examples/walkthrough.py --out report "$@"
