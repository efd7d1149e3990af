"""What a rig DBC may say, in one place: the names its ``GsRole`` attributes
may use and the rules its role signals and frames must follow.

Two readers: the Python codec (``gearsim.hil.codec``) and the build step of
the C runner (``hil/dbc_tables.py``), which loads this file by path so that
building the runner needs neither an installed gearsim nor its compiled
extension. Keep this module free of imports for that reason; it sees signals
as plain numbers, not as cantools objects.

The C side has the same flags and counters as X-macro lists in
``hil/include/gearsim/hil.h``; every table file the generator writes checks at
compile time that those lists and the tuples here agree name for name and in
order, so the two cannot drift apart without the build failing. The rig's
output fields are not here: they come from the C core's table
``include/gearsim/fields.h``.
"""

COMMAND_ROLES = ("cmd.base_speed", "cmd.base_torque", "cmd.load", "cmd.mode")
INPUT_ROLES = ("in.base_speed", "in.base_torque", "in.load")

#: Status flags. The first three are the state during the frame period that
#: ended with the status frame; the others are latched: set when the event
#: happened at least once since the previous status frame of the same ID.
STATUS_FLAGS = (
    "cmd_timeout",
    "safe_state",
    "drive_disabled",
    "cmd_rejected",
    "cmd_late",
    "fb_saturated",
    "overrun",
    "tx_error",
)
#: Counters (Counters attributes), encoded modulo 2**bits.
STATUS_COUNTS = (
    "rx_total",
    "rx_used",
    "rx_rejected",
    "rx_late",
    "rx_ignored",
    "tx_frames",
    "tx_errors",
    "timeouts",
    "recoveries",
    "overruns",
    "resyncs",
    "saturations",
    "periods",
)

MODES = ("disabled", "speed", "torque")
#: Value-table names a cmd.mode signal may use (lower-cased, stripped) -> mode.
MODE_ALIASES = {
    "disabled": "disabled",
    "disable": "disabled",
    "off": "disabled",
    "safe": "disabled",
    "speed": "speed",
    "torque": "torque",
}
#: Modes of a cmd.mode signal without a value table, by physical value.
DEFAULT_MODE_VALUES = {0: "disabled", 1: "speed", 2: "torque"}

#: The network attribute GsBlock names one of these rigs.
BLOCKS = ("simple_gear", "rack_pinion")


class RuleError(Exception):
    """A DBC breaks one of the rules here; the message names frame and signal."""


def raw_limits(length: int, signed: bool) -> tuple[int, int]:
    """Smallest and largest raw value of an integer signal of ``length`` bits."""
    if signed:
        return -(1 << (length - 1)), (1 << (length - 1)) - 1
    return 0, (1 << length) - 1


def signal_range(
    where: str,
    role,
    *,
    length: int,
    is_signed: bool,
    is_float: bool,
    scale: float,
    offset: float,
    minimum,
    maximum,
) -> tuple[float, float]:
    """[minimum, maximum] of a signal in physical units: the DBC's, else what
    its raw bits hold. RuleError when the range is empty, when a feedback
    signal's range is wider than its bits (encoding would wrap), when a
    counter is not an unsigned integer or a flag cannot hold 0 and 1."""
    if is_float:
        lo_phys, hi_phys = -float("inf"), float("inf")
    else:
        lo_raw, hi_raw = raw_limits(length, is_signed)
        a, b = lo_raw * scale + offset, hi_raw * scale + offset
        lo_phys, hi_phys = min(a, b), max(a, b)
    low = lo_phys if minimum is None else float(minimum)
    high = hi_phys if maximum is None else float(maximum)
    if low > high:
        raise RuleError(f"{where}: minimum {low} > maximum {high}")
    # the tolerance absorbs the decimal rounding of DBC limits
    tol = abs(scale) * 1e-6
    if (
        role is not None
        and not role.startswith("cmd.")
        and (low < lo_phys - tol or high > hi_phys + tol)
    ):
        raise RuleError(
            f"{where}: range [{low}, {high}] does not fit {length} "
            f"{'signed' if is_signed else 'unsigned'} bits at scale {scale} "
            f"([{lo_phys}, {hi_phys}]); values would wrap"
        )
    if role and (role.startswith("status.count.") or role == "status.counter"):
        if is_float or is_signed or scale != 1.0 or offset != 0.0:
            raise RuleError(
                f"{where}: a counter must be an unsigned integer signal (scale 1, offset 0)"
            )
    if role and role.startswith("status.flag.") and (low > 0 or high < 1):
        raise RuleError(f"{where}: a flag must hold 0 and 1")
    return low, high


def frame_kind(name: str, roles, *, has_cycle_time: bool, is_multiplexed: bool) -> str:
    """ "command", "feedback" or "other" for a frame whose signals carry
    ``roles``; RuleError for a frame mixing both, a feedback frame without a
    cycle time, or a multiplexed command or feedback frame."""
    is_cmd = any(r.startswith("cmd.") for r in roles)
    is_fb = any(not r.startswith("cmd.") for r in roles)
    if is_cmd and is_fb:
        raise RuleError(f"{name} mixes command and feedback roles")
    kind = "command" if is_cmd else "feedback" if is_fb else "other"
    if kind == "feedback" and not has_cycle_time:
        raise RuleError(f"feedback frame {name} has no GenMsgCycleTime")
    if is_multiplexed and kind != "other":
        raise RuleError(f"{name}: multiplexed frames are not supported for commands or feedback")
    return kind
