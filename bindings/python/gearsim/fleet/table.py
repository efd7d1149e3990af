"""The fleet's Parquet file: one row per unit, written in row groups.

The schema (docs/fleet.md, "The Parquet file") has a fixed part, one pair
of nrmse columns per output of the rig, and one value / standard-deviation
column pair per fitted parameter (the union over the units; empty where a
unit did not fit it). Rows are written ROW_GROUP at a time in the input
order, from the cache and the rows of this run, so the file never needs all
units in memory; the file is written to a temporary name and renamed into
place when complete.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from typing import Any

from .._outputs import atomic_writer
from .units import Unit

__all__ = ["ROW_GROUP", "FIXED_COLUMNS", "schema", "write_parquet", "param_column", "std_column"]

ROW_GROUP = 256

#: (name, pyarrow type name) of the columns every fleet file has, in order;
#: "ts" is the timestamp, "list" a list of strings.
FIXED_COLUMNS: tuple[tuple[str, str], ...] = (
    ("unit", "string"),
    ("path", "string"),
    ("line", "string"),
    ("station", "string"),
    ("timestamp", "ts"),
    ("status", "string"),
    ("error", "string"),
    ("error_kind", "string"),
    ("mode", "string"),
    ("effects_fitted", "list"),
    ("effects_found", "list"),
    ("samples", "int64"),
    ("dt", "float64"),
    ("nrmse_before", "float64"),
    ("nrmse_after", "float64"),
    ("validation_nrmse_before", "float64"),
    ("validation_nrmse_after", "float64"),
    ("outlier", "bool"),
    ("outlier_by", "string"),
    ("outlier_z", "float64"),
    ("outlier_reasons", "list"),
    ("warnings", "list"),
    ("content_hash", "string"),
    ("tool_version", "string"),
    ("code_id", "string"),
    ("worker", "string"),
    ("seconds", "float64"),
    ("cpu_seconds", "float64"),
    ("from_cache", "bool"),
    ("model", "string"),
)
_FIXED = {name for name, _ in FIXED_COLUMNS}


def param_column(name: str) -> str:
    """The value column of a fitted parameter: its name (prefixed param_
    only if it ever clashed with a fixed column)."""
    return f"param_{name}" if name in _FIXED else name


def std_column(name: str) -> str:
    return f"{param_column(name)}_std"


def _type(kind: str, aware: bool):
    import pyarrow as pa

    return {
        "string": pa.string(),
        "float64": pa.float64(),
        "int64": pa.int64(),
        "bool": pa.bool_(),
        "list": pa.list_(pa.string()),
        "ts": pa.timestamp("us", tz="UTC" if aware else None),
    }[kind]


def schema(outputs: list[str], params: list[str], aware: bool, meta: dict[str, Any]):
    import pyarrow as pa

    fields = [pa.field(n, _type(k, aware)) for n, k in FIXED_COLUMNS]
    for o in outputs:
        fields += [
            pa.field(f"nrmse_before_{o}", pa.float64()),
            pa.field(f"nrmse_after_{o}", pa.float64()),
        ]
    for p in params:
        fields += [pa.field(param_column(p), pa.float64()), pa.field(std_column(p), pa.float64())]
    return pa.schema(fields, metadata={"gearsim.fleet": json.dumps(meta)})


def _record(unit: Unit, row: dict, outputs: list[str], params: list[str], pop: dict) -> dict:
    rec: dict[str, Any] = {
        "unit": unit.unit,
        "path": unit.path,
        "line": unit.line,
        "station": unit.station,
        "timestamp": unit.timestamp,
    }
    for name, _ in FIXED_COLUMNS[5:]:
        if name not in rec:
            rec[name] = row.get(name)
    for key in ("effects_fitted", "effects_found", "warnings"):
        rec[key] = list(row.get(key) or [])
    o = pop.get(unit.unit)
    rec["outlier"] = o is not None if row.get("status") == "ok" else None
    rec["outlier_by"] = o["by"] if o else None
    rec["outlier_z"] = o["z"] if o else None
    rec["outlier_reasons"] = [r["metric"] for r in o["reasons"]] if o else []
    before, after = row.get("outputs_before") or {}, row.get("outputs_after") or {}
    for out in outputs:
        rec[f"nrmse_before_{out}"] = before.get(out)
        rec[f"nrmse_after_{out}"] = after.get(out)
    values = row.get("parameters") or {}
    for p in params:
        v = values.get(p)
        rec[param_column(p)] = None if v is None else v["value"]
        rec[std_column(p)] = None if v is None else v["std"]
    return rec


def write_parquet(
    path: str,
    pairs: Iterable[tuple[Unit, dict]],
    *,
    outputs: list[str],
    params: list[str],
    aware: bool,
    outliers: dict[str, dict],
    meta: dict[str, Any],
) -> int:
    """Write the (unit, row) pairs, in their order, ROW_GROUP rows per row
    group, atomically. outliers: unit id -> its outlier entry of the
    population. Returns the number of rows."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    sch = schema(outputs, params, aware, meta)
    count = 0
    with atomic_writer(path, "wb") as fh:
        writer = pq.ParquetWriter(fh, sch, compression="zstd")
        try:
            for batch in _batches(pairs, ROW_GROUP):
                recs = [_record(u, r, outputs, params, outliers) for u, r in batch]
                cols = {f.name: [rec[f.name] for rec in recs] for f in sch}
                writer.write_table(pa.Table.from_pydict(cols, schema=sch), row_group_size=ROW_GROUP)
                count += len(recs)
        finally:
            writer.close()
    return count


def _batches(items: Iterable[Any], size: int) -> Iterator[list[Any]]:
    batch: list[Any] = []
    for it in items:
        batch.append(it)
        if len(batch) == size:
            yield batch
            batch = []
    if batch:
        yield batch
