"""Authority inside the QP (``qp_blend``) against fusion before it (``gate``), in the closed loop (prints JSON).

Per world (``family:<seed>`` or a data kind; the bundle of ``bench_coming_error.py``'s cache where there, else
trained quick-sized; the gate's rule chosen in the closed loop as ``mpcshare train`` does, cached): on the first
``--trials`` held-out trials the choice did not use, ``--seconds`` each, sim seed 0, β 0.5, the default wearer:
``voluntary``, ``reactive``, ``mix25``/``mix50``/``mix75``, ``gate`` and ``qp_blend`` (both with the chosen
rule's settings: the same α rule, fused before the QP or inside it).

Per world one JSON line: per run RMS [mm], effort, line ratio, effort × the wearer's, stroke correlation (mean and
least), lag, least clearance, time in a body zone, limit violations, robot share, per-trial RMS. Then one summary
object: per world qp_blend's RMS over the gate's, and the paired one-sided Wilcoxon tests over every (world, trial)
pair that qp_blend tracks better than the gate, and worse. ``--markdown`` prints the table instead of the summary.

``--identity``: instead, the shadow-QP check (:func:`identity_check`) on each world's first evaluation trial.

Usage: ``python benchmarks/bench_qp_blend.py [--worlds default family:0 ...] [--trials 2] [--seconds 30]
[--workers 2] [--out DIR] [--markdown] [--identity] [--wearer-offset M]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # research/ is not installed

from mpcshare.calibration.trials import unseen_trials  # noqa: E402

CACHE = Path("/tmp/coming-error")  # bundles and gate choices of bench_coming_error.py, read if present
RUNS = ("voluntary", "reactive", "mix25", "mix50", "mix75", "gate", "qp_blend")
RULED = ("gate", "qp_blend")  # the runs given the chosen rule's settings


def _bundle_and_choice(world: str, root: Path) -> tuple[Any, Any, tuple[str, ...], dict[str, Any]]:
    """(bundle, demonstrations, mode names, gate choice): from the cache where there, else made and saved in root."""
    from mpcshare.bundle import is_bundle, load_bundle
    from research.coming_error.record import world_bundle, world_data, world_dir

    demos, mode_names, _ = world_data(world, True)
    cached = world_dir(world, CACHE)
    bundle = load_bundle(cached / "bundle") if is_bundle(cached / "bundle") else world_bundle(world, demos, True, root)
    for folder in (cached, world_dir(world, root)):
        if (folder / "choice.json").exists():
            return bundle, demos, mode_names, json.loads((folder / "choice.json").read_text())
    from mpcshare.calibration.rule_choice import choose_for_bundle

    full = choose_for_bundle(bundle, demos, mode_names=mode_names, log=None, workers=1)
    choice = {k: full[k] for k in ("settings", "trials", "wearer_modes")}
    world_dir(world, root).mkdir(parents=True, exist_ok=True)
    (world_dir(world, root) / "choice.json").write_text(json.dumps(choice, default=float))
    return bundle, demos, mode_names, choice


def run_world(world: str, n_trials: int, seconds: float, root: Path, offset_m: float | None = None
              ) -> dict[str, Any]:
    """The module docstring's figures for one world; ``offset_m``: qp_blend's ``wearer_offset_m`` (None: its
    default)."""
    import torch

    torch.set_num_threads(1)
    from mpcshare.control.types import ControllerConfig
    from research.learned_rule.teacher import World, pooled

    t0 = time.perf_counter()
    bundle, demos, mode_names, choice = _bundle_and_choice(world, root)
    w = World(bundle, demos, {t.trial_id: t for t in demos.trials}, tuple(mode_names), seconds)
    trials = unseen_trials(bundle.heldout_trials, choice["trials"])[:n_trials]
    config = {"gate": ControllerConfig(strategy_settings=dict(choice["settings"])),
              "qp_blend": ControllerConfig(strategy_settings={**choice["settings"], **(
                  {} if offset_m is None else {"wearer_offset_m": offset_m})})}
    cpu: dict[str, float] = {}
    runs = {}
    for s in RUNS:
        c0 = time.process_time()
        runs[s] = [w.run(t, s, {"config": config[s]} if s in RULED else None) for t in trials]
        cpu[s] = time.process_time() - c0
    vol = (pooled(runs["voluntary"])["effort"], pooled(runs["voluntary"])["rms_mm"] / 1e3)
    rea = (pooled(runs["reactive"])["effort"], pooled(runs["reactive"])["rms_mm"] / 1e3)
    out = {s: pooled(runs[s], vol, rea) for s in RUNS}
    res = {"world": world, "trials": trials, "gate_choice": choice["settings"], "wearer_offset_m": offset_m,
           "runs": out, "cpu_s_per_run": cpu, "qp_blend_over_gate": out["qp_blend"]["rms_mm"] / out["gate"]["rms_mm"],
           "seconds": time.perf_counter() - t0}
    (root / "results").mkdir(parents=True, exist_ok=True)
    (root / "results" / f"qp_blend_{world.replace(':', '_')}.json").write_text(json.dumps(res, default=float))
    return res


def identity_check(world: str, seconds: float, root: Path) -> dict[str, Any]:
    """``qp_blend`` on the world's first evaluation trial with a shadow QP beside its own: every step, a plain QP
    with the same constraint rows (the same keep-out object) tracks the blend α·x_r + (1 − α)·x_v of the two
    smoothed references the blended QP weighs. Returns the largest difference of their accelerations [rad/s²],
    and the steps where a limit bound (the answer ≥ 1e-6 from the unconstrained minimiser of the same cost)."""
    import torch

    torch.set_num_threads(1)
    from mpcshare.control.controller import SharedController
    from mpcshare.control.types import ControllerConfig
    from research.learned_rule.teacher import World
    from robot.qp import QPController

    bundle, demos, mode_names, choice = _bundle_and_choice(world, root)
    w = World(bundle, demos, {t.trial_id: t for t in demos.trials}, tuple(mode_names), seconds)
    trial = unseen_trials(bundle.heldout_trials, choice["trials"])[0]
    seen = {"steps": 0, "bound": 0, "max_diff": 0.0, "max_diff_bound": 0.0}

    def make(b: Any, **options: Any) -> Any:
        ctl = SharedController.from_bundle(b, **options)
        qp = ctl.qp
        shadow = QPController(qp.model, qp.frame_id, qp.limits, qp.config, constraints=qp.constraints)
        own_step = qp.step

        def step(q: Any, v: Any, p_ref: Any = None, v_ref: Any = None, a_ref: Any = None) -> Any:
            res = own_step(q, v, p_ref, v_ref, a_ref)
            w2, sec = qp.tip_task.second_weight, qp.tip_task._second
            if p_ref is None or sec.p_ref is None:  # a held step: one reference
                return res
            blend = [(1 - w2) * x + w2 * y for x, y in ((p_ref, sec.p_ref), (v_ref, sec.v_ref), (a_ref, sec.a_ref))]
            other = shadow.step(q, v, *blend)
            state = qp.evaluate(q, v)
            H, c = qp._objective(state)
            free = np.linalg.solve(H, -c)
            bound = bool(np.abs(free - res.a).max() > 1e-6)
            d = float(np.abs(res.a - other.a).max())
            seen["steps"] += 1
            seen["bound"] += bound
            seen["max_diff"] = max(seen["max_diff"], d)
            if bound:
                seen["max_diff_bound"] = max(seen["max_diff_bound"], d)
            return res

        qp.step = step
        return ctl

    w.run(trial, "qp_blend", {"config": ControllerConfig(strategy_settings=dict(choice["settings"]))},
          make_controller=make)
    return {"world": world, "trial": trial, **seen}


def _f(x: Any, fmt: str = ".2f") -> str:
    return "–" if x is None else format(x, fmt)


def markdown(results: list[dict[str, Any]]) -> str:
    """The per-world table."""
    rows = ["| world | run | RMS [mm] | effort × wearer | line ratio | stroke corr. mean (min) | lag [ms] | "
            "least clearance [mm] | in a zone [s] | limit violations | robot share |", "|" + "---|" * 11]
    for r in results:
        for s, m in r["runs"].items():
            lag = None if m.get("lag_s") is None else 1e3 * m["lag_s"]
            rows.append(f"| {r['world']} | `{s}` | {m['rms_mm']:.1f} | {_f(m.get('effort_vs_voluntary'))} | "
                        f"{_f(m.get('line_ratio'))} | {_f(m['stroke_correlation'])} "
                        f"({_f(m['stroke_correlation_min'])}) | {_f(lag, '.0f')} | {_f(m['min_clearance_mm'], '.0f')}"
                        f" | {m['time_inside_zone_s']:.2f} | {m['limit_violations']} | {m['robot_share']:.2f} |")
    return "\n".join(rows)


def summary(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Per world qp_blend's RMS over the gate's; the paired test over every (world, trial)."""
    from scipy import stats as st

    g = np.concatenate([r["runs"]["gate"]["per_trial_rms_m"] for r in results])
    q = np.concatenate([r["runs"]["qp_blend"]["per_trial_rms_m"] for r in results])
    diff = g - q
    return {"qp_blend_over_gate": {r["world"]: r["qp_blend_over_gate"] for r in results},
            "pairs": int(diff.size), "qp_blend_better_pairs": int(np.sum(diff > 0)),
            "p_qp_blend_better": float(st.wilcoxon(diff, alternative="greater").pvalue) if np.any(diff != 0)
            else None,
            "p_gate_better": float(st.wilcoxon(-diff, alternative="greater").pvalue) if np.any(diff != 0) else None}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", nargs="+", default=["default", "other_seed", "family:0", "family:1", "family:2"])
    ap.add_argument("--trials", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("/tmp/qpauth"))
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--identity", action="store_true", help="only the shadow-QP check on each world's first trial")
    ap.add_argument("--wearer-offset", type=float, default=None,
                    help="qp_blend's wearer_offset_m [m] (default: its own)")
    a = ap.parse_args(argv)
    if a.identity:
        for world in a.worlds:
            print(json.dumps(identity_check(world, a.seconds, a.out)), flush=True)
        return 0
    with ProcessPoolExecutor(a.workers) as pool:
        futures = [pool.submit(run_world, w, a.trials, a.seconds, a.out, a.wearer_offset) for w in a.worlds]
        results = []
        for f in futures:
            r = f.result()
            results.append(r)
            print(json.dumps(r, default=float), flush=True)
    print(markdown(results) if a.markdown else json.dumps(summary(results), default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
