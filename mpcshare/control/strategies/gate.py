"""``gate``: the default shared strategy; whole modes the robot cannot predict go to the wearer
(docs/design.md, "The default gate").

Score: v_j ∈ [0, 1] per task mode j is the held-out unpredictable share (``ModeFigures.voluntary_share``),
or, with the ``wearer_modes`` setting (the calibrated rule), the indicator of those modes; with the mode
model's transition matrix A per model period Δ [s], s_t = max_{k = 0..n} π_t·A^k·v, n = round(lead_s / Δ).

Who leads: the wearer from s_t ≥ ``share_on``; the robot again once s_t < ``share_off`` has held ``hold_s``
[s], never sooner than the Arbiter's ``min_dwell_s`` after the last hand-over; α ramps over ``handover_s``
and the Arbiter's safety overrides apply. The wearer also takes the lead by pushing: ‖û_v‖ > ``push_mps``
[m/s] against the robot (û_v·û_r < 0), a leaky integral x' = 1[push] − x/push_s reaching 1 − 1/e of its
limit (off at inf). With ``wearer_max_s`` [s] finite the wearer leads a stretch of wearer modes at most that
long, then the robot until s_t < ``share_off``.

Shares: while the wearer leads, û = a_w·û_r + (1 − a_w)·û_v with a_w = ``wearer_alpha`` ∈ [0, 0.5); while
the robot leads, α = π·a with a = ``robot_alphas`` ∈ [0.5, 1]^K (default 1, β the user's).

Settings: :class:`GateSettings` (the controller's ``strategy_settings``, else the bundle's calibrated rule,
else the defaults; ValueError names a wrong field). Without per-mode figures in the bundle: the paper's
gate (:mod:`mpcshare.control.strategies.paper_gate`; ``on_threshold``, ``off_threshold``; reasons say so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mpcshare.control.strategies.base import ArbiterView, StepInputs, StrategyContext, StrategySpec, Target
from mpcshare.control.strategies.paper_gate import PaperGate, PaperGateSettings, check_thresholds

__all__ = ["GateSettings", "ModeCostGate", "SPECS", "mode_forecast", "robot_shares", "voluntary_shares",
           "wearer_indicator"]

_FLOATS = ("share_on", "share_off", "lead_s", "hold_s", "push_mps", "push_s", "wearer_alpha", "wearer_max_s",
           "on_threshold", "off_threshold")


@dataclass(frozen=True)
class GateSettings:
    """The rule's settings (module docstring): share_on, share_off (thresholds on the score s), lead_s [s],
    hold_s [s], push_mps [m/s] (inf: off), push_s [s], wearer_alpha ∈ [0, 0.5), wearer_max_s [s] (inf: no
    bound), wearer_modes (None: v from the bundle's figures), robot_alphas (K shares in [0.5, 1]; None: 1);
    on_threshold, off_threshold: the paper's gate used without per-mode figures. ValueError naming a wrong
    field (the per-mode lengths are checked against the mode model when the policy is built)."""

    share_on: float = 0.3
    share_off: float = 0.2
    lead_s: float = 0.5
    hold_s: float = 0.5
    push_mps: float = math.inf
    push_s: float = 0.3
    wearer_alpha: float = 0.0
    wearer_max_s: float = math.inf
    wearer_modes: tuple[int, ...] | None = None
    robot_alphas: tuple[float, ...] | None = None
    on_threshold: float = PaperGateSettings.on_threshold
    off_threshold: float = PaperGateSettings.off_threshold

    def __post_init__(self) -> None:
        for k in _FLOATS:
            try:
                object.__setattr__(self, k, float(getattr(self, k)))
            except (TypeError, ValueError):
                raise ValueError(f"gate setting {k} must be a number, got {getattr(self, k)!r}") from None
        if not 0.0 <= self.share_off <= self.share_on <= 1.0:
            raise ValueError(f"need 0 <= share_off <= share_on <= 1, got {self.share_off!r}, {self.share_on!r}")
        for k in ("lead_s", "hold_s", "push_s"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"gate setting {k} must be finite and >= 0 s, got {v!r}")
        if not 0.0 <= self.wearer_alpha < 0.5:
            raise ValueError(f"gate setting wearer_alpha must be in [0, 0.5) (the wearer leads below 0.5), "
                             f"got {self.wearer_alpha!r}")
        if not self.wearer_max_s > 0:
            raise ValueError(f"gate setting wearer_max_s must be > 0 s (inf: no bound), got {self.wearer_max_s!r}")
        if not self.push_mps > 0:
            raise ValueError(f"gate setting push_mps must be > 0 m/s (inf: off), got {self.push_mps!r}")
        check_thresholds(self.on_threshold, self.off_threshold)
        if self.wearer_modes is not None:
            modes = tuple(int(j) for j in self.wearer_modes)
            if any(j < 0 for j in modes):
                raise ValueError(f"gate setting wearer_modes must be mode indices >= 0, got {self.wearer_modes!r}")
            object.__setattr__(self, "wearer_modes", modes)
        if self.robot_alphas is not None:
            a = tuple(float(x) for x in self.robot_alphas)
            if not all(0.5 <= x <= 1.0 for x in a):
                raise ValueError(f"gate setting robot_alphas must be in [0.5, 1] (the robot leads from 0.5), "
                                 f"got {self.robot_alphas!r}")
            object.__setattr__(self, "robot_alphas", a)


def robot_shares(alphas: Any, n_modes: int | None) -> np.ndarray | None:
    """(K,) the robot's share a_j while it leads mode j (the ``robot_alphas`` setting); None when not set.
    ValueError unless K shares in [0.5, 1] with the mode model's K."""
    if alphas is None:
        return None
    a = np.asarray(alphas, dtype=float)
    if n_modes is None or a.shape != (n_modes,):
        raise ValueError(f"gate setting robot_alphas needs one share per mode of the bundle's mode model "
                         f"({n_modes} modes), got {alphas!r}")
    if not np.all((a >= 0.5) & (a <= 1.0)):
        raise ValueError(f"gate setting robot_alphas must be in [0.5, 1] (the robot leads from 0.5), got {alphas!r}")
    return a


def voluntary_shares(shares: Any) -> np.ndarray | None:
    """(K,) v_j from the bundle's figures (``ModeFigures.voluntary_share``); None when absent. ValueError
    unless K shares in [0, 1]."""
    if shares is None:
        return None
    v = np.asarray(shares, dtype=float)
    if v.ndim != 1 or not np.all(np.isfinite(v)) or np.any(v < 0) or np.any(v > 1):
        raise ValueError(f"the voluntary shares must be K shares in [0, 1], got {shares!r}")
    return v


def wearer_indicator(modes: Any, n_modes: int | None) -> np.ndarray | None:
    """(K,) v_j = 1 for j in ``modes`` (the ``wearer_modes`` setting), else 0; None when ``modes`` is None.
    ValueError for a mode outside 0..K−1 or without the mode model's K."""
    if modes is None:
        return None
    if n_modes is None:
        raise ValueError("gate setting wearer_modes needs the bundle's mode model (its transition matrix)")
    idx = [int(j) for j in modes]
    bad = [j for j in idx if not 0 <= j < n_modes]
    if bad:
        raise ValueError(f"gate setting wearer_modes has mode(s) {bad}; valid: 0..{n_modes - 1}")
    v = np.zeros(n_modes)
    v[idx] = 1.0
    return v


def mode_forecast(v: np.ndarray, transmat: np.ndarray | None, steps: int) -> np.ndarray:
    """(n + 1, K) rows A^k·v, k = 0..n: row k times π is the forecast π·A^k·v (identity without A)."""
    rows = [np.asarray(v, dtype=float)]
    if transmat is not None:
        A = np.asarray(transmat, dtype=float)
        if A.shape != (v.size, v.size):
            raise ValueError(f"transmat has shape {A.shape}, the mode statistics {v.size} modes")
        for _ in range(int(steps)):
            rows.append(A @ rows[-1])
    return np.array(rows)


class ModeCostGate:
    """The expected-cost whole-mode rule (module docstring)."""

    overrides = True

    def __init__(self, v: np.ndarray, transmat: np.ndarray | None, model_dt: float, settings: GateSettings,
                 min_dwell_s: float, robot_alphas: np.ndarray | None = None) -> None:
        self.settings = s = settings
        self.robot_alphas = robot_alphas
        self.forecast = mode_forecast(v, transmat, round(s.lead_s / model_dt) if model_dt > 0 else 0)
        self.min_dwell_s = float(min_dwell_s)
        self.reset()

    def reset(self) -> None:
        """The robot leads unless the modes say otherwise."""
        self.wearer = False
        self._spent = False  # the bounded lead ran out in this stretch of wearer modes
        self._wearer_since = math.inf
        self._below_since = math.inf
        self._push = 0.0
        self._last_t = -math.inf
        self._pi: np.ndarray | None = None
        self._score = math.nan
        self._share: tuple[np.ndarray | None, float] | None = None  # (π, its robot share)

    def score(self, mode_proba: np.ndarray | None) -> float:
        """s = max_k π·A^k·v (NaN without mode probabilities); recomputed only for a new π object (the
        controller replaces π on its 10 Hz ticks)."""
        if mode_proba is self._pi:
            return self._score
        self._pi = mode_proba
        if mode_proba is None or np.shape(mode_proba) != (self.forecast.shape[1],):
            self._score = math.nan
        else:
            self._score = float(np.max(self.forecast @ mode_proba))
        return self._score

    def _pushing(self, t: float, inputs: StepInputs) -> bool:
        """Leaky integral of the wearer pushing against the robot above push_mps (module docstring)."""
        s = self.settings
        if not math.isfinite(s.push_mps) or inputs.u_v is None:
            return False
        dt = min(max(t - self._last_t, 0.0), 0.1) if math.isfinite(self._last_t) else 0.0
        u_v, u_r = inputs.u_v, inputs.u_r
        against = u_r is None or float(u_v @ u_r) < 0.0
        push = against and float(u_v @ u_v) > s.push_mps ** 2
        tau = max(s.push_s, 1e-6)
        self._push = self._push + dt * ((1.0 if push else 0.0) - self._push / tau) if tau > 0 else float(push)
        return self._push >= 0.63 * tau  # a sustained push: the integral has reached 1 − 1/e of its limit

    def _robot_share(self, mode_proba: np.ndarray | None) -> float:
        """α = π·a while the robot leads (1 without ``robot_alphas``; their largest without π); recomputed only
        for a new π object, as :meth:`score`."""
        if self._share is not None and mode_proba is self._share[0]:
            return self._share[1]
        a = self.robot_alphas
        if a is None:
            share = 1.0
        elif mode_proba is None or np.shape(mode_proba) != a.shape or not np.all(np.isfinite(mode_proba)):
            share = float(np.max(a))
        else:
            p = np.clip(np.asarray(mode_proba, dtype=float), 0.0, None)
            share = float(np.clip(p @ a / max(float(p.sum()), 1e-12), 0.5, 1.0))
        self._share = (mode_proba, share)
        return share

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        s = self.settings
        score = self.score(inputs.mode_proba)
        pushed = self._pushing(t, inputs)
        self._last_t = t
        dwell_ok = t - arbiter.last_switch_t >= self.min_dwell_s
        on = math.isfinite(score) and score >= s.share_on
        if self._spent and not (math.isfinite(score) and score >= s.share_off):
            self._spent = False  # the wearer modes ended: the next entry is handed over afresh
        wants = (on and not self._spent) or pushed
        if self.wearer and t - self._wearer_since >= s.wearer_max_s and dwell_ok and not pushed:
            self.wearer, self._spent, self._below_since = False, True, math.inf
        elif wants:
            self._below_since = math.inf
            if not self.wearer and dwell_ok:
                self.wearer, self._wearer_since = True, t
        elif self.wearer:
            low = not (math.isfinite(score) and score >= s.share_off)
            if low and not math.isfinite(self._below_since):
                self._below_since = t
            if not low:
                self._below_since = math.inf
            elif t - self._below_since >= s.hold_s and dwell_ok:
                self.wearer = False
        why = "the wearer pushes" if pushed else f"wearer-mode score {score:.2f}"
        if self._spent and not self.wearer:
            why += f", the wearer's {s.wearer_max_s:g} s lead spent"
        if not self.wearer:
            a = self._robot_share(inputs.mode_proba)
            return Target(a, why + ": the robot leads", ramp=True, beta=1.0 - a if a < 1 else None)
        a = s.wearer_alpha
        return Target(a, why + ": the wearer leads", ramp=True, beta=1.0 - a if a > 0 else None)


class _PaperFallback(PaperGate):
    """The paper's gate, for bundles without per-mode figures (its reasons say so)."""

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        d = super().decide(t, inputs, arbiter)
        return Target(d.alpha, "no per-mode figures in the bundle, the paper's gate: " + d.reason, ramp=d.ramp)


def make(ctx: StrategyContext) -> ModeCostGate | PaperGate:
    """The rule from the context's settings (:class:`GateSettings`), the bundle's figures and the dwell."""
    s: GateSettings = ctx.settings
    f = ctx.figures
    v = wearer_indicator(s.wearer_modes, f.n_modes)
    v = voluntary_shares(f.voluntary_share) if v is None else v
    if v is None:
        return _PaperFallback(s.on_threshold, s.off_threshold, ctx.min_dwell_s)
    return ModeCostGate(v, f.transmat, f.model_dt, s, ctx.min_dwell_s, robot_shares(s.robot_alphas, f.n_modes))


SPECS = (StrategySpec("gate", "The default shared strategy: whole modes the robot cannot predict go to the wearer, "
                      "handed over before they begin and held after they end.", tunable=True, color="#1f77b4",
                      factory=make, order=4, role="shared", settings=GateSettings),)
