"""cffi build script (API mode) of the extension module ``gearsim._gearsim``.

The C declarations seen by Python are not written here: ``generate_cdef()``
runs the C preprocessor over the public umbrella header
``include/gearsim/gearsim.h`` and the HIL library's ``hil/include/gearsim/hil.h``
at build time and hands its output to cffi, so the cdef is the headers
(tests/python/test_bindings_build.py checks it).

- ``cc -E -P -std=c99 -nostdinc -DGS_API=`` expands the field lists of
  gearsim/fields.h, the table sizes and the precision macros; ``-nostdinc``
  with an empty stub ``stddef.h`` keeps libc's declarations out (cffi knows
  ``size_t``). Nothing but the public headers is read: the internal structs of
  ``src/`` never reach Python.
- The object-like ``#define`` constants of the headers (``GS_TABLE_MAX``,
  ``GS_VERSION_STRING``, ...), which the preprocessor consumes, are listed with
  ``cc -E -dM`` (minus the compiler's predefined macros) and declared
  ``#define NAME ...`` (integers, value from the compiler) or
  ``static const char *const NAME;`` (strings).
- Structs are declared in full, so cffi checks every field offset and struct
  size against the C compiler when the type is first used, and the preamble
  carries a table of the compiler's ``sizeof``/``offsetof`` of every public
  struct (``gspy_layouts``) and the cdef itself (``GSPY_CDEF``) for the tests.

The library sources ``src/*.c`` are compiled apart from cffi's generated
wrapper, as the static library ``gearsim_core`` (``core_library()``, built by
setuptools' ``build_clib`` from ``setup.py``), and the HIL library's
``hil/src/*.c`` (the bridge that ``gearsim.hil`` runs: the same C as the
runner gearsim-hil) as ``gearsim_hil`` (``hil_library()``), with the library's warning set
``cmake/gearsim_warnings.txt`` (the list CMake reads) and the determinism
flags of CMake's ``gearsim_configure``: ``-ffp-contract=off -fno-fast-math``.
``GEARSIM_WERROR=1`` in the environment adds ``-Werror``. The wrapper (cffi's
code and ``SHIM``, the bindings' own C: no physics) links against it. The
extension is the double build (``GS_SINGLE_PRECISION`` is not defined).

Used by ``setup.py`` (``cffi_modules`` names ``make_builder``, ``libraries``
comes from ``core_library()``). ``python bindings/python/gearsim_build.py``
builds the extension in place (``setup.py build_ext --inplace``), and
``python bindings/python/gearsim_build.py --cdef`` prints the generated cdef.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

from cffi import FFI

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent  # repository root: include/, src/, hil/ and cmake/ live there
INCLUDE_DIR = ROOT / "include"
SRC_DIR = ROOT / "src"
UMBRELLA = INCLUDE_DIR / "gearsim" / "gearsim.h"
HIL_INCLUDE_DIR = ROOT / "hil" / "include"
HIL_SRC_DIR = ROOT / "hil" / "src"
HIL_HEADER = HIL_INCLUDE_DIR / "gearsim" / "hil.h"
WARNINGS_FILE = ROOT / "cmake" / "gearsim_warnings.txt"
CORE_LIBRARY = "gearsim_core"
HIL_LIBRARY = "gearsim_hil"
# What the cdef is generated from: the core's umbrella header, then the HIL's.
CDEF_SOURCE = '#include "gearsim/gearsim.h"\n#include "gearsim/hil.h"\n'

# The bindings' own declarations, appended to the generated cdef: the stepper
# of Rig.step (SHIM below) and the compiler's layout table (_layout_table).
BINDINGS_CDEF = r"""
typedef struct {
    gs_rig_output out;
    const gs_rig_consts *consts;
    gs_rig_state *state;
} gspy_stepper;

int gspy_rig_step(gspy_stepper *s, double base_speed, double base_torque, double load,
                  double ambient_temperature, double measured_temperature);

typedef struct {
    const char *type;    /* a public struct */
    const char *member;  /* "" for the struct itself */
    size_t offset;       /* offsetof(type, member), 0 for the struct */
    size_t size;         /* sizeof the member or of the struct */
} gspy_layout;

const gspy_layout *gspy_layouts(size_t *count);

static const char *const GSPY_CDEF;  /* this cdef, as the extension was built with it */

/* gs_hil_config.send of the bridges gearsim.hil makes (gearsim/hil/bridge.py) */
extern "Python" int gspy_hil_send(void *context, const gs_hil_frame *frame);
"""

# C compiled into the wrapper beside the cffi code (not part of the C API): a
# per-step entry point for Rig.step. One cffi call with the five inputs by value
# replaces writing them into a gs_rig_input from Python, checking them and
# calling gs_rig_step with four pointers (which cffi converts one by one).
SHIM = r"""
#include <math.h>
#include <stddef.h>

/* The output of the last step of one rig (first: Rig.step reads it from the
   start of the struct), and that rig's constants and state (owned by the
   caller). */
typedef struct {
    gs_rig_output out;
    const gs_rig_consts *consts;
    gs_rig_state *state;
} gspy_stepper;

/* One gs_rig_step with these inputs into s->out; returns 0. Returns 1 without
   stepping when an input is not finite (Rig.step then finds and names it). */
static int gspy_rig_step(gspy_stepper *s, double base_speed, double base_torque, double load,
                         double ambient_temperature, double measured_temperature)
{
    gs_rig_input in;
    if (!(isfinite(base_speed) && isfinite(base_torque) && isfinite(load) &&
          isfinite(ambient_temperature) && isfinite(measured_temperature)))
        return 1;
    in.base_speed = base_speed;
    in.base_torque = base_torque;
    in.load = load;
    in.ambient_temperature = ambient_temperature;
    in.measured_temperature = measured_temperature;
    gs_rig_step(s->consts, s->state, &in, &s->out);
    return 0;
}
"""

_MACRO = re.compile(r"#define\s+([A-Za-z_]\w*)(\(?)\s*(.*)")
_FLOAT = re.compile(r"^\(?\s*[-+]?(\d+\.\d*|\.\d+|\d+[eE])")
_ATTRIBUTE = re.compile(r"__attribute__\s*\(\((?:[^()]|\([^()]*\))*\)\)")


def _path(path: Path, absolute: bool) -> str:
    # setuptools wants paths relative to setup.py (the repository root, which
    # is the working directory of a pip build); absolute ones elsewhere.
    return path.as_posix() if absolute else path.relative_to(ROOT).as_posix()


def warning_flags() -> list[str]:
    """The library's warning set: cmake/gearsim_warnings.txt, one flag a line,
    '#' starts a comment."""
    flags = []
    for line in WARNINGS_FILE.read_text().splitlines():
        flag = line.split("#", 1)[0].strip()
        if flag:
            flags.append(flag)
    return flags


def core_cflags() -> list[str]:
    """Flags of the library sources src/*.c (appended after Python's own)."""
    if sys.platform == "win32":  # MSVC: no GCC warning syntax; strict IEEE
        return ["/fp:precise"]
    # Determinism (docs/style.md 9): no FMA contraction, never -ffast-math, as
    # CMake's gearsim_configure; hidden visibility as the library's build.
    flags = ["-std=c99", *warning_flags(), "-ffp-contract=off", "-fno-fast-math"]
    flags.append("-fvisibility=hidden")
    if os.environ.get("GEARSIM_WERROR", "") not in ("", "0"):
        flags.append("-Werror")
    return flags


def wrapper_cflags() -> list[str]:
    """Flags of cffi's wrapper (no physics; cffi's code is not warning-clean)."""
    if sys.platform == "win32":
        return ["/fp:precise"]
    return ["-std=c99", "-ffp-contract=off", "-fno-fast-math"]


def core_library(absolute: bool = False) -> tuple[str, dict]:
    """setuptools' build_clib entry of the static library gearsim_core (src/*.c)."""
    sources = sorted(SRC_DIR.glob("*.c"))
    if not sources:
        raise RuntimeError(f"gearsim: no C sources found in {SRC_DIR}")
    # build_clib recompiles when one of these is newer than the objects.
    deps = sorted(SRC_DIR.glob("*.h")) + sorted((INCLUDE_DIR / "gearsim").glob("*.h"))
    deps += [WARNINGS_FILE, Path(__file__).resolve(), ROOT / "setup.py"]
    return (
        CORE_LIBRARY,
        {
            "sources": [_path(p, absolute) for p in sources],
            "include_dirs": [_path(INCLUDE_DIR, absolute), _path(SRC_DIR, absolute)],
            "cflags": core_cflags(),
            "obj_deps": {"": [_path(p, absolute) for p in deps if p.exists()]},
        },
    )


def hil_library(absolute: bool = False) -> tuple[str, dict]:
    """build_clib entry of the static library gearsim_hil (hil/src/*.c): the
    HIL bridge, with the core's flags. Its frame tables come from the DBC
    files at run time (gearsim.hil.codec), not from hil/dbc_tables.py."""
    sources = sorted(HIL_SRC_DIR.glob("*.c"))
    if not sources:
        raise RuntimeError(f"gearsim: no C sources found in {HIL_SRC_DIR}")
    deps = [
        HIL_HEADER,
        *sorted(HIL_SRC_DIR.glob("*.h")),
        *sorted((INCLUDE_DIR / "gearsim").glob("*.h")),
    ]
    deps.append(WARNINGS_FILE)
    deps += [Path(__file__).resolve(), ROOT / "setup.py"]
    return (
        HIL_LIBRARY,
        {
            "sources": [_path(p, absolute) for p in sources],
            "include_dirs": [
                _path(HIL_INCLUDE_DIR, absolute),
                _path(INCLUDE_DIR, absolute),
                _path(HIL_SRC_DIR, absolute),
            ],
            "cflags": core_cflags(),
            "obj_deps": {"": [_path(p, absolute) for p in deps if p.exists()]},
        },
    )


def c_libraries(absolute: bool = False) -> list[tuple[str, dict]]:
    """Every static library of the extension, for setup.py's ``libraries``."""
    return [core_library(absolute), hil_library(absolute)]


def preprocessor() -> list[str]:
    """The C compiler used as preprocessor: $CC, else Python's, else cc."""
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    return shlex.split(cc)


def _preprocess(options: list[str], source: Path, stub_dir: Path, defines: list[str]) -> str:
    command = [
        *preprocessor(),
        "-E",
        "-std=c99",
        "-nostdinc",
        "-I",
        str(stub_dir),
        "-I",
        str(INCLUDE_DIR),
        "-I",
        str(HIL_INCLUDE_DIR),
        "-DGS_API=",
        *defines,
        *options,
        "-x",
        "c",
        str(source),
    ]
    try:
        done = subprocess.run(command, capture_output=True, text=True, check=False)
    except OSError as exc:
        raise RuntimeError(
            f"gearsim: cannot run the C preprocessor {command[0]!r} ({exc}); set CC"
        ) from None
    if done.returncode != 0:
        raise RuntimeError(
            f"gearsim: preprocessing {source} failed:\n{shlex.join(command)}\n{done.stderr}"
        )
    return done.stdout


def _constants(macros: str, predefined: str) -> list[str]:
    """cdef lines of the headers' object-like constants (upper-case names with
    a value; header guards, the function-like macros and the lower-case
    precision renames are left out)."""
    known = set(predefined.splitlines())
    lines = []
    for line in sorted(set(macros.splitlines()) - known):
        match = _MACRO.match(line)
        if not match:
            continue
        name, function_like, value = match.groups()
        if function_like or not value or name != name.upper():
            continue
        if value.startswith('"'):
            lines.append(f"static const char *const {name};")
        elif _FLOAT.match(value):
            lines.append(f"static const double {name};")
        else:
            lines.append(f"#define {name} ...")
    return lines


def _clean(declarations: str) -> str:
    """What pycparser (cffi) does not take: GNU attributes and __extension__."""
    text = _ATTRIBUTE.sub("", declarations)
    text = text.replace("__extension__", "")
    return "\n".join(line.strip() for line in text.splitlines() if line.strip()) + "\n"


def generate_cdef(single_precision: bool = False) -> str:
    """The cdef of the public headers (include/gearsim/gearsim.h and
    hil/include/gearsim/hil.h), without the bindings' own declarations
    (BINDINGS_CDEF)."""
    defines = ["-DGS_SINGLE_PRECISION"] if single_precision else []
    with tempfile.TemporaryDirectory(prefix="gearsim-cdef-") as tmp:
        stub_dir = Path(tmp)
        # cffi knows size_t and the fixed-width integers; nothing else of
        # <stddef.h> and <stdint.h> is used by the headers.
        (stub_dir / "stddef.h").write_text("/* stub: cffi declares size_t */\n")
        (stub_dir / "stdint.h").write_text("/* stub: cffi declares uint8_t, ... */\n")
        source = stub_dir / "cdef.c"
        source.write_text(CDEF_SOURCE)
        empty = stub_dir / "empty.c"
        empty.write_text("")
        declarations = _preprocess(["-P"], source, stub_dir, defines)
        macros = _preprocess(["-dM"], source, stub_dir, defines)
        predefined = _preprocess(["-dM"], empty, stub_dir, defines)
    header = (
        "/* generated by gearsim_build.py from include/gearsim/gearsim.h and "
        "hil/include/gearsim/hil.h */\n"
    )
    return header + "\n".join(_constants(macros, predefined)) + "\n" + _clean(declarations)


def _struct_names(cdef: str) -> list[str]:
    """Typedef names of the structs of a cdef (typedef struct {...} name;)."""
    return re.findall(r"^typedef\s+struct\s*\w*\s*\{[^}]*\}\s*(\w+)\s*;", cdef, re.M | re.S)


def _layout_table(cdef: str) -> str:
    """C of gspy_layouts(): the compiler's sizeof of every public struct and
    the offsetof and sizeof of each of its members."""
    probe = FFI()
    probe.cdef(cdef)
    rows = []
    for name in _struct_names(cdef):
        rows.append(f'    {{"{name}", "", 0, sizeof({name})}},')
        for member, _field in probe.typeof(name).fields:
            rows.append(
                f'    {{"{name}", "{member}", offsetof({name}, {member}), '
                f"sizeof((({name} *)0)->{member})}},"
            )
    body = "\n".join(rows)
    return (
        "typedef struct { const char *type; const char *member; size_t offset; size_t size; }"
        " gspy_layout;\n"
        f"static const gspy_layout gspy_layout_rows[] = {{\n{body}\n}};\n"
        "static const gspy_layout *gspy_layouts(size_t *count)\n{\n"
        "    *count = sizeof(gspy_layout_rows) / sizeof(gspy_layout_rows[0]);\n"
        "    return gspy_layout_rows;\n}\n"
    )


def _c_string(text: str) -> str:
    """text as a C string literal (one literal a line, concatenated)."""
    literals = [
        '    "' + line.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
        for line in text.splitlines(keepends=True)
    ]
    return "\n".join(literals) or '""'


def make_builder(absolute: bool = False) -> FFI:
    """The FFI builder of gearsim._gearsim (double precision), linked against
    gearsim_hil and gearsim_core (c_libraries(), built before it by build_clib)."""
    cdef = generate_cdef()
    builder = FFI()
    builder.cdef(cdef + BINDINGS_CDEF)
    stored = f"static const char *const GSPY_CDEF =\n{_c_string(cdef + BINDINGS_CDEF)};\n"
    builder.set_source(
        "gearsim._gearsim",
        CDEF_SOURCE + SHIM + _layout_table(cdef) + stored,
        include_dirs=[_path(INCLUDE_DIR, absolute), _path(HIL_INCLUDE_DIR, absolute)],
        # gearsim_hil calls the core: it comes first for the static linker
        libraries=[HIL_LIBRARY, CORE_LIBRARY] + ([] if sys.platform == "win32" else ["m"]),
        extra_compile_args=wrapper_cflags(),
    )
    return builder


if __name__ == "__main__":
    if sys.argv[1:] == ["--cdef"]:
        sys.stdout.write(generate_cdef() + BINDINGS_CDEF)
    else:
        # In-place build for development: puts gearsim/_gearsim.*.so in the
        # package (build_clib, then the wrapper).
        sys.exit(subprocess.call([sys.executable, "setup.py", "build_ext", "--inplace"], cwd=ROOT))
