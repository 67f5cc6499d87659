"""``training.md``: the held-out metrics of a bundle in words and tables, with the forecast's skill.

The skill table reads ``metrics.json`` → ``fast_forecast`` (:mod:`mpcshare.training.fast`): per
horizon the RMSE [mm] of the control-rate forecast, of the 10 Hz LSTM forecast it corrects, of
holding its present estimate and of extrapolating it at constant velocity, and the skill
``1 − RMSE_forecast / RMSE_baseline``; then the skill per mode and horizon.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from learning.atomic import atomic_open

__all__ = ["skill_lines", "training_markdown", "write_training_md"]


def _f(x: Any, scale: float = 1.0, digits: int = 3) -> str:
    if x is None or not math.isfinite(float(x)):
        return "–"
    return f"{float(x) * scale:.{digits}g}"


def _skill(x: Any) -> str:
    return "–" if x is None else f"{float(x):+.2f}"


def skill_lines(fast: dict[str, Any] | None, mode_names: dict[str, str] | None = None) -> list[str]:
    """Markdown lines of the skill tables (none when the bundle has no control-rate forecast)."""
    if not fast or "rmse" not in fast:
        reason = (fast or {}).get("skipped", "not trained")
        return [f"The control-rate forecast: {reason}.", ""]
    r, s, hs = fast["rmse"], fast["skill"], fast["horizons_s"]
    mm = 1e3 if str(fast.get("units", "")).startswith("m") else 1.0
    unit = "mm" if mm == 1e3 else "units"
    out = ["Held-out RMSE of the knife tip per horizon and the forecast's skill (1 − RMSE / RMSE of the "
           "baseline; above 0: better than the baseline):", "",
           f"| horizon [s] | forecast [{unit}] | 10 Hz LSTM [{unit}] | hold [{unit}] | constant velocity [{unit}] "
           "| skill vs hold | skill vs constant velocity | 10 Hz LSTM skill vs hold |",
           "|---|---|---|---|---|---|---|---|"]
    for k, h in enumerate(hs):
        out.append(f"| {h:g} | {_f(r['forecast'][k], mm)} | {_f(r['slow_lstm'][k], mm)} | {_f(r['hold'][k], mm)} | "
                   f"{_f(r['constant_velocity'][k], mm)} | {_skill(s['vs_hold'][k])} | "
                   f"{_skill(s['vs_constant_velocity'][k])} | {_skill(s['slow_lstm_vs_hold'][k])} |")
    out += ["", "Skill per mode (the controller's most probable HMM mode), against the hold / against constant "
            "velocity:", "", "| mode | steps | " + " | ".join(f"{h:g} s" for h in hs[1:]) + " |",
            "|---|---|" + "---|" * (len(hs) - 1)]
    for j, m in fast.get("by_mode", {}).items():
        name = (mode_names or {}).get(j, j)
        cells = [f"{_skill(a)} / {_skill(b)}" for a, b in zip(m["skill"]["vs_hold"][1:],
                                                             m["skill"]["vs_constant_velocity"][1:])]
        out.append(f"| {name} | {m['n_steps']} | " + " | ".join(cells) + " |")
    out += ["", "The MPC's preview uses the forecast up to the last horizon whose skill against the hold, on the "
            "validation trials, is above 0 in the current mode, and holds beyond it.", ""]
    return out


def training_markdown(metrics: dict[str, Any]) -> str:
    """The training summary of a bundle's ``metrics`` as markdown."""
    t, p, g = metrics["training"], metrics["predictor"], metrics["gate"]["overall"]
    k = "inf" if t["K"] is None else f"{t['K']:.4g}"
    lines = ["# Training", "", "| quantity | value |", "|---|---|",
             f"| K (percentile {t['percentile']:g}) | {k} |",
             f"| reactive share, training / held-out | {100 * t['reactive_share_train']:.1f} % / "
             f"{100 * metrics['heldout_reactive_share']:.1f} % |",
             f"| predictor RMSE on R / all held-out (standardised) | {_f(p['rmse_reactive'])} / {_f(p['rmse_all'])} |",
             f"| gate accuracy / F1 / Brier (held-out) | {_f(g['accuracy'])} / {_f(g['f1'])} / {_f(g['brier'])} |",
             f"| training time | {t['total_s']:.1f} s |", "",
             "## The forecast at the control rate", "", *skill_lines(metrics.get("fast_forecast"))]
    return "\n".join(lines) + "\n"


def write_training_md(metrics: dict[str, Any], path: str | Path, extra: str = "") -> Path:
    """Write :func:`training_markdown` (and ``extra`` Markdown after it, e.g. the closed-loop choice of
    the hand-over rule) to ``path`` (atomically); returns it."""
    path = Path(path)
    with atomic_open(path, "w") as f:
        f.write(training_markdown(metrics) + (f"\n{extra}" if extra else ""))
    return path
