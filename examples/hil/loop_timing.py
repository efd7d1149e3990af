"""Loop period error of the paced bridge on the virtual bus (docs/hil.md, "Figures").

Runs `Bridge.run` at the given period for the given wall time with a host peer
in a second thread that sends a command every 10 ms and drains the feedback,
then prints the period error (|t[k+1] - t[k] - period|) and the lateness of
each period start: median, p99 and max.

    python examples/hil/loop_timing.py [--seconds 60] [--period 0.001] [--spin 0.0002]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import threading
import time

import can

import gearsim
from gearsim.hil import Bridge, RigDbc
from gearsim.hil.codec import STATUS_COUNTS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--period", type=float, default=1e-3)
    ap.add_argument("--spin", type=float, default=2e-4)
    ap.add_argument("--model", default=os.path.join(os.path.dirname(__file__), "gear_model.toml"))
    args = ap.parse_args()

    model = gearsim.Model.load(args.model)
    dbc = RigDbc(block=model.block)
    stop = threading.Event()
    received = [0]

    def host(bus: can.BusABC) -> None:
        k = 0
        next_t = time.perf_counter()
        while not stop.is_set():
            speed = 20.0 * math.sin(2 * math.pi * 0.5 * k * 0.01)
            for msg in dbc.encode_command({"cmd.base_speed": speed, "cmd.load": 0.3}):
                bus.send(msg)
            while bus.recv(timeout=0.0) is not None:
                received[0] += 1
            k += 1
            next_t += 0.01
            time.sleep(max(0.0, next_t - time.perf_counter()))

    with (
        can.Bus(interface="virtual", channel="timing") as bridge_bus,
        can.Bus(interface="virtual", channel="timing") as host_bus,
    ):
        bridge = Bridge.from_model(model, dbc, period=args.period, bus=bridge_bus)
        peer = threading.Thread(target=host, args=(host_bus,), daemon=True)
        peer.start()
        stats = bridge.run(duration=args.seconds, spin=args.spin)
        stop.set()
        peer.join()
        summary = bridge.close()
    out = {
        "period_s": args.period,
        "seconds": args.seconds,
        "spin_s": args.spin,
        "loop": stats.summary(),
        "feedback_received_by_host": received[0],
        # every counter a status frame can carry, by the codec's one list of names
        "counters": {k: summary[k] for k in STATUS_COUNTS},
        "load_average": os.getloadavg(),
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
