"""The table stage: the wanted columns of the body rows parsed into a float
table, by pandas' C parser when the text is plain numbers, else row by row so
that the first short row or bad cell is named; and the file line of each row,
for the messages of the later stages."""

from __future__ import annotations

import io
import re
from collections.abc import Callable

import numpy as np

from ..._outputs import printable
from ..errors import MeasurementError
from .sniff import Column, Header, Layout, split
from .source import Text, decode, iter_lines

_EOL_TEXT = re.compile(r"\r\n|\r|\n")


def read_table(
    text: Text, layout: Layout, wanted: list[Column], shown: str
) -> tuple[np.ndarray, Callable[[int], int]]:
    """The `wanted` columns of every non-blank row after the header (in the
    header's units), and line_of(row): the file line of a row."""
    hdr = layout.header
    how_msg = f" (read{layout.how})" if layout.how else ""
    table = _parse_fast(
        text.data, hdr.body_start, [c.index for c in wanted], layout.sep, layout.dec
    )
    lines: list[int] | None = None
    if table is None or not np.isfinite(table).all():
        table, lines = _parse_slow(
            text.data[hdr.body_start :],
            hdr.body_line,
            wanted,
            layout.sep,
            layout.dec,
            len(layout.fields),
            shown,
            how_msg,
        )
    if table.shape[0] == 0:
        raise MeasurementError(
            f"has a header (line {hdr.line}) but no data rows{text.inside}", file=shown
        )
    return table, _line_finder(text.data, hdr, lines)


def _line_finder(data: bytes, hdr: Header, lines: list[int] | None) -> Callable[[int], int]:
    """line_of(row) from the lines the slow parse found, or, after the fast
    one, from the non-blank lines counted on the first call (a message only)."""
    line_cache: list[list[int]] = [lines] if lines is not None else []

    def line_of(row: int) -> int:
        if not line_cache:
            line_cache.append(
                [
                    ln
                    for ln, _s, raw, _n in iter_lines(data, hdr.body_start, hdr.body_line - 1)
                    if raw.strip()
                ]
            )
        found = line_cache[0]
        return found[row] if 0 <= row < len(found) else hdr.body_line + row

    return line_of


def _parse_fast(
    data: bytes, start: int, usecols: list[int], sep: str, dec: str
) -> np.ndarray | None:
    """The numeric table by pandas' C parser (about 3x faster than a Python loop
    on a million rows), or None when pandas is missing or the text is not
    plain numbers (empty cells, text, nan/inf, short rows): the slow path then
    parses it and locates any bad cell."""
    if sep == dec:
        return None
    try:
        import pandas as pd
    except ImportError:
        return None
    buf = io.BytesIO(data)  # shares the bytes; reading starts at the body
    buf.seek(start)
    try:
        frame = pd.read_csv(
            buf,
            header=None,
            sep=sep,
            decimal=dec,
            usecols=sorted(set(usecols)),
            dtype=float,
            na_filter=False,
            engine="c",
            encoding="latin-1",
        )
    except (ValueError, TypeError, IndexError, OverflowError, pd.errors.ParserError):
        return None
    # pandas orders usecols by position; the callers expect the given order
    order = sorted(set(usecols))
    table = frame[order].to_numpy(dtype=float)
    return np.ascontiguousarray(table[:, [order.index(c) for c in usecols]])


def _parse_slow(
    body: bytes,
    first_line: int,
    wanted: list[Column],
    sep: str,
    dec: str,
    ncols: int,
    shown: str,
    how: str,
) -> tuple[np.ndarray, list[int]]:
    """Parses row by row; raises at the first short row or bad cell.
    Returns the table and the file line of each row."""
    need = max(c.index for c in wanted)
    rows: list[list[float]] = []
    lines: list[int] = []
    text = decode(body)
    for k, line in enumerate(_EOL_TEXT.split(text)):
        if not line.strip():
            continue
        lineno = first_line + k
        row = split(line, sep)
        if len(row) <= need:
            missing = [c for c in wanted if c.index >= len(row)]
            raise MeasurementError(
                f"row has {len(row)} field{'s' if len(row) != 1 else ''}, the header has "
                f"{ncols}; no value for this column{how}",
                file=shown,
                line=lineno,
                column=missing[0].shown,
            )
        values: list[float] = []
        for c in wanted:
            cell = row[c.index].strip()
            try:
                values.append(float(cell.replace(",", ".") if dec == "," else cell))
            except ValueError:
                what = "is empty" if not cell else f"'{printable(cell, 30)}' is not a number"
                raise MeasurementError(
                    what + how, file=shown, line=lineno, column=c.shown
                ) from None
        rows.append(values)
        lines.append(lineno)
    table = np.array(rows, dtype=float).reshape(len(rows), len(wanted))
    return table, lines
