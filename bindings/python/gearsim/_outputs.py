"""Safe outputs for every ``gearsim`` command: nothing a user gives us is lost.

- :func:`check_output` refuses, before any work starts, an output path that is
  empty, names an input of the same command, is a directory where a file is
  wanted (or a file where a directory is wanted), or lies in a directory that
  does not exist or cannot be written. The error is an
  :class:`OutputPathError`, an :class:`~gearsim.errors.InputError`, so the
  command ends with exit status 2 and one line.
- :func:`atomic_writer` (and the two helpers on top of it) writes to a
  temporary file beside the target and renames it over the target only when
  the whole output is written: a reader never sees half a file, and a failed
  command leaves the old file (or none) in place.
- :func:`printable` makes any text safe for a one-line terminal message:
  control characters and undecodable bytes are shown escaped, and long text
  is cut.
"""

from __future__ import annotations

import contextlib
import os
import stat
import sys
import tempfile
from collections.abc import Iterable, Iterator
from typing import IO, Any

from .errors import InputError

__all__ = [
    "OutputPathError",
    "check_output",
    "atomic_writer",
    "atomic_write_text",
    "atomic_write_bytes",
    "printable",
    "one_line",
    "MESSAGE_LIMIT",
    "same_file",
    "file_mode",
    "say",
    "stdout_to_devnull",
]


class OutputPathError(InputError):
    """An output path that would lose data or cannot be written."""


def printable(text: Any, limit: int = 80) -> str:
    """``text`` (str or bytes) as one printable line of at most ``limit``
    characters: non-printable characters escaped (``\\x00``, ``\\u202e``, ...),
    bytes decoded as Latin-1 first, and ``...`` where it was cut."""
    if isinstance(text, (bytes, bytearray)):
        text = bytes(text).decode("latin-1")
    text = str(text)
    out: list[str] = []
    length = 0
    for ch in text:
        piece = ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii")
        if length + len(piece) > limit:
            out.append("...")
            break
        out.append(piece)
        length += len(piece)
    return "".join(out)


#: Longest error line a command writes on standard error.
MESSAGE_LIMIT = 600


def one_line(text: Any, limit: int = MESSAGE_LIMIT) -> str:
    """Any message as one printable line: whitespace runs folded, control
    characters escaped, cut at ``limit`` characters."""
    return printable(" ".join(str(text).split()), limit=limit)


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """True when ``a`` and ``b`` name the same file (the same inode when both
    exist, else the same resolved path)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def check_output(
    path: str | os.PathLike[str] | None,
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    *,
    option: str = "--out",
    directory: bool = False,
    probe: bool = True,
) -> str:
    """Validates an output path before the command does any work; returns it
    as a string. ``inputs`` are the files the command reads (``None`` and
    ``"-"`` entries are ignored). ``directory``: the output is a directory
    (created later by the command) rather than a file. ``probe=False`` skips
    the write probe of the directory, for files in one already checked."""
    if path is None or str(path).strip() == "":
        raise OutputPathError(f"{option}: empty path; name a file to write", parameter=option)
    target = os.fspath(path)
    if target == "-":
        return target  # standard output
    shown = printable(target)
    for src in inputs:
        if src is None or os.fspath(src) == "-":
            continue
        if same_file(target, src):
            raise OutputPathError(
                f"{option} {shown}: that is an input of this command "
                f"({printable(os.fspath(src))}); refusing to overwrite it, choose another path",
                parameter=option,
            )
    if directory:
        if os.path.exists(target) and not os.path.isdir(target):
            raise OutputPathError(
                f"{option} {shown}: exists and is not a directory", parameter=option
            )
        parent = target if os.path.isdir(target) else (os.path.dirname(os.path.abspath(target)))
    else:
        if os.path.isdir(target):
            raise OutputPathError(
                f"{option} {shown}: is a directory; name a file inside it", parameter=option
            )
        parent = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(parent):
        raise OutputPathError(
            f"{option} {shown}: directory {printable(parent)} does not exist", parameter=option
        )
    if probe:
        _check_writable(parent, option, shown)
    return target


def _check_writable(directory: str, option: str, shown: str) -> None:
    """Creates and removes a temporary file: os.access alone is wrong for root
    on read-only mounts and for ACLs."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".gearsim-probe-", dir=directory)
    except OSError as exc:
        raise OutputPathError(
            f"{option} {shown}: cannot write in {printable(directory)} ({exc.strerror or exc})",
            parameter=option,
        ) from None
    os.close(fd)
    os.unlink(tmp)


def file_mode(target: str) -> int:
    """The permissions the written file gets: those of the file it replaces,
    else what open() would give a new file (0666 minus the umask)."""
    try:
        return stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask


@contextlib.contextmanager
def atomic_writer(
    path: str | os.PathLike[str], mode: str = "w", **open_kwargs: Any
) -> Iterator[IO[Any]]:
    """A file object writing to a temporary file beside ``path``; renamed over
    ``path`` when the block ends without an exception, removed otherwise."""
    target = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(target))
    fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(target)}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, mode, **open_kwargs) as fh:
            os.fchmod(fh.fileno(), file_mode(target))  # not mkstemp's 0600
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> None:
    with atomic_writer(path, "w", encoding=encoding, newline="") as fh:
        fh.write(text)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    with atomic_writer(path, "wb") as fh:
        fh.write(data)


def say(line: str) -> None:
    """One line on stderr (a command's error or note); a closed stderr is not
    an error of its own."""
    try:
        sys.stderr.write(line + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def stdout_to_devnull() -> None:
    """Standard output is a pipe whose reader left: point its descriptor at
    /dev/null, so that the flush at interpreter shutdown does not print
    'Exception ignored ... BrokenPipeError'."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return  # not a real file (captured in a test): nothing is flushed at exit
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        return
    try:
        os.dup2(devnull, fd)
    except OSError:
        pass
    finally:
        os.close(devnull)
