#!/usr/bin/env python3
"""Generate the bundled small fleet (examples/data/fleet/) and its start model
(examples/data/fleet_start.toml) for scripts/fleet_demo.sh.

A production line of 40 gearboxes of one type (teeth ratio 3, follower
inertia 0.05 kg*m^2), each through the same 3 s test cycle (seed 11), each log
a gzip-compressed CSV with its own sensor noise (1 % on torque and load,
encoder-like speeds, a torque-sensor offset:
gearsim.analysis.synthetic.SensorModel). The units spread by a few percent:
efficiency 0.90 (its loss 1 - eta by 4 %), Coulomb friction 0.4 N*m (4 %),
the torque sensors' offsets 0.5 % of the range (4 %);
the Coulomb friction rises 8 % over the two days of the run (a lubricant
batch, say). Three units are planted faults and one log is broken:

- gbx-07: Coulomb friction twice the line's;
- gbx-19: efficiency 5 points low;
- gbx-28: a torque sensor with a 4 % offset;
- gbx-33: the log is cut short (a truncated gzip file): an error row.

manifest.csv gives every unit's line (L1/L2), station and end-of-line time.
The logs are made by gearsim's own C core (like the walkthrough's demo data):
they show the tool, they do not validate it.

    python examples/make_fleet_data.py            # rewrites examples/data/fleet/ and the model
    python examples/make_fleet_data.py --out DIR  # writes DIR/fleet/ and DIR/fleet_start.toml
"""

from __future__ import annotations

import csv
import gzip
import io
import os
import sys
from datetime import UTC, datetime, timedelta

HERE = os.path.dirname(os.path.abspath(__file__))
FOLDER = os.path.join(HERE, "data", "fleet")
START = os.path.join(HERE, "data", "fleet_start.toml")

UNITS = 40
SAMPLES = 3000
DT = 1e-3
CYCLE_SEED = 11
EFFICIENCY = 0.90
COULOMB_NM = 0.4
SPREAD = 0.04
DRIFT = 0.08
FAULTS = {7: "coulomb_2x", 19: "efficiency_minus_5_points", 28: "torque_sensor_offset"}
BROKEN = 33
FIRST = datetime(2026, 11, 23, 6, 0, tzinfo=UTC)
PERIOD = timedelta(minutes=70)


def start_model():
    import gearsim

    return gearsim.Model(
        "simple_gear",
        {"teeth_ratio": 3.0, "output_shaft_rotates": "opposite"},
        {"follower_inertia": 0.05},
    )


def unit_truth(i: int, rng):
    """(truth model, sensor model) of unit i."""
    from gearsim.analysis import synthetic as S

    spread = 1.0 + SPREAD * rng.standard_normal(3)
    eta = 1.0 - (1.0 - EFFICIENCY) * spread[0]
    coulomb = COULOMB_NM * spread[1] * (1.0 + DRIFT * i / (UNITS - 1))
    offset = 0.005 * spread[2]
    fault = FAULTS.get(i)
    if fault == "coulomb_2x":
        coulomb *= 2.0
    elif fault == "efficiency_minus_5_points":
        eta -= 0.05
    elif fault == "torque_sensor_offset":
        offset = 0.04
    truth = start_model().replace(
        block_params={"friction_model": "constant_efficiency", "efficiency_const": round(eta, 5)},
        rig_params={"load_coulomb_friction": round(coulomb, 5)},
    )
    return truth, S.SensorModel(torque_offset=offset)


def _csv_gz(meas) -> bytes:
    """The log as gzip bytes, the same on every run (no time stamp in the header)."""
    import tempfile

    from gearsim.analysis import write_measurement

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "log.csv")
        write_measurement(path, meas, digits=6)
        raw = open(path, "rb").read()
    buf = io.BytesIO()
    with gzip.GzipFile(fileobj=buf, mode="wb", mtime=0, filename="") as gz:
        gz.write(raw)
    return buf.getvalue()


def main(argv: list[str] | None = None) -> int:
    import argparse

    import numpy as np

    from gearsim.analysis import synthetic as S

    ap = argparse.ArgumentParser(description="write the bundled small fleet")
    ap.add_argument("--out", default=None, help="write the logs and the model into this directory")
    args = ap.parse_args(argv)
    folder = FOLDER if args.out is None else os.path.join(args.out, "fleet")
    start = START if args.out is None else os.path.join(args.out, "fleet_start.toml")
    os.makedirs(folder, exist_ok=True)
    rng = np.random.default_rng(2026)
    exc = S.excitation(SAMPLES, DT, max_speed=30.0, max_load=3.0, seed=CYCLE_SEED, temperature=None)
    rows = []
    total = 0
    for i in range(UNITS):
        unit = f"gbx-{i:02d}"
        truth, sensors = unit_truth(i, rng)
        meas = S.synthesize(truth, exc, sensors, seed=100 + i, path=unit)
        data = _csv_gz(meas)
        if i == BROKEN:
            data = data[: len(data) // 2]
        name = f"{unit}.csv.gz"
        with open(os.path.join(folder, name), "wb") as fh:
            fh.write(data)
        total += len(data)
        stamp = (FIRST + i * PERIOD).isoformat().replace("+00:00", "Z")
        rows.append([unit, name, f"L{1 + i % 2}", f"S{1 + (i // 2) % 3}", stamp])
    with open(os.path.join(folder, "manifest.csv"), "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["unit", "path", "line", "station", "timestamp"])
        w.writerows(rows)
    start_model().save(start)
    print(f"wrote {UNITS} logs ({total / 1e6:.2f} MB) and manifest.csv in {folder}, and {start}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
