"""The names of the HIL bridge, read from the C library (gearsim/hil.h, the one
list of each): what a DBC's ``GsRole`` attributes may say, the status flags
and counters, the modes, and the reasons a received frame ends with.

Needs only the compiled extension, not python-can or cantools.
"""

from __future__ import annotations

from .._lib import ffi, lib
from ..rig import OUTPUT_NAMES

__all__ = [
    "COMMAND_ROLES",
    "INPUT_ROLES",
    "OUTPUT_FIELDS",
    "DERIVED_OUTPUTS",
    "STATUS_FLAGS",
    "STATE_FLAGS",
    "STATUS_COUNTS",
    "MODES",
    "REASONS",
    "REJECT_REASONS",
    "LATE_REASONS",
    "IGNORE_REASONS",
    "FAULTS",
    "PARAM_RESULTS",
    "tunable_parameters",
    "parse_parameter",
]


def _names(getter, count: int) -> tuple[str, ...]:
    return tuple(ffi.string(getter(i)).decode("ascii") for i in range(count))


_ROLE_NAMES = _names(lib.gs_hil_role_name, lib.GS_HIL_ROLES)
#: Whole role names by family ("cmd.", "in."), in gearsim/hil.h's order.
COMMAND_ROLES: tuple[str, ...] = tuple(r for r in _ROLE_NAMES if r.startswith("cmd."))
INPUT_ROLES: tuple[str, ...] = tuple(r for r in _ROLE_NAMES if r.startswith("in."))
#: RigResult fields, usable as ``out.<field>`` (the C core's output table).
OUTPUT_FIELDS: tuple[str, ...] = OUTPUT_NAMES
#: ``out.`` roles that are no output field: out.follower_angle, the follower
#: position modulo 2*pi in [0, 2*pi).
DERIVED_OUTPUTS: tuple[str, ...] = tuple(
    r[len("out.") :] for r in _ROLE_NAMES if r.startswith("out.") and r != "out."
)
#: Status flags; the first STATE_FLAGS are states, the others latched.
STATUS_FLAGS: tuple[str, ...] = _names(lib.gs_hil_flag_name, lib.GS_HIL_FLAGS)
STATE_FLAGS: tuple[str, ...] = STATUS_FLAGS[: lib.GS_HIL_STATE_FLAGS]
#: Counters, in the order of the C counters (and of Counters).
STATUS_COUNTS: tuple[str, ...] = _names(lib.gs_hil_count_name, lib.GS_HIL_COUNTS)
MODES: tuple[str, ...] = _names(lib.gs_hil_mode_name, lib.GS_HIL_MODES)
#: "class.reason" of every fate of a received frame but "pending", in C order.
REASONS: tuple[str, ...] = _names(lib.gs_hil_reason_name, lib.GS_HIL_REASONS)[1:]


def _of_class(cls: str) -> tuple[str, ...]:
    return tuple(r.split(".", 1)[1] for r in REASONS if r.startswith(cls + "."))


REJECT_REASONS = _of_class("rejected")
LATE_REASONS = _of_class("late")
IGNORE_REASONS = _of_class("ignored")

#: Fault kinds a scenario's fault steps name, in C order.
FAULTS: tuple[str, ...] = _names(lib.gs_hil_fault_name, lib.GS_HIL_FAULTS)
#: The ack.result values of a parameter request, in C order (0 = applied).
PARAM_RESULTS: tuple[str, ...] = _names(lib.gs_hil_param_result_name, lib.GS_HIL_PARAM_RESULTS)

_BLOCK_CODES = {"simple_gear": lib.GS_RIG_SIMPLE_GEAR, "rack_pinion": lib.GS_RIG_RACK_PINION}


def tunable_parameters(block: str) -> tuple[str, ...]:
    """The keys of the parameters a running rig of ``block`` ("simple_gear"
    or "rack_pinion") may change, by their index (a parameter frame's
    param.id): the TUNABLE entries of the C parameter tables."""
    code = _BLOCK_CODES[block]
    n = lib.gs_hil_param_count(code)
    return tuple(ffi.string(lib.gs_hil_param_key(code, i)).decode("ascii") for i in range(n))


def parse_parameter(block: str, name: str) -> tuple[int, int]:
    """(index, element) of "key", "key[i]" or "key[i][j]"; ValueError when
    no tunable parameter of the rig has that name or element."""
    index, element = ffi.new("unsigned *"), ffi.new("unsigned *")
    if lib.gs_hil_param_parse(_BLOCK_CODES[block], name.encode(), index, element) != 0:
        raise ValueError(
            f"{name!r} is no tunable parameter of the {block} rig (key, key[i] or key[i][j] of: "
            f"{' '.join(tunable_parameters(block))})"
        )
    return int(index[0]), int(element[0])
