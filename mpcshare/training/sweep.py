"""The paper's trade-off between the robot's accuracy and the wearer's effort.

For each percentile p of the training trials' within-mode quotients, K_p = percentile(q, p); gates and the
reactive predictor are trained at K_p on the training trials (preprocessing, HMM modes and quotients fitted
once, shared) and measured on the held-out trials (:func:`mpcshare.training.evaluation.evaluate`). Expected
(Song & Asada): as K is lowered, the predictor's RMSE on R falls and the wearer's effort rises.

:func:`run_sweep` returns a :class:`SweepResult`; :func:`mpcshare.reports.sweep.write_sweep` writes
``sweep.json`` (rows ``{kind, percentile, K, rmse_reactive, rmse_all, voluntary_share, voluntary_effort,
gate_accuracy, …}``: ``kind="gate+predictor"`` per percentile; ``kind="lstm_all"``, ``percentile: null``, the
same LSTM on every point without a gate, share 0 and effort 0; ``kind="ridge"``, ridge regression on the
window), ``sweep.md`` (the table, the baselines on each R, whether RMSE falls and effort rises) and
``sweep.png`` (RMSE and effort against the percentile). Units: ``rmse_*`` in standardised action units (RMS
over channels, ``rmse_units``); ``*_by_group`` physical; effort per ``effort_units``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from learning.analysis.predictability import threshold_from_percentile
from learning.data import Demonstrations
from mpcshare.training.config import DEFAULT_PERCENTILES, TrainConfig
from mpcshare.training.data import prepare_training_data, reactive_labels
from mpcshare.training.stages import Stages
from mpcshare.training.train import fit_gates, fit_predictor

__all__ = ["SweepResult", "run_sweep"]



@dataclass
class SweepResult:
    """Rows of the trade-off (module docstring) and timings [s]."""

    rows: list[dict[str, Any]]
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def percentile_rows(self) -> list[dict[str, Any]]:
        return [r for r in self.rows if r["kind"] == "gate+predictor"]


def _row(kind: str, p: float | None, K: float | None, m: dict[str, Any]) -> dict[str, Any]:
    pred = m["predictor"]
    g = m["gate"]["overall"]
    return {
        "kind": kind, "percentile": p, "K": K,
        "rmse_reactive": pred["rmse_reactive"], "rmse_all": pred["rmse_all"],
        "voluntary_share": m["voluntary_share"], "voluntary_effort": m["voluntary_effort"],
        "gate_accuracy": g["accuracy"], "gate_f1": g["f1"], "gate_brier": g["brier"],
        "rmse_gated": pred.get("rmse_gated"),
        "heldout_reactive_share": m["heldout_reactive_share"],
        "rmse_reactive_lstm_all": m["baselines"].get("lstm_all", {}).get("rmse_reactive"),
        "rmse_reactive_ridge": m["baselines"].get("ridge", {}).get("rmse_reactive"),
        "rmse_reactive_by_group": pred["rmse_reactive_by_group"],
        "rmse_all_by_group": pred["rmse_all_by_group"],
        "gate_per_mode": m["gate"]["per_mode"],
        "effort_if_all_voluntary": m["effort_if_all_voluntary"],
        "rmse_units": m["rmse_units"], "effort_source": m["effort_source"],
        "effort_units": m["effort_units"],
    }


def _baseline_row(kind: str, errors: dict[str, Any], m: dict[str, Any]) -> dict[str, Any]:
    return {
        "kind": kind, "percentile": None, "K": None, "rmse_reactive": None,
        "rmse_all": errors["rmse_all"], "voluntary_share": 0.0, "voluntary_effort": 0.0,
        "gate_accuracy": None, "rmse_all_by_group": errors["rmse_all_by_group"],
        "note": "no gate: the robot acts on every step; its RMSE on each R is in the percentile rows",
        "rmse_units": m["rmse_units"], "effort_source": m["effort_source"],
        "effort_units": m["effort_units"],
    }


def run_sweep(demos: Demonstrations, config: TrainConfig | None = None,
              percentiles: Sequence[float] = DEFAULT_PERCENTILES, progress: bool = True) -> SweepResult:
    """Train and evaluate gates + predictor at each percentile (module docstring).

    Raises:
        TrainingError: unusable data (see :func:`mpcshare.training.prepare_training_data`).
        ValueError: an empty list of percentiles or one outside [0, 100].
    """
    from mpcshare.training.evaluation import evaluate, fit_ridge, predict_side

    config = config or TrainConfig()
    ps = [float(p) for p in percentiles]
    if not ps or any(not 0.0 <= p <= 100.0 for p in ps):
        raise ValueError(f"percentiles must be a non-empty list in [0, 100], got {list(percentiles)}")
    ps = sorted(set(ps), reverse=True)
    t0 = time.perf_counter()
    names = ["preprocess", "modes", "quotients", "baselines"] + [f"p{p:g}" for p in ps]
    stages = Stages(names, progress, desc="sweep")
    try:
        data = prepare_training_data(demos, config, stages, progress=progress)
        all_points = np.ones(len(data.train.q), dtype=bool)
        lstm_all = fit_predictor(data, all_points, progress=progress)
        ridge = fit_ridge(data)
        base_pred = {"lstm_all": predict_side(lstm_all, data.heldout),
                     "ridge": predict_side(ridge, data.heldout)}
        stages.done("baselines")
        rows, last = [], None
        for p in ps:
            K = threshold_from_percentile(data.train.q, p)
            Z = reactive_labels(data.train.q, K)
            gates = fit_gates(data, Z)
            # R = every point (p = 100, or ties): the LSTM on R is the LSTM on all points
            predictor = lstm_all if Z.all() else fit_predictor(data, Z.astype(bool), progress=progress)
            last = evaluate(data, gates, predictor, K, baseline_predictions=base_pred)
            row = _row("gate+predictor", p, last["K"], last)
            row["train_reactive_share"] = float(Z.mean())
            row["predictor_is_lstm_all"] = predictor is lstm_all
            rows.append(row)
            stages.done(f"p{p:g}")
        for kind in ("lstm_all", "ridge"):
            rows.append(_baseline_row(kind, last["baselines"][kind], last))
        result = SweepResult(rows=rows, info={
            "percentiles": ps, "train_trials": data.train_trials, "heldout_trials": data.heldout_trials,
            "fit_trials": data.fit_trials, "val_trials": data.val_trials, "config": config.to_dict(),
            "n_train_windows": int(len(data.train.q)), "n_heldout_windows": int(len(data.heldout.q)),
            "act_names": data.act_names, "timings_s": stages.timings})
    finally:
        stages.close()
    result.info["total_s"] = round(time.perf_counter() - t0, 3)
    return result
