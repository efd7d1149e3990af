#!/usr/bin/env python3
"""Python-side benchmarks of gearsim, and the alternatives a user would write.

Measures, on the input of bench/alternatives.py (the same tones as the C
benchmark):

- batch: Rig.run on 1e6 samples (numpy in, RigResult out) and the low-level
  Rig.run_array into a preallocated output, for a few rigs; median of several
  repeats after a warm-up, in steps per second;
- per step: Rig.step, median of the mean call time over blocks of calls;
- the alternatives (bench/alternatives.py): the rigid rig stepped in a
  Python loop and as vectorised numpy, the full Simple Gear rig (sg_full)
  stepped in a Python loop, and the backlash rig as an ODE for
  scipy.integrate.solve_ivp; their results are compared with gearsim's (max
  abs difference of the base torque and the follower speed, RMS difference
  of the follower speed for the ODE) so that the ratios compare like with
  like.

Prints a summary and writes every figure to --json. Never asserts a time.
Usage: python_bench.py [--json FILE] [--quick]
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import alternatives as alt  # noqa: E402

P = alt.GEAR_PARAMS

# The comparison rig (= C configuration sg_constant_viscous).
RIGID_BLOCK = {
    "teeth_ratio": P["teeth_ratio"],
    "output_shaft_rotates": "opposite",
    "friction_model": "constant_efficiency",
    "efficiency_const": P["efficiency"],
    "power_threshold": P["power_threshold"],
    "viscous_coefficients": [P["mu_base"], P["mu_follower"]],
}
BACKLASH_BLOCK = {
    **RIGID_BLOCK,
    "backlash_enabled": True,
    "hard_stop_model": "smooth",
    "linear_backlash": P["linear_backlash"],
    "base_radius": P["base_radius"],
    "transition_region": P["transition_region"],
    "stiffness": P["stiffness"],
    "damping": P["damping"],
}
# The full Simple Gear rig (= C configuration sg_full), from the numbers of
# the Python alternative (alternatives.FULL_PARAMS).
FULL_BLOCK, FULL_RIG = alt.full_gearsim_params()
RIG = {"follower_inertia": P["follower_inertia"]}


def median_time(fn: Callable[[], Any], repeats: int, warmup: int = 1) -> dict[str, float]:
    """Median/min/max wall time (s) of fn() over repeats, after warm-up calls, and
    the median thread CPU time (s): the two apart mean the machine was busy."""
    for _ in range(warmup):
        fn()
    times = []
    cpu = []
    for _ in range(repeats):
        gc.collect()
        c0 = time.thread_time()
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.thread_time() - c0)
    return {
        "median": statistics.median(times),
        "min": min(times),
        "max": max(times),
        "cpu_median": statistics.median(cpu),
    }


def make_rig(gearsim: Any, block: dict, rig: dict) -> Any:
    return gearsim.Model(block="simple_gear", block_params=block, rig_params=rig).rig(dt=P["dt"])


def time_rig_run(rig: Any, w: np.ndarray, load: np.ndarray, repeats: int) -> dict[str, float]:
    """median_time of Rig.run on (w, load) from the initial state."""

    def run() -> None:
        rig.reset()
        rig.run(base_speed=w, load=load)

    return median_time(run, repeats)


def alternative_row(
    t: dict[str, float], n: int, torque: Any, ref: np.ndarray, scale: float
) -> dict:
    """Time per step of an alternative of the rigid rig over its first n samples
    and its base torque against gearsim's (ref)."""
    return {
        "samples": n,
        "ns_per_step": t["median"] / n * 1e9,
        "cpu_ns_per_step": t["cpu_median"] / n * 1e9,
        "max_abs_diff_base_torque_Nm": float(np.max(np.abs(np.asarray(torque) - ref[:n]))),
        "max_abs_base_torque_Nm": scale,
    }


def bench_batch(gearsim: Any, n: int, repeats: int) -> list[dict]:
    w, load = alt.scenario(n)
    rows = []
    for name, block, rig_params in (
        ("sg_constant_viscous", RIGID_BLOCK, RIG),
        ("sg_full", FULL_BLOCK, FULL_RIG),
    ):
        rig = make_rig(gearsim, block, rig_params)
        cold_rig = make_rig(gearsim, block, rig_params)
        t0 = time.perf_counter()
        cold_rig.run(base_speed=w, load=load)
        cold = time.perf_counter() - t0
        t = time_rig_run(rig, w, load, repeats)
        inputs = rig.inputs(base_speed=w, load=load)
        out = np.empty((n, 15))

        def run_array(rig: Any = rig, inputs: np.ndarray = inputs, out: np.ndarray = out) -> None:
            rig.reset()
            rig.run_array(inputs, out)

        ta = median_time(run_array, repeats)
        rows.append(
            {
                "config": name,
                "samples": n,
                "repeats": repeats,
                "run_ns_per_step": t["median"] / n * 1e9,
                "run_ns_per_step_min": t["min"] / n * 1e9,
                "run_ns_per_step_max": t["max"] / n * 1e9,
                "run_steps_per_s": n / t["median"],
                "run_cpu_ns_per_step": t["cpu_median"] / n * 1e9,
                "run_first_call_ns_per_step": cold / n * 1e9,
                "run_array_ns_per_step": ta["median"] / n * 1e9,
                "run_array_steps_per_s": n / ta["median"],
            }
        )
    return rows


def bench_step(gearsim: Any, blocks: int, calls: int) -> dict:
    rig = make_rig(gearsim, RIGID_BLOCK, RIG)
    w, load = alt.scenario(calls)
    ws = w.tolist()
    loads = load.tolist()
    step = rig.step

    def block() -> None:
        for i in range(calls):
            step(base_speed=ws[i], load=loads[i])

    block()  # warm-up
    means = []
    cpu = []
    for _ in range(blocks):
        c0 = time.thread_time()
        t0 = time.perf_counter()
        block()
        means.append((time.perf_counter() - t0) / calls)
        cpu.append((time.thread_time() - c0) / calls)
    means.sort()
    return {
        "config": "sg_constant_viscous",
        "calls": blocks * calls,
        "block": calls,
        "median_us": statistics.median(means) * 1e6,
        "min_us": means[0] * 1e6,
        "max_us": means[-1] * 1e6,
        "cpu_median_us": statistics.median(cpu) * 1e6,
        "q1_us": means[len(means) // 4] * 1e6,
        "q3_us": means[(3 * len(means)) // 4] * 1e6,
    }


def bench_alternatives(gearsim: Any, n_loop: int, gs_row: dict, repeats: int) -> dict:
    """The rigid rig's alternatives against Rig.run on sg_constant_viscous,
    whose time is bench_batch's (gs_row): the same run, not timed twice."""
    n_vec = gs_row["samples"]
    res: dict[str, Any] = {
        "gearsim_run_ns_per_step": gs_row["run_ns_per_step"],
        "gearsim_run_cpu_ns_per_step": gs_row["run_cpu_ns_per_step"],
    }
    # gearsim reference on the same inputs
    w, load = alt.scenario(n_vec)
    ref = make_rig(gearsim, RIGID_BLOCK, RIG).run(base_speed=w, load=load).base_torque
    scale = float(np.max(np.abs(ref)))

    # numpy, vectorised
    vec = alt.numpy_vectorised(w, load)
    t_vec = median_time(lambda: alt.numpy_vectorised(w, load), repeats)
    res["numpy_vectorised"] = alternative_row(t_vec, n_vec, vec, ref, scale)

    # Python loop, one step per sample
    wl, ll = w[:n_loop], load[:n_loop]
    loop = alt.python_loop(wl, ll)
    t_loop = median_time(lambda: alt.python_loop(wl, ll), max(3, repeats // 2), warmup=0)
    res["python_loop"] = alternative_row(t_loop, n_loop, loop, ref, scale)
    # the same loop over numpy arrays and numpy scalar functions (slower still)
    n_np = max(1000, n_loop // 10)
    wn, ln = w[:n_np], load[:n_np]
    loop_np = alt.python_loop_numpy(wn, ln)
    t_np = median_time(lambda: alt.python_loop_numpy(wn, ln), 3, warmup=0)
    res["python_loop_numpy"] = alternative_row(t_np, n_np, loop_np, ref, scale)
    return res


def bench_full_loop(gearsim: Any, n_loop: int, gs_row: dict, repeats: int) -> dict:
    """The full rig (sg_full) in a Python loop against gearsim's Rig.run on it,
    whose time is bench_batch's (gs_row): the same run, not timed twice."""
    # = the first n_loop samples of the batch's input (scenario is elementwise in t)
    wl, ll = alt.scenario(n_loop)
    rig = make_rig(gearsim, FULL_BLOCK, FULL_RIG)
    ref = rig.run(base_speed=wl, load=ll)
    loop = alt.python_loop_full(wl, ll)  # also the warm-up of the timing
    t_loop = median_time(lambda: alt.python_loop_full(wl, ll), max(3, repeats // 2), warmup=0)
    tau = np.asarray(loop["base_torque"])
    w_f = np.asarray(loop["follower_speed"])
    tau_peak = float(np.max(np.abs(ref.base_torque)))
    w_f_peak = float(np.max(np.abs(ref.follower_speed)))
    tau_diff = float(np.max(np.abs(tau - ref.base_torque)))
    w_f_diff = float(np.max(np.abs(w_f - ref.follower_speed)))
    return {
        "config": "sg_full",
        "samples": n_loop,
        "substeps": loop["substeps"],
        "gearsim_substeps": rig.substeps,
        "ns_per_step": t_loop["median"] / n_loop * 1e9,
        "cpu_ns_per_step": t_loop["cpu_median"] / n_loop * 1e9,
        "gearsim_samples": gs_row["samples"],
        "gearsim_run_ns_per_step": gs_row["run_ns_per_step"],
        "gearsim_run_cpu_ns_per_step": gs_row["run_cpu_ns_per_step"],
        "max_abs_diff_base_torque_Nm": tau_diff,
        "max_abs_base_torque_Nm": tau_peak,
        "rel_diff_base_torque": tau_diff / tau_peak,
        "max_abs_diff_driven_speed_rad_s": w_f_diff,
        "max_abs_driven_speed_rad_s": w_f_peak,
        "rel_diff_driven_speed": w_f_diff / w_f_peak,
    }


def bench_ode(gearsim: Any, n: int, repeats: int) -> dict:
    try:
        import scipy
    except ImportError:
        return {"available": False, "reason": "scipy is not installed"}
    w, load = alt.scenario(n)
    rig = make_rig(gearsim, BACKLASH_BLOCK, RIG)
    ref = rig.run(base_speed=w, load=load)
    # a short run is dominated by fixed Python costs: time a 100x longer one per step too
    t_gs = time_rig_run(rig, w, load, repeats)
    w_long, load_long = alt.scenario(100 * n)
    t_gs_long = time_rig_run(rig, w_long, load_long, max(3, repeats // 2))
    out: dict[str, Any] = {
        "available": True,
        "scipy": scipy.__version__,
        "samples": n,
        "substeps": rig.substeps,
        "gearsim_run_ns_per_step": t_gs["median"] / n * 1e9,
        "gearsim_run_long_ns_per_step": t_gs_long["median"] / (100 * n) * 1e9,
        "gearsim_run_long_cpu_ns_per_step": t_gs_long["cpu_median"] / (100 * n) * 1e9,
        "methods": [],
    }
    rms_ref = float(np.sqrt(np.mean(ref.follower_speed**2)))
    for method in ("RK45", "LSODA"):
        c0 = time.thread_time()
        t0 = time.perf_counter()
        sol = alt.backlash_ode(w, load, method=method)
        dt = time.perf_counter() - t0
        dc = time.thread_time() - c0
        diff = sol["follower_speed"] - ref.follower_speed
        out["methods"].append(
            {
                "method": method,
                "status": sol["status"],
                "nfev": sol["nfev"],
                "ns_per_step": dt / n * 1e9,
                "cpu_ns_per_step": dc / n * 1e9,
                "rms_diff_driven_speed_rel": float(np.sqrt(np.mean(diff**2))) / rms_ref,
                "max_abs_diff_driven_speed_rad_s": float(np.max(np.abs(diff))),
            }
        )
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path)
    ap.add_argument("--quick", action="store_true", help="fewer repeats (a smoke run)")
    args = ap.parse_args()
    try:
        import gearsim

        gearsim.Model  # noqa: B018
    except Exception as exc:  # the package may not be built yet
        print(f"python_bench.py: gearsim is not importable ({exc}); skipping", file=sys.stderr)
        if args.json:
            args.json.write_text(json.dumps({"available": False, "reason": str(exc)}) + "\n")
        return 0
    quick = args.quick
    repeats = 3 if quick else 7
    res: dict[str, Any] = {
        "available": True,
        "python": sys.version.split()[0],
        "numpy": np.__version__,
    }
    res["batch"] = bench_batch(gearsim, 100_000 if quick else 1_000_000, repeats)
    batch = {row["config"]: row for row in res["batch"]}
    for row in res["batch"]:
        print(
            f"Rig.run {row['config']:20s} {row['samples']:.0e} samples: "
            f"{row['run_ns_per_step']:7.1f} ns/step = "
            f"{row['run_steps_per_s'] / 1e6:6.2f} M steps/s "
            f"(cpu {row['run_cpu_ns_per_step']:.1f}) "
            f"(first call {row['run_first_call_ns_per_step']:.1f} ns/step; "
            f"run_array {row['run_array_steps_per_s'] / 1e6:.2f} M steps/s)"
        )
    res["step"] = bench_step(gearsim, 30 if quick else 100, 1000)
    s = res["step"]
    print(
        f"Rig.step {s['config']}: median {s['median_us']:.2f} us per call "
        f"[{s['min_us']:.2f}..{s['max_us']:.2f}] over {s['calls']} calls "
        f"(cpu {s['cpu_median_us']:.2f})"
    )
    res["alternatives"] = bench_alternatives(
        gearsim, 20_000 if quick else 200_000, batch["sg_constant_viscous"], repeats
    )
    a = res["alternatives"]
    for key in ("python_loop", "python_loop_numpy", "numpy_vectorised"):
        r = a[key]
        print(
            f"{key:17s}: {r['ns_per_step']:8.1f} ns/step, "
            f"{r['ns_per_step'] / a['gearsim_run_ns_per_step']:6.1f}x gearsim Rig.run; "
            f"max |diff| base torque {r['max_abs_diff_base_torque_Nm']:.2e} N*m "
            f"(of {r['max_abs_base_torque_Nm']:.2f})"
        )
    a["python_loop_full"] = bench_full_loop(
        gearsim, 4000 if quick else 20_000, batch["sg_full"], repeats
    )
    r = a["python_loop_full"]
    print(
        f"python_loop_full : {r['ns_per_step']:8.1f} ns/step, "
        f"{r['ns_per_step'] / r['gearsim_run_ns_per_step']:6.1f}x gearsim Rig.run sg_full "
        f"({r['gearsim_run_ns_per_step']:.1f} ns/step; "
        f"{r['cpu_ns_per_step'] / r['gearsim_run_cpu_ns_per_step']:.1f}x on CPU time); "
        f"max |diff| base torque {r['rel_diff_base_torque']:.1e} of its peak "
        f"{r['max_abs_base_torque_Nm']:.2f} N*m, follower speed "
        f"{r['rel_diff_driven_speed']:.1e} of {r['max_abs_driven_speed_rad_s']:.2f} rad/s"
    )
    res["ode"] = bench_ode(gearsim, 500 if quick else 2000, 3 if quick else 5)
    o = res["ode"]
    if o.get("available"):
        for m in o["methods"]:
            print(
                f"solve_ivp {m['method']:5s}: {m['ns_per_step'] / 1e3:8.1f} us/step, "
                f"{m['ns_per_step'] / o['gearsim_run_long_ns_per_step']:8.0f}x gearsim Rig.run "
                f"(backlash, {o['substeps']} sub-steps); follower speed RMS diff "
                f"{m['rms_diff_driven_speed_rel']:.2%}, "
                f"max {m['max_abs_diff_driven_speed_rad_s']:.3f} rad/s"
            )
    else:
        print(f"solve_ivp: skipped ({o.get('reason')})")
    if args.json:
        args.json.write_text(json.dumps(res, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
