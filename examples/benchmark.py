#!/usr/bin/env python3
"""Timing of the analysis layer on this machine.

Prints the wall time of
- diagnose on a 100 000-sample gear measurement (1 kHz, hidden Coulomb
  friction, realistic sensor noise) - target: under 10 s;
- compare on a 1 000 000-sample measurement - target: under 2 s;
- the CSV load of that 1 000 000-sample file, and the whole `gearsim compare`
  command on it (process start, imports, load, simulate, metrics, JSON).

Usage: python examples/benchmark.py [--keep DIR]
The measurements are synthesized with the C core (gearsim.analysis.synthetic)
into a temporary directory.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--keep", help="write the generated files into this directory and keep them")
    args = ap.parse_args()

    import numpy as np

    import gearsim
    from gearsim.analysis import compare, diagnose, load_measurement, write_measurement
    from gearsim.analysis import synthetic as S

    tmp = args.keep or tempfile.mkdtemp(prefix="gearsim-bench-")
    os.makedirs(tmp, exist_ok=True)
    model = gearsim.Model("simple_gear", {"teeth_ratio": 3.0}, {"follower_inertia": 0.05})
    truth = model.replace(rig_params={"load_coulomb_friction": 1.5})

    exc = S.excitation(100_000, 1e-3, max_speed=30.0, max_load=3.0, seed=11)
    meas = S.synthesize(truth, exc, seed=12)
    t0 = time.perf_counter()
    d = diagnose(model, meas)
    t_diag = time.perf_counter() - t0
    best = d.best
    print(
        f"diagnose, {meas.n} samples: {t_diag:.2f} s (target < 10 s); best effect {best.effect}, "
        f"nrmse {d.baseline_nrmse:.4f} -> {best.nrmse_after:.4f}"
    )

    n = 1_000_000
    exc = S.excitation(n, 1e-3, max_speed=30.0, max_load=3.0, seed=13, temperature=None)
    big = S.synthesize(truth, exc, seed=14)
    t0 = time.perf_counter()
    c = compare(model, big)
    t_cmp = time.perf_counter() - t0
    print(
        f"compare, {big.n} samples (in memory): {t_cmp:.2f} s (target < 2 s); nrmse {c.nrmse:.4f}"
    )

    path = os.path.join(tmp, "big.csv")
    write_measurement(path, big)
    mpath = os.path.join(tmp, "model.toml")
    model.save(mpath)
    t0 = time.perf_counter()
    load_measurement(path, "simple_gear")
    t_load = time.perf_counter() - t0
    print(f"CSV load, {n} rows: {t_load:.2f} s")
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "gearsim.cli", "compare", path, "--model", mpath, "--json"],
        capture_output=True,
        text=True,
    )
    t_cli = time.perf_counter() - t0
    print(
        f"`gearsim compare --json` on the {n}-row CSV, end to end: {t_cli:.2f} s (exit "
        f"{proc.returncode})"
    )
    if not args.keep:
        for f in (path, mpath):
            os.remove(f)
        os.rmdir(tmp)
    del np
    return 0


if __name__ == "__main__":
    sys.exit(main())
