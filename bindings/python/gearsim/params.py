"""The parameters of the blocks and rigs: program name, kind, SI unit, C field
and description of each, read from the C core's parameter tables
(gs_simple_gear_param_info, gs_rack_pinion_param_info, gs_backlash_param_info,
gs_rig_param_info), which are expanded from the one declaration of every
parameter, include/gearsim/parameters.h. Nothing about a parameter is written
here (docs/physics.md sections 9-11, docs/python-api.md).

This module converts user values (plain SI numbers, unit strings, lists) into
normalised Python values, writes them into the C ``*_params`` structs and reads
the C defaults back. It never re-implements a validity rule that the C core
checks; the only checks made here are those the C structs cannot express:
types, table capacity, and the lengths of tables that share one C count
(``efficiency_vector`` vs ``temperature_vector``, the shape of
``efficiency_matrix``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from numbers import Integral, Real
from typing import Any

import numpy as np

from ._lib import ffi, lib, status_message, status_name
from .errors import ModelFileError, ParameterError
from .units import UnitConversionError, to_si

__all__ = [
    "Param",
    "SIMPLE_GEAR_PARAMS",
    "RACK_PINION_PARAMS",
    "GEAR_RIG_PARAMS",
    "RACK_RIG_PARAMS",
    "BLOCKS",
    "param_units",
]

REAL = "real"  # float
VECTOR = "vector"  # list of floats (a table of up to GS_TABLE_MAX entries)
MATRIX = "matrix"  # list of rows (lists of floats)
ARRAY = "array"  # list of exactly Param.length floats
OPTION = "option"  # one string of a fixed list
BOOL = "bool"
INT = "int"
OPTIONAL_REAL = "optional_real"  # float or None (absent)


@dataclass(frozen=True)
class Param:
    """One user parameter.

    name: program name (TOML key, Python keyword, error ``.parameter``).
    kind: REAL, VECTOR, MATRIX, ARRAY, OPTION, BOOL, INT or OPTIONAL_REAL.
    unit: SI unit in pint syntax ("" = dimensionless); unit strings given by the
        user are converted to it.
    field: C field path in the params struct ("backlash.stiffness_N_m"), or ""
        for a parameter that lives only in Python.
    count: C field holding the used length of a VECTOR, or the rows of a MATRIX.
    count2: C field holding the columns of a MATRIX.
    sets_count: writing this VECTOR sets its count (the first table that names
        a count owns it; later ones must have the same length where used).
    length: number of values of an ARRAY.
    options: (option string, C enum value) pairs of an OPTION.
    doc: one line for the documentation.
    """

    name: str
    kind: str
    unit: str = ""
    field: str = ""
    count: str = ""
    count2: str = ""
    sets_count: bool = False
    length: int = 0
    options: tuple[tuple[str, int], ...] = ()
    doc: str = ""

    def option_value(self, text: str) -> int:
        """C enum value of an option string."""
        return dict(self.options)[text]

    def option_text(self, value: int) -> str:
        for text, c_value in self.options:
            if c_value == int(value):
                return text
        raise ValueError(f"{self.name}: C value {value} has no option string")  # pragma: no cover


# ---------------------------------------------------------------- the C tables


def _text(p: Any) -> str:
    return ffi.string(p).decode("utf-8") if p != ffi.NULL else ""


_KINDS = {
    int(lib.GS_PARAM_REAL): REAL,
    int(lib.GS_PARAM_INT): INT,
    int(lib.GS_PARAM_BOOL): BOOL,
    int(lib.GS_PARAM_OPTION): OPTION,
    int(lib.GS_PARAM_ARRAY): ARRAY,
    int(lib.GS_PARAM_TABLE): VECTOR,
    int(lib.GS_PARAM_MATRIX): MATRIX,
}


def _entries(table: Any, count: int, prefix: str = "") -> Iterator[tuple[Any, str, str]]:
    """(entry, C field path, field path prefix) of a C parameter table, nested
    groups (the backlash) flattened in member order."""
    for i in range(count):
        e = table[i]
        if int(e.kind) == int(lib.GS_PARAM_GROUP):
            yield from _entries(e.members, int(e.member_count), f"{prefix}{_text(e.member)}.")
        else:
            yield e, prefix + _text(e.member), prefix


def _options(e: Any) -> tuple[tuple[str, int], ...]:
    o = e.options
    return tuple((_text(o.items[k].name), int(o.items[k].value)) for k in range(int(o.count)))


def _from_table(table: Any, count: int, rack: bool) -> tuple[Param, ...]:
    """The user parameters of a C parameter table in one rig: the counts are
    set from the tables' lengths, not given; GEAR_ONLY entries are left out of
    the rack rig."""
    specs = []
    owned: set[str] = set()
    for e, field, prefix in _entries(table, count):
        kind = int(e.kind)
        if kind == int(lib.GS_PARAM_COUNT) or (
            rack and int(e.flags) == int(lib.GS_PARAM_GEAR_ONLY)
        ):
            continue
        counter = prefix + _text(e.count) if _text(e.count) else ""
        sets_count = kind == int(lib.GS_PARAM_TABLE) and counter not in owned
        if sets_count:
            owned.add(counter)
        specs.append(
            Param(
                name=_text(e.rack_key if rack else e.key),
                kind=_KINDS[kind],
                unit=_text(e.rack_unit if rack else e.gear_unit),
                field=field,
                count=counter,
                count2=prefix + _text(e.count2) if _text(e.count2) else "",
                sets_count=sets_count,
                length=int(e.length),
                options=_options(e),
                doc=_text(e.doc),
            )
        )
    return tuple(specs)


SIMPLE_GEAR_PARAMS: tuple[Param, ...] = _from_table(
    lib.gs_simple_gear_param_info, lib.GS_SIMPLE_GEAR_PARAM_FIELDS, rack=False
)
RACK_PINION_PARAMS: tuple[Param, ...] = _from_table(
    lib.gs_rack_pinion_param_info, lib.GS_RACK_PINION_PARAM_FIELDS, rack=True
)

# The Python rig takes the step and the temperature source as arguments of
# Rig (dt=..., temperature_input=...), not as model-file keys; it sets the
# heat path from thermal_resistance (absent = adiabatic); and it has one
# parameter of its own, the ambient temperature that run() and step() use when
# they are given none.
RIG_ARGUMENTS = ("dt", "temperature_input")
_HEAT_PATH = "heat_path"
_OPTIONAL = "thermal_resistance"
_AMBIENT = Param(
    "ambient_temperature", REAL, "K", doc="ambient temperature used when run/step get none"
)

#: Python-side default of the rig parameters the C rig does not hold.
PYTHON_RIG_DEFAULTS: dict[str, Any] = {_OPTIONAL: None, _AMBIENT.name: 293.15}


def _rig_specs(rack: bool) -> tuple[tuple[Param, ...], dict[str, Param]]:
    """The rig's model-file parameters, and its argument parameters (dt, ...)."""
    all_specs = _from_table(lib.gs_rig_param_info, lib.GS_RIG_PARAM_FIELDS, rack)
    specs: list[Param] = []
    for p in all_specs:
        if p.name in RIG_ARGUMENTS or p.name == _HEAT_PATH:
            continue
        if p.name == _OPTIONAL:
            specs += [replace(p, kind=OPTIONAL_REAL, doc=f"{p.doc}; absent = adiabatic"), _AMBIENT]
        else:
            specs.append(p)
    return tuple(specs), {p.name: p for p in all_specs if p.name in RIG_ARGUMENTS}


GEAR_RIG_PARAMS, RIG_ARGUMENT_PARAMS = _rig_specs(rack=False)
RACK_RIG_PARAMS, _ = _rig_specs(rack=True)

#: Block name -> (block parameters, rig parameters, C params type, default function).
BLOCKS: dict[str, tuple[tuple[Param, ...], tuple[Param, ...], str, str]] = {
    "simple_gear": (
        SIMPLE_GEAR_PARAMS,
        GEAR_RIG_PARAMS,
        "gs_simple_gear_params",
        "gs_simple_gear_params_default",
    ),
    "rack_pinion": (
        RACK_PINION_PARAMS,
        RACK_RIG_PARAMS,
        "gs_rack_pinion_params",
        "gs_rack_pinion_params_default",
    ),
}


def c_rig_names(block: str) -> dict[str, str]:
    """C member of gs_rig_params -> the Python name in a rig of this block, where
    they differ (to translate a gs_error that names a member)."""
    rack = block == "rack_pinion"
    return {
        _text(e.member): _text(e.rack_key if rack else e.key)
        for e, _, _ in _entries(lib.gs_rig_param_info, lib.GS_RIG_PARAM_FIELDS)
        if _text(e.member) != _text(e.rack_key if rack else e.key)
    }


def units_of(specs: Iterable[Param]) -> dict[str, str]:
    """Parameter name -> SI unit (pint syntax) of the numeric parameters of specs."""
    return {p.name: p.unit for p in specs if p.kind not in (OPTION, BOOL, INT)}


def param_units(block: str) -> dict[str, str]:
    """Parameter name -> SI unit (pint syntax) of a block's block and rig parameters."""
    block_specs, rig_specs, _, _ = BLOCKS[block]
    return units_of((*block_specs, *rig_specs))


def describe(specs: Iterable[Param]) -> str:
    """One line per parameter (name, unit or options, description), for docstrings."""
    lines = []
    for p in specs:
        if p.options:
            what = " | ".join(repr(text) for text, _ in p.options)
        elif p.kind in (BOOL, INT):
            what = p.kind
        else:
            what = p.unit or "1"
            if p.kind == ARRAY:
                what = f"{p.length} values, {what}"
            elif p.kind in (VECTOR, MATRIX):
                what = f"{p.kind}, {what}"
        lines.append(f"    {p.name} ({what}): {p.doc}")
    return "\n".join(lines)


# ---------------------------------------------------------------- documentation


def _doc_number(x: float) -> str:
    text = f"{x:.15g}"
    return text.replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


def _doc_value(p: Param, value: Any) -> str:
    """A default as the docs write it."""
    if value is None:
        return "absent"
    if p.kind == OPTION:
        return f'`"{value}"`'
    if p.kind == BOOL:
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(_doc_value(p, v) for v in value) + "]"
    if isinstance(value, int):
        return str(value)
    return _doc_number(float(value))


def _doc_kind(p: Param, unit: str) -> str:
    if p.options:
        return " / ".join(f'`"{text}"`' for text, _ in p.options)
    if p.kind in (BOOL, INT):
        return {BOOL: "bool", INT: "integer"}[p.kind]
    unit = unit or "–"
    if p.kind == ARRAY:
        return f"{p.length} values, {unit}"
    return unit


def markdown_table(block: str, part: str) -> str:
    """The Markdown table of a block's "block" or "rig" parameters (key, SI
    unit or options, default, meaning), from the C tables and defaults; the rig
    table gives both rigs' names and units. docs/python.md carries these
    (doc_tables() prints them; a test keeps them current)."""
    rows = ["| key | SI unit / values | default | meaning |", "|---|---|---|---|"]
    if part == "block":
        specs, _, _, _ = BLOCKS[block]
        defaults = block_defaults(block)
        for p in specs:
            what = _doc_kind(p, p.unit)
            rows.append(f"| `{p.name}` | {what} | {_doc_value(p, defaults[p.name])} | {p.doc} |")
        return "\n".join(rows)
    rows[0] = "| key | SI unit / values (gear rig; rack rig) | default | meaning |"
    rows.append('| `block` | `"simple_gear"` / `"rack_pinion"` | required | the block |')
    gear_defaults = rig_defaults("simple_gear")
    for g, r in zip(GEAR_RIG_PARAMS, RACK_RIG_PARAMS, strict=True):
        name = f"`{g.name}`" if g.name == r.name else f"`{g.name}` (gear) / `{r.name}` (rack)"
        what = _doc_kind(g, g.unit)
        if r.unit != g.unit:
            what = f"{what}; {_doc_kind(r, r.unit)}"
        rows.append(f"| {name} | {what} | {_doc_value(g, gear_defaults[g.name])} | {g.doc} |")
    return "\n".join(rows)


def doc_tables() -> str:
    """The three tables of docs/python.md: Simple Gear, Rack & Pinion, rig."""
    parts = (("simple_gear", "block"), ("rack_pinion", "block"), ("simple_gear", "rig"))
    return "\n\n".join(markdown_table(block, part) for block, part in parts)


# ---------------------------------------------------------------- conversion


def _type_error(p: Param, expected: str, value: Any) -> ModelFileError:
    return ModelFileError(
        f"expected {expected}, got {type(value).__name__} {value!r}", parameter=p.name
    )


def _is_number(value: Any) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def _scalar(p: Param, value: Any) -> float:
    if _is_number(value):
        return float(value)
    if isinstance(value, str):
        try:
            result = to_si(value, p.unit)
        except UnitConversionError as exc:
            raise ParameterError(str(exc), parameter=p.name) from None
        if isinstance(result, list):
            raise _type_error(p, "a number", value)
        return result
    unit = f" (SI: {p.unit})" if p.unit else ""
    raise _type_error(p, f"a number or a unit string{unit}", value)


def _vector(p: Param, value: Any) -> list[float]:
    if isinstance(value, str):
        try:
            result = to_si(value, p.unit)
        except UnitConversionError as exc:
            raise ParameterError(str(exc), parameter=p.name) from None
        values = result if isinstance(result, list) else [result]
    elif _is_sequence(value):
        values = [_scalar(p, item) for item in _items(p, value)]
    else:
        raise _type_error(p, "a list of numbers", value)
    return values


def _is_sequence(value: Any) -> bool:
    if isinstance(value, (str, bytes, Mapping)):
        return False
    return isinstance(value, Sequence) or hasattr(value, "__array__")


def _items(p: Param, value: Any) -> list[Any]:
    if hasattr(value, "__array__") and not isinstance(value, Sequence):
        arr = np.asarray(value)
        if arr.ndim != 1:
            raise _type_error(p, "a one-dimensional list of numbers", value)
        return arr.tolist()
    return list(value)


def normalize(p: Param, value: Any) -> Any:
    """User value -> normalised Python value (SI floats, lists, str, bool, int).

    Raises ModelFileError for a wrong type, ParameterError for a value that
    cannot be stored (bad unit, unknown option, table longer than GS_TABLE_MAX).
    """
    kind = p.kind
    if kind == REAL:
        return _scalar(p, value)
    if kind == OPTIONAL_REAL:
        return None if value is None else _scalar(p, value)
    if kind == BOOL:
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        raise _type_error(p, "true or false", value)
    if kind == INT:
        if isinstance(value, Integral) and not isinstance(value, bool):
            return int(value)
        raise _type_error(p, "an integer", value)
    if kind == OPTION:
        if not isinstance(value, str):
            raise _type_error(p, "a string", value)
        allowed = [text for text, _ in p.options]
        if value not in allowed:
            raise ParameterError(
                f"{value!r} is not one of {', '.join(repr(a) for a in allowed)}",
                parameter=p.name,
                status=status_name(lib.GS_E_OPTION),
            )
        return value
    if kind in (VECTOR, ARRAY):
        values = _vector(p, value)
        if kind == ARRAY and len(values) != p.length:
            raise ParameterError(
                f"needs exactly {p.length} values, got {len(values)}",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_SIZE_MISMATCH),
            )
        if len(values) > lib.GS_TABLE_MAX:
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_LENGTH)} (GS_TABLE_MAX = {lib.GS_TABLE_MAX}, "
                f"got {len(values)})",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_LENGTH),
            )
        return values
    if kind == MATRIX:
        if not _is_sequence(value):
            raise _type_error(p, "a list of rows (lists of numbers)", value)
        rows = _items_2d(p, value)
        width = {len(r) for r in rows}
        if len(width) > 1:
            raise ParameterError(
                "rows have different lengths",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_SIZE_MISMATCH),
            )
        if len(rows) > lib.GS_TABLE_MAX or (rows and len(rows[0]) > lib.GS_TABLE_MAX):
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_LENGTH)} (GS_TABLE_MAX = {lib.GS_TABLE_MAX})",
                parameter=p.name,
                status=status_name(lib.GS_E_TABLE_LENGTH),
            )
        return rows
    raise AssertionError(kind)  # pragma: no cover


def _items_2d(p: Param, value: Any) -> list[list[float]]:
    if hasattr(value, "__array__") and not isinstance(value, Sequence):
        arr = np.asarray(value)
        if arr.ndim != 2:
            raise _type_error(p, "a two-dimensional list of numbers", value)
        value = arr.tolist()
    rows = []
    for row in value:
        if not _is_sequence(row):
            raise _type_error(p, "a list of rows (lists of numbers)", value)
        rows.append([_scalar(p, item) for item in _items(p, row)])
    return rows


def normalize_all(
    specs: Mapping[str, Param], values: Mapping[str, Any], what: str
) -> dict[str, Any]:
    """Normalise a mapping of user values; unknown keys raise ModelFileError."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        p = specs.get(key)
        if p is None:
            known = ", ".join(sorted(specs))
            raise ModelFileError(
                f"unknown {what} parameter {key!r} (known: {known})", parameter=str(key)
            )
        out[key] = normalize(p, value)
    return out


# ---------------------------------------------------------------- C structs


def _get_field(struct: Any, path: str) -> Any:
    obj = struct
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def _set_field(struct: Any, path: str, value: Any) -> None:
    *head, last = path.split(".")
    obj = struct
    for part in head:
        obj = getattr(obj, part)
    setattr(obj, last, value)


def read_struct(specs: Sequence[Param], struct: Any) -> dict[str, Any]:
    """C params struct -> normalised values (used for the C defaults): tables
    take their used length from their count field, the matrix is rows x
    columns of its two counts."""
    out: dict[str, Any] = {}
    for p in specs:
        if not p.field:
            continue
        raw = _get_field(struct, p.field)
        if p.kind in (REAL, OPTIONAL_REAL):
            out[p.name] = float(raw)
        elif p.kind == BOOL:
            out[p.name] = bool(raw)
        elif p.kind == INT:
            out[p.name] = int(raw)
        elif p.kind == OPTION:
            out[p.name] = p.option_text(int(raw))
        elif p.kind == ARRAY:
            out[p.name] = [float(raw[i]) for i in range(p.length)]
        elif p.kind == VECTOR:
            n = int(_get_field(struct, p.count))
            out[p.name] = [float(raw[i]) for i in range(n)]
        elif p.kind == MATRIX:
            rows = int(_get_field(struct, p.count))
            cols = int(_get_field(struct, p.count2))
            out[p.name] = [[float(raw[i][j]) for j in range(cols)] for i in range(rows)]
    return out


def write_struct(specs: Sequence[Param], values: Mapping[str, Any], struct: Any) -> None:
    """Write normalised values into a C params struct (fields not in values keep
    their current content)."""
    for p in specs:
        if not p.field or p.name not in values:
            continue
        value = values[p.name]
        if p.kind in (REAL, OPTIONAL_REAL):
            if value is not None:
                _set_field(struct, p.field, value)
        elif p.kind in (BOOL, INT):
            _set_field(struct, p.field, int(value))
        elif p.kind == OPTION:
            _set_field(struct, p.field, p.option_value(value))
        elif p.kind in (VECTOR, ARRAY):
            arr = _get_field(struct, p.field)
            for i, v in enumerate(value):
                arr[i] = v
            if p.sets_count:
                _set_field(struct, p.count, len(value))
        elif p.kind == MATRIX:
            arr = _get_field(struct, p.field)
            for i, row in enumerate(value):
                for j, v in enumerate(row):
                    arr[i][j] = v


def block_defaults(block: str) -> dict[str, Any]:
    """Defaults of a block's parameters, read from the C core."""
    specs, _, _, default_fn = BLOCKS[block]
    return read_struct(specs, getattr(lib, default_fn)())


def rig_defaults(block: str) -> dict[str, Any]:
    """Defaults of a rig's parameters: the C core's, plus the Python-side ones."""
    _, specs, _, _ = BLOCKS[block]
    values = read_struct(specs, lib.gs_rig_params_default())
    values.update(PYTHON_RIG_DEFAULTS)
    return values


def check_table_shapes(block: str, values: Mapping[str, Any]) -> None:
    """Lengths of tables that share one C count (the C struct cannot tell).

    Checked only where the friction model uses the tables (the C core does not
    validate inactive parameters either), and only once temperature_vector and
    load_vector have a length the C core accepts, so that the C core reports
    problems of the breakpoints themselves.
    """
    model = values["friction_model"]
    n_t = len(values["temperature_vector"])
    ok_t = 2 <= n_t <= lib.GS_TABLE_MAX
    mismatch = status_name(lib.GS_E_TABLE_SIZE_MISMATCH)
    if model == "temperature_dependent_efficiency" and ok_t:
        n_e = len(values["efficiency_vector"])
        if n_e != n_t:
            raise ParameterError(
                f"{status_message(lib.GS_E_TABLE_SIZE_MISMATCH)}: {n_e} efficiencies for "
                f"{n_t} temperatures",
                parameter="efficiency_vector",
                status=mismatch,
            )
    if block == "simple_gear" and model == "temperature_load_dependent_efficiency":
        n_l = len(values["load_vector"])
        matrix = values["efficiency_matrix"]
        if ok_t and 2 <= n_l <= lib.GS_TABLE_MAX:
            shape = (len(matrix), len(matrix[0]) if matrix else 0)
            if shape != (n_t, n_l):
                raise ParameterError(
                    f"{status_message(lib.GS_E_TABLE_SIZE_MISMATCH)}: {shape[0]} x {shape[1]} "
                    f"matrix for {n_t} temperatures x {n_l} loads",
                    parameter="efficiency_matrix",
                    status=mismatch,
                )


def canonical(value: Any) -> Any:
    """Hashable, exactly comparable form of a normalised value (floats by bit
    pattern, so NaN equals NaN and -0.0 differs from 0.0)."""
    if isinstance(value, float):
        return ("f", value.hex() if math.isfinite(value) else repr(value))
    if isinstance(value, (list, tuple)):
        return tuple(canonical(v) for v in value)
    if isinstance(value, Mapping):
        return tuple(sorted((k, canonical(v)) for k, v in value.items()))
    return value


def new_struct(ctype: str) -> Any:
    return ffi.new(ctype + " *")
