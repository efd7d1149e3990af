"""Access to the compiled C core (``gearsim._gearsim``, built by cffi in API mode
from include/gearsim and src/; see bindings/python/gearsim_build.py).

Everything that depends on the C layout is checked here once, at import. The
names, units and docs of the rig's inputs, outputs and state are read here from
the C field tables (gs_rig_input_info, ... of include/gearsim/fields.h).
"""

from __future__ import annotations

from typing import Any, NamedTuple

from .errors import GearsimError, ParameterError

try:
    from ._gearsim import ffi, lib  # type: ignore[import-not-found]
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        "gearsim: the compiled extension gearsim._gearsim is missing; install the "
        "package with `pip install .` (or `pip install -e .`) from the repository root"
    ) from exc

__all__ = [
    "ffi",
    "lib",
    "REAL_SIZE",
    "FieldInfo",
    "INPUT_INFO",
    "OUTPUT_INFO",
    "STATE_INFO",
    "status_name",
    "check",
]

REAL_SIZE: int = ffi.sizeof("gs_real")
if REAL_SIZE != 8:  # pragma: no cover - the package always uses the double build
    raise ImportError(f"gearsim: extension built with sizeof(gs_real) = {REAL_SIZE}, need double")


class FieldInfo(NamedTuple):
    """One entry of a C field table (gs_field_info, include/gearsim/fields.h)."""

    name: str  #: the field's name in every layer (C member, Python, FMU, CSV)
    gear_unit: str  #: unit in the Simple Gear rig (pint syntax)
    rack_unit: str  #: unit in the Rack & Pinion rig
    doc: str  #: one-line description
    offset: int  #: byte offset of the member in its C struct
    is_integer: bool  #: an int member (else gs_real)

    def unit(self, kind: str) -> str:
        """The unit in a rig of this block kind ("simple_gear" or "rack_pinion")."""
        return self.rack_unit if kind == "rack_pinion" else self.gear_unit


def _text(p: Any) -> str:
    return ffi.string(p).decode("utf-8") if p != ffi.NULL else ""


def _table(table: Any, count: int, ctype: str) -> tuple[FieldInfo, ...]:
    """A C field table of count entries, checked against the struct it describes."""
    fields = tuple(
        FieldInfo(
            _text(e.name),
            _text(e.gear_unit),
            _text(e.rack_unit),
            _text(e.doc),
            int(e.offset),
            bool(e.is_integer),
        )
        for e in (table[i] for i in range(count))
    )
    size = ffi.sizeof(ctype)
    names = [f.name for f in fields]
    if len(set(names)) != len(names) or not all(names):  # pragma: no cover
        raise ImportError(f"gearsim: the field table of {ctype} has empty or repeated names")
    for f in fields:
        width = ffi.sizeof("int") if f.is_integer else REAL_SIZE
        if f.offset + width > size:  # pragma: no cover
            raise ImportError(f"gearsim: field {f.name} lies outside {ctype}")
    return fields


def _packed_reals(fields: tuple[FieldInfo, ...], ctype: str) -> None:
    """Check that ctype is len(fields) gs_real members in table order (so that
    an array of N structs is an N x len(fields) array of doubles)."""
    if ffi.sizeof(ctype) != len(fields) * REAL_SIZE or any(
        f.is_integer or f.offset != i * REAL_SIZE for i, f in enumerate(fields)
    ):  # pragma: no cover
        raise ImportError(f"gearsim: {ctype} is not {len(fields)} packed gs_real fields")


#: The rig's inputs: the columns of the N x GS_RIG_INPUT_FIELDS input array.
INPUT_INFO: tuple[FieldInfo, ...] = _table(
    lib.gs_rig_input_info, lib.GS_RIG_INPUT_FIELDS, "gs_rig_input"
)
#: The rig's outputs: the columns of the N x GS_RIG_OUTPUT_FIELDS output array.
OUTPUT_INFO: tuple[FieldInfo, ...] = _table(
    lib.gs_rig_output_info, lib.GS_RIG_OUTPUT_FIELDS, "gs_rig_output"
)
#: The rig's state (gs_rig_state, its block's fields first).
STATE_INFO: tuple[FieldInfo, ...] = _table(
    lib.gs_rig_state_info, lib.GS_RIG_STATE_FIELDS, "gs_rig_state"
)
_packed_reals(INPUT_INFO, "gs_rig_input")
_packed_reals(OUTPUT_INFO, "gs_rig_output")


def status_name(status: int) -> str:
    """Name of a gs_status value ("GS_E_NOT_POSITIVE"), from the compiled enum."""
    name = ffi.string(ffi.cast("gs_status", status))
    return (
        name if isinstance(name, str) and not name.lstrip("-").isdigit() else f"GS_STATUS_{status}"
    )


def status_message(status: int) -> str:
    """gs_status_str() of a status."""
    return ffi.string(lib.gs_status_str(status)).decode("utf-8", "replace")


def check(
    status: int, err: Any, rename: dict[str, str] | None = None, value_of: Any = None
) -> None:
    """Raise ParameterError for a failed *_init (err is the gs_error * it filled).

    rename maps C parameter names to Python names where they differ; value_of
    is an optional callable name -> value used to quote the offending value.
    """
    if status == lib.GS_OK:
        return
    parameter = ffi.string(err.parameter).decode() if err.parameter != ffi.NULL else ""
    message = ffi.string(err.message).decode() if err.message != ffi.NULL else ""
    if not message:
        message = status_message(status)
    if rename:
        parameter = rename.get(parameter, parameter)
    if status == lib.GS_E_NULL:  # pragma: no cover - the bindings never pass NULL
        raise GearsimError(
            f"C API misuse: {message}", parameter=parameter or None, status=status_name(status)
        )
    if value_of is not None and parameter:
        try:
            value = value_of(parameter)
        except KeyError:
            pass
        else:
            message = f"{message} (got {value!r})"
    raise ParameterError(message, parameter=parameter or None, status=status_name(status))
