"""Helpers of the C runner tests (test_c_runner*.py): the built runner, its
parameter file, candump lines, and a pipe peer that talks to a live runner."""

from __future__ import annotations

import io
import json
import os
import select
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

can = pytest.importorskip("can")
pytest.importorskip("cantools")
pytest.importorskip("gearsim")

from gearsim.hil import runner as runner_mod  # noqa: E402


def _test_build() -> Path | None:
    """The newest double-precision runner under build/ (the test command builds
    build/test-double/hil/gearsim-hil): the tests' own fallback, which
    gearsim itself never takes (it starts only a runner it was told about,
    an installed one or the documented build/hil)."""
    root = Path(__file__).resolve().parents[3]
    found = [p for p in (root / "build").glob("*/hil/gearsim-hil") if os.access(p, os.X_OK)]
    for path in sorted(found, key=lambda p: p.stat().st_mtime, reverse=True):
        if runner_mod.runner_precision(path) == "double":
            return path
    return None


RUNNER = runner_mod.find_runner() or _test_build()
needs_runner = pytest.mark.skipif(
    RUNNER is None,
    reason="the C runner gearsim-hil is not built (cmake -S . -B build && cmake --build build "
    "--target gearsim-hil, or set GEARSIM_HIL_RUNNER)",
)


def candump_line(msg: Any, stamp: float | None = None) -> str:
    """One candump -L line as python-can writes it (can.Logger to .log)."""
    t = msg.timestamp if stamp is None else stamp
    if msg.is_error_frame:
        return f"({t:f}) can0 200000FF#\n"
    ident = f"{msg.arbitration_id:08X}" if msg.is_extended_id else f"{msg.arbitration_id:03X}"
    body = "R" if msg.is_remote_frame else bytes(msg.data).hex().upper()
    return f"({t:f}) can0 {ident}#{body}\n"


def write_log(path: Path, msgs: list[Any]) -> Path:
    with can.Logger(str(path)) as log:
        for m in msgs:
            log.on_message_received(m)
    return path


def read_log(path: Path) -> list[Any]:
    return list(can.LogReader(str(path)))


def run(cmd: list[str], timeout: float = 60.0) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def summary(stderr: str) -> dict[str, Any]:
    """The JSON object the runner prints with --json (last line of stderr)."""
    return json.loads(stderr.strip().splitlines()[-1])


def command(dbc: Any, t: float, is_extended: bool = False, **values: Any) -> list[Any]:
    """Command frames for role values (base_speed=..., load=..., mode=...), stamped t."""
    msgs = dbc.encode_command({f"cmd.{k}": v for k, v in values.items()})
    for m in msgs:
        m.timestamp = t
        m.is_extended_id = is_extended
    return msgs


class PipePeer:
    """A live runner on candump pipes (stdin/stdout): send() writes command
    lines, collect() gathers the answer lines, stop() ends it with SIGINT and
    returns its JSON summary."""

    def __init__(
        self,
        params: Path,
        *args: str,
        period: float = 1e-3,
        substeps: int = 1,
        timeout: float = 0.1,
    ) -> None:
        cmd = runner_mod.live_command(
            params, period=period, substeps=substeps, timeout=timeout, runner=RUNNER
        )
        self.proc = subprocess.Popen(
            [*cmd, *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE
        )
        os.set_blocking(self.proc.stdout.fileno(), False)
        self._buffer = b""
        self.lines: list[tuple[float, str]] = []  # (receive time, line)

    def send(self, lines: list[str]) -> None:
        self.proc.stdin.write("".join(lines).encode())
        self.proc.stdin.flush()

    def collect(self, seconds: float) -> None:
        """Read answers for `seconds` of wall time."""
        end = time.monotonic() + seconds
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return
            ready, _, _ = select.select([self.proc.stdout], [], [], left)
            if ready:
                chunk = self.proc.stdout.read() or b""
                self._buffer += chunk
                *done, self._buffer = self._buffer.split(b"\n")
                now = time.monotonic()
                self.lines.extend((now, d.decode()) for d in done if d.strip())

    def stop(self) -> tuple[int, dict[str, Any], str]:
        self.proc.send_signal(signal.SIGINT)
        os.set_blocking(self.proc.stdout.fileno(), True)
        out, err = self.proc.communicate(timeout=20)
        self._buffer += out
        self.lines.extend(
            (time.monotonic(), d.decode()) for d in self._buffer.split(b"\n") if d.strip()
        )
        text = err.decode()
        return self.proc.returncode, summary(text), text

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()

    def messages(self) -> list[Any]:
        """The answers as python-can messages (parsed by python-can's .log reader)."""
        text = "".join(line + "\n" for _, line in self.lines)
        return list(can.CanutilsLogReader(io.StringIO(text)))

    def decoded(self, dbc: Any) -> list[tuple[int, dict[str, Any]]]:
        """(frame ID, signal values decoded by cantools) of every answer, in order."""
        return [
            (m.arbitration_id, dbc.database.decode_message(m.arbitration_id, m.data))
            for m in self.messages()
        ]
