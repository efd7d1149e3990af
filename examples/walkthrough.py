#!/usr/bin/env python3
"""Model vs measurement, end to end: compare, see where it fails, find the
missing effect, fit it, watch the error fall.

    python examples/walkthrough.py --out report/

1. Loads the bundled demo measurement of a Simple Gear test rig
   (examples/data/demo_gear.csv, made by examples/make_demo_data.py with the C
   core and realistic sensor noise) and the engineer's starting model
   (examples/data/demo_gear_start.toml).
2. compare: the error of the starting model, overall and per operating regime.
3. Rounds of diagnose -> fit: each round ranks the effects the model lacks with
   the evidence from the residual, adds the best one, fits it (re-estimating
   the parameters that trade off against it) and compares again, until no
   effect helps (lowers the error on held-out validation blocks by 2 % and the
   score; docs/analysis.md).
4. Reveals what was hidden in the demo data and sets it beside the fit.
5. Writes report/report.html (self-contained) and the PNG figures.
6. If the real EMPS data is present ($GEARSIM_EMPS_DATA, else
   data/emps/DATA_EMPS.mat; README "Real data"), does
   the same on it (report/emps/) and compares the fitted mass and friction
   with the published values.

Each step prints the equivalent `gearsim` command. Progress goes to stderr.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def _say(msg: str) -> None:
    sys.stderr.write(f"  .. {msg}\n")


def _hr(title: str) -> None:
    print(f"\n=== {title} " + "=" * max(0, 70 - len(title)))


def _fmt_params(p: dict) -> str:
    out = []
    for k, v in p.items():
        if isinstance(v, list):
            out.append(f"{k}=[{', '.join(f'{x:.4g}' for x in v)}]")
        elif isinstance(v, float):
            out.append(f"{k}={v:.4g}")
        else:
            out.append(f"{k}={v}")
    return ", ".join(out)


def _show_rounds(rounds, csv: str, model_path: str) -> None:
    from gearsim.analysis.fitting import REFIT

    for i, r in enumerate(rounds):
        d = r.diagnosis
        if d is None:
            continue
        _hr(f"round {i + 1}: diagnose")
        print(
            f"$ gearsim diagnose {csv} --model {model_path if i == 0 else f'model-round-{i}.toml'}"
        )
        print(
            f"baseline nrmse {d.baseline_nrmse:.4f}; failing regimes: "
            + (
                ", ".join(
                    f"{x['regime']} ({x['worst_ratio']:.1f}x)" for x in d.baseline.failing_regimes
                )
                or "none stands out"
            )
        )
        for k, c in enumerate(d.candidates[:4], 1):
            print(
                f"  {k}. {c.effect:34s} score {c.score:10.1f}  nrmse after "
                f"{c.nrmse_after:.4f}, validation {c.validation_nrmse_after:.4f} "
                f"({'fit' if c.method == 'fit' else 'screening estimate'})"
            )
            if c.evidence.get("text"):
                print(f"     evidence: {c.evidence['text']}")
        for w in d.warnings:
            print(f"  warning: {w['text']}")
        print(d.conclusion)
        if i + 1 < len(rounds):
            f = rounds[i + 1].fit
            _hr(f"round {i + 1}: fit {f.effect}")
            if f.effect != REFIT:
                print(
                    f"$ gearsim fit {csv} --model ... --add {f.effect} "
                    f"--out model-round-{i + 1}.toml"
                )
            print(
                f"nrmse {f.nrmse_before:.4f} -> {f.nrmse_after:.4f}; validation (held-out "
                f"blocks) {f.validation_nrmse_before:.4f} -> {f.validation_nrmse_after:.4f}"
            )
            if f.effect == REFIT:
                print(f"$ gearsim fit {csv} --model ... --refit --out model-round-{i + 1}.toml")
            print(f.verdict)
            for p in f.fitted:
                before = "" if p["before"] is None else f" (was {p['before']:.4g})"
                # no std: the record does not determine it (a warning says why)
                std = "(not identifiable)" if p["std"] is None else f"+- {p['std']:.2g}"
                print(f"  {p['name']:26s} = {p['value']:.5g} {std}{before}  [{p['role']}]")
            for w in f.warnings:
                print(f"  warning: {w['text']}")


def demo(out: str) -> int:
    import make_demo_data as demo_data

    from gearsim import Model
    from gearsim.analysis import load_measurement
    from gearsim.analysis.report import run_rounds, write_report

    csv, start_path = demo_data.CSV, demo_data.START
    if not os.path.exists(csv):
        _say("demo data missing - generating it")
        demo_data.main()
    rel_csv = os.path.relpath(csv)
    rel_model = os.path.relpath(start_path)
    model = Model.load(start_path)
    meas = load_measurement(csv, model.block)
    _hr("the measurement and the starting model")
    print(
        f"{rel_csv}: {meas.n} samples at {1 / meas.dt:.0f} Hz, columns "
        f"{', '.join(['time', *meas.data.keys()])}"
    )
    print(f"{rel_model}: {model.block}, {_fmt_params({**model.block_params, **model.rig_params})}")

    t0 = time.perf_counter()
    rounds = run_rounds(model, meas, rounds=4, progress=_say)
    base = rounds[0].compare
    _hr("compare the starting model")
    print(f"$ gearsim compare {rel_csv} --model {rel_model}")
    for name, m in base.outputs.items():
        print(
            f"  {name:16s} nrmse {m.nrmse:.4f}  (fit {m.fit_percent:.1f} %, max error "
            f"{m.max_abs:.3g} at "
            f"t = {m.t_max_abs:.3g} s)"
        )
    print(f"  overall nrmse {base.nrmse:.4f}")
    _show_rounds(rounds, rel_csv, rel_model)

    _hr("the error fall")
    for i, r in enumerate(rounds):
        print(
            f"  round {i}: {('+ ' + r.effect) if r.effect else 'starting model':34s} nrmse "
            f"{r.compare.nrmse:.4f}"
        )

    _hr("what was hidden in the demo data")
    print("  the real gear has: " + _fmt_params({**demo_data.HIDDEN_BLOCK, **demo_data.HIDDEN_RIG}))
    final = rounds[-1].model
    fb = final.resolved_block_params
    print(
        f"  fitted:            friction_model={fb['friction_model']}, efficiency_const="
        f"{fb['efficiency_const']:.4g}, viscous_coefficients=[{fb['viscous_coefficients'][0]:.4g}, "
        f"{fb['viscous_coefficients'][1]:.4g}]"
    )
    print(
        "  and the sensors: noise, quantized speeds and a torque-sensor offset; a model can only "
        "express that offset as a load_offset"
    )
    found = [r.effect for r in rounds[1:]]
    print(f"  effects found, in order: {', '.join(found)}")

    paths = write_report(
        out, meas, rounds, title="gearsim walkthrough: demo gear rig", progress=_say
    )
    for i, r in enumerate(rounds):
        r.model.save(os.path.join(out, f"model-round-{i}.toml"))
    print(f"\nreport: {paths['html']}  ({time.perf_counter() - t0:.1f} s)")
    return 0


def emps(out: str, data: str) -> int:
    import emps_adapter

    from gearsim.analysis.report import run_rounds, write_report

    _hr("real data: EMPS ball-screw axis (examples/emps_adapter.py)")
    meas = emps_adapter.load_emps(data)
    model = emps_adapter.starting_model()
    print(
        "$ python examples/emps_adapter.py --out emps/ && gearsim report emps/emps.csv "
        "--model emps/emps-start.toml --rounds 3 --out report/emps"
    )
    rounds = run_rounds(model, meas, rounds=3, progress=_say)
    _show_rounds(rounds, "emps.csv", "emps-start.toml")
    final = rounds[-1].model
    rig, blk = final.resolved_rig_params, final.resolved_block_params
    fitted = {
        "M": rig["rack_mass"],
        "Fv": blk["rack_viscous_coefficient"],
        "Fc": rig["load_coulomb_friction"],
        "offset": -rig["load_offset"],
    }
    _hr("EMPS: fitted vs published (Janot, Gautier, Brunot 2019)")
    for k, pub in emps_adapter.PUBLISHED.items():
        print(
            f"  {k:7s} fitted {fitted[k]:10.4f}   published {pub:10.4f}   "
            f"({100 * (fitted[k] / pub - 1):+.1f} %)"
        )
    os.makedirs(os.path.join(out, "emps"), exist_ok=True)
    paths = write_report(
        os.path.join(out, "emps"), meas, rounds, title="gearsim: EMPS real data", progress=_say
    )
    print(f"\nreport: {paths['html']}")
    return 0


def main(argv: list[str] | None = None) -> int:
    import emps_adapter  # beside this script: where the EMPS data is looked for

    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--out", default="report", help="report directory (default: report/)")
    ap.add_argument(
        "--emps",
        default=None,
        help=f"path of DATA_EMPS.mat; skipped when absent (default: {emps_adapter.WHERE})",
    )
    ap.add_argument("--no-emps", action="store_true", help="skip the real-data part")
    args = ap.parse_args(argv)
    if args.emps is None:
        args.emps = emps_adapter.default_data_path()
    os.makedirs(args.out, exist_ok=True)
    rc = demo(args.out)
    if rc == 0 and not args.no_emps:
        if os.path.exists(args.emps):
            rc = emps(args.out, args.emps)
        else:
            print(f"\n(EMPS data not found at {args.emps}: real-data part skipped)")
    return rc


if __name__ == "__main__":
    sys.exit(main())
