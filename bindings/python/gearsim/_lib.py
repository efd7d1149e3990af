"""Access to the compiled C core (``gearsim._gearsim``, built by cffi in API mode
from include/gearsim and src/; see bindings/python/gearsim_build.py).

Everything that depends on the C layout is checked here once, at import.
"""

from __future__ import annotations

from typing import Any

from .errors import GearsimError, ParameterError

try:
    from ._gearsim import ffi, lib  # type: ignore[import-not-found]
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        "gearsim: the compiled extension gearsim._gearsim is missing; install the "
        "package with `pip install .` (or `pip install -e .`) from the repository root"
    ) from exc

__all__ = ["ffi", "lib", "REAL_SIZE", "status_name", "check", "INPUT_COLUMNS", "OUTPUT_COLUMNS"]

REAL_SIZE: int = ffi.sizeof("gs_real")
if REAL_SIZE != 8:  # pragma: no cover - the package always uses the double build
    raise ImportError(f"gearsim: extension built with sizeof(gs_real) = {REAL_SIZE}, need double")


def _columns(ctype: str, count: int) -> dict[str, int]:
    """Column index of each field of an all-gs_real struct, from the compiled layout."""
    t = ffi.typeof(ctype)
    if ffi.sizeof(t) != count * REAL_SIZE:  # pragma: no cover
        raise ImportError(f"gearsim: {ctype} is not {count} packed gs_real fields")
    return {name: field.offset // REAL_SIZE for name, field in t.fields}


#: C field name -> column of the N x GS_RIG_INPUT_FIELDS input array.
INPUT_COLUMNS: dict[str, int] = _columns("gs_rig_input", lib.GS_RIG_INPUT_FIELDS)
#: C field name -> column of the N x GS_RIG_OUTPUT_FIELDS output array.
OUTPUT_COLUMNS: dict[str, int] = _columns("gs_rig_output", lib.GS_RIG_OUTPUT_FIELDS)


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
