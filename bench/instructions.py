#!/usr/bin/env python3
"""Instructions per step of every benchmark configuration, with callgrind.

For each configuration and mode (``step``: one gs_rig_step call at a time,
``run``: gs_rig_run over the input table), runs

    valgrind --tool=callgrind gearsim_bench --count CONFIG MODE N

once with N steps and once with 0 steps (set-up only), reads the total ``Ir``
(instructions executed) from each output file's ``totals:`` line, and reports
(Ir(N) - Ir(0)) / N. The figure includes the benchmark loop around the step
(input indexing and one addition, about 5 instructions). Instruction counts
are repeatable to the instruction on a noisy machine, unlike wall-clock time.

Usage: instructions.py BENCH_BINARY [--steps N] [--config NAME]... [--json FILE]
Standard library only.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


def total_ir(out_file: Path) -> int:
    """The ``totals:`` (or ``summary:``) figure of a callgrind output file."""
    summary = None
    for line in out_file.read_text().splitlines():
        if line.startswith("totals:"):
            return int(line.split()[1])
        if line.startswith("summary:"):
            summary = int(line.split()[1])
    if summary is None:
        raise RuntimeError(f"no totals in {out_file}")
    return summary


def callgrind_ir(binary: str, config: str, mode: str, steps: int, workdir: Path) -> int:
    out = workdir / f"callgrind.{config}.{mode}.{steps}"
    cmd = [
        "valgrind",
        "--tool=callgrind",
        f"--callgrind-out-file={out}",
        binary,
        "--count",
        config,
        mode,
        str(steps),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr[-2000:]}")
    return total_ir(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("binary")
    ap.add_argument(
        "--steps",
        type=int,
        default=8000,
        help="steps per counted run (default 8000 = two input periods)",
    )
    ap.add_argument("--config", action="append", default=[])
    ap.add_argument("--modes", default="step,run")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        print("instructions.py: valgrind not found; skipping instruction counts", file=sys.stderr)
        if args.json:
            args.json.write_text(json.dumps({"available": False, "results": []}, indent=2) + "\n")
        return 0
    configs = (
        args.config
        or subprocess.run(
            [args.binary, "--list"], check=True, text=True, stdout=subprocess.PIPE
        ).stdout.split()
    )
    modes = [m for m in args.modes.split(",") if m]
    results = []
    with tempfile.TemporaryDirectory(prefix="gearsim-callgrind-") as tmp:
        work = Path(tmp)
        print(
            f"{'configuration':26s} {'mode':5s} {'instr/step':>10s}   "
            f"(callgrind Ir, {args.steps} steps minus 0)"
        )
        for config in configs:
            base = callgrind_ir(args.binary, config, "step", 0, work)
            for mode in modes:
                total = callgrind_ir(args.binary, config, mode, args.steps, work)
                per_step = (total - base) / args.steps
                results.append(
                    {
                        "config": config,
                        "mode": mode,
                        "steps": args.steps,
                        "ir_total": total,
                        "ir_setup": base,
                        "ir_per_step": per_step,
                    }
                )
                print(f"{config:26s} {mode:5s} {per_step:10.1f}", flush=True)
    if args.json:
        args.json.write_text(
            json.dumps({"available": True, "steps": args.steps, "results": results}, indent=2)
            + "\n"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
