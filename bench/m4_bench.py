#!/usr/bin/env python3
"""Cortex-M4F figures of the gearsim float build: code size and instructions per step.

1. Compiles every src/*.c with the firmware flags
       -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard -Os
       -DGS_SINGLE_PRECISION -ffp-contract=off -ffunction-sections -fdata-sections
   and reports arm-none-eabi-size of each object.
2. Links small images that use one model each (a block alone, a rig) with
   --gc-sections and reports what gearsim adds to an empty image (text+data).
   The friction and hard-stop models are chosen at run time by a switch in the
   step, so every model of a block is in its image; these sizes are per block
   and rig, not per friction model.
3. If qemu-system-arm is present, runs bench/m4/m4_bench.c on QEMU's
   mps2-an386 (Cortex-M4) with -icount shift=0 and reports instructions per
   step of every benchmark configuration (instructions, not cycles).

Usage: m4_bench.py [--json FILE] [--build-dir DIR]. Standard library only;
skips what the toolchain does not provide.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# QEMU's mps2-an386: the linker script, start-up code and board.h that the
# firmware programs use too
BOARD = ROOT / "firmware" / "mps2-an386"
CC = "arm-none-eabi-gcc"
SIZE = "arm-none-eabi-size"
QEMU = "qemu-system-arm"
FLAGS = [
    "-mcpu=cortex-m4",
    "-mthumb",
    "-mfpu=fpv4-sp-d16",
    "-mfloat-abi=hard",
    "-Os",
    "-DGS_SINGLE_PRECISION",
    "-ffp-contract=off",
    "-fno-fast-math",
    "-std=c99",
    "-ffunction-sections",
    "-fdata-sections",
]
LINK = [
    "-nostdlib",
    "-nostartfiles",
    "-Wl,--gc-sections",
    f"-T{BOARD / 'mps2_an386.ld'}",
]

# Programs that pull in one model each (err may be NULL; step once on zeros).
EMPTY = "empty image (start-up only)"  # the baseline the other images are measured against
PROGRAMS = {
    EMPTY: "",
    "Simple Gear block": """
        gs_simple_gear_params p = gs_simple_gear_params_default();
        static gs_simple_gear_consts c; static gs_block_state st;
        gs_gear_ports_in in = {0}; gs_gear_ports_out out;
        if (gs_simple_gear_init(&c, &st, &p, 0) != GS_OK) return 1;
        gs_simple_gear_step(&c, &st, 1e-3f, &in, &out); return (int)out.base_torque_Nm;""",
    "Rack & Pinion block": """
        gs_rack_pinion_params p = gs_rack_pinion_params_default();
        static gs_rack_pinion_consts c; static gs_block_state st;
        gs_rack_ports_in in = {0}; gs_rack_ports_out out;
        if (gs_rack_pinion_init(&c, &st, &p, 0) != GS_OK) return 1;
        gs_rack_pinion_step(&c, &st, 1e-3f, &in, &out); return (int)out.pinion_torque_Nm;""",
    "Simple Gear rig": """
        gs_simple_gear_params p = gs_simple_gear_params_default();
        gs_rig_params r = gs_rig_params_default();
        static gs_rig_consts c; static gs_rig_state st; gs_rig_input in = {0}; gs_rig_output out;
        if (gs_rig_init_gear(&c, &st, &p, &r, 0) != GS_OK) return 1;
        gs_rig_step(&c, &st, &in, &out); return (int)out.base_torque;""",
    "Rack & Pinion rig": """
        gs_rack_pinion_params p = gs_rack_pinion_params_default();
        gs_rig_params r = gs_rig_params_default();
        static gs_rig_consts c; static gs_rig_state st; gs_rig_input in = {0}; gs_rig_output out;
        if (gs_rig_init_rack(&c, &st, &p, &r, 0) != GS_OK) return 1;
        gs_rig_step(&c, &st, &in, &out); return (int)out.base_torque;""",
    "both rigs + gs_status_str": """
        gs_simple_gear_params p = gs_simple_gear_params_default();
        gs_rack_pinion_params q = gs_rack_pinion_params_default();
        gs_rig_params r = gs_rig_params_default();
        static gs_rig_consts ca, cb; static gs_rig_state sa, sb;
        gs_rig_input in = {0}; gs_rig_output out;
        gs_status s = gs_rig_init_gear(&ca, &sa, &p, &r, 0);
        if (s == GS_OK) s = gs_rig_init_rack(&cb, &sb, &q, &r, 0);
        if (s != GS_OK) return (int)gs_status_str(s)[0];
        gs_rig_step(&ca, &sa, &in, &out); gs_rig_step(&cb, &sb, &in, &out);
        return (int)out.base_torque;""",
}

MEM_FUNCS = """
#include <stddef.h>
void *memset(void *d, int c, size_t n); void *memcpy(void *d, const void *s, size_t n);
void *memset(void *d, int c, size_t n)
{ unsigned char *p = d; while (n--) *p++ = (unsigned char)c; return d; }
void *memcpy(void *d, const void *s, size_t n)
{ unsigned char *p = d; const unsigned char *q = s; while (n--) *p++ = *q++; return d; }
"""


def run(cmd: list[str], **kw) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, check=True, text=True, capture_output=True, **kw)


def size_of(path: Path) -> dict[str, int]:
    line = run([SIZE, str(path)]).stdout.splitlines()[1].split()
    return {"text": int(line[0]), "data": int(line[1]), "bss": int(line[2])}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path)
    ap.add_argument("--build-dir", type=Path)
    args = ap.parse_args()
    result: dict = {"available": False, "flags": " ".join(FLAGS)}
    if shutil.which(CC) is None or shutil.which(SIZE) is None:
        print(
            "m4_bench.py: arm-none-eabi-gcc not found; skipping the Cortex-M4 figures",
            file=sys.stderr,
        )
    else:
        with tempfile.TemporaryDirectory(prefix="gearsim-m4-") as tmp:
            build = args.build_dir or Path(tmp)
            build.mkdir(parents=True, exist_ok=True)
            result.update(measure(build))
            result["available"] = True
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


def measure(build: Path) -> dict:
    inc = [f"-I{ROOT / 'include'}", f"-I{ROOT / 'src'}"]
    objects = []
    per_object = {}
    for src in sorted((ROOT / "src").glob("*.c")):
        obj = build / (src.stem + ".o")
        run([CC, *FLAGS, *inc, "-c", str(src), "-o", str(obj)])
        objects.append(obj)
        per_object[src.name] = size_of(obj)
    total = {k: sum(v[k] for v in per_object.values()) for k in ("text", "data", "bss")}
    print(f"Cortex-M4F objects ({' '.join(FLAGS)}):")
    print(f"  {'object':16s} {'text':>6s} {'data':>5s} {'bss':>5s}")
    for name, s in per_object.items():
        print(f"  {name:16s} {s['text']:6d} {s['data']:5d} {s['bss']:5d}")
    print(f"  {'total':16s} {total['text']:6d} {total['data']:5d} {total['bss']:5d}")

    startup = build / "startup.o"
    run([CC, *FLAGS, "-c", str(BOARD / "startup.c"), "-o", str(startup)])

    def link(elf: Path, main_file: Path) -> None:
        """An image of main_file (C source or object), the start-up code and the core."""
        inputs = [str(main_file), str(startup), *map(str, objects)]
        run([CC, *FLAGS, *inc, *LINK, "-o", str(elf), *inputs, "-lgcc"])

    images = {}
    for label, body in PROGRAMS.items():
        src = build / "image.c"
        src.write_text(
            '#include "gearsim/gearsim.h"\n'
            + MEM_FUNCS
            + "int main(void);\nint main(void)\n{\n"
            + (body or "return 0;")
            + "\n}\n"
        )
        elf = build / "image.elf"
        link(elf, src)
        images[label] = size_of(elf)
    base = images[EMPTY]
    linked = {
        label: {
            "text": s["text"] - base["text"],
            "data": s["data"] - base["data"],
            "bss": s["bss"] - base["bss"],
        }
        for label, s in images.items()
        if label != EMPTY
    }
    print("Linked with --gc-sections, bytes added to an empty image (text / data / bss):")
    for label, s in linked.items():
        print(f"  {label:28s} {s['text']:6d} {s['data']:5d} {s['bss']:6d}")

    out = {"objects": per_object, "objects_total": total, "linked": linked}
    if shutil.which(QEMU) is None:
        print("m4_bench.py: qemu-system-arm not found; no instruction counts", file=sys.stderr)
        return out
    bench_obj = build / "m4_bench.o"
    bench_src = ROOT / "bench" / "m4" / "m4_bench.c"
    run([CC, *FLAGS, *inc, f"-I{BOARD}", "-c", str(bench_src), "-o", str(bench_obj)])
    elf = build / "m4_bench.elf"
    link(elf, bench_obj)
    try:
        proc = run(
            [
                QEMU,
                "-M",
                "mps2-an386",
                "-cpu",
                "cortex-m4",
                "-nographic",
                "-monitor",
                "none",
                "-serial",
                "none",
                "-semihosting-config",
                "enable=on,target=native",
                "-icount",
                "shift=0",
                "-kernel",
                str(elf),
            ],
            timeout=300,
        )
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired) as exc:
        print(f"m4_bench.py: QEMU run failed: {exc}", file=sys.stderr)
        return out
    # QEMU writes the semihosting console to stderr or stdout depending on its version
    text = proc.stdout + "\n" + proc.stderr
    lines = [f for f in map(str.split, text.splitlines()) if len(f) == 3 and f[1].isdigit()]
    calib = next(int(ln[1]) for ln in lines if ln[0].startswith("calibration"))
    instr_per_tick = 2_000_000 / calib
    counts = []
    print(
        f"QEMU mps2-an386 (Cortex-M4F), -icount shift=0: {instr_per_tick:g} instructions "
        "per SysTick tick"
    )
    print(f"  {'configuration':26s} {'instr/step':>10s}")
    for ln in lines:
        if ln[0].startswith("calibration"):
            continue
        steps, ticks = int(ln[1]), int(ln[2])
        per_step = ticks * instr_per_tick / steps
        counts.append({"config": ln[0], "steps": steps, "instructions_per_step": per_step})
        print(f"  {ln[0]:26s} {per_step:10.1f}")
    out["qemu"] = {
        "machine": "mps2-an386",
        "instructions_per_tick": instr_per_tick,
        "resolution_per_step": instr_per_tick / max(c["steps"] for c in counts),
        "results": counts,
    }
    return out


if __name__ == "__main__":
    sys.exit(main())
