#!/usr/bin/env python3
"""Compares the scenario outputs of the host program and the QEMU program.

Lines starting with '#' are informational and skipped. Every other line must
match in structure; step lines ("kkkk v0 ... v14", IEEE-754 bit patterns in
hex) are compared value by value. Prints, per scenario, how many values are
bit-identical and, where they differ, the largest distance in units in the
last place (ULP) and the largest relative difference. Exit 1 when the runs
differ in structure or when any value differs by more than --max-ulp ULP.

usage: compare_outputs.py HOST.txt TARGET.txt [--max-ulp N]
"""

import argparse
import struct
import sys


def ordered(bits, width):
    """Maps an IEEE bit pattern to an integer that orders like the value."""
    sign = 1 << (width - 1)
    return -(bits & (sign - 1)) if bits & sign else bits


def as_float(bits, width):
    if width == 32:
        return struct.unpack("<f", struct.pack("<I", bits))[0]
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


def load(path):
    with open(path, encoding="utf-8", errors="replace") as fh:
        return [ln.rstrip("\n") for ln in fh if ln.strip() and not ln.startswith("#")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("host")
    ap.add_argument("target")
    ap.add_argument("--max-ulp", type=int, default=0)
    args = ap.parse_args()
    host, target = load(args.host), load(args.target)
    if len(host) != len(target):
        print(f"FAIL: {len(host)} lines on the host, {len(target)} on the target")
        return 1
    scenario, stats, order, bad = None, {}, [], 0
    for hl, tl in zip(host, target, strict=True):  # equal line counts: checked above
        hf, tf = hl.split(), tl.split()
        if hf and hf[0] == "scenario":
            scenario = hf[1]
            order.append(scenario)
            stats[scenario] = {"values": 0, "same": 0, "ulp": 0, "rel": 0.0, "where": ""}
        if not (hf and hf[0].isdigit()):
            if hf[0] == "hash" or hl == tl:
                continue
            print(f"FAIL: line differs:\n  host:   {hl}\n  target: {tl}")
            bad += 1
            continue
        if len(hf) != len(tf) or hf[0] != tf[0]:
            print(f"FAIL: step line structure differs:\n  host:   {hl}\n  target: {tl}")
            bad += 1
            continue
        st = stats[scenario]
        for i, (a, b) in enumerate(zip(hf[1:], tf[1:], strict=True)):  # lengths checked above
            width = 4 * len(a)
            st["values"] += 1
            v = as_float(int(a, 16), width)
            if v != v or v in (float("inf"), float("-inf")):
                print(f"FAIL: {scenario} step {hf[0]} field {i} is not finite on the host")
                bad += 1
            if a == b:
                st["same"] += 1
                continue
            x, y = int(a, 16), int(b, 16)
            ulp = abs(ordered(x, width) - ordered(y, width))
            fx, fy = as_float(x, width), as_float(y, width)
            rel = abs(fx - fy) / max(abs(fx), abs(fy), 1e-300)
            if ulp > st["ulp"]:
                st["ulp"], st["where"] = ulp, f"step {hf[0]} field {i}"
            st["rel"] = max(st["rel"], rel)
    total = sum(s["values"] for s in stats.values())
    same = sum(s["same"] for s in stats.values())
    for name in order:
        s = stats[name]
        note = (
            "bit-identical"
            if s["same"] == s["values"]
            else (f"max {s['ulp']} ULP ({s['where']}), max relative {s['rel']:.3g}")
        )
        print(f"  {name:24s} {s['same']:6d}/{s['values']:<6d} values identical  {note}")
        if s["ulp"] > args.max_ulp:
            bad += 1
    print(
        f"compared {total} values in {len(order)} scenarios: {same} bit-identical, "
        f"{total - same} different (allowed: up to {args.max_ulp} ULP)"
    )
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
