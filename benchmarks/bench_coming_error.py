"""Causal signals of the robot's coming error, scored on held-out trials of many worlds (prints JSON).

For each world (``family:<seed>`` quick-sized, and the data kinds of ``benchmarks/bench_task.py``), train
a bundle with the defaults (at most 20 LSTM epochs; cached under ``--root``), run the robot alone
(``reactive``) and the wearer alone (``voluntary``) in the closed loop on the held-out trials (and, on a
family world, further trials of the same world that training never saw), 40 s each, sim seed 0, then score
every signal of :data:`research.coming_error.score.SIGNALS` by AUC for "the robot errs more than the wearer
over the next H s" (H = 0.3, 0.5, 1 s) and Spearman's ρ against the difference of their mean squared tip
errors (:mod:`research.coming_error.score`). Prints one JSON line per world, then one JSON object: every
world and, per signal and horizon, the median, min and max AUC over the worlds. ``--markdown`` prints the
tables per horizon instead of the final object. ``--fusion`` also runs the fusion candidates in the closed
loop beside the mixes, ``gate`` and matched random hand-overs
(:func:`research.coming_error.evaluate_fusion.evaluate_world`, one JSON line ``"fusion"`` per world; about
25 episodes and the gate's rule choice a world).

Cost: about 1.5 min of one core per family world (training ≈ 20 s, 16 episodes of 40 s, scoring ≈ 15 s),
several minutes per data kind (training on 30–36 min of data).

Usage: ``python benchmarks/bench_coming_error.py [--worlds 0 1 2] [--kinds default] [--root /tmp/coming-error]
[--markdown] [--fusion]``; ``--worlds`` or ``--kinds`` with no value leaves that part out.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # research/ is not installed

SHORT = {"conformal_radius": "conformal", "forecast_revision": "revision", "shoulder_deflection": "shoulder",
         "correction_against": "against", "correction_displacement": "displacement", "mode_hazard": "hazard",
         "mode_change_within_h": "change ≤ H", "time_in_mode": "time in mode",
         "forecaster_disagreement": "fast vs LSTM", "mode_entropy": "entropy", "novelty": "novelty",
         "robot_past_error": "(robot's past error)", "mode_posterior_only": "mode posterior",
         "combined_observable": "**combined**",
         "combined_with_reference": "(combined + past error)"}


def summary(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Per horizon and signal: median, min, max AUC over the worlds."""
    out: dict[str, Any] = {}
    for h in results[0]["horizons"]:
        out[h] = {}
        for k in results[0]["horizons"][h]["auc"]:
            v = np.array([r["horizons"][h]["auc"][k] for r in results if r["horizons"][h]["auc"][k] is not None])
            if v.size:
                out[h][k] = {"median": float(np.median(v)), "min": float(v.min()), "max": float(v.max())}
    return out


def markdown(results: list[dict[str, Any]], h: str = "0.5") -> str:
    """A world × signal table of AUC at horizon ``h`` (with the robot's and the wearer's RMS)."""
    keys = list(results[0]["horizons"][h]["auc"])
    head = "| world | robot / wearer RMS [mm] | robot errs more | " + " | ".join(SHORT.get(k, k) for k in keys) + " |"
    rows = [head, "|" + "---|" * (len(keys) + 3)]
    for r in results:
        row = r["horizons"][h]
        cells = ["–" if row["auc"][k] is None else f"{row['auc'][k]:.2f}" for k in keys]
        rows.append(f"| {r['world']} | {np.mean(r['robot_rms_mm']):.1f} / {np.mean(r['wearer_rms_mm']):.1f} | "
                    f"{row['robot_errs_more_share']:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--worlds", type=int, nargs="*", default=[0, 1, 2], help="family seeds (default 0 1 2)")
    p.add_argument("--kinds", nargs="*", default=["default"], choices=["default", "other_seed", "other_structure"])
    p.add_argument("--root", default="/tmp/coming-error", help="cache of bundles and run files")
    p.add_argument("--markdown", action="store_true", help="print the tables as markdown at the end")
    p.add_argument("--fusion", action="store_true", help="also evaluate the fusion candidates in the closed loop")
    a = p.parse_args(argv)

    from research.coming_error.record import record_world
    from research.coming_error.score import score_world

    worlds = [f"family:{s}" for s in a.worlds] + list(a.kinds)
    t0 = time.perf_counter()
    results = []
    for w in worlds:
        tw = time.perf_counter()
        folder = record_world(w, root=Path(a.root), log=lambda s: print(s, file=sys.stderr, flush=True))
        r = score_world(folder)
        r["seconds"] = time.perf_counter() - tw
        results.append(r)
        print(json.dumps(r, default=float), flush=True)
        if a.fusion:
            from research.coming_error.evaluate_fusion import evaluate_world

            f = evaluate_world(w, root=Path(a.root), log=lambda s: print(s, file=sys.stderr, flush=True))
            print(json.dumps({"fusion": f}, default=float), flush=True)
    if a.markdown:
        for h in results[0]["horizons"]:
            print(f"\nH = {h} s\n\n" + markdown(results, h))
    else:
        print(json.dumps({"worlds": results, "summary": summary(results), "seconds": time.perf_counter() - t0},
                         default=float, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
