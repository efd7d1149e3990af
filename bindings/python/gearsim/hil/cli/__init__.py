"""``gearsim hil``: run the bridge on a CAN bus, replay a log, turn a log into a
measurement CSV (docs/hil.md). One module per subcommand, each with
``NAME``, ``add_parser(subparsers)`` and ``execute(args)``:

    gearsim hil run    --model M.toml [-i IFACE] [-c CHANNEL] [-b BITRATE] [--dbc F] ...  (run)
    gearsim hil run    --model M.toml --runner c [-i socketcan -c CHANNEL | -i candump]   (run_c)
    gearsim hil replay LOG --model M.toml [-o ANSWERS.asc] [--dbc F] ...                 (replay)
    gearsim hil to-csv LOG (--rig gear|rack | --dbc F | --model M.toml) -o DATA.csv ...  (to_csv)
    gearsim hil dbc    gear|rack [-o FILE]                                               (dbc)

Hooked into the ``gearsim`` command by gearsim/cli.py through
:func:`add_subparsers`; :func:`main` runs it standalone
(``python -m gearsim.hil``).

Exit status: 0 success, 2 bad input (one line on standard error, no
traceback), 1 internal failure (one line; the traceback only with
GEARSIM_DEBUG set), 3 a scenario expectation failed (run, replay), 130
interrupted, 141 when standard output is a pipe closed by its reader
(``... -o - | head``; nothing printed). Without the hil extra (python-can,
cantools) every command exits with status 2 and one line naming it:
``pip install 'gearsim[hil]'``. ``--json`` prints exactly one JSON object on
standard output.

Outputs (``-o``, ``--log``) are checked before any work starts (not an input of
the command, not a directory, in a writable directory, a log format python-can
writes) and written atomically: to a temporary file beside the target, renamed
over it only on success. Messages echo user data through ``printable``.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from ..._extras import EXTRAS, missing_extra, require
from ..._outputs import one_line, say, stdout_to_devnull
from ...cli import EXIT_BROKEN_PIPE, EXIT_INTERRUPTED
from ...errors import GearsimError
from . import dbc, replay, run, to_csv
from .common import Parser

__all__ = ["add_subparsers", "build_parser", "main", "run_args", "EXIT_BROKEN_PIPE"]

_DESCRIPTION = "HIL bridge: a gearsim rig behind a CAN bus (docs/hil.md)"
#: The subcommands, in the order --help lists them.
SUBCOMMANDS = {m.NAME: m for m in (run, replay, to_csv, dbc)}


def _fill(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="hil_command", metavar="{" + ",".join(SUBCOMMANDS) + "}")
    sub.required = True
    for command in SUBCOMMANDS.values():
        command.add_parser(sub)


def build_parser(prog: str = "gearsim hil") -> argparse.ArgumentParser:
    """The standalone parser of ``gearsim hil``."""
    parser = Parser(prog=prog, description=_DESCRIPTION)
    _fill(parser)
    return parser


def add_subparsers(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``hil`` on the subparsers of the ``gearsim`` command.

    Sets ``func`` to :func:`run_args` (call ``args.func(args)`` and exit with
    its return value). Returns the ``hil`` parser."""
    parser = subparsers.add_parser(
        "hil", help="HIL bridge on CAN: run, replay, to-csv", description=_DESCRIPTION
    )
    _fill(parser)
    parser.set_defaults(func=run_args)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``gearsim hil`` run standalone; returns the exit status."""
    return run_args(build_parser().parse_args(argv))


def run_args(args: argparse.Namespace) -> int:
    """Run the parsed ``hil`` command; returns the exit status (0, 1, 2, 3, 130
    or 141). Nothing escapes as a traceback unless GEARSIM_DEBUG is set."""
    prog = f"gearsim hil {args.hil_command}"
    _quiet_python_can()
    try:
        # every command decodes or encodes through python-can and cantools (the
        # DBC module imports both): checked here, before any input is read
        require(f"'{prog}'", EXTRAS["hil"])
        status = SUBCOMMANDS[args.hil_command].execute(args)
        sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
        return status
    except BrokenPipeError:
        stdout_to_devnull()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt:
        say(f"{prog}: interrupted")
        return EXIT_INTERRUPTED
    except (GearsimError, ValueError, OSError) as exc:
        # bad input: missing or unreadable files, a log or DBC that does not fit,
        # options out of range, a bus that does not open, a full disk, ...
        say(f"{prog}: error: {one_line(exc)}")
        return 2
    except Exception as exc:  # internal failure: one line, the traceback on request
        missing = missing_extra(exc, f"'{prog}'")
        if missing is not None:  # the hil extra (or a part of it) is not installed
            say(f"gearsim: {missing}")
            return 2
        if os.environ.get("GEARSIM_DEBUG"):
            raise
        say(
            f"{prog}: internal error: {type(exc).__name__}: {one_line(exc)} "
            "(set GEARSIM_DEBUG=1 for the traceback)"
        )
        return 1


def _quiet_python_can() -> None:
    """python-can logs what it meets in a log or on a bus (e.g. "Unknown
    compression method" in a damaged .blf) through the logging module, which
    without a configured handler prints each record on stderr: a second line
    beside the command's own one-line result. The command reports what went
    wrong itself, so python-can's records are dropped here; GEARSIM_DEBUG
    keeps them."""
    if os.environ.get("GEARSIM_DEBUG"):
        return
    import logging

    log = logging.getLogger("can")
    log.addHandler(logging.NullHandler())
    log.propagate = False


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
