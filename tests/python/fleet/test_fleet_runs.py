"""Runs of the fleet: bad logs become error rows without touching the
others, a grown folder only analyses its new logs, and a real distributed
run (a `dask scheduler` and two `dask worker` processes on localhost) gives
the local run's rows, even when one worker is killed mid-run."""

from __future__ import annotations

import bz2
import gzip
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import fleet_helpers as H
import pyarrow.parquet as pq
import pytest

from gearsim.fleet import FleetOptions, run_fleet

#: columns that say where or when a row was computed, not what
RUN_COLUMNS = {"worker", "seconds", "cpu_seconds", "from_cache", "path"}
#: columns that depend on the population a unit is judged in
POPULATION_COLUMNS = {"outlier", "outlier_by", "outlier_z", "outlier_reasons"}
DASK = Path(sys.executable).with_name("dask")
GEARSIM = Path(sys.executable).with_name("gearsim")
BOUND_S = 240  # any process of these tests


def _frame(path):
    return pq.read_table(path).to_pandas().set_index("unit")


def _same_rows(a, b, units, skip=RUN_COLUMNS | POPULATION_COLUMNS):
    cols = [c for c in a.columns if c not in skip]
    assert cols == [c for c in b.columns if c not in skip]
    for u in units:
        ra, rb = a.loc[u, cols], b.loc[u, cols]
        for c in cols:
            va, vb = ra[c], rb[c]
            same = (
                repr(list(va)) == repr(list(vb))
                if hasattr(va, "__len__") and not isinstance(va, str)
                else ((va != va and vb != vb) or va == vb or repr(va) == repr(vb))
            )
            assert same, (u, c, va, vb)


def _bad_logs(folder: Path, good: Path) -> dict[str, str]:
    """The battery: name -> what its error must say."""
    text = good.read_text()
    lines = text.splitlines(keepends=True)
    cut = "".join(lines[:200]) + lines[200][: len(lines[200]) // 3]
    (folder / "bad-truncated.csv").write_text(cut)
    (folder / "bad-binary.csv").write_bytes(bytes(range(256)) * 40)
    (folder / "bad-columns.csv").write_text(
        "t,speed,torque\n" + "".join(f"{i * 1e-3},1,2\n" for i in range(100))
    )
    (folder / "bad-empty.csv").write_bytes(b"")
    (folder / "bad-header-only.csv").write_text(lines[0])
    (folder / "bad-nan.csv").write_text(
        "".join(lines[:50])
        + lines[50].replace(lines[50].split(",")[2], "nan", 1)
        + "".join(lines[51:300])
    )
    gz = gzip.compress(text.encode(), mtime=0)
    (folder / "bad-truncated-gz.csv.gz").write_bytes(gz[: len(gz) // 2])
    # a rack's log in a gear fleet: the model does not fit the rig
    import dataclasses

    sys.path.insert(0, str(Path(H.__file__).parent.parent / "analysis"))
    from independent import generate

    from gearsim.analysis import write_measurement

    rack = generate("rack_pinion", ("coulomb_friction",), duration_s=0.5, seed=3)
    write_measurement(folder / "bad-rack.csv", rack.measurement)
    _ = dataclasses, bz2
    return {
        "bad-truncated": "line 201",
        "bad-binary": "not a text",
        "bad-columns": "base_speed",
        "bad-empty": "bad-empty.csv",
        "bad-header-only": "no data",
        "bad-nan": "line 51",
        "bad-truncated-gz": "gzip",
        "bad-rack": "base_speed",
    }


def test_bad_logs_become_error_rows_and_a_grown_folder_only_does_the_new(line, tmp_path):
    specs, manifest, model = line
    good = tmp_path / "good"
    mixed = tmp_path / "mixed"
    good.mkdir()
    mixed.mkdir()
    for s in specs[:10]:
        shutil.copy(manifest.parent / f"{s.unit}.csv", good)
        shutil.copy(manifest.parent / f"{s.unit}.csv", mixed)
    expect = _bad_logs(mixed, manifest.parent / f"{specs[0].unit}.csv")
    opts = FleetOptions(effects=H.EFFECTS)
    ref = run_fleet(
        str(good),
        model=str(model),
        out=str(tmp_path / "ref"),
        options=opts,
        workers=2,
        quiet=True,
        report=False,
    )
    out = tmp_path / "out"
    res = run_fleet(str(mixed), model=str(model), out=str(out), options=opts, workers=2, quiet=True)
    assert res.counts["units"] == 18 and res.counts["ok"] == 10 and res.counts["errors"] == 8
    a, b = _frame(ref.parquet), _frame(res.parquet)
    _same_rows(a, b, [s.unit for s in specs[:10]])  # the good units are unaffected
    for unit, words in expect.items():
        row = b.loc[unit]
        assert row["status"] == "error" and row["error_kind"] == "input", (unit, row["error"])
        assert words in row["error"] and "\n" not in row["error"], (unit, row["error"])
        assert len(row["error"]) <= 600
    assert "bad-rack" in open(res.report, encoding="utf-8").read()
    # the folder grows by two logs: only they are analysed
    for s in specs[10:12]:
        shutil.copy(manifest.parent / f"{s.unit}.csv", mixed)
    again = run_fleet(
        str(mixed),
        model=str(model),
        out=str(out),
        options=opts,
        workers=2,
        quiet=True,
        report=False,
    )
    assert again.counts["cached"] == 18 and again.counts["computed"] == 2
    c = _frame(again.parquet)
    assert c.loc[[s.unit for s in specs[:10]], "from_cache"].all()
    assert not c.loc[[s.unit for s in specs[10:12]], "from_cache"].any()
    _same_rows(b, c, list(expect) + [s.unit for s in specs[:10]])
    # another option is another key: nothing from the cache
    other = run_fleet(
        str(good),
        model=str(model),
        out=str(out),
        options=FleetOptions(effects=H.EFFECTS[:2]),
        workers=2,
        quiet=True,
        report=False,
    )
    assert other.counts["cached"] == 0
    assert not list(out.glob(".*.tmp"))  # no temporary file left


def _start(cmd, log: Path, env) -> subprocess.Popen:
    fh = open(log, "w")
    return subprocess.Popen(
        cmd, stdout=fh, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two workers (no nanny: a killed worker stays dead)
    on 127.0.0.1; all stopped at the end."""
    env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    info = tmp_path / "scheduler.json"
    procs = []
    try:
        procs.append(
            _start(
                [
                    str(DASK),
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(info),
                ],
                tmp_path / "scheduler.log",
                env,
            )
        )
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(info.read_text())["address"]
        workers = []
        for name in ("w1", "w2"):
            workers.append(
                _start(
                    [
                        str(DASK),
                        "worker",
                        address,
                        "--nthreads",
                        "1",
                        "--no-nanny",
                        "--no-dashboard",
                        "--name",
                        name,
                    ],
                    tmp_path / f"{name}.log",
                    env,
                )
            )
        procs += workers
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers, tmp_path / "scheduler.log"
    finally:
        for p in reversed(procs):
            _stop(p)


def _fleet_cli(manifest, model, out, address, extra=()):
    return subprocess.Popen(
        [
            str(GEARSIM),
            "fleet",
            "--manifest",
            str(manifest),
            "--model",
            str(model),
            "--out",
            str(out),
            "--add",
            ",".join(H.EFFECTS),
            "--scheduler",
            address,
            "--json",
            "--quiet",
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_distributed_run_equals_the_local_one_even_with_a_worker_killed(
    line, line_run, cluster, tmp_path
):
    from gearsim.fleet.cache import Cache

    specs, manifest, model = line
    address, workers, sched_log = cluster
    sub = tmp_path / "manifest.csv"
    rows = manifest.read_text().splitlines(keepends=True)
    n = 24
    sub.write_text(
        rows[0] + "".join(r.replace(",gx-", f",{manifest.parent}/gx-", 1) for r in rows[1 : n + 1])
    )
    local = _frame(line_run.parquet)
    units = [s.unit for s in specs[:n]]

    out = tmp_path / "dist"
    proc = _fleet_cli(sub, model, out, address)
    stdout, stderr = proc.communicate(timeout=BOUND_S)
    assert proc.returncode == 0, stderr
    summary = json.loads(stdout)
    assert summary["ok"] == n and summary["errors"] == 0
    dist = _frame(out / "units.parquet")
    _same_rows(local, dist, units)
    assert dist["worker"].nunique() == 2  # both workers took units

    # again, and kill the second worker once a few units are in
    out2 = tmp_path / "killed"
    proc = _fleet_cli(sub, model, out2, address)
    deadline = time.monotonic() + BOUND_S
    while Cache.count(str(out2 / "cache.sqlite")) < 4 and time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    workers[1].send_signal(signal.SIGKILL)
    workers[1].wait(10)
    done_at_kill = Cache.count(str(out2 / "cache.sqlite"))
    stdout, stderr = proc.communicate(timeout=BOUND_S)
    assert proc.returncode == 0, stderr
    summary = json.loads(stdout)
    assert summary["ok"] == n and summary["lost"] == 0, summary
    killed = _frame(out2 / "units.parquet")
    _same_rows(local, killed, units)
    assert done_at_kill < n
    assert "Remove worker" in sched_log.read_text() and "name: w2" in sched_log.read_text()
    print(
        f"fleet distributed: {n} units equal to the local run; worker w2 killed after "
        f"{done_at_kill} units, all {n} rows ok ({(killed['worker'].value_counts()).to_dict()})"
    )


def test_unreachable_scheduler_is_one_line(line, tmp_path):
    specs, manifest, model = line
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nobody listens there now
    proc = subprocess.run(
        [
            str(GEARSIM),
            "fleet",
            str(manifest.parent / "gx-000*.csv"),
            "--model",
            str(model),
            "--out",
            str(tmp_path / "o"),
            "--add",
            "coulomb_friction",
            "--scheduler",
            f"tcp://127.0.0.1:{port}",
        ],
        capture_output=True,
        text=True,
        timeout=BOUND_S,
    )
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and "cannot connect" in proc.stderr, (
        proc.stderr
    )


def test_an_interrupted_run_leaves_no_partial_output_and_resumes(line, tmp_path):
    from gearsim.fleet.cache import Cache

    specs, manifest, model = line
    logs = tmp_path / "logs"
    logs.mkdir()
    for s in specs[:16]:
        shutil.copy(manifest.parent / f"{s.unit}.csv", logs)
    out = tmp_path / "out"
    cmd = [
        str(GEARSIM),
        "fleet",
        str(logs),
        "--model",
        str(model),
        "--out",
        str(out),
        "--add",
        ",".join(H.EFFECTS),
        "--workers",
        "2",
        "--json",
        "--quiet",
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + BOUND_S
    while Cache.count(str(out / "cache.sqlite")) < 3 and time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=BOUND_S)
    kept = Cache.count(str(out / "cache.sqlite"))
    if proc.returncode == 0:  # pragma: no cover - the run beat the signal
        pytest.skip("the run finished before it could be interrupted")
    assert proc.returncode == 130, stderr
    assert stdout == ""
    assert not (out / "units.parquet").exists() and not list(out.glob(".*.tmp"))
    assert 3 <= kept < 16
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=BOUND_S)
    assert again.returncode == 0, again.stderr
    summary = json.loads(again.stdout)
    assert summary["cached"] == kept and summary["computed"] == 16 - kept and summary["ok"] == 16
