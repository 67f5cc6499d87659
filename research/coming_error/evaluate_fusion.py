"""The fusion candidate (:mod:`.fusion`) in the closed loop beside the parties, the constant mixes, ``gate``
(its rule chosen in the closed loop as ``mpcshare train`` does) and random hand-overs matched to it.

Per world: the bundle of :mod:`.record` (cached), the fusion fitted on the recorded runs of the further
trials (never the evaluation's), the gate's rule chosen on the last held-out trials, every run on the other
held-out trials (sim seed 0, ``duration_s`` each); figures pooled over the trials as ``bench_family.py``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mpcshare.bundle import CalibratedRule
from mpcshare.calibration.trials import unseen_trials
from research.coming_error.fusion import fit_fusion, fusion_controller
from research.coming_error.record import ROOT, world_bundle, world_data, world_dir

RUNS = ("voluntary", "reactive", "mix25", "mix50", "mix75", "gate")
DRAWS = 5


def _pooled(done: list[tuple[Any, dict[str, Any]]]) -> dict[str, Any]:
    from mpcshare.evaluation.pooling import pool_metrics

    ms = [m for _, m in done]
    p = pool_metrics(ms, [np.asarray(ep.step_time, dtype=float) for ep, _ in done],
                     [float(ep.t[-1] - ep.t[0]) for ep, _ in done])
    saw = [m["saw_correlation"] for m in ms if m.get("saw_correlation") is not None]
    return {"rms_m": float(p["tracking_rmse_m"]), "effort": float(p["voluntary_effort"]),
            "per_trial_rms_m": [float(m["tracking_rmse_m"]) for m in ms],
            "stroke_correlation": float(np.mean(saw)) if saw else None,
            "stroke_correlation_min": float(np.min(saw)) if saw else None,
            "robot_share": float(np.mean(np.concatenate([np.asarray(ep.alpha, dtype=float) for ep, _ in done]))),
            "limit_violations": int(p["limit_violations"])}


def evaluate_world(world: str, duration_s: float = 30.0, n_eval: int = 2, root: Path = ROOT,
                   log: Any = print, runs: tuple[str, ...] = RUNS, placebo: bool = True) -> dict[str, Any]:
    """The module docstring's table for one world (figures of sim seed 0, line ratios, p vs random):
    ``runs`` (voluntary and reactive always), then ``fusion`` and ``fusion_lead``; ``placebo``: random
    hand-overs matched to ``fusion``."""
    import torch
    from scipy import stats as st

    from mpcshare.calibration.rule_choice import choose_for_bundle
    from mpcshare.evaluation.episode import simulate_episode
    from mpcshare.evaluation.handover import random_schedules_from, schedule_record
    from mpcshare.line_ratio import line_ratio
    from mpcshare.run_table import StrategyRun

    torch.set_num_threads(1)
    folder = world_dir(world, root)
    demos, mode_names, extra = world_data(world, True, 5)
    bundle = world_bundle(world, demos, True, root)
    meta = json.loads((folder / "meta.json").read_text())
    fit_trials = [t for t in meta["trials"] if t not in bundle.heldout_trials]
    if not fit_trials:  # a data kind: no further trials, fit on the held-out trials the evaluation leaves
        fit_trials = list(bundle.heldout_trials)[n_eval:]
    params = fit_fusion(folder, fit_trials)
    cache = folder / "choice.json"
    if cache.exists():
        choice = json.loads(cache.read_text())
        bundle.rule = CalibratedRule("gate", choice["settings"])
    else:
        choice = choose_for_bundle(bundle, demos, mode_names=mode_names, log=None, workers=1)
        cache.write_text(json.dumps({k: choice[k] for k in ("settings", "trials", "wearer_modes")}, default=float))
    trials = [t for t in unseen_trials(bundle.heldout_trials, choice["trials"]) if t not in fit_trials][:n_eval]
    by_id = {t.trial_id: t for t in list(demos.trials) + extra}
    kw = dict(beta=0.5, duration_s=duration_s, seed=0, wearer=None, mode_names=mode_names)
    out: dict[str, Any] = {}
    runs = ("voluntary", "reactive") + tuple(r for r in runs if r not in ("voluntary", "reactive"))
    fusion_eps = []
    for name in runs + ("fusion", "fusion_lead"):
        done = []
        for tid in trials:
            if name.startswith("fusion"):
                done.append(simulate_episode(bundle, demos, by_id[tid], StrategyRun(name, "mix50"), {},
                                             make_controller=fusion_controller(params, name == "fusion_lead"),
                                             **kw))
                if name == "fusion":
                    fusion_eps.append(done[-1][0])
            else:
                done.append(simulate_episode(bundle, demos, by_id[tid], StrategyRun(name, name), {}, **kw))
        out[name] = _pooled(done)
        log(f"{world} {name}: {1e3 * out[name]['rms_m']:.1f} mm")
    rand = []
    for i, (tid, ep) in enumerate(zip(trials, fusion_eps) if placebo else ()):
        scheds = random_schedules_from(schedule_record(ep), DRAWS, [0, i])
        rand.append([simulate_episode(bundle, demos, by_id[tid], StrategyRun("random_handover", "schedule"),
                                      {"schedule": s}, **kw) for s in scheds])
    if placebo:
        draws = [_pooled([rand[i][j] for i in range(len(trials))]) for j in range(DRAWS)]
        out["random_handover"] = {k: float(np.mean([d[k] for d in draws])) for k in ("rms_m", "effort",
                                                                                     "robot_share")}
        out["random_handover"]["per_trial_rms_m"] = np.mean([d["per_trial_rms_m"] for d in draws],
                                                            axis=0).tolist()
    vol = (out["voluntary"]["effort"], out["voluntary"]["rms_m"])
    rea = (out["reactive"]["effort"], out["reactive"]["rms_m"])
    for r in out.values():
        r["line_ratio"] = line_ratio(r["rms_m"], r["effort"], vol, rea)
        r["effort_vs_voluntary"] = r["effort"] / vol[0]
    res = {"world": world, "trials": trials, "fit_trials": fit_trials, "gate_choice": choice["settings"],
           "fusion_params": params, "runs": out}
    if placebo:
        d = np.array(out["random_handover"]["per_trial_rms_m"]) - np.array(out["fusion"]["per_trial_rms_m"])
        res.update(fusion_over_random=out["fusion"]["rms_m"] / out["random_handover"]["rms_m"], pairs=int(d.size),
                   fusion_below_random_p=float(st.wilcoxon(d, alternative="greater").pvalue) if np.any(d != 0)
                   else None)
    return res
