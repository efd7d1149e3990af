"""Cost of `diagnose` on a long record (required: under 3 s on 100 000
samples), on data gearsim did not make: a gear rig with a hidden
Coulomb friction from the independent test generator
(tests/python/analysis/independent: compliant mesh, drive speed loop, encoder
speeds, torque noise and offset).

    .venv/bin/python bench/diagnose_bench.py [--samples 100000] [--effect coulomb_friction]

Prints the seconds of each phase (from diagnose's own progress lines: the time
from one line to the next is the phase the first one announces), diagnose's
notes (which candidates were left to their screening estimate) and the
total. The typical cases: --effect coulomb_friction and --effect backlash on
the gear, --block rack_pinion. Generating the record (pure Python RK4, a few
seconds) is not counted. No time is asserted.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests" / "python" / "analysis"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000, help="record length (1 kHz)")
    parser.add_argument("--block", default="simple_gear", choices=("simple_gear", "rack_pinion"))
    parser.add_argument("--effect", default="coulomb_friction", help="the hidden effect")
    args = parser.parse_args()
    if args.samples < 1000:
        parser.error("--samples must be at least 1000")

    from independent import DT, TRUTHS, gearsim_model, generate

    if args.effect not in TRUTHS[args.block]:
        parser.error(f"--effect must be one of {', '.join(TRUTHS[args.block])}")
    from gearsim.analysis import diagnose

    t0 = time.perf_counter()
    record = generate(args.block, (args.effect,), duration_s=args.samples * DT)
    print(
        f"record: {record.measurement.n} samples of {args.block} with hidden {args.effect} "
        f"(generated in {time.perf_counter() - t0:.1f} s, not counted)"
    )
    marks: list[tuple[float, str]] = []

    def progress(line: str) -> None:
        marks.append((time.perf_counter(), line))

    start = time.perf_counter()
    result = diagnose(gearsim_model(args.block), record.measurement, progress=progress)
    total = time.perf_counter() - start
    ends = [m[0] for m in marks[1:]] + [start + total]
    print("phase seconds (diagnose's own progress lines):")
    if marks and marks[0][0] > start:
        print(f"  {marks[0][0] - start:8.3f}  before the first progress line (input conditioning)")
    for (at, line), end in zip(marks, ends, strict=True):
        print(f"  {end - at:8.3f}  {line}")
    for note in result.notes:  # e.g. the candidates left to their screening estimate
        print(f"  note: {note}")
    best = result.candidates[0].effect if result.candidates else "nothing"
    print(f"total: {total:.2f} s (required < 3 s); ranked first: {best}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
