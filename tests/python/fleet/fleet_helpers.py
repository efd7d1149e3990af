"""A synthetic production line for the fleet tests, made by the independent
generator (tests/python/analysis/independent: numpy physics, its own
integrator and sensors, never gearsim's C core).

Every unit is the same gear type run through the same test cycle (the rich
profile, DURATION_S long); units differ by a spread of SPREAD (relative
standard deviation) in each physical parameter (Coulomb friction, the loss
1 - eta of the mesh efficiency, the backlash, the torque sensor's offset)
and by their own sensor noise (the generator's sensors: encoder speeds,
1 % torque and load noise). DEFECTS plants one unit of each kind; EXPECTED
says by which metric the population must find it: the fitted parameter, or
the remaining error where the effect is not in EFFECTS (backlash and the
compliant shaft are not fitted).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import multiprocessing
import os
import sys
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
sys.path.insert(0, str(HERE.parent / "analysis"))

from independent import excitation, plant  # noqa: E402
from independent import generator as G  # noqa: E402

BLOCK = "simple_gear"
DURATION_S = 3.0
CYCLE_SEED = 5
SPREAD = 0.03
NOMINAL_EFFICIENCY = 0.8
NOMINAL_COULOMB_NM = 1.5
NOMINAL_BACKLASH_M = 3e-4
NOMINAL_TORQUE_OFFSET = 0.005  # fraction of the torque's range (generator's sensors)
#: what every unit gets fitted (backlash and compliance are not in the list)
EFFECTS = ("coulomb_friction", "meshing_efficiency", "load_offset")
#: defect -> the metric that must single the unit out
EXPECTED = {
    "backlash_3x": "nrmse_after",
    "coulomb_2x": "load_coulomb_friction",
    "efficiency_minus_5_points": "efficiency_const",
    "torque_sensor_offset": "load_offset",
    "compliance": "nrmse_after",
}
START = datetime(2026, 11, 2, 6, 0, tzinfo=UTC)
UNIT_PERIOD = timedelta(minutes=13)
#: the drift planted on the Coulomb friction over the whole run (relative)
COULOMB_DRIFT = 0.06


def start_model():
    """The gear as the line's engineer states it: geometry, inertia, the
    smoothing thresholds; no losses."""
    return G.gearsim_model(BLOCK, ())


@dataclasses.dataclass(frozen=True)
class UnitSpec:
    index: int
    unit: str
    defect: str | None
    efficiency: float
    coulomb: float
    backlash_m: float
    torque_offset: float
    seed: int
    timestamp: datetime


def unit_specs(n: int, defects: dict[int, str], seed: int = 2026) -> list[UnitSpec]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        spread = 1.0 + SPREAD * rng.standard_normal(4)
        drift = 1.0 + COULOMB_DRIFT * i / max(n - 1, 1)
        eff = 1.0 - (1.0 - NOMINAL_EFFICIENCY) * spread[0]
        coul = NOMINAL_COULOMB_NM * spread[1] * drift
        gap = NOMINAL_BACKLASH_M * spread[2]
        off = NOMINAL_TORQUE_OFFSET * spread[3]
        d = defects.get(i)
        if d == "backlash_3x":
            gap *= 3.0
        elif d == "coulomb_2x":
            coul *= 2.0
        elif d == "efficiency_minus_5_points":
            eff -= 0.05
        elif d == "torque_sensor_offset":
            off = 0.03
        out.append(
            UnitSpec(i, f"gx-{i:04d}", d, eff, coul, gap, off, 1000 + i, START + i * UNIT_PERIOD)
        )
    return out


def _mechanism(spec: UnitSpec):
    mech = dataclasses.replace(
        G.RIGS[BLOCK],
        losses=plant.Losses(efficiency=spec.efficiency, coulomb=spec.coulomb),
        backlash_m=spec.backlash_m,
    )
    if spec.defect == "compliance":
        # a soft coupling between the motor and the base gear (52 Hz with the
        # motor held), the rig's inertia otherwise unchanged
        mech = dataclasses.replace(
            mech, shaft_stiffness_Nm_rad=600.0, shaft_damping_Nms_rad=0.2, gear_inertia=1e-4
        )
    return mech


def measure(spec: UnitSpec, duration_s: float = DURATION_S):
    """The unit's Measurement through the test cycle."""
    from gearsim.analysis.measurement import Measurement

    prof = excitation.rich(duration_s, G.DT, *G.PEAKS[BLOCK], CYCLE_SEED)
    run = plant.simulate_true(
        _mechanism(spec), prof.time, prof.speed_command, prof.load, prof.temperature
    )
    sens = dataclasses.replace(G.GEAR_SENSORS, torque_offset=spec.torque_offset)
    cols = G._measure(BLOCK, run, sens, spec.seed)
    return Measurement.from_arrays(BLOCK, prof.time, path=spec.unit, **cols)


def _write(job: tuple[UnitSpec, str, float]) -> str:
    from gearsim.analysis import write_measurement

    spec, path, duration = job
    write_measurement(path, measure(spec, duration), digits=7)
    return path


def write_fleet(
    folder: Path, specs: list[UnitSpec], duration_s: float = DURATION_S, processes: int = 2
) -> Path:
    """Write one CSV per unit and manifest.csv (unit, path, line, station,
    timestamp) into folder; returns the manifest's path."""
    folder.mkdir(parents=True, exist_ok=True)
    jobs = [(s, str(folder / f"{s.unit}.csv"), duration_s) for s in specs]
    todo = [j for j in jobs if not os.path.exists(j[1])]
    if todo:
        with multiprocessing.get_context("spawn").Pool(processes) as pool:
            pool.map(_write, todo, chunksize=4)
    manifest = folder / "manifest.csv"
    with open(manifest, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["unit", "path", "line", "station", "timestamp"])
        for s in specs:
            w.writerow(
                [
                    s.unit,
                    f"{s.unit}.csv",
                    f"L{1 + s.index % 2}",
                    f"S{1 + s.index % 4}",
                    s.timestamp.isoformat().replace("+00:00", "Z"),
                ]
            )
    return manifest


def defect_map(n: int) -> dict[int, str]:
    """The five planted defects, spread over the run."""
    kinds = list(EXPECTED)
    step = n // (len(kinds) + 1)
    return {step * (k + 1) + 3: kind for k, kind in enumerate(kinds)}


def finite(x) -> bool:
    return x is not None and math.isfinite(x)
