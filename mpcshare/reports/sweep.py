"""The K trade-off sweep (:mod:`mpcshare.training.sweep`) in words and a figure: the trend sentences and
the files ``sweep.json``, ``sweep.md`` and ``sweep.png`` (their contents: the sweep module's docstring)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Sequence

from learning.atomic import atomic_open, write_json
from mpcshare.training.sweep import SweepResult

__all__ = ["baseline_sentence", "trend_sentence", "write_sweep"]


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
             trend_sentence(result.rows), "", baseline_sentence(result.rows), "",
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
