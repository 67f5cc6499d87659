"""CPU cost of ``mpcshare run``'s per-tick status (a DiagnosticArray of ~26 key/values); prints JSON.

In one process, interleaved rounds of the same status (the values a tick of the SuperLimb's controller
reports: ages of five inputs, α, β, the mode, its probabilities, the tip reference, six clearances …)
published on a writer with a matched reader (a DDS domain of its own, loopback):

* ``cyclone``: ``status_message`` (Cyclone's IDL objects) + ``Writer.write`` (Cyclone's pure-Python
  serialiser), the path before; ``rosbags``: ``status_cdr`` (rosbags' generated ROS 2 CDR serialiser) +
  ``Writer.write_cdr``, the path ``run`` takes;
* per path: ``build_us`` (the message or its bytes), ``publish_us`` (the write), ``total_us``: CPU time
  (``time.process_time``) per status, the median over rounds; ``ratio``: cyclone / rosbags totals;
* ``bytes_equal``: the two paths' bytes are the same.

Usage: ``python benchmarks/bench_status.py [--rounds 20] [--per-round 500]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from mpcshare.runtime.convert import status_cdr, status_message
from mpcshare.runtime.messages import DiagnosticArray, Time
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport


def tick_values() -> dict[str, object]:
    """A tick's status values as ``RunLoop`` builds them (the SuperLimb's, six body zones)."""
    values: dict[str, object] = {"status": "ok", "stamp": "1234.500000000", "tick": 12345, "t": 123.45}
    values.update({f"age_{n}": 0.00123 for n in ("arm", "fork", "fork_wrench", "shoulder", "torso")})
    values.update(stale_inputs="", input_stamp="1234.490000000", alpha=0.73, beta=0.5, leader="robot", mode=1,
                  mode_proba=np.array([0.1, 0.7, 0.2]), novelty=0.8, reasons="", step_s=0.0031,
                  tip_reference=np.array([0.1, 0.2, 0.3]), clearance_m=0.12)
    values.update({f"clearance_{z}_m": 0.2 for z in ("head", "face", "chest", "upper_arm", "forearm", "hand")})
    return values


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--per-round", type=int, default=500)
    args = ap.parse_args()
    transport = Transport(NetworkSettings(domain_id=97))
    writer = transport.writer("/bench/status", DiagnosticArray, QosSettings("reliable", 1))
    reader = transport.reader("/bench/status", DiagnosticArray, QosSettings("reliable", 1))
    end = time.monotonic() + 5.0
    while not writer.matched and time.monotonic() < end:
        time.sleep(0.01)
    values, stamp, n = tick_values(), Time(1234, 500_000_000), args.per_round
    args_ = (stamp, "mpcshare: shared controller", "superlimb", 0, "ok", values)
    times: dict[str, list[float]] = {k: [] for k in ("cyclone_build", "cyclone_publish", "rosbags_build",
                                                     "rosbags_publish")}
    for _ in range(args.rounds):
        c0 = time.process_time()
        msgs = [status_message(*args_) for _ in range(n)]
        c1 = time.process_time()
        for m in msgs:
            writer.write(m)
        c2 = time.process_time()
        datas = [status_cdr(*args_) for _ in range(n)]
        c3 = time.process_time()
        for d in datas:
            writer.write_cdr(d)
        c4 = time.process_time()
        reader.take(10_000)
        for key, dt in zip(times, (c1 - c0, c2 - c1, c3 - c2, c4 - c3)):
            times[key].append(dt / n * 1e6)
    med = {k: statistics.median(v) for k, v in times.items()}
    out: dict[str, object] = {
        path: {"build_us": round(med[f"{path}_build"], 1), "publish_us": round(med[f"{path}_publish"], 1),
               "total_us": round(med[f"{path}_build"] + med[f"{path}_publish"], 1)} for path in ("cyclone", "rosbags")}
    totals = [med[f"{path}_build"] + med[f"{path}_publish"] for path in ("cyclone", "rosbags")]
    out["ratio"] = round(totals[0] / totals[1], 2)
    out["keys"] = len(values)
    out["bytes_equal"] = bytes(status_message(*args_).serialize()) == status_cdr(*args_)
    out["rounds"], out["per_round"] = args.rounds, n
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
