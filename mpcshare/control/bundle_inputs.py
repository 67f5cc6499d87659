"""What the controller takes from a bundle, checked once when it is built: the channel layout, the
learned parts' interfaces, the shoulder map, the mode figures and the rule's settings.

Everything here raises ``mpcshare.errors.ControllerSetupError`` (a ValueError) naming what is wrong;
nothing here runs in the loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from learning.preprocessing.preprocess import window_lags
from learning.preprocessing.resample import decimation_factor
from mpcshare.control.strategies import REGISTRY
from mpcshare.control.strategies.base import ModeFigures
from mpcshare.errors import ControllerSetupError
from robot.shoulder import ShoulderMap
from sim.task import Task, recorded_task

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["BundleLayout", "check_bundle", "mode_figures", "rule_settings", "shoulder_map"]

DEFAULT_TIP = ("knife_x", "knife_y", "knife_z")
DEFAULT_FORK = ("fork_x", "fork_y", "fork_z")
_FIELDS = ("obs_names", "act_names", "rate_hz", "model_hz", "window_s", "preprocessor", "modes", "gates",
           "predictor", "novelty_threshold")


@dataclass(frozen=True)
class BundleLayout:
    """Where the controller finds its channels in a bundle.

    d_o, d_u: obs/act dimensions; n_modes; lags: window length L; tip_index: (3,) act
    columns of the knife tip x, y, z; fork_index: (3,) obs columns of the fork tip;
    act_mean, act_scale: the act standardiser (u = u_std·scale + mean).
    """

    d_o: int
    d_u: int
    n_modes: int
    lags: int
    tip_index: np.ndarray
    fork_index: np.ndarray
    act_mean: np.ndarray
    act_scale: np.ndarray


def _indices(names: tuple[str, ...], wanted: tuple[str, ...], what: str, option: str) -> np.ndarray:
    wanted = tuple(wanted)
    if len(wanted) != 3:
        raise ControllerSetupError(f"{option} must name 3 channels (x, y, z), got {wanted!r}")
    missing = [w for w in wanted if w not in names]
    if missing:
        raise ControllerSetupError(f"the bundle's {what} {list(names)} have no channel(s) {missing}; the controller "
                                   f"needs the tip position channels: pass {option}=(x, y, z names) to map them "
                                   f"explicitly")
    return np.array([names.index(w) for w in wanted])


def check_bundle(bundle: ModelBundle, tip_channels: Sequence[str] | None = None,
                 fork_channels: Sequence[str] | None = None) -> BundleLayout:
    """Check that ``bundle`` fits the robot and is complete; return its :class:`BundleLayout`."""
    absent = [f for f in _FIELDS if not hasattr(bundle, f)]
    if absent:
        raise ControllerSetupError(f"bundle lacks field(s) {absent} (a mpcshare.bundle.ModelBundle is expected)")
    obs_names, act_names = tuple(bundle.obs_names), tuple(bundle.act_names)
    tip = _indices(act_names, tip_channels or DEFAULT_TIP, "act_names", "tip_channels")
    fork = _indices(obs_names, fork_channels or DEFAULT_FORK, "obs_names", "fork_channels")
    shoulder_map(bundle)  # raises for shoulder channels no map reads
    d_o, d_u = len(obs_names), len(act_names)
    pre = bundle.preprocessor
    for side, d in (("obs", d_o), ("act", d_u)):
        got = int(getattr(getattr(pre, side), "n_features_in_", -1))
        if got != d:
            raise ControllerSetupError(f"bundle.preprocessor.{side} was fitted on {got} channels, {side}_names has {d}")
    n_in = int(getattr(bundle.modes, "n_features_in_", -1))
    if n_in != d_o:
        raise ControllerSetupError(f"bundle.modes expects {n_in} features per sample, obs_names has {d_o}")
    K = int(bundle.modes.model_.n_components)
    decimation_factor(bundle.rate_hz, bundle.model_hz)  # raises for a non-integer factor
    L = window_lags(float(bundle.window_s), float(bundle.model_hz))
    if not (float(bundle.novelty_threshold) == float(bundle.novelty_threshold)):
        raise ControllerSetupError("bundle.novelty_threshold is NaN")
    # the learned parts must accept the controller's inputs
    try:
        p = float(bundle.gates.proba_one(np.zeros(L * d_o), 0))
    except Exception as exc:
        raise ControllerSetupError(f"bundle.gates.proba_one(window of {L * d_o}, mode 0) failed: {exc}") from exc
    if not 0.0 <= p <= 1.0:
        raise ControllerSetupError(f"bundle.gates.proba_one returned {p!r}, not a probability")
    try:
        out = np.asarray(bundle.predictor.make_stream().step(np.zeros(d_o + K)), dtype=float)
    except Exception as exc:
        raise ControllerSetupError(f"bundle.predictor stream step on an input of {d_o}+{K} failed: {exc}") from exc
    if out.shape != (d_u,):
        raise ControllerSetupError(f"bundle.predictor stream returns shape {out.shape}, expected ({d_u},) "
                                   f"(act channels)")
    return BundleLayout(d_o, d_u, K, L, tip, fork, np.asarray(pre.act.mean_, dtype=float),
                        np.asarray(pre.act.scale_, dtype=float))


def bundle_task(bundle: ModelBundle) -> Task:
    """The task the bundle was trained for (:func:`sim.task.recorded_task` of ``bundle.config``; none recorded:
    the default task). Raises ControllerSetupError naming the task that cannot be found."""
    try:
        return recorded_task(getattr(bundle, "config", None))
    except ValueError as exc:
        raise ControllerSetupError(f"the bundle's task: {exc}") from None


def shoulder_map(bundle: ModelBundle, shoulder: ShoulderMap | None = None) -> ShoulderMap:
    """The shoulder map of the bundle's voluntary channels (``vol_names``): ``shoulder`` when given (its
    channels must match), else the map of the names of the task the bundle was trained for
    (:func:`sim.task.recorded_task`, :meth:`sim.task.Task.shoulder_map`; none: the task's angles). Raises
    ControllerSetupError naming the channels, or the task that cannot be found."""
    vol = [str(n) for n in (getattr(bundle, "vol_names", ()) or ())]
    if shoulder is not None:
        if vol and shoulder.n_channels != len(vol):
            raise ControllerSetupError(f"the shoulder map reads {shoulder.n_channels} angle(s), the bundle's "
                                       f"vol_names {vol} are {len(vol)}")
        return shoulder
    task = bundle_task(bundle)
    try:
        return task.shoulder_map(vol)
    except ValueError as exc:
        raise ControllerSetupError(f"the bundle's vol_names: {exc}") from None


def mode_figures(bundle: ModelBundle) -> ModeFigures:
    """What the strategies read of a bundle (:class:`~mpcshare.control.strategies.base.ModeFigures`):
    v_j = 1 − n_positive/n of the held-out gate figures per mode (``bundle.metrics["gate"]["per_mode"]``;
    None when absent or a mode has no held-out point), the mode model's transition matrix per model tick
    (None when it has none) and the model period [s]."""
    metrics = getattr(bundle, "metrics", None) or {}
    transmat = getattr(bundle.modes, "transmat_", None)
    per_mode = (metrics.get("gate") or {}).get("per_mode") or {}
    shares = [1.0 - m["n_positive"] / m["n"] if m.get("n") else None for _, m in sorted(per_mode.items(),
                                                                                        key=lambda kv: int(kv[0]))]
    return ModeFigures(np.asarray(shares, dtype=float) if shares and None not in shares else None,
                       None if transmat is None else np.asarray(transmat, dtype=float), 1.0 / float(bundle.model_hz))


def rule_settings(bundle: ModelBundle, strategy: str, given: Any = None) -> Any:
    """The settings the strategy runs with: ``given`` (the controller's ``strategy_settings``) when not None,
    else the bundle's calibrated rule's (``bundle.rule``) when it is for ``strategy`` (or the strategy its spec's
    ``rule_of`` names) and was not skipped, else None (the strategy's defaults). The Arbiter turns them into the
    strategy's typed settings."""
    if given is not None:
        return given
    rule = getattr(bundle, "rule", None)
    spec = REGISTRY.get(strategy)
    reads = spec.rule_of if spec is not None and spec.rule_of is not None else strategy
    ran = rule is not None and getattr(rule, "skipped", None) is None
    return rule.settings if ran and rule.strategy == reads else None
