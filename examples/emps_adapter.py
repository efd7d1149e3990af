#!/usr/bin/env python3
"""EMPS (a real ball-screw axis) -> the canonical rack-rig CSV of gearsim.

The EMPS benchmark (A. Janot, M. Gautier, M. Brunot, "Data Set and Reference
Models of EMPS", 2019; data description in ../shared/data/emps/README.md) gives,
on the load side, the motor-encoder position ``qm`` (m), the drive command
``vir`` (V) and the drive gain ``gtau`` (N/V), at 1 kHz. A ball screw turns a
rotation into a translation like a rack and pinion with an unknown radius, so
it maps onto gearsim's rack rig (docs/measurement-format.md section 1):

=================  ==========================================================
``rack_velocity``  d(qm)/dt: qm through a zero-phase 4th-order Butterworth
                   low-pass (``--cutoff``, default 100 Hz, as the benchmark's
                   own identification), then central differences
``pinion_speed``   rack_velocity / r            (r: ``--radius``, assumed)
``pinion_torque``  r * gtau * vir               (drive force times r)
``load_force``     0                            (no external load)
=================  ==========================================================

The assumed radius r cancels in the force balance: the fitted rack mass,
rack viscous coefficient, Coulomb friction and offset are the load-side M, Fv,
Fc and offset of the benchmark's model ``gtau*vir = M*a + Fv*v + Fc*sign(v) +
offset``. gearsim's ``load_offset`` is a force the load applies to the rack, so
it is the benchmark's offset with the opposite sign.

The data stays where it is: this script reads DATA_EMPS.mat and writes a CSV
and a starting model (mass + viscous friction, rough guesses) wherever you ask.

    python examples/emps_adapter.py [--data DATA_EMPS.mat] --out DIR
    gearsim diagnose DIR/emps.csv --model DIR/emps-start.toml
"""

from __future__ import annotations

import argparse
import os
import sys

#: The published reference values (benchmark paper, IDIM-LS, symmetric model).
PUBLISHED = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "offset": -3.1648}

HERE = os.path.dirname(os.path.abspath(__file__))
#: Where DATA_EMPS.mat is looked for: the file this environment variable
#: names, else data/emps/DATA_EMPS.mat in the repository (ignored by git: the
#: data's license is unstated, so gearsim does not distribute it).
DATA_ENV = "GEARSIM_EMPS_DATA"
REPO_DATA_RELATIVE = os.path.join("data", "emps", "DATA_EMPS.mat")
REPO_DATA = os.path.normpath(os.path.join(HERE, "..", REPO_DATA_RELATIVE))
WHERE = f"${DATA_ENV}, else {REPO_DATA_RELATIVE}"


def default_data_path() -> str:
    """The EMPS data's path: $GEARSIM_EMPS_DATA, else the repository's data/emps/."""
    return os.environ.get(DATA_ENV) or REPO_DATA


def load_emps(path: str, radius: float = 0.01, cutoff_hz: float = 100.0):
    """Read DATA_EMPS.mat and return a gearsim rack Measurement (see module doc)."""
    import numpy as np
    import scipy.io
    from scipy.signal import butter, sosfiltfilt

    from gearsim.analysis import Measurement

    d = scipy.io.loadmat(path)
    t = np.asarray(d["t"], dtype=float).ravel()
    qm = np.asarray(d["qm"], dtype=float).ravel()
    vir = np.asarray(d["vir"], dtype=float).ravel()
    gtau = float(np.asarray(d["gtau"]).ravel()[0])
    fs = 1.0 / float(np.median(np.diff(t)))
    sos = butter(4, cutoff_hz, fs=fs, output="sos")
    q_f = sosfiltfilt(sos, qm)
    v = np.gradient(q_f, t)
    force = gtau * vir
    return Measurement.from_arrays(
        "rack_pinion",
        t,
        path=path,
        pinion_speed=v / radius,
        load_force=np.zeros_like(t),
        pinion_torque=radius * force,
        rack_velocity=v,
    )


def starting_model(radius: float = 0.01, mass: float = 80.0, viscous: float = 300.0):
    """Rack model with mass and viscous friction only (rough guesses, as a
    person would start): no Coulomb friction, no offset, no meshing loss."""
    import gearsim

    return gearsim.Model(
        "rack_pinion",
        {"pinion_radius": radius, "rack_viscous_coefficient": viscous},
        {"rack_mass": mass},
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--data", default=None, help=f"path of DATA_EMPS.mat (default: {WHERE})")
    ap.add_argument("--out", required=True, help="directory for emps.csv and emps-start.toml")
    ap.add_argument(
        "--radius", type=float, default=0.01, help="assumed pinion radius in m (default 0.01)"
    )
    ap.add_argument(
        "--cutoff", type=float, default=100.0, help="position low-pass cut-off in Hz (default 100)"
    )
    args = ap.parse_args(argv)
    if args.data is None:
        args.data = default_data_path()
    if not os.path.exists(args.data):
        sys.stderr.write(
            f"emps_adapter: error: {args.data}: no such file (DATA_EMPS.mat is not part of "
            f"this repository: download it from nonlinearbenchmark.org and put it in "
            f"data/emps/ or name it in {DATA_ENV})\n"
        )
        return 2
    from gearsim.analysis import write_measurement

    os.makedirs(args.out, exist_ok=True)
    meas = load_emps(args.data, args.radius, args.cutoff)
    csv = os.path.join(args.out, "emps.csv")
    write_measurement(csv, meas, digits=10)
    model = os.path.join(args.out, "emps-start.toml")
    starting_model(args.radius).save(model)
    print(f"wrote {csv} ({meas.n} samples) and {model}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
