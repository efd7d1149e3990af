"""``gearsim compare DATA.csv --model MODEL.toml [--json]``: simulate the model
on the measured inputs and report its error, overall and per regime."""

from __future__ import annotations

import argparse

from ..._outputs import printable
from .common import common_options, emit_json, g4, input_filter, load, progress

NAME = "compare"
HELP = "simulate a model on a measurement and report its error"
#: None of the analysis extra: without pandas the measurement is read with the
#: csv module, and zstandard is asked for only by a .zst file (one line naming
#: the extra).
REQUIRES: tuple[str, ...] = ()


def configure(p: argparse.ArgumentParser) -> None:
    common_options(p)


def execute(args: argparse.Namespace) -> int:
    from ..compare import compare

    say = progress(args)
    filt = input_filter(args.input_filter)
    model, meas = load(args, filt)
    say(f"compare: {meas.n} samples")
    res = compare(model, meas, input_filter=filt)
    if args.json:
        emit_json(res.to_json())
    else:
        _print_compare(res)
    return 0


def _print_compare(res) -> None:
    meas = res.meas
    print(
        f"{printable(meas.path, limit=200)}: {meas.n} samples, dt = {meas.dt:.6g} s; "
        f"model block {meas.block}"
    )
    print(
        f"{'output':16s} {'nrmse':>8s} {'fit %':>7s} {'rmse':>10s} "
        f"{'max |err|':>10s} {'at t (s)':>9s}"
    )
    for name, m in res.outputs.items():
        print(
            f"{name:16s} {m.nrmse:8.4f} {m.fit_percent:7.2f} {m.rmse:10.4g} "
            f"{m.max_abs:10.4g} {m.t_max_abs:9.4g}"
        )
    print(f"{'overall':16s} {res.nrmse:8.4f} {100 * (1 - res.nrmse):7.2f}")
    _print_regimes(res)


def _print_regimes(res) -> None:
    if not res.regimes:
        return
    from ..regimes import FAILING_RATIO

    outs = list(res.outputs)
    floors = ", ".join(
        f"{o} {g4(res.regimes[0]['outputs'][o].get('noise_floor', float('nan')))}" for o in outs
    )
    print(
        "\nerror by regime (rms residual in the regime / std of the output; x = ratio to "
        f"overall; a regime fails at >= {FAILING_RATIO:g}x and >= {FAILING_RATIO:g}x the noise "
        f"floor: {floors}):"
    )
    print(f"{'regime':20s} {'share':>6s} " + " ".join(f"{o:>22s}" for o in outs))
    for r in res.regimes:
        cells = []
        for o in outs:
            e = r["outputs"][o]
            cells.append(f"{g4(e['nrmse']):>10s} ({g4(e['ratio']):>5s}x)   ")
        flag = f"  <- fails (>= {FAILING_RATIO:g}x)" if r["failing"] else ""
        print(f"{r['regime']:20s} {100 * r['fraction']:5.1f}% " + " ".join(cells) + flag)
