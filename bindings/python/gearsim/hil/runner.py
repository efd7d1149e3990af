"""The Python side of the C HIL runner ``gearsim-hil`` (docs/hil-runner.md).

- :func:`params_text` / :func:`write_params`: the runner's parameter file from a
  gearsim model (the C parameter structs the Python rig is built from, field
  by field, so that the C runner and ``Bridge`` step the same rig);
- :func:`locate_runner`: the executable to start, and where it was found;
  :func:`find_runner`: the same, in a given precision;
- :func:`live_command`, :func:`replay_command`, :func:`launch`: command lines
  and a started process, with the Python bridge's defaults (period 1 ms,
  1 sub-step, timeout 0.1 s).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import params as P
from .._lib import ffi, lib
from .._outputs import atomic_write_text
from ..errors import GearsimError

__all__ = [
    "RunnerError",
    "RUNNER_ENV",
    "params_text",
    "write_params",
    "RunnerChoice",
    "locate_runner",
    "find_runner",
    "runner_precision",
    "live_command",
    "replay_command",
    "launch",
]

#: Environment variable naming the runner executable (after --runner-path).
RUNNER_ENV = "GEARSIM_HIL_RUNNER"
RUNNER_NAME = "gearsim-hil"
#: Where the build docs/hil-runner.md gives (cmake -S . -B build) puts the
#: runner, in the source tree.
DOCUMENTED_BUILD = Path("build") / "hil" / RUNNER_NAME
#: How to get one, for the message when there is none.
HOW_TO_BUILD = (
    "build it from the source tree with CMake (on by default on Linux): cmake -S . -B build "
    f"&& cmake --build build --target {RUNNER_NAME}, which makes {DOCUMENTED_BUILD}; or "
    f"install it (cmake --install build); or name it with --runner-path or {RUNNER_ENV} "
    "(docs/hil-runner.md)"
)


class RunnerError(GearsimError, ValueError):
    """The C runner cannot be found or given this model."""


def _format_value(ctype: Any, value: Any) -> str:
    kind = ctype.kind
    if kind == "enum":
        return ctype.elements[int(value)]
    if kind == "array":
        items: list[str] = []
        for item in value:
            items.append(_format_value(ctype.item, item))
        return " ".join(items)
    if ctype.cname in ("double", "float"):
        return repr(float(value))  # shortest text that reads back as the same double
    return str(int(value))


def _struct_lines(prefix: str, struct: Any, skip: Sequence[str] = ()) -> list[str]:
    """``prefix.field = value`` for every member of a cffi struct (nested
    structs as ``prefix.member.field``)."""
    lines = []
    for name, field in ffi.typeof(struct).fields:
        if name in skip:
            continue
        value = getattr(struct, name)
        if field.type.kind == "struct":
            lines.extend(_struct_lines(f"{prefix}.{name}", value))
        else:
            lines.append(f"{prefix}.{name} = {_format_value(field.type, value)}")
    return lines


def params_text(model: Any) -> str:
    """The runner's parameter file for a gearsim.Model: the block's and the
    rig's C parameter structs as the Python rig fills them, every field, plus
    the ambient temperature. The step (rig.dt_s) is not in it: the runner
    takes it from --period / --substeps, like the Python bridge."""
    rig = model.rig(dt=1e-3)  # validates the model as the bridge would
    kind = rig.kind
    c_rig = ffi.new("gs_rig_params *")
    c_rig[0] = lib.gs_rig_params_default()
    full = rig.params
    P.write_struct(P.BLOCKS[kind][1], full, c_rig)
    c_rig.heat_path = 0 if full["thermal_resistance"] is None else 1
    c_rig.temperature_source = lib.GS_TEMPERATURE_FROM_MODEL
    lines = [
        "# gearsim-hil parameter file (docs/hil-runner.md), written by gearsim.hil.runner",
        f"block = {kind}",
        *_struct_lines("block", rig.block._c_params[0]),
        *_struct_lines("rig", c_rig[0], skip=("dt_s",)),
        f"run.ambient_temperature_K = {float(rig.ambient_temperature)!r}",
    ]
    return "\n".join(lines) + "\n"


def write_params(model: Any, path: str | os.PathLike[str]) -> Path:
    """Write :func:`params_text` to ``path`` atomically; returns the path."""
    atomic_write_text(path, params_text(model))
    return Path(path)


@dataclass(frozen=True)
class RunnerChoice:
    """A runner executable and where it was found."""

    path: Path
    how: str
    """where: --runner-path, $GEARSIM_HIL_RUNNER, installed (on PATH), built in
    the source tree (build/hil), or built in the working directory (build/hil)"""


def _source_tree() -> Path | None:
    """The source tree this package runs from (an editable install), or None."""
    root = Path(__file__).resolve().parents[4]
    return root if (root / "hil" / "CMakeLists.txt").is_file() else None


def _candidates(explicit: str | os.PathLike[str] | None) -> list[tuple[Path, str, bool]]:
    """(path, how, named): where a runner is looked for, in order. A named one
    (--runner-path, the environment) must be there; the others may not."""
    out: list[tuple[Path, str, bool]] = []
    if explicit is not None:
        out.append((Path(explicit), "--runner-path", True))
    env = os.environ.get(RUNNER_ENV)
    if env:
        out.append((Path(env), f"${RUNNER_ENV}", True))
    on_path = shutil.which(RUNNER_NAME)
    if on_path:
        out.append((Path(on_path), "installed (on PATH)", False))
    root = _source_tree()
    if root is not None:
        out.append((root / DOCUMENTED_BUILD, "built in the source tree (build/hil)", False))
    cwd = Path.cwd() / DOCUMENTED_BUILD
    if root is None or cwd.resolve() != (root / DOCUMENTED_BUILD).resolve():
        out.append((cwd, "built in the working directory (build/hil)", False))
    return out


def _executable(path: Path) -> bool:
    return path.is_file() and os.access(path, os.X_OK)


def locate_runner(explicit: str | os.PathLike[str] | None = None) -> RunnerChoice:
    """The runner ``gearsim hil run --runner c`` starts: ``explicit``
    (--runner-path), else $GEARSIM_HIL_RUNNER, else ``gearsim-hil`` on PATH
    (an installed runner), else the documented CMake build, build/hil/gearsim-hil,
    of this package's source tree or of the working directory. Other build
    folders (the test builds, build/*/hil) are never picked. RunnerError
    when a named one is not an executable file, or none is found."""
    tried = []
    for path, how, named in _candidates(explicit):
        if _executable(path):
            return RunnerChoice(path, how)
        if named:
            raise RunnerError(f"{how} {path}: not an executable file")
        tried.append(str(path))
    raise RunnerError(
        f"the C runner {RUNNER_NAME} is not built or installed (looked on PATH and at "
        f"{', '.join(tried) or 'nothing'}): {HOW_TO_BUILD}"
    )


def runner_precision(path: str | os.PathLike[str]) -> str | None:
    """ "double" or "float": the precision the runner was built in (its
    --version), or None if it does not run."""
    try:
        res = subprocess.run(
            [os.fspath(path), "--version"], capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.SubprocessError):
        return None
    words = res.stdout.split()
    return words[-1] if res.returncode == 0 and words and words[0] == RUNNER_NAME else None


def find_runner(precision: str | None = "double") -> Path | None:
    """The first runner locate_runner() would consider (--runner-path
    aside) that runs in the given precision ("double", the Python bindings'
    precision, whose answers are bit-identical to the Python bridge's;
    "float"; None: any). None when there is none."""
    for path, _, _ in _candidates(None):
        if _executable(path) and (precision is None or runner_precision(path) == precision):
            return path
    return None


def _runner_or_fail(runner: str | os.PathLike[str] | None) -> str:
    return os.fspath(runner if runner is not None else locate_runner().path)


def _command_head(
    runner: str | os.PathLike[str] | None,
    params: str | os.PathLike[str],
    period: float,
    substeps: int,
    timeout: float,
) -> list[str]:
    """The runner, its parameter file and the timing options: how every
    command line of the runner starts."""
    return [
        _runner_or_fail(runner),
        "--params",
        os.fspath(params),
        "--period",
        repr(float(period)),
        "--substeps",
        str(int(substeps)),
        "--timeout",
        repr(float(timeout)),
    ]


def live_command(
    params: str | os.PathLike[str],
    *,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.1,
    transport: str = "candump",
    rx: str = "-",
    tx: str = "-",
    channel: str = "can0",
    listen: str = "127.0.0.1:29536",
    duration: float | None = None,
    spin_us: int | None = None,
    fifo: int | None = None,
    cpu: int | None = None,
    mlockall: bool = False,
    json: bool = True,
    runner: str | os.PathLike[str] | None = None,
) -> list[str]:
    """Command line of a live (paced) run of the runner."""
    cmd = _command_head(runner, params, period, substeps, timeout)
    cmd += ["--transport", transport]
    if transport == "socketcan":
        cmd += ["--channel", channel]
    elif transport == "socketcand":
        cmd += ["--listen", listen, "--channel", channel]
    else:
        cmd += ["--rx", rx, "--tx", tx]
    if duration is not None:
        cmd += ["--duration", repr(float(duration))]
    if spin_us is not None:
        cmd += ["--spin-us", str(int(spin_us))]
    if fifo is not None:
        cmd += ["--fifo", str(int(fifo))]
    if cpu is not None:
        cmd += ["--cpu", str(int(cpu))]
    if mlockall:
        cmd.append("--mlockall")
    return cmd + (["--json"] if json else [])


def replay_command(
    params: str | os.PathLike[str],
    log: str | os.PathLike[str],
    out: str | os.PathLike[str] | None = None,
    *,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.1,
    tail: float = 0.0,
    json: bool = True,
    runner: str | os.PathLike[str] | None = None,
) -> list[str]:
    """Command line of a replay of a candump .log through the runner."""
    cmd = _command_head(runner, params, period, substeps, timeout)
    cmd += ["--replay", os.fspath(log), "--tail", repr(float(tail))]
    if out is not None:
        cmd += ["-o", os.fspath(out)]
    return cmd + (["--json"] if json else [])


def launch(command: Sequence[str], **popen: Any) -> subprocess.Popen:
    """Start the runner (subprocess.Popen; pipes as given in ``popen``). Stop
    it with ``proc.send_signal(signal.SIGINT)`` or ``terminate()``: it prints
    its counters (and loop timing) on stderr and exits 0."""
    return subprocess.Popen(list(command), **popen)
