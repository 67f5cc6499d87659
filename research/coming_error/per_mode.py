"""Each party's tracking error per *true* mode of a world (research; the product does not import it).

Per world the robot alone (``reactive``) and the wearer alone (``voluntary``) are recorded on the held-out trials
(:func:`research.coming_error.record.record_world`, 40 s a trial, at most 3 trials, no further trials) and their
RMS tip error against the intent is pooled per true mode label: if the robot is worse in every mode, no rule that
hands whole modes over can beat the wearer alone there. Prints one JSON line a world: per party, per mode name,
[RMS mm, steps].

Usage: ``python -m research.coming_error.per_mode family:0 [family:1 ...] [--full] [--root DIR]``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from research.coming_error.record import STRATEGIES, record_world


def per_mode(folder: Path) -> dict[str, dict[str, list[float]]]:
    """{party: {mode name: [RMS mm, steps]}} of a recorded world folder."""
    meta = json.loads((folder / "meta.json").read_text())
    names = meta["mode_names"]
    out: dict[str, dict[str, list[float]]] = {}
    for party in STRATEGIES:
        sq: dict[int, list[np.ndarray]] = {}
        for tid in meta["trials"]:
            z = np.load(folder / f"{party}_{tid}.npz")
            e2 = np.sum((z["tip"] - z["intent"]) ** 2, axis=1)
            for k in np.unique(z["true_mode"]):
                sq.setdefault(int(k), []).append(e2[z["true_mode"] == k])
        out[party] = {(names[k] if 0 <= k < len(names) else str(k)): [1e3 * float(np.sqrt(np.mean(np.concatenate(v)))),
                                                                       int(sum(len(a) for a in v))]
                      for k, v in sorted(sq.items())}
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("worlds", nargs="+")
    p.add_argument("--full", action="store_true", help="full-sized worlds and training (default: quick)")
    p.add_argument("--root", default="/tmp/coming-error", help="cache folder (default /tmp/coming-error)")
    a = p.parse_args(argv)
    root = Path(a.root) / ("full" if a.full else "quick")
    for world in a.worlds:
        folder = record_world(world, quick=not a.full, duration_s=40.0, max_trials=3, extra_trials=0, root=root,
                              log=lambda _: None)
        print(json.dumps({"world": world, "full": a.full, "rms_mm_steps": per_mode(folder)}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
