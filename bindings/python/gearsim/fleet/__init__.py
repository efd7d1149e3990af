"""gearsim.fleet: the analysis over a fleet of logs, on Dask.

Every unit of a production line leaves one log of the same test cycle. The
fleet layer runs the analysis on each (compare -> fit -> compare, or the
full diagnose rounds) as one Dask task per log, on a local cluster or on a
scheduler's workers, keeps one row per unit in a Parquet file, and judges
the population: robust centre and spread per parameter, outliers by robust
z-score and the parameter that makes each one, drift against time. It calls
the analysis' public functions and adds no physics (docs/fleet.md).

    from gearsim.fleet import FleetOptions, run_fleet

    res = run_fleet("logs/", model="model.toml", out="fleet-out",
                    options=FleetOptions(effects=("coulomb_friction", "meshing_efficiency")))
    res.parquet                       # fleet-out/units.parquet, one row per unit
    [(o["unit"], o["by"], o["z"]) for o in res.outliers]

Needs the fleet extra (dask[distributed], pyarrow, tqdm) and the analysis
extra: ``pip install 'gearsim[fleet]'``. Importing this package imports
neither; they are loaded when a run starts.
"""

from __future__ import annotations

from .population import MIN_UNITS, REMAINING_ERROR, THRESHOLD, Sample, population
from .run import CACHE, OVERLAYS, PARQUET, POPULATION, REPORT, FleetOptions, FleetResult, run_fleet
from .task import analyse_unit, code_id
from .units import MANIFEST_COLUMNS, FleetInputError, Unit, find_units

__all__ = [
    "run_fleet",
    "FleetOptions",
    "FleetResult",
    "FleetInputError",
    "find_units",
    "Unit",
    "MANIFEST_COLUMNS",
    "analyse_unit",
    "code_id",
    "population",
    "Sample",
    "THRESHOLD",
    "MIN_UNITS",
    "REMAINING_ERROR",
    "PARQUET",
    "POPULATION",
    "REPORT",
    "CACHE",
    "OVERLAYS",
]
