"""HIL loop timing and replay throughput: the C runner and the Python bridge
side by side, in one run (docs/hil-runner.md, docs/performance.md "HIL").

Loop timing, at each rate (default 1 kHz and 10 kHz) for --seconds of wall
time each, with the rig step, the codec and the transport in the loop:

- C runner, default scheduling: gearsim-hil on candump pipes, a host process
  sending a command every 10 ms and draining the feedback;
- C runner, SCHED_FIFO (--fifo PRIO), where permitted (else reported refused);
- Python bridge: Bridge.run on python-can's virtual bus, a host thread sending
  a command every 10 ms and draining the feedback (examples/hil/loop_timing.py).

Lateness is the period start minus its deadline; period error is
|start[k+1] - start[k] - period|; CPU share is the loop's CPU time over its
wall time (the C runner's process; the Python loop's thread).

Under load (--loads, default idle,other,same): the same loops with the loop
pinned to --cpu (default 0) and a CPU hog (a busy Python process) pinned to
the other core ("other") or to the same one ("same"); the C runner with
--cpu, and for its SCHED_FIFO run also --mlockall; the Python bridge's
process pinned with sched_setaffinity. p50, p99, p99.9 and max lateness and
the overruns are reported side by side with the idle figures.

Replay throughput: one session log (commands every 10 ms and the recorded
feedback, --replay-seconds of simulated time, candump .log) replayed by
gearsim-hil and by gearsim.hil.replay; input frames per wall second.

    python bench/hil_bench.py [--seconds 60] [--rates 1000,10000] [--spin-us US]
                              [--fifo 50] [--loads idle,other,same] [--cpu 0]
                              [--replay-seconds 60] [--no-python] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import can

import gearsim
from gearsim._outputs import atomic_write_text
from gearsim.hil import Bridge, LoopStats, RigDbc, replay
from gearsim.hil import runner as runner_mod

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "examples" / "hil" / "gear_model.toml"
COMMAND_EVERY = 0.01  # s, as a rig controller commands


def command_lines(dbc: RigDbc, t: float) -> bytes:
    speed = 20.0 * math.sin(2 * math.pi * 0.5 * t)
    msgs = dbc.encode_command({"cmd.base_speed": speed, "cmd.load": 0.3})
    return "".join(
        f"({time.time():.6f}) can0 {m.arbitration_id:03X}#{m.data.hex().upper()}\n" for m in msgs
    ).encode()


@contextlib.contextmanager
def cpu_hog(cpu: int | None):
    """A busy process pinned to cpu for the duration (None: no hog)."""
    if cpu is None:
        yield
        return
    hog = subprocess.Popen(
        [sys.executable, "-c", f"import os; os.sched_setaffinity(0, {{{cpu}}})\nwhile True: pass"]
    )
    try:
        time.sleep(0.2)  # running before the loop starts
        yield
    finally:
        hog.kill()
        hog.wait()


def c_loop(
    runner: Path,
    params: Path,
    rate: float,
    seconds: float,
    spin_us: int | None,
    fifo: int | None,
    cpu: int | None = None,
) -> dict[str, Any]:
    """The C runner paced for `seconds`, driven by this process over pipes;
    with cpu pinned there (and with fifo, memory locked)."""
    dbc = RigDbc(block="gear")
    cmd = runner_mod.live_command(
        params,
        period=1.0 / rate,
        duration=seconds,
        spin_us=spin_us,
        fifo=fifo,
        cpu=cpu,
        mlockall=fifo is not None and cpu is not None,
        runner=runner,
    )
    proc = subprocess.Popen(
        cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    os.set_blocking(proc.stdout.fileno(), False)
    received = 0
    start = time.monotonic()
    next_t = start
    try:
        while proc.poll() is None:
            now = time.monotonic()
            if now >= next_t:
                try:
                    proc.stdin.write(command_lines(dbc, now - start))
                    proc.stdin.flush()
                except BrokenPipeError:
                    break
                next_t += COMMAND_EVERY
            ready, _, _ = select.select([proc.stdout], [], [], max(0.0, next_t - time.monotonic()))
            if ready:
                received += (proc.stdout.read() or b"").count(b"\n")
        try:
            proc.stdin.close()
        except BrokenPipeError:  # the runner exited first (refused or done): its stderr says why
            pass
        proc.stdin = None
    except BaseException:
        proc.send_signal(signal.SIGINT)
        raise
    os.set_blocking(proc.stdout.fileno(), True)
    out, err = proc.communicate(timeout=60)
    received += out.count(b"\n")
    text = err.decode()
    if proc.returncode != 0:
        return {
            "refused": text.strip().splitlines()[-1] if text.strip() else f"exit {proc.returncode}"
        }
    s = json.loads(text.strip().splitlines()[-1])
    loop = s["loop"]
    return {
        "periods": s["periods"],
        "lateness_median_us": loop["lateness"]["median_us"],
        "lateness_p99_us": loop["lateness"]["p99_us"],
        "lateness_p999_us": loop["lateness"]["p999_us"],
        "lateness_max_us": loop["lateness"]["max_us"],
        "period_error_median_us": loop["period_error"]["median_us"],
        "period_error_p99_us": loop["period_error"]["p99_us"],
        "period_error_max_us": loop["period_error"]["max_us"],
        "work_median_us": loop["work"]["median_us"],
        "work_max_us": loop["work"]["max_us"],
        "overruns": s["overruns"],
        "resyncs": s["resyncs"],
        "cpu_share": s["cpu_share"],
        "rx_used": s["rx_used"],
        "rx_late": s["rx_late"],
        "tx_frames": s["tx_frames"],
        "feedback_received_by_host": received,
    }


def python_loop(rate: float, seconds: float, spin: float, cpu: int | None = None) -> dict[str, Any]:
    """Bridge.run on the virtual bus with a host thread (examples/hil/loop_timing.py);
    with cpu, the process pinned there for the run."""
    allowed = os.sched_getaffinity(0)
    if cpu is not None:
        os.sched_setaffinity(0, {cpu})
    try:
        return _python_loop(rate, seconds, spin)
    finally:
        os.sched_setaffinity(0, allowed)


def _python_loop(rate: float, seconds: float, spin: float) -> dict[str, Any]:
    model = gearsim.Model.load(MODEL)
    dbc = RigDbc(block=model.block)
    stop = threading.Event()
    received = [0]

    def host(bus: can.BusABC) -> None:
        next_t = time.perf_counter()
        start = next_t
        while not stop.is_set():
            t = time.perf_counter() - start
            for msg in dbc.encode_command(
                {"cmd.base_speed": 20.0 * math.sin(math.pi * t), "cmd.load": 0.3}
            ):
                bus.send(msg)
            while bus.recv(timeout=0.0) is not None:
                received[0] += 1
            next_t += COMMAND_EVERY
            time.sleep(max(0.0, next_t - time.perf_counter()))

    channel = f"hil-bench-{os.getpid()}-{rate}"
    with (
        can.Bus(interface="virtual", channel=channel) as bridge_bus,
        can.Bus(interface="virtual", channel=channel) as host_bus,
    ):
        bridge = Bridge.from_model(model, dbc, period=1.0 / rate, bus=bridge_bus)
        peer = threading.Thread(target=host, args=(host_bus,), daemon=True)
        peer.start()
        cpu0, wall0 = time.thread_time(), time.perf_counter()
        stats: LoopStats = bridge.run(duration=seconds, spin=spin)
        cpu, wall = time.thread_time() - cpu0, time.perf_counter() - wall0
        stop.set()
        peer.join()
        summary = bridge.close()
    loop = stats.summary()
    import numpy as np

    late = np.frombuffer(stats.lateness, dtype=np.float64) * 1e6
    return {
        "periods": int(loop["periods"]),
        "lateness_median_us": loop.get("lateness_median_us"),
        "lateness_p99_us": loop.get("lateness_p99_us"),
        "lateness_p999_us": float(np.percentile(late, 99.9)) if len(late) else None,
        "lateness_max_us": loop.get("lateness_max_us"),
        "period_error_median_us": loop.get("period_error_median_us"),
        "period_error_p99_us": loop.get("period_error_p99_us"),
        "period_error_max_us": loop.get("period_error_max_us"),
        "overruns": summary["overruns"],
        "resyncs": summary["resyncs"],
        "cpu_share": cpu / wall if wall > 0 else 0.0,
        "rx_used": summary["rx_used"],
        "rx_late": summary["rx_late"],
        "tx_frames": summary["tx_frames"],
        "feedback_received_by_host": received[0],
    }


def session_log(path: Path, seconds: float) -> int:
    """Commands every 10 ms and the bridge's feedback, 1 ms periods, as recorded (no wall clock)."""
    model = gearsim.Model.load(MODEL)
    dbc = RigDbc(block=model.block)
    n = 0
    with can.Logger(str(path)) as logger:

        def log(msg: can.Message) -> None:
            nonlocal n
            n += 1
            logger.on_message_received(msg)

        bridge = Bridge.from_model(model, dbc, period=1e-3, send=log, stamp=lambda t: 1.7e9 + t)
        for k in range(round(seconds / 1e-3)):
            if k % 10 == 0:
                t = k * 1e-3
                for msg in dbc.encode_command(
                    {"cmd.base_speed": 20.0 * math.sin(math.pi * t), "cmd.load": 0.3}
                ):
                    msg.timestamp = 1.7e9 + t
                    msg.is_extended_id = False
                    log(msg)
                    bridge.handle(msg)
            bridge.advance(1)
    return n


def replay_throughput(runner: Path, params: Path, seconds: float, workdir: Path) -> dict[str, Any]:
    log = workdir / "session.log"
    frames = session_log(log, seconds)
    t0 = time.perf_counter()
    res = subprocess.run(
        runner_mod.replay_command(params, log, workdir / "c_answers.log", runner=runner),
        capture_output=True,
        text=True,
        check=True,
    )
    c_wall = time.perf_counter() - t0
    c = json.loads(res.stderr.strip().splitlines()[-1])
    py = replay(gearsim.Model.load(MODEL), log, workdir / "py_answers.log")
    return {
        "simulated_s": seconds,
        "input_frames": frames,
        "c": {
            "frames_per_s": frames / c_wall,
            "frames_per_s_inside": frames / c["wall_time"] if c["wall_time"] > 0 else None,
            "answers": c["frames_out"],
            "wall_s": c_wall,
        },
        "python": {
            "frames_per_s": py.frames_per_second,
            "answers": py.frames_out,
            "wall_s": py.wall_time,
        },
    }


def fmt(x: Any, digits: int = 1) -> str:
    return "-" if x is None else f"{x:,.{digits}f}" if isinstance(x, float) else f"{x:,}"


def table(results: dict[str, Any]) -> str:
    rows = [
        "| load | loop | rate | lateness p50 / p99 / p99.9 / max (us) "
        "| period error p99 / max (us) | overruns | CPU share |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in results["loops"]:
        m = r["result"]
        where = f"| {r.get('load', 'idle')} | {r['loop']} | {r['rate_hz']:g} Hz |"
        if "refused" in m:
            rows.append(f"{where} refused: {m['refused']} | | | |")
            continue
        late = " / ".join(fmt(m.get(f"lateness_{q}_us")) for q in ("median", "p99", "p999", "max"))
        error = " / ".join(fmt(m[f"period_error_{q}_us"]) for q in ("p99", "max"))
        share = 100 * m["cpu_share"]
        rows.append(
            f"{where} {late} | {error} | {m['overruns']:,} of {m['periods']:,} | {share:.0f} % |"
        )
    rp = results.get("replay")
    if rp:
        rows += [
            "",
            f"Replay of a {rp['simulated_s']:g} s session "
            f"({rp['input_frames']:,} frames, candump .log): "
            f"C {fmt(rp['c']['frames_per_s'], 0)} frames/s (whole process), "
            f"Python {fmt(rp['python']['frames_per_s'], 0)} frames/s.",
        ]
    rows.append(
        f"\nLoad average before / after: {results['load_before']} / {results['load_after']}"
    )
    return "\n".join(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="wall seconds per loop measurement")
    ap.add_argument("--rates", default="1000,10000", help="frame rates in Hz, comma-separated")
    ap.add_argument(
        "--spin-us",
        type=int,
        default=None,
        help="the C runner's final spin in us (default: the runner's automatic one)",
    )
    ap.add_argument("--python-spin", type=float, default=2e-4, help="the Python bridge's spin (s)")
    ap.add_argument(
        "--fifo",
        type=int,
        default=50,
        help="SCHED_FIFO priority of the C runner's second run (0: skip)",
    )
    ap.add_argument(
        "--replay-seconds",
        type=float,
        default=60.0,
        help="simulated length of the replayed session",
    )
    ap.add_argument("--no-python", action="store_true", help="skip the Python bridge's loop")
    ap.add_argument(
        "--loads",
        default="idle,other,same",
        help="idle (no hog, no pinning), other (a CPU hog on the other core), same (on the "
        "loop's core); comma-separated",
    )
    ap.add_argument("--cpu", type=int, default=0, help="the core the loaded runs pin the loop to")
    ap.add_argument("--out", help="also write the results as JSON (atomically)")
    args = ap.parse_args()
    runner = runner_mod.find_runner()
    if runner is None:
        print(
            "hil_bench: gearsim-hil is not built (cmake --build build --target gearsim-hil)",
            file=sys.stderr,
        )
        return 2
    rates = [float(r) for r in args.rates.split(",") if r.strip()]
    results: dict[str, Any] = {
        "runner": str(runner),
        "seconds": args.seconds,
        "spin_us": args.spin_us,
    }
    results["load_before"] = [round(x, 2) for x in os.getloadavg()]
    results["loops"] = []
    with tempfile.TemporaryDirectory(prefix="gearsim-hil-bench-") as tmp:
        workdir = Path(tmp)
        params = runner_mod.write_params(gearsim.Model.load(MODEL), workdir / "gear.params")
        cores = sorted(os.sched_getaffinity(0))
        other = next((c for c in cores if c != args.cpu), None)
        for load in [x.strip() for x in args.loads.split(",") if x.strip()]:
            if load not in ("idle", "other", "same"):
                print(f"hil_bench: --loads {load}: expected idle, other or same", file=sys.stderr)
                return 2
            if load == "other" and other is None:
                print("hil_bench: one core only: no 'other' load", file=sys.stderr)
                continue
            pin = None if load == "idle" else args.cpu
            hog = {"idle": None, "other": other, "same": args.cpu}[load]
            for rate in rates:
                spin = args.spin_us
                runs: list[tuple[str, Any, tuple[Any, ...]]] = [
                    (
                        "C runner, default scheduling",
                        c_loop,
                        (runner, params, rate, args.seconds, spin, None, pin),
                    ),
                ]
                if args.fifo:
                    fifo = (runner, params, rate, args.seconds, spin, args.fifo, pin)
                    label = f"C runner, SCHED_FIFO {args.fifo}" + (
                        ", mlockall" if pin is not None else ""
                    )
                    runs.append((label, c_loop, fifo))
                if not args.no_python:
                    runs.append(
                        ("Python bridge", python_loop, (rate, args.seconds, args.python_spin, pin))
                    )
                for name, measure, measure_args in runs:
                    print(
                        f"hil_bench: [{load}] {name} at {rate:g} Hz for {args.seconds:g} s ...",
                        file=sys.stderr,
                        flush=True,
                    )
                    with cpu_hog(hog):
                        result = measure(*measure_args)
                    results["loops"].append(
                        {"load": load, "loop": name, "rate_hz": rate, "result": result}
                    )
        print(
            f"hil_bench: replay of a {args.replay_seconds:g} s session ...",
            file=sys.stderr,
            flush=True,
        )
        results["replay"] = replay_throughput(runner, params, args.replay_seconds, workdir)
    results["load_after"] = [round(x, 2) for x in os.getloadavg()]
    print(table(results))
    if args.out:
        atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
