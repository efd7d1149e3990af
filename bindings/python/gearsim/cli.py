"""The ``gearsim`` command: a dispatcher of subcommands.

    gearsim compare DATA.csv --model MODEL.toml [--json]
    gearsim diagnose DATA.csv --model MODEL.toml [--json]
    gearsim fit DATA.csv --model MODEL.toml --add EFFECT [--out NEW.toml] [--json]
    gearsim report DATA.csv --model MODEL.toml --out DIR [--rounds N] [--json]

The files and columns are described in docs/measurement-format.md.

Exit status: 0 on success; 2 on bad input (missing file, bad column or value,
unknown effect, invalid parameter, an output path that would overwrite an
input or cannot be written, a usage error of the options) with one line on
standard error naming the file, line, column, key or option; 1 on an internal
failure, also one line (set GEARSIM_DEBUG=1 for the traceback); 130 on
Ctrl-C. No command prints a traceback unless GEARSIM_DEBUG is set.

A command that needs an extra which is not installed (docs/python.md,
"Installing") exits with status 2 and one line naming it, e.g.
``gearsim: 'gearsim fit' needs the analysis extra: pip install
'gearsim[analysis]' (missing module: scipy)``: checked before the command
starts for the modules it declares (``add_command(..., requires=...)``), and
for any other module of an extra whose import fails while it runs.

Standard output closed early (``gearsim compare ... --json | head -c 1``):
the command stops quietly, prints nothing on standard error and exits with
status 141 (128 + SIGPIPE, what a shell reports for a program killed by
SIGPIPE), so that ``set -o pipefail`` still sees that not everything was
read. When the reader took everything before it closed, the status is 0.

Every message that repeats user data (file names, header cells, values) is
made printable first (:func:`gearsim._outputs.printable`): control characters
and raw bytes never reach the terminal.

Other layers add subcommands without editing this file: a module listed in
``PLUGIN_MODULES`` (``gearsim.hil.cli`` is one: ``gearsim hil ...``), or an
entry point in the ``gearsim.commands`` group, defines either
``register(subparsers)``, which calls ``add_command(subparsers, name, help,
configure, handler, requires=...)`` (handler(args) returns the exit status and
may raise the errors above; requires names the modules of extras it needs), or
``add_subparsers(subparsers)``, which adds its own parser and sets ``func``
(func(args) returns the exit status). A plugin whose package is not installed
is skipped.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence

from ._extras import missing_extra, require
from ._outputs import one_line, say, stdout_to_devnull

__all__ = [
    "main",
    "add_command",
    "build_parser",
    "PLUGIN_MODULES",
    "EXIT_BAD_INPUT",
    "EXIT_INTERNAL",
    "EXIT_BROKEN_PIPE",
    "START_HERE",
]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2
#: Standard output closed by its reader before everything was written.
EXIT_BROKEN_PIPE = 141
EXIT_INTERRUPTED = 130

#: Modules tried for a ``register(subparsers)`` function, in order.
PLUGIN_MODULES: list[str] = ["gearsim.analysis.cli", "gearsim.hil.cli", "gearsim.fleet.cli"]

#: The first lines of ``gearsim --help``.
START_HERE = """\
start here:  gearsim compare  data.csv --model model.toml     # the error, overall and per regime
             gearsim diagnose data.csv --model model.toml     # the missing effect, with evidence
             gearsim fit      data.csv --model model.toml --add EFFECT --out fitted.toml
"""


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one printable line on stderr and exit 2;
    the top-level help starts with START_HERE."""

    start_here: str | None = None

    def error(self, message: str) -> None:  # type: ignore[override]
        say(f"{self.prog}: error: {one_line(message)}")
        raise SystemExit(EXIT_BAD_INPUT)

    def _print_message(self, message: str, file=None) -> None:  # type: ignore[override]
        # argparse swallows OSError here; a closed stdout must end the command
        # like any other output does (quietly, EXIT_BROKEN_PIPE)
        if message:
            out = file or sys.stderr
            out.write(message)
            out.flush()

    def format_help(self) -> str:
        text = super().format_help()
        return f"{self.start_here}\n{text}" if self.start_here else text


def add_command(
    subparsers: argparse._SubParsersAction,
    name: str,
    help: str,
    configure: Callable[[argparse.ArgumentParser], None],
    handler: Callable[[argparse.Namespace], int],
    description: str | None = None,
    requires: Sequence[str] = (),
) -> argparse.ArgumentParser:
    """Register subcommand `name`: configure(parser) adds its arguments,
    handler(args) runs it and returns the exit status. requires: the modules
    (top-level names of gearsim._extras.EXTRAS) without which the command
    cannot run; a missing one is reported before the handler starts."""
    p = subparsers.add_parser(
        name,
        help=help,
        description=description or help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    configure(p)
    p.set_defaults(_handler=handler, _command=name, _requires=tuple(requires))
    return p


def _plugins(subparsers: argparse._SubParsersAction) -> None:
    for mod in PLUGIN_MODULES:
        try:
            m = importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            if exc.name and mod.startswith(exc.name):
                continue  # the optional package is not installed
            raise
        if hasattr(m, "register"):
            m.register(subparsers)
        elif hasattr(m, "add_subparsers"):
            m.add_subparsers(subparsers)
    try:
        from importlib.metadata import entry_points

        for ep in entry_points(group="gearsim.commands"):
            ep.load()(subparsers)
    except Exception:  # pragma: no cover - a broken third-party plugin must not break gearsim
        pass


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="gearsim",
        description="gearsim: Simple Gear and Rack & Pinion models; "
        "compare, diagnose and fit them against measurements. Files and columns: "
        "docs/measurement-format.md; a demo to start with: examples/data/demo_gear.csv "
        "with examples/data/demo_gear_start.toml.",
    )
    parser.start_here = START_HERE
    try:
        from . import __version__ as version
    except Exception:  # pragma: no cover
        version = "unknown"
    parser.add_argument("--version", action="version", version=f"gearsim {version}")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND", parser_class=_Parser)
    _plugins(sub)
    return parser


def _bad_input_types() -> tuple[type[BaseException], ...]:
    from .errors import InputError, ModelFileError, ParameterError

    out: list[type[BaseException]] = [ModelFileError, ParameterError, InputError]
    try:
        from .analysis.errors import EffectError, MeasurementError

        out += [MeasurementError, EffectError]
    except ImportError:  # pragma: no cover
        pass
    return tuple(out)


def _exit_code(code: object) -> int:
    """The status of a SystemExit code (None -> 0, a message -> 1)."""
    if code is None:
        return EXIT_OK
    if isinstance(code, int):
        return code
    say(one_line(code))
    return EXIT_INTERNAL


def _run(argv: Sequence[str] | None) -> int:
    prog = "gearsim"
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help, --version, a usage error (already reported)
            return _exit_code(exc.code)
        handler = getattr(args, "_handler", None) or getattr(args, "func", None)
        if handler is None:
            parser.print_help(sys.stderr)
            return EXIT_BAD_INPUT
        words = list(sys.argv[1:] if argv is None else argv) or [""]
        prog = f"gearsim {getattr(args, '_command', '') or words[0]}"
        require(f"'{prog}'", getattr(args, "_requires", ()))
        return int(handler(args) or 0)
    except BrokenPipeError:
        raise  # main() ends quietly
    except _bad_input_types() as exc:
        say(f"{one_line(prog)}: error: {one_line(exc)}")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        if os.environ.get("GEARSIM_DEBUG"):
            raise
        say(f"{one_line(prog)}: interrupted")
        return EXIT_INTERRUPTED
    except Exception as exc:  # internal failure: one line, traceback only on request
        missing = missing_extra(exc, f"'{one_line(prog)}'")
        if missing is not None:  # not a failure of gearsim: the user can fix it
            say(f"gearsim: {missing}")
            return EXIT_BAD_INPUT
        if os.environ.get("GEARSIM_DEBUG"):
            raise
        say(
            f"{one_line(prog)}: internal error: {type(exc).__name__}: {one_line(exc)} "
            f"(set GEARSIM_DEBUG=1 for the traceback)"
        )
        return EXIT_INTERNAL


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status (argparse's
    exits, --help and usage errors included, are returned, not raised)."""
    try:
        status = _run(argv)
        sys.stdout.flush()  # a reader that left shows here, not at shutdown
    except BrokenPipeError:
        stdout_to_devnull()
        return EXIT_BROKEN_PIPE
    return status


if __name__ == "__main__":
    sys.exit(main())
