"""Benchmark: ``mpcshare import`` speed (messages per second) on a large rosbag2 bag.

    python benchmarks/bench_import.py [--mb 100] [--storage mcap|sqlite3] [--dir /tmp/bench-import] [--keep]

Writes (once; reused when it exists) a bag of about ``--mb`` megabytes with rosbags'
writer — PoseStamped fork and knife poses at 120 and 90 Hz, WrenchStamped at 200 Hz,
JointState at 50 Hz, as the test bags — then imports it with
:func:`learning.data.rosbag.import_bags` (no progress bar) and prints one JSON object:
the bag's size, the messages read, the wall time and messages per second, and the
samples of the data set.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np

RATES = {"/fork/pose": 120.0, "/knife/pose": 90.0, "/fork/wrench": 200.0, "/shoulder": 50.0}
BYTES_PER_SECOND = 64_000  # about, for the rates above (CDR messages plus MCAP records)
MAPPING = """\
[obs]
fork_x = "/fork/pose pose.position.x"
fork_y = "/fork/pose pose.position.y"
fork_z = "/fork/pose pose.position.z"
fork_roll = "/fork/pose pose.orientation@roll"
fork_pitch = "/fork/pose pose.orientation@pitch"
fork_yaw = "/fork/pose pose.orientation@yaw"
fork_fx = "/fork/wrench wrench.force.x"
fork_fy = "/fork/wrench wrench.force.y"
fork_fz = "/fork/wrench wrench.force.z"
[act]
knife_x = "/knife/pose pose.position.x"
knife_y = "/knife/pose pose.position.y"
knife_z = "/knife/pose pose.position.z"
[voluntary]
shoulder_elevation = "/shoulder position[0]"
shoulder_protraction = "/shoulder position[1]"
shoulder_abduction = "/shoulder position[2]"
"""


def write_large_bag(path: Path, mb: float, storage: str) -> int:
    """A bag of about ``mb`` MB; returns the number of messages."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    duration = mb * 1e6 / BYTES_PER_SECOND
    rng = np.random.default_rng(0)
    events = []
    for topic, rate in RATES.items():
        t = np.arange(int(duration * rate)) / rate
        t[1:] += rng.uniform(-0.002, 0.002, len(t) - 1)
        events.extend((float(x), topic) for x in t)
    events.sort()
    msgtypes = {"/fork/pose": "geometry_msgs/msg/PoseStamped", "/knife/pose": "geometry_msgs/msg/PoseStamped",
                "/fork/wrench": "geometry_msgs/msg/WrenchStamped", "/shoulder": "sensor_msgs/msg/JointState"}
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    base = 1_700_000_000_000_000_000
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = {tp: writer.add_connection(tp, mt, typestore=ts) for tp, mt in msgtypes.items()}
        for t, topic in events:
            ns = base + int(t * 1e9)
            hdr = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
                                           frame_id="plate")
            s, c = np.sin(t), np.cos(t)
            if topic.endswith("pose"):
                pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=s, y=c, z=0.1 * s),
                                                   orientation=T["geometry_msgs/msg/Quaternion"](
                                                       x=0.0, y=0.0, z=np.sin(t / 2), w=np.cos(t / 2)))
                msg = T["geometry_msgs/msg/PoseStamped"](header=hdr, pose=pose)
            elif topic == "/fork/wrench":
                V = T["geometry_msgs/msg/Vector3"]
                msg = T["geometry_msgs/msg/WrenchStamped"](header=hdr, wrench=T["geometry_msgs/msg/Wrench"](
                    force=V(x=s, y=c, z=-1.0), torque=V(x=0.0, y=0.0, z=0.0)))
            else:
                msg = T["sensor_msgs/msg/JointState"](header=hdr, name=["e", "p", "a"],
                                                      position=np.array([s, c, 0.0]), velocity=np.zeros(3),
                                                      effort=np.zeros(3))
            writer.write(conns[topic], ns + 4_000_000, ts.serialize_cdr(msg, msgtypes[topic]))
    return len(events)


def _size(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mb", type=float, default=100.0, help="bag size [MB] (default 100)")
    ap.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    ap.add_argument("--dir", default="/tmp/bench-import", help="where the bag is written (default /tmp/bench-import)")
    ap.add_argument("--keep", action="store_true", help="keep the bag for the next run")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from learning.data.mapping import parse_mapping
    from learning.data.rosbag import import_bags

    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib

    folder = Path(args.dir)
    folder.mkdir(parents=True, exist_ok=True)
    bag = folder / f"bench_{args.mb:g}mb_{args.storage}"
    write_s = None
    if not bag.exists():
        t0 = time.perf_counter()
        write_large_bag(bag, args.mb, args.storage)
        write_s = time.perf_counter() - t0
    mapping = parse_mapping(tomllib.loads(MAPPING))
    t0 = time.perf_counter()
    res = import_bags([bag], mapping, progress=False)
    wall = time.perf_counter() - t0
    out = {"bag_mb": round(_size(bag) / 1e6, 1), "storage": args.storage, "messages": res.messages,
           "import_s": round(wall, 2), "messages_per_s": round(res.messages / wall),
           "samples": res.demos.n_samples, "channels": res.demos.obs_dim + res.demos.act_dim + 3,
           "write_s": None if write_s is None else round(write_s, 1), "cores": os.cpu_count()}
    if not args.keep:
        shutil.rmtree(bag)
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()
