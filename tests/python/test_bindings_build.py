"""The extension's build: the cffi cdef generated from the public headers and
checked against them and the compiler, the library's warning set applied to
src/, and only the public API exported (bindings/python/gearsim_build.py)."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gearsim._lib import INPUT_INFO, OUTPUT_INFO, STATE_INFO, ffi, lib

ROOT = Path(__file__).resolve().parents[2]
# the core's public headers and the HIL library's, which the cdef is made of
HEADERS = sorted((ROOT / "include" / "gearsim").glob("*.h")) + [
    ROOT / "hil" / "include" / "gearsim" / "hil.h"
]


def _build_module():
    spec = importlib.util.spec_from_file_location(
        "gearsim_build", ROOT / "bindings" / "python" / "gearsim_build.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


build = _build_module()


def _compiler_or_skip() -> list[str]:
    cc = build.preprocessor()
    if sys.platform == "win32" or shutil.which(cc[0]) is None:
        pytest.skip(f"no C compiler {cc[0]!r}")
    return cc


def _header_code() -> str:
    """The public headers without comments and preprocessor lines."""
    text = "\n".join(h.read_text() for h in HEADERS)
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    text = re.sub(r"^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", " ", text, flags=re.M)
    return text


def _public_api() -> tuple[set[str], set[str]]:
    """Names of the GS_API functions and of the GS_API extern tables."""
    code = _header_code()
    functions, tables = set(), set()
    for match in re.finditer(r"\bGS_API\b([^;{]*?)\b(\w+)\s*([(\[])", code):
        (tables if match.group(3) == "[" else functions).add(match.group(2))
    return functions, tables


def test_the_header_scan_finds_the_api():
    functions, tables = _public_api()
    assert {"gs_rig_init_gear", "gs_rig_step", "gs_rig_run", "gs_version"} <= functions
    assert tables == set(FIELD_TABLES) | set(PARAM_TABLES)


#: The exported tables: field tables (gearsim/fields.h) and parameter tables
#: (gearsim/parameters.h), with the constant that gives their length.
FIELD_TABLES = {
    "gs_rig_input_info": "GS_RIG_INPUT_FIELDS",
    "gs_rig_output_info": "GS_RIG_OUTPUT_FIELDS",
    "gs_rig_state_info": "GS_RIG_STATE_FIELDS",
}
PARAM_TABLES = {
    "gs_rig_param_info": "GS_RIG_PARAM_FIELDS",
    "gs_simple_gear_param_info": "GS_SIMPLE_GEAR_PARAM_FIELDS",
    "gs_rack_pinion_param_info": "GS_RACK_PINION_PARAM_FIELDS",
    "gs_backlash_param_info": "GS_BACKLASH_PARAM_FIELDS",
}


def test_every_public_function_and_table_is_in_the_cdef():
    functions, tables = _public_api()
    cdef = ffi.string(lib.GSPY_CDEF).decode()
    for name in sorted(functions):
        assert re.search(rf"\b{name}\s*\(", cdef), name
        assert ffi.typeof(getattr(lib, name)).kind == "function", name
    for name in sorted(tables):
        item = "gs_field_info" if name in FIELD_TABLES else "gs_param_info"
        assert re.search(rf"\bextern const {item} {name}\[[^\]]+\];", cdef), name
        table_type = ffi.typeof(getattr(lib, name))
        assert table_type.item is ffi.typeof(item)
        count = getattr(lib, {**FIELD_TABLES, **PARAM_TABLES}[name])
        assert table_type.length == count, name


def test_the_hil_library_is_in_the_cdef():
    """gearsim.hil runs the C HIL library: every function of gearsim/hil.h
    is callable, and the send callback is the bindings' own."""
    code = _header_code()
    declared = set(re.findall(r"\b(gs_hil_\w+)\s*\(", code))
    assert {"gs_hil_bridge_init", "gs_hil_handle", "gs_hil_advance", "gs_hil_dbc_check"} <= declared
    for name in sorted(declared):
        assert ffi.typeof(getattr(lib, name)).kind == "function", name
    assert ffi.typeof(lib.gspy_hil_send) is ffi.typeof("int(*)(void *, const gs_hil_frame *)")


def test_the_extension_was_built_from_these_headers():
    """The cdef stored in the extension is what the headers give today (a
    stale extension fails here: rebuild with pip install -e .)."""
    _compiler_or_skip()
    stored = ffi.string(lib.GSPY_CDEF).decode()
    assert stored == build.generate_cdef() + build.BINDINGS_CDEF


def test_the_generated_cdef_parses_in_both_precisions():
    _compiler_or_skip()
    from cffi import FFI

    for single in (False, True):
        text = build.generate_cdef(single_precision=single)
        probe = FFI()
        probe.cdef(text)
        real = probe.sizeof("gs_real")
        assert real == (4 if single else 8)
        assert probe.sizeof("gs_rig_input") == 5 * real
        if single:  # the float build's init functions carry the _f32 suffix
            assert "gs_rig_init_gear_f32(" in text


def test_struct_layouts_are_the_compilers():
    """Every public struct: cffi's sizeof and offsetof equal the C compiler's
    (gspy_layouts, compiled from the headers into the extension)."""
    count = ffi.new("size_t *")
    rows = lib.gspy_layouts(count)
    types = set()
    for i in range(count[0]):
        row = rows[i]
        ctype = ffi.string(row.type).decode()
        member = ffi.string(row.member).decode()
        types.add(ctype)
        if member:
            field = dict(ffi.typeof(ctype).fields)[member]
            assert (ffi.offsetof(ctype, member), ffi.sizeof(field.type)) == (
                row.offset,
                row.size,
            ), f"{ctype}.{member}"
        else:
            assert ffi.sizeof(ctype) == row.size, ctype
    declared = set(re.findall(r"typedef\s+struct\s*\w*\s*\{[^}]*\}\s*(\w+)\s*;", _header_code()))
    assert declared == types
    assert {"gs_rig_state", "gs_rig_consts", "gs_block_state", "gs_rig_info"} <= types


def test_published_sizes():
    real = ffi.sizeof("gs_real")
    assert ffi.sizeof("gs_rig_consts") == lib.GS_RIG_CONSTS_REALS * real
    assert ffi.sizeof("gs_simple_gear_consts") == lib.GS_BLOCK_CONSTS_REALS * real
    assert ffi.sizeof("gs_rack_pinion_consts") == lib.GS_BLOCK_CONSTS_REALS * real
    assert ffi.sizeof("gs_rig_input") == lib.GS_RIG_INPUT_FIELDS * real
    assert ffi.sizeof("gs_rig_output") == lib.GS_RIG_OUTPUT_FIELDS * real


def test_field_tables_agree_with_the_cdef():
    """The library's tables (compiled with its own flags) name the cdef's
    members at the cdef's offsets."""
    for info, ctype in (
        (INPUT_INFO, "gs_rig_input"),
        (OUTPUT_INFO, "gs_rig_output"),
    ):
        assert [f.name for f in info] == [name for name, _ in ffi.typeof(ctype).fields]
        for f in info:
            assert ffi.offsetof(ctype, f.name) == f.offset
            assert f.gear_unit and f.rack_unit and f.doc
    block = [name for name, _ in ffi.typeof("gs_block_state").fields]
    rig = [name for name, _ in ffi.typeof("gs_rig_state").fields if name != "block"]
    assert [f.name for f in STATE_INFO] == block + rig
    for f in STATE_INFO:
        path = ("block", f.name) if f.name in block else (f.name,)
        assert ffi.offsetof("gs_rig_state", *path) == f.offset
        kind = "int" if f.is_integer else "gs_real"
        owner = ffi.typeof("gs_block_state" if f.name in block else "gs_rig_state")
        assert dict(owner.fields)[f.name].type is ffi.typeof(kind)


def test_parameter_tables_agree_with_the_cdef():
    """The parameter tables (gearsim/parameters.h, compiled into the library)
    name the cdef's members, at its offsets and sizes, in member order, and
    their option values are the cdef's enumerators."""

    def check(table, count: int, ctype: str) -> int:
        fields = ffi.typeof(ctype).fields
        assert [ffi.string(table[i].member).decode() for i in range(count)] == [
            n for n, _ in fields
        ]
        options = 0
        for i in range(count):
            e = table[i]
            member = ffi.string(e.member).decode()
            assert ffi.offsetof(ctype, member) == e.offset, member
            assert ffi.sizeof(dict(fields)[member].type) == e.size, member
            if e.kind == lib.GS_PARAM_GROUP:
                options += check(e.members, e.member_count, dict(fields)[member].type.cname)
            for k in range(e.options.count):
                item = e.options.items[k]
                assert getattr(lib, ffi.string(item.enumerator).decode()) == item.value
                options += 1
        return options

    assert check(lib.gs_rig_param_info, lib.GS_RIG_PARAM_FIELDS, "gs_rig_params") == 4
    assert (
        check(
            lib.gs_simple_gear_param_info, lib.GS_SIMPLE_GEAR_PARAM_FIELDS, "gs_simple_gear_params"
        )
        == 12
    )
    assert (
        check(
            lib.gs_rack_pinion_param_info, lib.GS_RACK_PINION_PARAM_FIELDS, "gs_rack_pinion_params"
        )
        == 12
    )


def test_every_header_constant_and_enumerator_reaches_python():
    text = "\n".join(h.read_text() for h in HEADERS)
    macros = set(re.findall(r"^\s*#\s*define\s+(GS_[A-Z0-9_]+)[ \t]+\S", text, flags=re.M))
    macros -= {"GS_API"}  # the export attribute, defined empty for the cdef
    for name in sorted(macros):
        assert hasattr(lib, name), name
    enumerators = re.findall(
        r"^\s*(GS_[A-Z0-9_]+)\s*=\s*(-?\d+)[ \t]*,?[ \t]*$", _header_code(), re.M
    )
    # with explicit values: the statuses, the parameter kinds, the rig blocks
    # (the option enums take 0, 1, ... from their lists: checked with the
    # parameter tables above)
    assert len(enumerators) >= 30
    for name, value in enumerators:
        assert getattr(lib, name) == int(value), name
    version = re.search(r'#define\s+GS_VERSION_STRING\s+"([^"]+)"', text).group(1)
    assert ffi.string(lib.GS_VERSION_STRING).decode() == version
    assert ffi.string(lib.gs_version()).decode() == version


# ---- the library's warnings on src/


def test_the_warning_list_is_applied_to_src():
    flags = build.core_cflags()
    listed = [
        line.split("#", 1)[0].strip()
        for line in (ROOT / "cmake" / "gearsim_warnings.txt").read_text().splitlines()
    ]
    listed = [f for f in listed if f]
    assert listed and "-Wsign-conversion" in listed
    if sys.platform != "win32":
        assert all(f in flags for f in listed)
        assert {"-ffp-contract=off", "-fno-fast-math", "-std=c99"} <= set(flags)
    name, info = build.core_library()
    assert name == "gearsim_core" and info["cflags"] == flags
    assert sorted(info["sources"]) == sorted(
        p.relative_to(ROOT).as_posix() for p in (ROOT / "src").glob("*.c")
    )


def _compile(cc: list[str], source: Path, flags: list[str]) -> str:
    done = subprocess.run(
        [*cc, "-O2", *flags, "-I", str(ROOT / "include"), "-I", str(ROOT / "src")]
        + ["-c", str(source), "-o", "/dev/null"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return done.stderr


def test_src_compiles_without_warnings():
    cc = _compiler_or_skip()
    for source in sorted((ROOT / "src").glob("*.c")):
        assert _compile(cc, source, build.core_cflags()) == "", source.name


def test_a_warning_in_src_would_show(tmp_path):
    """The flags take effect: a sign conversion, which -Wall -Wextra alone let
    pass, is reported."""
    cc = _compiler_or_skip()
    source = tmp_path / "bad.c"
    source.write_text(
        "#include <stddef.h>\n"
        "size_t gs_scratch_index(int i);\n"
        "size_t gs_scratch_index(int i) { return i; }\n"
    )
    assert _compile(cc, source, ["-std=c99", "-Wall", "-Wextra"]) == ""
    assert "-Wsign-conversion" in _compile(cc, source, build.core_cflags())


def test_the_extension_exports_only_the_public_api():
    from gearsim import _gearsim

    nm = shutil.which("nm")
    path = Path(_gearsim.__file__)
    if nm is None or sys.platform != "linux" or path.suffix != ".so":
        pytest.skip("needs nm and an ELF extension")
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(path)], capture_output=True, text=True, check=True
    ).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.strip()}
    functions, tables = _public_api()
    assert exported - {"PyInit__gearsim"} == functions | tables


# ---- the extension's numerics are the C library's


def _golden() -> dict[str, int]:
    """The double build's golden hashes of tests/c/test_determinism.c (read
    from there: one place to update them)."""
    text = (ROOT / "tests" / "c" / "test_determinism.c").read_text()
    double = text[text.index("#else", text.index("#ifdef GS_SINGLE_PRECISION")) :]
    return {
        kind: int(re.search(rf"#define GOLDEN_{kind.upper()} (0x[0-9A-F]+)ULL", double)[1], 16)
        for kind in ("gear", "rack")
    }


def _scripted_inputs(torque_driven: bool, n: int = 3000):
    """script_inputs() of tests/c/test_determinism.c (same xorshift64, same
    libm sin, same operation order)."""
    import math

    import numpy as np

    mask, s = (1 << 64) - 1, 20240601

    def unit() -> float:
        nonlocal s
        s ^= (s << 13) & mask
        s ^= s >> 7
        s ^= (s << 17) & mask
        return (s >> 11) * (1.0 / 9007199254740992.0)

    def uniform(lo: float, hi: float) -> float:
        return lo + (hi - lo) * unit()

    pi = 3.14159265358979323846
    rows = np.zeros((n, len(INPUT_INFO)))
    col = {f.name: f.offset // 8 for f in INPUT_INFO}
    for k in range(n):
        t = k * 1e-3
        base = 8.0 * math.sin(2.0 * pi * 1.5 * t) + (-6.0 if 1500 < k < 1800 else 0.0)
        load = 0.6 * math.sin(2.0 * pi * 0.4 * t) + (0.8 if k > 2200 else 0.0)
        if 1000 < k < 1200:
            base = 0.0
        base += uniform(-0.05, 0.05)
        if torque_driven:
            base = 0.3 * math.sin(2.0 * pi * 1.1 * t) + uniform(-0.02, 0.02)
            load *= 5.0
        rows[k, col["base_speed"]] = rows[k, col["base_torque"]] = base
        rows[k, col["load"]] = load
        rows[k, col["ambient_temperature"]] = 296.0 + 2.0 * math.sin(t)
        rows[k, col["measured_temperature"]] = 305.0
    return rows


def _fnv1a64(data: bytes) -> int:
    h = 0xCBF29CE484222325
    for byte in data:
        h = ((h ^ byte) * 0x100000001B3) & ((1 << 64) - 1)
    return h


def _full_rig(rack: bool):
    """init_full() of tests/c/test_determinism.c, through the C API."""
    rp = ffi.new("gs_rig_params *", lib.gs_rig_params_default())
    if rack:
        bp = ffi.new("gs_rack_pinion_params *", lib.gs_rack_pinion_params_default())
        bp.parameterization = lib.GS_PARAMETERIZE_TOOTH_PARAMETERS
        bp.teeth_count, bp.spacing_m = 24.0, 0.006
        bp.rack_directionality = lib.GS_RACK_NEGATIVE
        bp.friction_model = lib.GS_FRICTION_CONSTANT_EFFICIENCY
        bp.efficiency_const, bp.power_threshold_W = 0.82, 0.02
        bp.pinion_viscous_coefficient, bp.rack_viscous_coefficient = 0.001, 1.5
        bp.backlash = lib.gs_simple_gear_params_default().backlash
        bp.backlash.enabled = 1
        bp.backlash.hard_stop_model = lib.GS_HARD_STOP_FULL_DAMPED
        bp.backlash.linear_backlash_m = 5e-4
        bp.backlash.stiffness_N_m, bp.backlash.damping_N_s_m = 2e6, 800.0
        rp.dt_s, rp.base_drive = 1e-3, lib.GS_BASE_TORQUE_DRIVEN
        rp.base_inertia_kg_m2, rp.initial_base_speed_rad_s = 2e-3, 1.0
        rp.driven_inertia, rp.load_coulomb_friction = 1.2, 2.0
        rp.load_coulomb_speed_threshold, rp.contact_substeps = 0.005, 8
        init = lib.gs_rig_init_rack
    else:
        bp = ffi.new("gs_simple_gear_params *", lib.gs_simple_gear_params_default())
        bp.teeth_ratio, bp.output_shaft_rotates = 3.2, lib.GS_ROTATES_OPPOSITE
        bp.friction_model = lib.GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY
        bp.power_threshold_W = 0.05
        bp.viscous_coefficients = [0.002, 0.004]
        bp.thermal_mass_J_K, bp.initial_temperature_K = 3.0, 295.0
        b = bp.backlash
        b.enabled, b.hard_stop_model = 1, lib.GS_HARD_STOP_SMOOTH
        b.linear_backlash_m, b.base_radius_m, b.transition_region_m = 8e-4, 0.04, 5e-5
        b.stiffness_N_m, b.damping_N_s_m, b.initial_position_m = 5e6, 400.0, 1e-4
        rp.dt_s, rp.base_inertia_kg_m2, rp.driven_inertia = 5e-4, 0.003, 0.02
        rp.load_coulomb_friction, rp.load_coulomb_speed_threshold = 0.05, 0.01
        rp.load_offset, rp.heat_path, rp.thermal_resistance_K_W = 0.1, 1, 4.0
        rp.accel_filter_time_constant_s, rp.contact_substeps = 0.002, 0
        init = lib.gs_rig_init_gear
    consts, state = ffi.new("gs_rig_consts *"), ffi.new("gs_rig_state *")
    err = ffi.new("gs_error *")
    assert init(consts, state, bp, rp, err) == lib.GS_OK, ffi.string(err.message)
    return consts, state


@pytest.mark.skipif(
    not (ROOT / "tests" / "c" / "test_determinism.c").is_file(), reason="no tests/c"
)
@pytest.mark.parametrize("kind", ["gear", "rack"])
def test_the_extension_reproduces_the_c_golden_hashes(kind):
    """src/ compiled by the Python build gives the C tests' bits (the golden
    FNV-1a hashes of test_determinism.c, over the 15 outputs in the order
    fields.h declares them, which is the hashed order)."""
    import numpy as np

    consts, state = _full_rig(kind == "rack")
    inputs = np.ascontiguousarray(_scripted_inputs(kind == "rack"))
    out = np.empty((inputs.shape[0], len(OUTPUT_INFO)))
    lib.gs_rig_run(
        consts,
        state,
        inputs.shape[0],
        ffi.cast("gs_rig_input *", ffi.from_buffer(inputs)),
        ffi.cast("gs_rig_output *", ffi.from_buffer(out, require_writable=True)),
    )
    assert _fnv1a64(out.astype("<f8").tobytes()) == _golden()[kind]
