"""The analysis subcommands of ``gearsim``: compare, diagnose, fit, report.

A thin shell over gearsim.analysis: parse arguments, load and check the model
and the measurement (all input is checked before anything is written), call
the function, print a table or exactly one JSON object on stdout. Progress
goes to stderr (silence it with --quiet), never into the JSON.

Outputs (``fit --out``, ``report --out``) are checked by
:func:`gearsim._outputs.check_output` first thing in the handler, before any
input is read: an empty path, an input of the command, a directory where a
file is wanted (or the reverse), a missing or unwritable directory end the
command at once with exit status 2. Every file is written atomically
(:func:`gearsim._outputs.atomic_writer`) and only after the work succeeded.

Options that would silently give a wrong answer are refused: an
``--input-filter`` cut-off at or above the Nyquist frequency of the data,
negative or fractional counts (``--rounds``, ``--top``, ``--max-samples``,
``--max-gap``). The loader's notes on how the data was read or changed
(separator, units, ``--resample``) and its warnings are printed on stderr, one
line each, even with --quiet.

One module per subcommand (:mod:`.compare`, :mod:`.diagnose`, :mod:`.fit`,
:mod:`.report`), each with ``NAME``, ``HELP``, ``REQUIRES`` (the modules of the
analysis extra it cannot run without, checked before it starts),
``configure(parser)`` (its options) and ``execute(args)`` (its run, returning
the exit status); what they share is in :mod:`.common`. gearsim/cli.py finds
:func:`register` through its ``PLUGIN_MODULES``.
"""

from __future__ import annotations

import argparse

from ...cli import add_command
from . import compare, diagnose, fit, report

__all__ = ["register", "COMMANDS"]

#: The subcommands, in the order ``gearsim --help`` lists them.
COMMANDS = (compare, diagnose, fit, report)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Adds every analysis subcommand to the ``gearsim`` command."""
    for command in COMMANDS:
        add_command(
            subparsers,
            command.NAME,
            command.HELP,
            command.configure,
            command.execute,
            requires=command.REQUIRES,
        )
