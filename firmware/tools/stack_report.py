#!/usr/bin/env python3
"""Worst-case stack per public gearsim function, from GCC's call graphs.

Reads the .ci files that `-fcallgraph-info=su` writes next to each object
(VCG graphs: one node per function with its frame size, one edge per call),
adds the frames of the external leaf routines the library calls (memcpy,
memset: measured from their push/sub sp in the linked program's disassembly)
and prints, per public function, its own frame and the deepest path through
its callees. Fails (exit 1) on recursion, a dynamic or unknown frame, an
indirect call, or a worst case above --budget bytes.

usage: stack_report.py --objdir DIR --headers DIR --elf PROG.elf --objdump TOOL [--budget N]
"""

import argparse
import glob
import os
import re
import subprocess
import sys

NODE = re.compile(r'^node: \{ title: "([^"]+)" label: "([^"]*)"(.*)\}$')
EDGE = re.compile(r'^edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r"\\n(\d+) bytes \(([a-z,]+)\)")


def parse_graphs(objdir):
    frames, kinds, edges, labels = {}, {}, {}, {}
    files = sorted(glob.glob(os.path.join(objdir, "**", "*.ci"), recursive=True))
    if not files:
        sys.exit(f"stack_report: no .ci files under {objdir} (build with -fcallgraph-info=su)")
    for path in files:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                line = line.strip()
                m = NODE.match(line)
                if m:
                    title, label, rest = m.groups()
                    labels.setdefault(title, label.split("\\n")[0])
                    f = FRAME.search(label)
                    if f:
                        frames[title] = int(f.group(1))
                        kinds[title] = f.group(2)
                    continue
                m = EDGE.match(line)
                if m:
                    edges.setdefault(m.group(1), set()).add(m.group(2))
    return frames, kinds, edges, labels


def leaf_frame(objdump, elf, name):
    """Stack bytes of a leaf routine in the linked program: push/stmdb + vpush + sub sp."""
    out = subprocess.run(
        [objdump, "-d", "--no-show-raw-insn", elf], check=True, capture_output=True, text=True
    ).stdout
    m = re.search(rf"^[0-9a-f]+ <{re.escape(name)}>:\n(.*?)(?:\n\n|\Z)", out, re.S | re.M)
    if not m:
        return None
    total = 0
    for ins in m.group(1).splitlines():
        if re.search(r"\b(bl|blx)\b", ins):
            return None  # not a leaf: refuse to guess
        p = re.search(r"\b(push|stmdb\s+sp!,)\s*\{([^}]*)\}", ins)
        if p:
            regs = 0
            for part in p.group(2).split(","):
                part = part.strip()
                r = re.match(r"r(\d+)-r(\d+)", part)
                regs += int(r.group(2)) - int(r.group(1)) + 1 if r else 1
            total += 4 * regs
        v = re.search(r"\bvpush\s*\{([^}]*)\}", ins)
        if v:
            for part in v.group(1).split(","):
                r = re.match(r"\s*[sd](\d+)-[sd](\d+)", part)
                size = 8 if part.strip().startswith("d") else 4
                total += size * ((int(r.group(2)) - int(r.group(1)) + 1) if r else 1)
        w = re.search(r"\[sp, #-(\d+)\]!", ins)
        if w:
            total += int(w.group(1))
        s = re.search(r"\bsub(?:\.w)?\s+sp,\s*(?:sp,\s*)?#(\d+)", ins)
        if s:
            total += int(s.group(1))
    return total


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--objdir", required=True)
    ap.add_argument("--headers", required=True)
    ap.add_argument("--elf", required=True, help="a linked program holding memcpy/memset")
    ap.add_argument("--objdump", default="arm-none-eabi-objdump")
    ap.add_argument("--budget", type=int, default=0)
    args = ap.parse_args()

    frames, kinds, edges, labels = parse_graphs(args.objdir)
    problems = []

    # External leaves (memcpy/memset and whatever else appears without a frame).
    for callee in sorted({t for ts in edges.values() for t in ts} - set(frames)):
        size = leaf_frame(args.objdump, args.elf, callee)
        if size is None:
            problems.append(f"no frame size for callee {callee}")
            frames[callee] = 0
        else:
            frames[callee] = size
            kinds[callee] = "static, external leaf"
    externals = [f"{c} {frames[c]} B" for c in sorted(kinds) if kinds[c] == "static, external leaf"]
    if externals:
        print("external leaf routines (from the linked program): " + ", ".join(externals))
    for fn, kind in kinds.items():
        if kind not in ("static", "static, external leaf"):
            problems.append(f"{labels.get(fn, fn)}: stack is {kind}")

    memo, onpath = {}, set()

    def worst(fn):
        if fn in memo:
            return memo[fn]
        if fn in onpath:
            problems.append(f"recursion through {labels.get(fn, fn)}")
            return (0, [fn])
        onpath.add(fn)
        best = (0, [])
        for callee in sorted(edges.get(fn, ())):
            best = max(best, worst(callee), key=lambda t: t[0])
        onpath.discard(fn)
        memo[fn] = (frames.get(fn, 0) + best[0], [fn] + best[1])
        return memo[fn]

    header_text = ""
    for h in sorted(glob.glob(os.path.join(args.headers, "*.h"))):
        with open(h, encoding="utf-8") as fh:
            header_text += fh.read()
    public = []
    for title in frames:
        base = re.sub(r"_f32$", "", title)
        if ":" not in title and re.search(rf"\b{re.escape(base)}\s*\(", header_text):
            public.append(title)
    if not public:
        problems.append("no public function found")

    print(f"{'public function':34s} {'own frame':>9s} {'worst case':>10s}  deepest path")
    deepest = ("", 0)
    for fn in sorted(public):
        total, path = worst(fn)
        names = " > ".join(labels.get(p, p) for p in path)
        print(f"{fn:34s} {frames[fn]:7d} B {total:8d} B  {names}")
        if total > deepest[1]:
            deepest = (fn, total)
    print(
        f"deepest public entry: {deepest[0]} = {deepest[1]} bytes "
        f"(frames from -fstack-usage, call graph from -fcallgraph-info; "
        f"memcpy/memset frames from the linked newlib)"
    )
    if args.budget and deepest[1] > args.budget:
        problems.append(f"worst case {deepest[1]} B exceeds the budget of {args.budget} B")
    for p in problems:
        print(f"FAIL: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
