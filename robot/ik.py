"""Numerical inverse kinematics of any arm's tip position (Pinocchio and scipy).

For a tip target p* [m] in the model's world frame, bounded least squares (scipy's
``least_squares``, trust-region reflective, Jacobian from Pinocchio):

    1.  min_q ‖p(q) − p*‖² + λ‖q − q_pref‖²     s.t. lower ≤ q ≤ upper     (picks a posture near q_pref)
    2.  min_q ‖p(q) − p*‖²                      from the answer of 1       (removes the bias of λ)

from q_pref first, then from uniform random starts until one reaches p* within ``tol``;
otherwise the in-limit configuration whose tip is nearest (best effort, so that an episode
can always start; the starts stop when two more find the same error to 1 µm). The SuperLimb
has an exact closed form (:mod:`robot.superlimb.kinematics`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["inverse_tip_position"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_POSTURE_WEIGHT = 1e-4  # λ [m²/rad²]: a posture 1 rad away costs as much as 1 cm of tip error
_MAX_EVALUATIONS = 100  # per solve: a reachable tip converges in ≈ 10; an unreachable one stops here


def inverse_tip_position(model, frame_id: int, tip: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                         q_prefer: np.ndarray | None = None, n_starts: int = 8, seed: int = 0,
                         tol: float = 1e-6) -> np.ndarray:
    """A configuration (nq,) [rad] within [lower, upper] whose tip is nearest ``tip`` (3,) [m] (module docstring)."""
    from scipy.optimize import least_squares

    data = model.createData()
    target = np.asarray(tip, dtype=float)
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    pref = 0.5 * (lower + upper) if q_prefer is None else np.clip(np.asarray(q_prefer, dtype=float), lower, upper)
    w = np.sqrt(_POSTURE_WEIGHT)
    eye = w * np.eye(model.nv)

    def error(q: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[frame_id].translation - target

    def jac(q: np.ndarray) -> np.ndarray:
        return pin.computeFrameJacobian(model, data, q, frame_id, _LWA)[:3]

    def solve(q0: np.ndarray) -> np.ndarray:
        first = least_squares(lambda q: np.concatenate([error(q), w * (q - pref)]), q0,
                              jac=lambda q: np.vstack([jac(q), eye]), bounds=(lower, upper), max_nfev=_MAX_EVALUATIONS)
        polished = least_squares(error, first.x, jac=jac, bounds=(lower, upper), xtol=1e-12, ftol=1e-12,
                                 max_nfev=_MAX_EVALUATIONS)
        return np.clip(polished.x, lower, upper)

    rng = np.random.default_rng(seed)
    best, best_err = pref, np.inf
    starts = [pref] + [rng.uniform(lower, upper) for _ in range(max(n_starts, 1) - 1)]
    repeats = 0
    for q0 in starts:
        q = solve(np.clip(q0, lower, upper))
        e = float(np.linalg.norm(error(q)))
        repeats = repeats + 1 if abs(e - best_err) <= 1e-6 else 0  # the same best-effort optimum again
        if e < best_err - 1e-12:
            best, best_err = q, e
        if best_err <= tol or repeats >= 2:
            break
    return best.copy()
