"""The fleet's cache: one row per (content hash, model, options, code).

A SQLite file (the standard library's sqlite3) beside the outputs. Each
result is committed as soon as it arrives, so a run that is stopped (Ctrl-C,
a crash, a lost client) keeps every unit it finished, and the next run with
the same model and options only analyses the units it does not have: the new
logs of a grown folder, a log whose content changed, the rows of an
"internal" error. The key does not depend on the path or the unit id: a log
moved or renamed is still found.
"""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
from collections.abc import Iterable, Iterator

__all__ = ["Cache", "cache_key", "CACHEABLE_KINDS"]

#: error rows kept like results (the same file gives the same error)
CACHEABLE_KINDS = (None, "input", "analysis")
_SCHEMA = "CREATE TABLE IF NOT EXISTS rows (key TEXT PRIMARY KEY, row TEXT NOT NULL)"


def cache_key(content_hash: str | None, model_text: str, options: dict, code: str) -> str | None:
    """sha256 over the four (None when the file could not be hashed)."""
    if content_hash is None:
        return None
    blob = json.dumps(
        {"data": content_hash, "model": model_text, "options": options, "code": code},
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


class Cache:
    """Rows by key, committed one transaction per put_many."""

    def __init__(self, path: str) -> None:
        self.path = path
        self._db = sqlite3.connect(path, timeout=30.0)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute(_SCHEMA)
        self._db.commit()

    def keys_present(self, keys: Iterable[str]) -> set[str]:
        out: set[str] = set()
        batch: list[str] = []
        for k in keys:
            batch.append(k)
            if len(batch) == 500:
                out |= self._present(batch)
                batch = []
        if batch:
            out |= self._present(batch)
        return out

    def _present(self, batch: list[str]) -> set[str]:
        marks = ",".join("?" * len(batch))
        cur = self._db.execute(f"SELECT key FROM rows WHERE key IN ({marks})", batch)
        return {r[0] for r in cur}

    def get(self, key: str) -> dict | None:
        cur = self._db.execute("SELECT row FROM rows WHERE key = ?", (key,))
        hit = cur.fetchone()
        return None if hit is None else json.loads(hit[0])

    def rows(self, keys: Iterable[str | None]) -> Iterator[dict | None]:
        """The row of each key in order (None where absent)."""
        for k in keys:
            yield None if k is None else self.get(k)

    def put_many(self, items: list[tuple[str, dict]]) -> None:
        if not items:
            return
        self._db.executemany(
            "INSERT OR REPLACE INTO rows (key, row) VALUES (?, ?)",
            [(k, json.dumps(r, allow_nan=True)) for k, r in items],
        )
        self._db.commit()

    def __len__(self) -> int:
        return int(self._db.execute("SELECT COUNT(*) FROM rows").fetchone()[0])

    def close(self) -> None:
        self._db.close()

    @staticmethod
    def count(path: str) -> int:
        """Rows in a cache file (0 when there is none): for watching a run."""
        if not os.path.exists(path):
            return 0
        db = sqlite3.connect(path, timeout=30.0)
        try:
            return int(db.execute("SELECT COUNT(*) FROM rows").fetchone()[0])
        except sqlite3.OperationalError:
            return 0
        finally:
            db.close()
