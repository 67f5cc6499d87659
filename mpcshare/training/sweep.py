"""The paper's trade-off between the robot's accuracy and the wearer's effort.

For each percentile p of the within-mode quotients of the training trials, K_p =
percentile(q, p); gates and the reactive predictor are trained at K_p on the training
trials (preprocessing, HMM modes and quotients are fitted once and shared) and measured
on the held-out trials (:func:`mpcshare.training.evaluation.evaluate`). Expected (Song & Asada):
as K is lowered, the predictor's RMSE on the reactive subset falls (R keeps only the
predictable situations) and the wearer's effort rises (more is handed over).

:func:`run_sweep` returns a :class:`SweepResult`; with ``out`` it writes

- ``sweep.json`` — a list of rows ``{kind, percentile, K, rmse_reactive, rmse_all,
  voluntary_share, voluntary_effort, gate_accuracy, …}``: one ``kind="gate+predictor"``
  row per percentile, a ``kind="lstm_all"`` row (``percentile: null``: the same LSTM
  trained on every point, no gate, so the robot acts everywhere: share 0, effort 0) and
  a ``kind="ridge"`` row (ridge regression on the window, all points);
- ``sweep.md`` — the table, the baselines on each R, and one sentence on whether RMSE
  falls and effort rises as K is lowered;
- ``sweep.png`` — RMSE and effort against the percentile.

Units: ``rmse_*`` scalars are in standardised action units (RMS over channels; see
``rmse_units``); ``*_by_group`` in physical units; effort per ``effort_units``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from learning.analysis.predictability import threshold_from_percentile
from learning.atomic import atomic_open, write_json
from learning.data import Demonstrations
from mpcshare.training.config import DEFAULT_PERCENTILES, TrainConfig
from mpcshare.training.data import prepare_training_data, reactive_labels
from mpcshare.training.stages import Stages
from mpcshare.training.train import fit_gates, fit_predictor

__all__ = ["SweepResult", "baseline_sentence", "run_sweep", "trend_sentence", "write_sweep"]



@dataclass
class SweepResult:
    """Rows of the trade-off (module docstring), the conclusion sentence and timings [s]."""

    rows: list[dict[str, Any]]
    conclusion: str
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


def _monotone(values: list[float], direction: int) -> list[int]:
    """Indices i where values[i+1] goes against ``direction`` (+1 rising, −1 falling)."""
    return [i for i in range(len(values) - 1) if direction * (values[i + 1] - values[i]) < -1e-12]


def trend_sentence(rows: Sequence[dict[str, Any]]) -> str:
    """One sentence: does the reactive RMSE fall and the effort rise as K is lowered?"""
    rs = sorted([r for r in rows if r.get("kind") == "gate+predictor" and r["rmse_reactive"] is not None],
                key=lambda r: -r["percentile"])
    if len(rs) < 2:
        return "Fewer than two percentiles: no trend to report."
    p = [r["percentile"] for r in rs]
    rm = [r["rmse_reactive"] for r in rs]
    ef = [r["voluntary_effort"] for r in rs]
    parts = []
    for name, v, d, verb in (("the reactive RMSE", rm, -1, "falls"), ("the voluntary effort", ef, +1, "rises")):
        bad = _monotone(v, d)
        overall = d * (v[-1] - v[0]) > 0
        s = f"{name} goes from {v[0]:#.3g} to {v[-1]:#.3g}"
        if overall and not bad:
            s += f" ({verb} at every step)"
        elif overall:
            s += (f" ({verb} overall, but not at every step: against the trend between the "
                  + ", ".join(f"{p[i]:g}th and {p[i + 1]:g}th" for i in bad) + " percentile)")
        else:
            s += f" (it does not {verb.rstrip('s')}, against the paper's expectation)"
        parts.append(s)
    ok = all(d * (v[-1] - v[0]) > 0 for v, d in ((rm, -1), (ef, 1)))
    verdict = "as the paper expects" if ok else "which is NOT what the paper expects"
    return (f"As K is lowered from the {p[0]:g}th to the {p[-1]:g}th percentile, {parts[0]} and "
            f"{parts[1]}, {verdict}.")


def baseline_sentence(rows: Sequence[dict[str, Any]]) -> str:
    """One sentence on the all-points LSTM evaluated on each R_p: does R itself get easier
    as K is lowered (independent of training on fewer points)?"""
    rs = sorted([r for r in rows if r.get("kind") == "gate+predictor"
                 and r.get("rmse_reactive_lstm_all") is not None], key=lambda r: -r["percentile"])
    if len(rs) < 2:
        return ""
    v = [r["rmse_reactive_lstm_all"] for r in rs]
    own = [r["rmse_reactive"] for r in rs]
    better = sum(o < b - 1e-12 for o, b in zip(own, v) if o is not None)
    trend = "falls" if v[-1] < v[0] else "does not fall"
    steps = "at every step" if not _monotone(v, -1) else "not at every step"
    return (f"The LSTM trained on all points, measured on the same subsets R, {trend} from {v[0]:#.3g} to "
            f"{v[-1]:#.3g} ({steps}): this is how much easier R itself gets; the LSTM trained on R "
            f"beats it on {better} of {len(rs)} percentiles.")


def run_sweep(demos: Demonstrations, config: TrainConfig | None = None,
              percentiles: Sequence[float] = DEFAULT_PERCENTILES, out: str | Path | None = None,
              progress: bool = True) -> SweepResult:
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
    names = ["preprocess", "modes", "quotients", "baselines"] + [f"p{p:g}" for p in ps] + ["files"]
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
        result = SweepResult(rows=rows, conclusion=trend_sentence(rows), info={
            "percentiles": ps, "train_trials": data.train_trials, "heldout_trials": data.heldout_trials,
            "fit_trials": data.fit_trials, "val_trials": data.val_trials, "config": config.to_dict(),
            "n_train_windows": int(len(data.train.q)), "n_heldout_windows": int(len(data.heldout.q)),
            "act_names": data.act_names, "timings_s": stages.timings})
        if out is not None:
            write_sweep(result, out)
        stages.done("files")
    finally:
        stages.close()
    result.info["total_s"] = round(time.perf_counter() - t0, 3)
    return result


# ------------------------------------------------------------------ files

def _f(x: Any, digits: int = 4) -> str:
    if x is None:
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)


def _markdown(result: SweepResult) -> str:
    rows = result.percentile_rows
    first = rows[0] if rows else result.rows[0]
    lines = ["# Trade-off: robot accuracy against wearer effort", "",
             f"Held-out trials {result.info.get('heldout_trials')}, training trials "
             f"{result.info.get('train_trials')} (LSTM early stopping on {result.info.get('val_trials')}).", "",
             result.conclusion, "", baseline_sentence(result.rows), "",
             "| percentile | K | RMSE on R | RMSE all | RMSE gated | voluntary share | effort | gate accuracy "
             "| gate F1 | R share (held-out) |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {_f(r['percentile'])} | {_f(r['K'])} | {_f(r['rmse_reactive'])} | {_f(r['rmse_all'])} "
                     f"| {_f(r['rmse_gated'])} | {_f(r['voluntary_share'], 3)} | {_f(r['voluntary_effort'])} "
                     f"| {_f(r['gate_accuracy'], 3)} | {_f(r['gate_f1'], 3)} | {_f(r['heldout_reactive_share'], 3)} |")
    for r in result.rows:
        if r["kind"] != "gate+predictor":
            lines.append(f"| {r['kind']} (no gate) | – | – | {_f(r['rmse_all'])} | – | 0 | 0 | – | – | – |")
    lines += ["", "Baselines on the same reactive subset R of each percentile (RMSE on R):", "",
              "| percentile | LSTM on R | LSTM on all points | ridge on window |", "|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {_f(r['percentile'])} | {_f(r['rmse_reactive'])} | {_f(r['rmse_reactive_lstm_all'])} "
                     f"| {_f(r['rmse_reactive_ridge'])} |")
    lines += ["", "Units and definitions:", "",
              f"- RMSE: {first['rmse_units']}; per channel group in physical units in `sweep.json` "
              "(`rmse_reactive_by_group`).",
              f"- effort E = (1/N)·Σ_t (1 − ĥ_t)·‖θ_t‖ over held-out steps (θ the shoulder angles, ĥ the gate "
              "decision; the closed loop's effort with the wearer at rest while the robot acts); "
              f"source: {first['effort_source']}, units: {first['effort_units']}.",
              "- voluntary share: held-out steps the gate hands to the wearer (probability < 0.5).",
              "- R on held-out trials: quotients within HMM modes among held-out points, at the training K.",
              "- At the 100th percentile R holds every point, so its LSTM is the all-points LSTM.",
              "", "Time per stage: " + ", ".join(f"{k} {v:.1f} s" for k, v in
                                                 (result.info.get("timings_s") or {}).items()) + ".", ""]
    return "\n".join(lines)


def _plot(result: SweepResult, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rows = result.percentile_rows
    p = [r["percentile"] for r in rows]
    fig = Figure(figsize=(10, 4))
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(p, [r["rmse_reactive"] for r in rows], "o-", label="LSTM on R, RMSE on R")
    ax1.plot(p, [r["rmse_all"] for r in rows], "s-", label="LSTM on R, RMSE on all")
    ax1.plot(p, [r["rmse_reactive_lstm_all"] for r in rows], "^--", label="LSTM on all points, RMSE on R")
    ax1.plot(p, [r["rmse_reactive_ridge"] for r in rows], "v:", label="ridge, RMSE on R")
    ax1.set_xlabel("percentile of K (lower K →)")
    ax1.set_ylabel("RMSE [standardised units]")
    ax1.invert_xaxis()
    ax1.legend(fontsize=7)
    ax1.set_title("robot accuracy on held-out trials")
    ax2.plot(p, [r["voluntary_effort"] for r in rows], "o-", color="C3", label="effort")
    ax2.set_xlabel("percentile of K (lower K →)")
    ax2.set_ylabel(f"effort [{rows[0]['effort_units']}]" if rows else "effort")
    ax2.invert_xaxis()
    share = ax2.twinx()
    share.plot(p, [r["voluntary_share"] for r in rows], "s--", color="C4", label="voluntary share")
    share.set_ylabel("voluntary share")
    ax2.set_title("wearer effort")
    h1, l1 = ax2.get_legend_handles_labels()
    h2, l2 = share.get_legend_handles_labels()
    ax2.legend(h1 + h2, l1 + l2, fontsize=7)
    fig.tight_layout()
    with atomic_open(path, "wb") as f:
        fig.savefig(f, format="png", dpi=110)


def write_sweep(result: SweepResult, out: str | Path) -> None:
    """Write ``sweep.json``, ``sweep.md`` and ``sweep.png`` into ``out`` (each atomically)."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    write_json(result.rows, folder / "sweep.json")
    with atomic_open(folder / "sweep.md", "w") as f:
        f.write(_markdown(result))
    _plot(result, folder / "sweep.png")
