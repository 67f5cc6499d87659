"""What each task mode costs under each party, measured in the closed loop.

:func:`mode_costs` reads two closed-loop runs on the same held-out trials, the wearer alone (``voluntary``) and
the robot alone (``reactive``), grouped by the controller's own mode estimate (the ``mode`` of each control step,
what the online rule sees too). Per mode j:

    p_j = share of the control steps in mode j (over both runs),
    m_j^w, m_j^r = mean squared tracking error  (1/n_j)·Σ ‖p_k − p*_k‖²  [m²] of the wearer and the robot,
    E_j^w, E_j^r = mean effort  (1/n_j)·Σ ‖θ_k‖  [rad] (the shoulder's angles, ``sim.metrics``),

and the *price* of handing mode j to the wearer, the squared error saved per unit of effort spent:

    ρ_j = (m_j^r − m_j^w) / max(E_j^w − E_j^r, ε)      [m²/rad],  ρ_j = 0 where m_j^r ≤ m_j^w.

:func:`price_order` gives the modes in decreasing ρ_j, the lower hull of (effort, mean squared error) over
whole-mode assignments, hand-over costs left out (the greedy order of a fractional knapsack; the closed-loop
check of :mod:`mpcshare.calibration.rule_choice` puts them back); :func:`cutting_modes` the modes that carry the
labelled cutting. Why the costs are measured rather than read off the data: docs/design.md.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from mpcshare.reports.rule_choice import pruned_why

__all__ = ["beyond_the_wearer_alone", "cutting_effort", "cutting_modes", "mode_costs", "predicted_point",
           "price_order", "prune_sets"]

_EFFORT_FLOOR_RAD = 1e-3  # ε: a mode that costs the wearer no effort to lead has a finite price


def _per_mode(episodes: Sequence[Any], n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(steps, Σ squared error [m²], Σ effort [rad]) per mode over ``episodes`` (steps with mode −1 dropped)."""
    n, e2, eff = np.zeros(n_modes), np.zeros(n_modes), np.zeros(n_modes)
    for ep in episodes:
        mode = np.asarray(ep.mode, dtype=int)
        ok = (mode >= 0) & (mode < n_modes)
        err = np.sum((np.asarray(ep.tip) - np.asarray(ep.tip_intent)) ** 2, axis=1)
        effort = np.linalg.norm(np.asarray(ep.voluntary), axis=1)
        n += np.bincount(mode[ok], minlength=n_modes)
        e2 += np.bincount(mode[ok], weights=err[ok], minlength=n_modes)
        eff += np.bincount(mode[ok], weights=effort[ok], minlength=n_modes)
    return n, e2, eff


def mode_costs(voluntary: Sequence[Any], reactive: Sequence[Any], n_modes: int) -> dict[str, Any]:
    """Per-mode figures and prices (module docstring) from the episodes of the two parties.

    Returns ``{"share", "rms_wearer_mm", "rms_robot_mm", "effort_wearer_rad", "effort_robot_rad",
    "price_mm2_per_rad"}``, each a list of ``n_modes`` floats (None where a party never saw the mode).
    Raises ValueError without episodes or modes.
    """
    if n_modes < 1 or not voluntary or not reactive:
        raise ValueError(f"mode_costs needs episodes of both parties and >= 1 mode, got {len(voluntary)} "
                         f"voluntary, {len(reactive)} reactive, {n_modes} modes")
    nv, ev, fv = _per_mode(voluntary, n_modes)
    nr, er, fr = _per_mode(reactive, n_modes)
    with np.errstate(invalid="ignore", divide="ignore"):
        mw, mr = ev / nv, er / nr
        Ew, Er = fv / nv, fr / nr
        gain = mr - mw
        price = np.where(np.isfinite(gain) & (gain > 0), gain / np.maximum(Ew - Er, _EFFORT_FLOOR_RAD), 0.0)
    share = (nv + nr) / max(float(np.sum(nv + nr)), 1.0)
    return {"share": _listed(share), "rms_wearer_mm": _listed(1e3 * np.sqrt(mw)),
            "rms_robot_mm": _listed(1e3 * np.sqrt(mr)), "effort_wearer_rad": _listed(Ew),
            "effort_robot_rad": _listed(Er), "price_mm2_per_rad": _listed(1e6 * price)}


def _listed(x: np.ndarray) -> list[float | None]:
    """JSON-able: floats, None where undefined."""
    return [float(v) if np.isfinite(v) else None for v in x]


def price_order(costs: dict[str, Any]) -> list[int]:
    """The modes worth handing to the wearer (ρ_j > 0), most saved error per effort first."""
    price = np.array([0.0 if p is None else float(p) for p in costs["price_mm2_per_rad"]])
    return [int(j) for j in np.argsort(-price, kind="stable") if price[j] > 0]


def cutting_modes(episodes: Sequence[Any], true_modes: Sequence[np.ndarray], cutting_label: int,
                  n_modes: int) -> list[int]:
    """The controller's modes j whose steps are mostly (> 50 %) labelled ``cutting_label`` in the
    demonstrations (``true_modes[i]``: the labels of episode i's trial at its control steps)."""
    n, cut = np.zeros(n_modes), np.zeros(n_modes)
    for ep, labels in zip(episodes, true_modes):
        mode = np.asarray(ep.mode, dtype=int)
        lab = np.asarray(labels)[:mode.size]
        ok = (mode[:lab.size] >= 0) & (mode[:lab.size] < n_modes)
        m = mode[:lab.size][ok]
        n += np.bincount(m, minlength=n_modes)
        cut += np.bincount(m, weights=(lab[ok] == cutting_label).astype(float), minlength=n_modes)
    return [int(j) for j in range(n_modes) if n[j] > 0 and cut[j] / n[j] > 0.5]


def cutting_effort(costs: dict[str, Any], cutting: Sequence[int]) -> float | None:
    """The least effort of leaving the ``cutting`` modes to the wearer, as a share of the wearer's effort
    alone: Σ_j p_j·E_j / Σ_j p_j·E_j^w with E_j = E_j^w for a cutting mode and E_j^r (the robot leads)
    for the rest, from :func:`mode_costs`. No whole-mode rule that leaves the cutting to the wearer costs
    less, before the hand-overs' own cost (one that saws while the robot leads part of the cutting may).
    None without cutting modes or where a figure is missing."""
    if not cutting:
        return None
    p, ew, er = (costs[k] for k in ("share", "effort_wearer_rad", "effort_robot_rad"))
    if any(v is None for v in (*p, *ew, *er)):
        return None
    alone = sum(pj * e for pj, e in zip(p, ew))
    led = sum(pj * (ew[j] if j in set(cutting) else er[j]) for j, pj in enumerate(p))
    return float(led / alone) if alone > 0 else None


def predicted_point(costs: dict[str, Any], wearer_modes: Sequence[int]) -> tuple[float, float] | None:
    """(effort [rad], RMS [m]) of the whole-mode rule that hands the wearer ``wearer_modes`` and the robot the
    rest, before the hand-overs' own cost: Σ_j p_j·E_j and √(Σ_j p_j·m_j) with (E_j, m_j) the wearer's or the
    robot's figures of :func:`mode_costs`. None where a figure is missing."""
    p, ew, er, rw, rr = (costs[k] for k in ("share", "effort_wearer_rad", "effort_robot_rad", "rms_wearer_mm",
                                            "rms_robot_mm"))
    if any(v is None for v in (*p, *ew, *er, *rw, *rr)):
        return None
    led = set(int(j) for j in wearer_modes)
    effort = sum(pj * (ew[j] if j in led else er[j]) for j, pj in enumerate(p))
    ms = sum(pj * ((rw[j] if j in led else rr[j]) * 1e-3) ** 2 for j, pj in enumerate(p))
    return float(effort), float(np.sqrt(ms))


def beyond_the_wearer_alone(costs: dict[str, Any], wearer_modes: Sequence[int]) -> bool:
    """Whether the per-mode costs put the rule that hands the wearer ``wearer_modes`` at no less effort and no
    less error than the wearer leading every mode (:func:`predicted_point` of both): the wearer would lead
    where the robot tracks better and spend more for it. False for the empty set (the robot leads every
    mode) and where a figure is missing."""
    if not len(wearer_modes):
        return False
    mine, alone = predicted_point(costs, wearer_modes), predicted_point(costs, range(len(costs["share"])))
    return mine is not None and alone is not None and mine[0] >= alone[0] and mine[1] >= alone[1]


def prune_sets(costs: dict[str, Any], sets: Sequence[Sequence[int]], voluntary_effort: float, prune: bool = True
               ) -> tuple[list[list[int]], list[dict[str, Any]]]:
    """(the wearer-mode ``sets`` kept, a record per set left out): with ``prune``, those
    :func:`beyond_the_wearer_alone` are left out, each recorded with its modes, :func:`predicted_point`
    (effort as a share of ``voluntary_effort`` [rad], RMS [m]) and why in words
    (:func:`mpcshare.reports.rule_choice.pruned_why`)."""
    kept, pruned = [], []
    for modes in sets:
        if prune and beyond_the_wearer_alone(costs, modes):
            effort, rms = predicted_point(costs, modes) or (float("nan"), float("nan"))
            share = effort / voluntary_effort
            pruned.append({"wearer_modes": list(modes), "predicted_effort_vs_voluntary": share,
                           "predicted_rmse_m": rms,
                           "why": pruned_why(share, rms)})
        else:
            kept.append(list(modes))
    return kept, pruned
