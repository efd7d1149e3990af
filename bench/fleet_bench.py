#!/usr/bin/env python3
"""Fleet throughput on this machine: units per second with 1 and 2 local
workers, the per-task overhead of Dask, and the peak memory of a run of
--units logs (default 1000). Prints figures; asserts nothing.

The logs are the bundled fleet's kind (examples/make_fleet_data.py: a gear
through a 3 s test cycle, gearsim's C core, sensor noise), written as plain
CSV into a temporary folder; every unit fits coulomb_friction,
meshing_efficiency and load_offset, as scripts/fleet_demo.sh does.

- units/s: units / wall time of gearsim.fleet.run_fleet with --no-report,
  cluster start-up included (reported apart: the time to the first task);
- per-unit cost: the median of the rows' `seconds` and `cpu_seconds` (the
  analysis alone, on the worker: wall and CPU time; the CPU time moves less
  with other jobs on the machine);
- per-task overhead: (wall x workers - sum of the rows' seconds) / units,
  i.e. what one task costs beyond its analysis (scheduling, transfer, the
  client's cache and Parquet writes, start-up spread over the run), and the
  round trip of an empty task (1000 no-op submits);
- peak memory: the client's peak RSS (ru_maxrss of this process) and the
  largest worker's (ru_maxrss of the children once the cluster is closed).

    .venv/bin/python bench/fleet_bench.py [--units N] [--workers 1,2] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "examples"))

EFFECTS = ("coulomb_friction", "meshing_efficiency", "load_offset")


def write_logs(folder: str, n: int) -> str:
    import make_fleet_data as F
    import numpy as np

    from gearsim.analysis import synthetic as S
    from gearsim.analysis import write_measurement

    rng = np.random.default_rng(7)
    exc = S.excitation(
        F.SAMPLES, F.DT, max_speed=30.0, max_load=3.0, seed=F.CYCLE_SEED, temperature=None
    )
    for i in range(n):
        truth, sensors = F.unit_truth(i % F.UNITS, rng)
        meas = S.synthesize(truth, exc, sensors, seed=10_000 + i)
        write_measurement(os.path.join(folder, f"u{i:05d}.csv"), meas, digits=6)
    model = os.path.join(folder, "..", "start.toml")
    F.start_model().save(model)
    return model


def empty_task_round_trip(workers: int, count: int = 1000) -> float:
    """Seconds per no-op task, submitted all at once and gathered."""
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
        silence_logs=logging.CRITICAL,
    ) as cl:
        with Client(cl) as client:
            client.gather(client.map(int, range(50)))  # warm
            t0 = time.perf_counter()
            client.gather(client.map(int, range(count), pure=False))
            return (time.perf_counter() - t0) / count


def one_run(logs: str, model: str, out: str, workers: int) -> dict:
    import pyarrow.parquet as pq

    from gearsim.fleet import FleetOptions, run_fleet

    first = []
    t0 = time.perf_counter()
    res = run_fleet(
        logs,
        model=model,
        out=out,
        options=FleetOptions(effects=EFFECTS),
        workers=workers,
        report=False,
        progress=lambda s: first.append(time.perf_counter() - t0) if "to analyse" in s else None,
    )
    wall = time.perf_counter() - t0
    tab = pq.read_table(res.parquet, columns=["seconds", "cpu_seconds"])
    secs = tab.column(0).to_pylist()
    cpu = tab.column(1).to_pylist()
    n = res.counts["units"]
    return {
        "workers": workers,
        "units": n,
        "ok": res.counts["ok"],
        "wall_s": wall,
        "startup_s": first[0] if first else float("nan"),
        "units_per_s": n / wall,
        "unit_cost_median_s": statistics.median(secs),
        "unit_cpu_median_s": statistics.median(cpu),
        "overhead_per_task_s": (wall * workers - sum(secs)) / n,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--units", type=int, default=1000)
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    counts = [int(w) for w in args.workers.split(",")]
    out = {"units": args.units, "cpus": os.cpu_count(), "runs": []}
    with tempfile.TemporaryDirectory(prefix="fleet-bench-") as tmp:
        logs = os.path.join(tmp, "logs")
        os.makedirs(logs)
        t0 = time.perf_counter()
        model = write_logs(logs, args.units)
        print(
            f"fleet bench: wrote {args.units} logs in {time.perf_counter() - t0:.1f} s", flush=True
        )
        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        for w in counts:
            r = one_run(logs, model, os.path.join(tmp, f"out{w}"), w)
            out["runs"].append(r)
            print(
                f"fleet bench: {w} worker(s): {r['units']} units in {r['wall_s']:.1f} s = "
                f"{r['units_per_s']:.2f} units/s (start-up {r['startup_s']:.1f} s); per unit "
                f"{r['unit_cost_median_s'] * 1e3:.0f} ms of analysis (median; CPU "
                f"{r['unit_cpu_median_s'] * 1e3:.0f} ms), overhead "
                f"{r['overhead_per_task_s'] * 1e3:.0f} ms per task",
                flush=True,
            )
        out["client_peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        out["client_rss_before_runs_mb"] = rss0 / 1024
        out["worker_peak_rss_mb"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        out["empty_task_s"] = empty_task_round_trip(max(counts))
    print(
        f"fleet bench: peak memory: client {out['client_peak_rss_mb']:.0f} MB (before the runs "
        f"{out['client_rss_before_runs_mb']:.0f} MB), largest worker "
        f"{out['worker_peak_rss_mb']:.0f} MB; "
        f"an empty task: {out['empty_task_s'] * 1e3:.2f} ms"
    )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
