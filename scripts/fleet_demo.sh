#!/usr/bin/env bash
# The fleet job: sets up gearsim (scripts/setup.sh), then analyses the bundled
# small production line (examples/data/fleet: 40 logs, three planted faults,
# one broken log) on a local Dask cluster and writes fleet-report/: the
# Parquet file of one row per unit, population.json and fleet.html.
# Extra arguments go to `gearsim fleet` (e.g. --workers 1, --json,
# --scheduler tcp://host:8786).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
.venv/bin/gearsim fleet --manifest examples/data/fleet/manifest.csv \
  --model examples/data/fleet_start.toml \
  --add coulomb_friction,meshing_efficiency,load_offset \
  --out fleet-report "$@"
