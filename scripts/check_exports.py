#!/usr/bin/env python3
"""Checks that the gearsim shared library exports exactly its public API.

The public API is every declaration marked GS_API in include/gearsim/*.h:
functions and `extern const` data. Names the headers map through
GS_PRECISION_NAME (`#define gs_rig_init_gear GS_PRECISION_NAME(gs_rig_init_gear)`)
carry the _f32 suffix in the float build (--single). The exports are the
dynamic symbols the library defines (nm -D --defined-only), less those the
linker and sanitizer/coverage runtimes add. Fails naming every symbol
exported without a GS_API declaration and every GS_API declaration not
exported. Run by CTest as build.exports; python3 standard library only.

usage: check_exports.py --library libgearsim.so --headers include/gearsim [--single] [--nm nm]
"""

import argparse
import re
import subprocess
import sys
from pathlib import Path

# Defined by the linker or by instrumentation, not by the library's code.
LINKER_SYMBOLS = {
    "_init",
    "_fini",
    "_edata",
    "_end",
    "__bss_start",
    "__end__",
    "_etext",
    "__data_start",
}
INSTRUMENTATION_PREFIXES = (
    "__asan",
    "__odr_asan",
    "__ubsan",
    "__sancov",
    "__tsan",
    "__msan",
    "__lsan",
    "__gcov",
    "__llvm_",
    "__hwasan",
    "__start_",
    "__stop_",
)

PRECISION_SUFFIX = "_f32"


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def logical_lines(text):
    """Joins backslash-continued lines."""
    return re.sub(r"\\\n", " ", text).split("\n")


def public_api(headers, single):
    """Returns {exported name: header file} for every GS_API declaration."""
    declared = {}
    for header in sorted(Path(headers).glob("*.h")):
        lines = logical_lines(strip_comments(header.read_text()))
        # name -> precision-mapped name, from `#define NAME GS_PRECISION_NAME(BASE)`
        renames = {}
        code = []
        for line in lines:
            stripped = line.strip()
            if stripped.startswith("#"):
                m = re.match(
                    r"#\s*define\s+(\w+)\s+GS_PRECISION_NAME\s*\(\s*(\w+)\s*\)\s*$", stripped
                )
                if m:
                    renames[m.group(1)] = m.group(2) + (PRECISION_SUFFIX if single else "")
                continue
            code.append(line)
        body = " ".join(code)
        body = re.sub(
            r"GS_PRECISION_NAME\s*\(\s*(\w+)\s*\)",
            lambda m: m.group(1) + (PRECISION_SUFFIX if single else ""),
            body,
        )
        for m in re.finditer(r"\bGS_API\b([^;{]*)", body):
            decl = m.group(1)
            if "(" in decl:
                # function: the identifier before the parameter list
                # (`T *(name)(...)` would need more; the headers don't use it)
                head = decl.split("(", 1)[0]
            else:
                # data: drop array bounds and any initialiser
                head = re.sub(r"\[[^\]]*\]", " ", decl.split("=", 1)[0])
            names = re.findall(r"[A-Za-z_]\w*", head)
            if not names:
                raise SystemExit(
                    "check_exports: cannot parse the GS_API declaration in "
                    f"{header}: {decl.strip()}"
                )
            name = renames.get(names[-1], names[-1])
            declared[name] = header.name
    return declared


def exported(library, nm):
    """Returns (defined dynamic symbols of the library, ignored toolchain symbols)."""
    result = subprocess.run(
        [nm, "-D", "--defined-only", "-P", library], capture_output=True, text=True
    )
    if result.returncode != 0:
        raise SystemExit(f"check_exports: {nm} failed on {library}: {result.stderr.strip()}")
    symbols, ignored = set(), set()
    for line in result.stdout.splitlines():
        fields = line.split()
        if len(fields) < 2:
            continue
        name = fields[0].split("@", 1)[0]
        if name in LINKER_SYMBOLS or name.startswith(INSTRUMENTATION_PREFIXES):
            ignored.add(name)
        else:
            symbols.add(name)
    return symbols, ignored


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--library", required=True, help="the shared library (libgearsim.so)")
    parser.add_argument(
        "--headers", required=True, help="the public headers' directory (include/gearsim)"
    )
    parser.add_argument(
        "--single", action="store_true", help="float build: GS_PRECISION_NAME adds _f32"
    )
    parser.add_argument("--nm", default="nm", help="nm program (default: nm)")
    args = parser.parse_args()

    declared = public_api(args.headers, args.single)
    symbols, ignored = exported(args.library, args.nm)
    extra = sorted(symbols - declared.keys())
    missing = sorted(declared.keys() - symbols)
    precision = "float" if args.single else "double"
    print(
        f"check_exports: {Path(args.library).name} ({precision}): {len(symbols)} exported symbols, "
        f"{len(declared)} GS_API declarations in {args.headers}/*.h"
    )
    if ignored:
        print(f"check_exports: ignored (linker/instrumentation): {' '.join(sorted(ignored))}")
    for name in extra:
        print(
            f"check_exports: EXTRA   {name}: exported, "
            "but no GS_API declaration in the public headers"
        )
    for name in missing:
        print(
            f"check_exports: MISSING {name}: declared GS_API in {declared[name]}, but not exported"
        )
    if extra or missing:
        print(f"check_exports: FAIL: {len(extra)} extra, {len(missing)} missing")
        return 1
    print(
        f"check_exports: ok: the {len(symbols)} exports are exactly the public API: "
        + " ".join(sorted(symbols))
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
