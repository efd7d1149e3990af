"""The ``gearsim`` command: a dispatcher of subcommands.

    gearsim compare DATA.csv --model MODEL.toml [--json]
    gearsim diagnose DATA.csv --model MODEL.toml [--json]
    gearsim fit DATA.csv --model MODEL.toml --add EFFECT [--out NEW.toml] [--json]
    gearsim report DATA.csv --model MODEL.toml --out DIR [--rounds N] [--json]

Exit status (docs/measurement-contract.md section 4): 0 on success; 2 on bad
input (missing file, bad column or value, unknown effect, invalid parameter)
with one line on standard error naming the file, line, column or key; 1 on an
internal failure (set GEARSIM_DEBUG=1 for the traceback).

Other layers add subcommands without editing this file: a module listed in
``PLUGIN_MODULES`` (``gearsim.hil.cli`` is one: ``gearsim hil ...``), or an
entry point in the ``gearsim.commands`` group, defines either
``register(subparsers)``, which calls ``add_command(subparsers, name, help,
configure, handler)`` (handler(args) returns the exit status and may raise the
errors above), or ``add_subparsers(subparsers)``, which adds its own parser and
sets ``func`` (func(args) returns the exit status). A plugin whose package is
not installed is skipped.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence

__all__ = [
    "main",
    "add_command",
    "build_parser",
    "PLUGIN_MODULES",
    "EXIT_BAD_INPUT",
    "EXIT_INTERNAL",
]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2

#: Modules tried for a ``register(subparsers)`` function, in order.
PLUGIN_MODULES: list[str] = ["gearsim.analysis.commands", "gearsim.hil.cli"]


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on stderr and exit 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(EXIT_BAD_INPUT)


def add_command(
    subparsers: argparse._SubParsersAction,
    name: str,
    help: str,
    configure: Callable[[argparse.ArgumentParser], None],
    handler: Callable[[argparse.Namespace], int],
    description: str | None = None,
) -> argparse.ArgumentParser:
    """Register subcommand `name`: configure(parser) adds its arguments,
    handler(args) runs it and returns the exit status."""
    p = subparsers.add_parser(
        name,
        help=help,
        description=description or help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    configure(p)
    p.set_defaults(_handler=handler, _command=name)
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
        "compare, diagnose and fit them against measurements.",
    )
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    handler = getattr(args, "_handler", None) or getattr(args, "func", None)
    if handler is None:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    prog = f"gearsim {getattr(args, '_command', '') or (argv or sys.argv[1:] or [''])[0]}"
    try:
        return int(handler(args) or 0)
    except _bad_input_types() as exc:
        msg = " ".join(str(exc).split())
        sys.stderr.write(f"{prog}: error: {msg}\n")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        sys.stderr.write(f"{prog}: interrupted\n")
        return 130
    except BrokenPipeError:  # pragma: no cover
        return EXIT_INTERNAL
    except Exception as exc:  # internal failure: one line, traceback only on request
        if os.environ.get("GEARSIM_DEBUG"):
            raise
        msg = " ".join(str(exc).split())
        sys.stderr.write(
            f"{prog}: internal error: {type(exc).__name__}: {msg} "
            f"(set GEARSIM_DEBUG=1 for the traceback)\n"
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
