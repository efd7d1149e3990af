#!/usr/bin/env python3
"""Generate the walkthrough's demo measurement (examples/data/demo_gear.csv)
and its starting model (examples/data/demo_gear_start.toml).

A Simple Gear test rig (teeth ratio 3, follower inertia 0.05 kg*m^2) is run by
the C core on a deterministic excitation (seed 7): 8 s at 1 kHz, back-and-forth
motion with reversals and dwells, a load that both resists and overruns, and a
measured temperature ramp. The "real" gear has two effects that the starting
model lacks: they are written below, and the walkthrough reveals them only at
the end, after diagnose and fit have found them. The viscous friction is
strong enough that the starting model fails in the high-speed regime (its
error there is above 1.5x the overall error), as a missing viscous loss
should. Sensor imperfections: 1 % noise
on torque and load, encoder-like speeds (0.2 % quantization and noise), a 0.5 %
torque-sensor offset (gearsim.analysis.synthetic.SensorModel).

    python examples/make_demo_data.py        # rewrites the two files
"""

from __future__ import annotations

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "data")
CSV = os.path.join(DATA, "demo_gear.csv")
START = os.path.join(DATA, "demo_gear_start.toml")

#: The rig as the engineer believes it is (the starting model).
START_BLOCK = {"teeth_ratio": 3.0, "output_shaft_rotates": "opposite"}
START_RIG = {"follower_inertia": 0.05}
#: What the real gear also has (hidden from the analysis).
HIDDEN_BLOCK = {
    "friction_model": "constant_efficiency",
    "efficiency_const": 0.85,
    "viscous_coefficients": [0.0, 0.4],
}
HIDDEN_RIG: dict = {}

SAMPLES = 8000
DT = 1e-3
SEED = 7


def models():
    import gearsim

    start = gearsim.Model("simple_gear", START_BLOCK, START_RIG)
    truth = start.replace(block_params=HIDDEN_BLOCK, rig_params=HIDDEN_RIG)
    return start, truth


def make():
    """The demo measurement (a gearsim.analysis.Measurement) and the starting model."""
    from gearsim.analysis import synthetic as S

    start, truth = models()
    exc = S.excitation(SAMPLES, DT, max_speed=30.0, max_load=3.0, seed=SEED)
    meas = S.synthesize(truth, exc, S.SensorModel(), seed=SEED + 1, path=CSV)
    return meas, start


def main() -> int:
    from gearsim.analysis import write_measurement

    os.makedirs(DATA, exist_ok=True)
    meas, start = make()
    write_measurement(CSV, meas, digits=7)
    start.save(START)
    print(f"wrote {CSV} ({meas.n} samples, {os.path.getsize(CSV) / 1e3:.0f} kB) and {START}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
