#!/usr/bin/env python3
"""Collects the benchmark results into one table and checks the targets.

Reads the JSON files written by gearsim_bench (--json), instructions.py,
m4_bench.py and python_bench.py from a results directory, prints the figures
and the target check, and writes them as Markdown (results.md in the same
directory). With --update-docs FILE it also replaces the part of FILE between
the markers ``<!-- bench:results:begin -->`` and ``<!-- bench:results:end -->``
(docs/performance.md).

The targets are reported as met or missed; nothing here fails on a time.
Standard library only.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

BEGIN = "<!-- bench:results:begin -->"
END = "<!-- bench:results:end -->"

DESCRIPTIONS = {
    "sg_ideal": "Simple Gear, ideal (no losses)",
    "sg_constant": "Simple Gear, constant efficiency",
    "sg_load": "Simple Gear, load-dependent efficiency",
    "sg_temp": "Simple Gear, temperature table + thermal",
    "sg_temp_load": "Simple Gear, temperature x load table + thermal",
    "sg_backlash_smooth": "Simple Gear, backlash, smooth hard stop",
    "sg_backlash_full_undamped": "Simple Gear, backlash, full, undamped rebound",
    "sg_backlash_full_damped": "Simple Gear, backlash, full, damped rebound",
    "sg_full": "**Full Simple Gear rig** (backlash + T x load table + heat path + viscous)",
    "sg_constant_viscous": "Simple Gear, constant efficiency + viscous (Python comparison rig)",
    "sg_stribeck": "Simple Gear, constant efficiency + Stribeck friction",
    "sg_backlash_stribeck": "Simple Gear, backlash + Stribeck friction",
    "sg_compliance": "Simple Gear, constant efficiency + compliant base shaft",
    "sg_ripple": "Simple Gear, constant efficiency + torque ripple",
    "rp_constant_radius": "Rack & Pinion, constant efficiency, radius",
    "rp_constant_teeth": "Rack & Pinion, constant efficiency, tooth parameters",
    "rp_temp_radius": "Rack & Pinion, temperature table, radius",
    "rp_temp_teeth": "Rack & Pinion, temperature table, tooth parameters",
    "rp_backlash_radius": "Rack & Pinion, backlash + constant efficiency, radius",
    "rp_backlash_teeth": "Rack & Pinion, backlash + constant efficiency, tooth parameters",
}


def load(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def machine() -> str:
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        cc = subprocess.run(
            ["cc", "--version"], text=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL
        ).stdout.splitlines()[0]
    except (OSError, IndexError):
        cc = "?"
    import os

    load_avg = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (
        f"{platform.machine()} {cpu}, {os.cpu_count()} cores, {platform.system()} "
        f"{platform.release()}; {cc}; load average {load_avg:.1f} when the report was written"
    )


def ratio(x: float) -> str:
    """A speed ratio, with a decimal below 10."""
    return f"{x:.1f}x" if x < 10 else f"{x:.0f}x"


def verdict(value: float, cpu_value: float, ok: Any) -> str:
    """'met', 'met on CPU time only' or 'missed' for a figure and its CPU-time twin."""
    if ok(value):
        return "met"
    return "met on CPU time only" if ok(cpu_value) else "missed"


C_INTRO = (
    "Wall-clock ns per step: median [min..max] and interquartile range over the runs; "
    "steps/s from the median; *cpu* is the median thread CPU time per step (lower than "
    "wall when other processes took the core). *instr* is callgrind's Ir per step "
    "(x86-64), *M4 instr* the instructions per step of the float build on a "
    "Cortex-M4F (QEMU). *step* is one gs_rig_step call at a time, *run* is gs_rig_run "
    "over 4000-sample arrays."
)
C_HEADER = (
    "| configuration | sub-steps | mode | median ns | [min..max] | IQR | steps/s "
    "| cpu ns | instr | M4 instr |"
)


def c_section(c: dict, timing: dict, counts: dict, m4_counts: dict) -> list[str]:
    md = [
        f"### C core (double, Release -O3), {c['runs']} runs x {c['steps_per_run']} steps, "
        "dt = 1 ms",
        "",
        C_INTRO,
        "",
        C_HEADER,
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    configs = list(dict.fromkeys(r["config"] for r in c["results"]))
    for cfg in configs:
        for mode in ("step", "run"):
            r = timing.get((cfg, mode))
            if not r:
                continue
            ins = counts.get((cfg, mode))
            m4i = m4_counts.get(cfg) if mode == "step" else None
            ins_s = "" if ins is None else f"{ins:.0f}"
            m4_s = "" if m4i is None else f"{m4i:.0f}"
            md.append(
                f"| {DESCRIPTIONS.get(cfg, cfg)} (`{cfg}`) | {r['substeps']} | {mode} | "
                f"{r['median_ns']:.1f} | [{r['min_ns']:.1f}..{r['max_ns']:.1f}] | "
                f"{r['q1_ns']:.1f}..{r['q3_ns']:.1f} | {r['steps_per_s']:.3g} | "
                f"{r['cpu_median_ns']:.1f} | {ins_s} | {m4_s} |"
            )
    md.append("")
    return md


def m4_section(m4: dict | None) -> list[str]:
    if not (m4 and m4.get("available")):
        return ["Cortex-M4F: not measured (arm-none-eabi-gcc not found).", ""]
    md = [
        f"### Cortex-M4F float build (`{m4['flags']}`)",
        "",
        "Object sizes (bytes, arm-none-eabi-size):",
        "",
        "| object | text | data | bss |",
        "|---|---|---|---|",
    ]
    for name, s in m4["objects"].items():
        md.append(f"| {name} | {s['text']} | {s['data']} | {s['bss']} |")
    t = m4["objects_total"]
    md += [
        f"| total | {t['text']} | {t['data']} | {t['bss']} |",
        "",
        "What each model adds to an empty image when linked with `--gc-sections` "
        "(bss includes the program's own model objects). Friction and hard-stop models "
        "are selected at run time, so a block's image holds all of its models:",
        "",
        "| image | text | data | bss |",
        "|---|---|---|---|",
    ]
    for name, s in m4["linked"].items():
        md.append(f"| {name} | {s['text']} | {s['data']} | {s['bss']} |")
    md.append("")
    q = m4.get("qemu")
    if not q:
        return md + ["Instructions per step on the M4: not measured (no qemu-system-arm).", ""]
    md += [
        f"Instructions per step on QEMU {q['machine']} (Cortex-M4F, `-icount shift=0`, "
        f"SysTick resolution {q['resolution_per_step']:.3f} instructions per step); "
        "instructions, not cycles — QEMU does not model the M4 pipeline:",
        "",
        "| configuration | M4 instr/step |",
        "|---|---|",
    ]
    for r in q["results"]:
        md.append(f"| `{r['config']}` | {r['instructions_per_step']:.0f} |")
    md.append("")
    return md


ALTERNATIVES = (
    ("python_loop", "Python loop (floats, `math`), same rig"),
    ("python_loop_numpy", "Python loop over numpy arrays (`np.tanh`), same rig"),
    ("numpy_vectorised", "numpy, vectorised, same rig"),
)


def python_section(py: dict, c_step: dict | None, c_full: dict | None) -> list[str]:
    md = [
        f"### Python (Python {py['python']}, numpy {py['numpy']})",
        "",
        "| what | samples | median ns/step | steps/s | cpu ns/step | note |",
        "|---|---|---|---|---|---|",
    ]
    for r in py["batch"]:
        spread = f"[{r['run_ns_per_step_min']:.1f}..{r['run_ns_per_step_max']:.1f}]"
        first = f"first call {r['run_first_call_ns_per_step']:.1f}"
        md.append(
            f"| `Rig.run` `{r['config']}` | {r['samples']:.0e} | "
            f"{r['run_ns_per_step']:.1f} | {r['run_steps_per_s']:.3g} | "
            f"{r['run_cpu_ns_per_step']:.1f} | {spread}; {first} "
            "(page faults of the fresh output arrays) |"
        )
        array_rate = r["run_array_steps_per_s"]
        md.append(
            f"| `Rig.run_array` `{r['config']}` (preallocated out) | {r['samples']:.0e} | "
            f"{1e9 / array_rate:.1f} | {array_rate:.3g} | | |"
        )
    s = py["step"]
    md.append(
        f"| `Rig.step` `{s['config']}` | {s['calls']} calls | {s['median_us'] * 1e3:.0f} | "
        f"{1e6 / s['median_us']:.3g} | {s['cpu_median_us'] * 1e3:.0f} | median of the mean "
        f"over blocks of {s['block']} calls, [{s['min_us']:.2f}..{s['max_us']:.2f}] us |"
    )
    a = py["alternatives"]
    gs = a["gearsim_run_ns_per_step"]
    gs_cpu = a.get("gearsim_run_cpu_ns_per_step")
    for key, label in ALTERNATIVES:
        r = a.get(key)
        if not r:
            continue
        note = f"{ratio(r['ns_per_step'] / gs)} gearsim `Rig.run` ({gs:.1f} ns/step)"
        if gs_cpu:
            note += f" ({ratio(r['cpu_ns_per_step'] / gs_cpu)} on CPU time)"
        if c_step:
            note += f", {ratio(r['ns_per_step'] / c_step['median_ns'])} C `gs_rig_step`"
        note += (
            f"; max abs diff of base torque {r['max_abs_diff_base_torque_Nm']:.1e} N*m "
            f"(peak {r['max_abs_base_torque_Nm']:.2f})"
        )
        md.append(
            f"| {label} | {r['samples']:.0e} | {r['ns_per_step']:.1f} | "
            f"{1e9 / r['ns_per_step']:.3g} | {r['cpu_ns_per_step']:.1f} | {note} |"
        )
    r = a.get("python_loop_full")
    if r:
        gs_full = r["gearsim_run_ns_per_step"]
        note = (
            f"{ratio(r['ns_per_step'] / gs_full)} gearsim `Rig.run` on `sg_full` "
            f"({gs_full:.1f} ns/step) "
            f"({ratio(r['cpu_ns_per_step'] / r['gearsim_run_cpu_ns_per_step'])} on CPU time)"
        )
        if c_full:
            note += f", {ratio(r['ns_per_step'] / c_full['median_ns'])} C `gs_rig_step`"
        note += (
            f"; {r['substeps']} sub-steps; max abs diff of base torque "
            f"{r['max_abs_diff_base_torque_Nm']:.1e} N*m (peak {r['max_abs_base_torque_Nm']:.2f}), "
            f"of follower speed {r['max_abs_diff_driven_speed_rad_s']:.1e} rad/s "
            f"(peak {r['max_abs_driven_speed_rad_s']:.2f})"
        )
        md.append(
            "| Python loop (floats, `math`), full Simple Gear rig (`sg_full`) | "
            f"{r['samples']:.0e} | {r['ns_per_step']:.1f} | {1e9 / r['ns_per_step']:.3g} | "
            f"{r['cpu_ns_per_step']:.1f} | {note} |"
        )
    o = py.get("ode", {})
    if o.get("available"):
        gs_ode = o["gearsim_run_long_ns_per_step"]
        for m in o["methods"]:
            note = (
                f"{ratio(m['ns_per_step'] / gs_ode)} gearsim `Rig.run` on the same rig "
                f"({gs_ode:.0f} ns/step, {o['substeps']} sub-steps); {m['nfev']} RHS calls; "
                f"follower speed differs by {m['rms_diff_driven_speed_rel']:.2%} RMS, "
                f"{m['max_abs_diff_driven_speed_rad_s']:.3f} rad/s max"
            )
            md.append(
                f"| scipy {o['scipy']} `solve_ivp` {m['method']}, backlash rig as an ODE | "
                f"{o['samples']} | {m['ns_per_step']:.0f} | {1e9 / m['ns_per_step']:.3g} | "
                f"{m['cpu_ns_per_step']:.0f} | {note} |"
            )
    else:
        md.append(f"| scipy `solve_ivp` | | | | | skipped: {o.get('reason', 'not run')} |")
    md.append("")
    return md


def alternative_target(py: dict, c_step: dict | None, c_full: dict | None) -> tuple[str, str]:
    """Figure and verdict of ">= 100x faster than the per-step Python
    alternative", for the full rig (sg_full: what a user who needs backlash or
    heating writes) and the rigid rig (sg_constant_viscous), from the measured
    ratios to Rig.run (wall clock; CPU time decides "met on CPU time only")."""
    a = py["alternatives"]
    target = 100.0
    parts = []
    verdicts = []
    full = a.get("python_loop_full")
    if full:
        gs_full = full["gearsim_run_ns_per_step"]
        speedup = full["ns_per_step"] / gs_full
        cpu_speedup = full["cpu_ns_per_step"] / full["gearsim_run_cpu_ns_per_step"]
        fig = (
            f"full rig (`sg_full`): {ratio(speedup)} vs `Rig.run` "
            f"({ratio(cpu_speedup)} on CPU time)"
        )
        if c_full:
            fig += f", {ratio(full['ns_per_step'] / c_full['median_ns'])} vs C `gs_rig_step`"
        parts.append(fig)
        verdicts.append(("full", verdict(speedup, cpu_speedup, lambda v: v >= target)))
    else:
        parts.append("full rig: not measured")
    gs = a["gearsim_run_ns_per_step"]
    gs_cpu = a.get("gearsim_run_cpu_ns_per_step")
    loop = a["python_loop"]
    speedup = loop["ns_per_step"] / gs
    cpu_speedup = loop["cpu_ns_per_step"] / gs_cpu if gs_cpu else speedup
    fig = f"rigid rig (`sg_constant_viscous`): {ratio(speedup)} (`math` loop)"
    loop_np = a.get("python_loop_numpy")
    if loop_np:
        fig += f" / {ratio(loop_np['ns_per_step'] / gs)} (numpy-scalar loop)"
    fig += " vs `Rig.run`"
    if gs_cpu:
        fig += f" ({ratio(cpu_speedup)} on CPU time)"
    if c_step:
        fig += f", {ratio(loop['ns_per_step'] / c_step['median_ns'])} vs C `gs_rig_step`"
    parts.append(fig)
    verdicts.append(("rigid", verdict(speedup, cpu_speedup, lambda v: v >= target)))
    if len(verdicts) == 1:
        verdict_ = f"{verdicts[0][1]} for the rigid rig; full rig not measured"
    elif verdicts[0][1] == verdicts[1][1]:
        verdict_ = f"{verdicts[0][1]} for both rigs"
    else:
        verdict_ = ", ".join(f"{v} for the {name} rig" for name, v in verdicts)
    return "; ".join(parts), verdict_


def python_targets(
    py: dict, c_step: dict | None, c_full: dict | None
) -> list[tuple[str, str, str, str]]:
    batch = py["batch"][0]
    s = py["step"]
    rate = batch["run_steps_per_s"]
    cpu_rate = 1e9 / batch["run_cpu_ns_per_step"]
    alt_fig, alt_verdict = alternative_target(py, c_step, c_full)
    return [
        (
            "Python batch >= 5 M steps/s",
            f"{rate / 1e6:.2f} M steps/s wall, {cpu_rate / 1e6:.2f} M cpu "
            f"(`Rig.run`, `{batch['config']}`, {batch['samples']:.0e} samples)",
            verdict(rate, cpu_rate, lambda v: v >= 5e6),
            "",
        ),
        (
            "one Rig.step call <= 2 us",
            f"{s['median_us']:.2f} us wall, {s['cpu_median_us']:.2f} us cpu",
            verdict(s["median_us"], s["cpu_median_us"], lambda v: v <= 2.0),
            "",
        ),
        (
            ">= 100x faster than the per-step Python alternative",
            alt_fig,
            alt_verdict,
            "",
        ),
    ]


def build(results: Path) -> tuple[list[str], list[tuple[str, str, str, str]]]:
    c = load(results / "c.json")
    ir = load(results / "instructions.json")
    m4 = load(results / "m4.json")
    py = load(results / "python.json")
    md: list[str] = []
    targets: list[tuple[str, str, str, str]] = []  # (target, figure, verdict, note)

    timing: dict[tuple[str, str], dict] = {}
    if c:
        for r in c["results"]:
            timing[(r["config"], r["mode"])] = r
    counts: dict[tuple[str, str], float] = {}
    if ir and ir.get("available"):
        for r in ir["results"]:
            counts[(r["config"], r["mode"])] = r["ir_per_step"]
    m4_counts: dict[str, float] = {}
    if m4 and m4.get("qemu"):
        for r in m4["qemu"]["results"]:
            m4_counts[r["config"]] = r["instructions_per_step"]

    md += [f"Run of {datetime.now(UTC):%Y-%m-%d %H:%M} UTC on {machine()}.", ""]
    if c:
        md += c_section(c, timing, counts, m4_counts)

    for label, cfg, limit in (
        ("full Simple Gear rig <= 150 ns/step", "sg_full", 150.0),
        ("constant-efficiency rig <= 40 ns/step", "sg_constant", 40.0),
    ):
        r = timing.get((cfg, "step"))
        if not r:
            targets.append((label, "not measured", "-", ""))
            continue
        targets.append(
            (
                label,
                f"{r['median_ns']:.1f} ns wall, {r['cpu_median_ns']:.1f} ns cpu (`{cfg}`, step)",
                verdict(r["median_ns"], r["cpu_median_ns"], lambda v, lim=limit: v <= lim),
                "",
            )
        )
    label = "<= 1,000 instructions per full step"
    if ("sg_full", "step") in counts:
        v = counts[("sg_full", "step")]
        fig = f"{v:.0f} Ir (`sg_full`, x86-64)"
        if "sg_full" in m4_counts:
            fig += f"; {m4_counts['sg_full']:.0f} on the M4"
        targets.append((label, fig, "met" if v <= 1000 else "missed", ""))
    else:
        targets.append((label, "not measured (no valgrind)", "-", ""))

    md += m4_section(m4)

    c_step = timing.get(("sg_constant_viscous", "step"))
    c_full = timing.get(("sg_full", "step"))
    if py and py.get("available"):
        md += python_section(py, c_step, c_full)
        targets += python_targets(py, c_step, c_full)
    else:
        reason = (py or {}).get("reason", "not run")
        md += [f"Python: not measured ({reason}).", ""]
        for label in (
            "Python batch >= 5 M steps/s",
            "one Rig.step call <= 2 us",
            ">= 100x faster than the per-step Python alternative",
        ):
            targets.append((label, "not measured", "-", ""))

    md += ["### Targets", "", "| target | figure | verdict |", "|---|---|---|"]
    for t, fig, verdict_, _ in targets:
        md.append(f"| {t} | {fig} | {verdict_} |")
    md.append("")
    return md, targets


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="directory with c.json, instructions.json, ...")
    ap.add_argument(
        "--update-docs",
        type=Path,
        metavar="FILE",
        help="also replace the results section of FILE (docs/performance.md)",
    )
    args = ap.parse_args()
    md, targets = build(args.results)
    text = "\n".join(md) + "\n"
    (args.results / "results.md").write_text(text)
    print()
    print("== Targets")
    width = max(len(t[0]) for t in targets)
    for t, fig, verdict_, _ in targets:
        print(f"  {t:{width}s}  {verdict_:22s} {fig}")
    print(f"\nMarkdown: {args.results / 'results.md'}")
    if args.update_docs:
        doc = args.update_docs.read_text() if args.update_docs.exists() else ""
        if BEGIN in doc and END in doc:
            head, rest = doc.split(BEGIN, 1)
            _, tail = rest.split(END, 1)
            doc = f"{head}{BEGIN}\n{text}{END}{tail}"
        else:
            doc = doc.rstrip("\n") + f"\n\n{BEGIN}\n{text}{END}\n"
        args.update_docs.write_text(doc)
        print(f"Updated {args.update_docs}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
