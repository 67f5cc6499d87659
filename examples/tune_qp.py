"""Tune the SuperLimb QP controller: sweep gains and weights, print tracking error, limit margins, step time.

Scenario: a knife-tip reference that follows a cutting stroke over a plate
and jumps 6 cm every 1.5 s (control passing between robot and wearer).  The
jumps go through the ruckig smoother (as in the real pipeline) or, with
``--raw``, straight to the QP.  The arm is integrated with the controller's
own constant-acceleration step (the torque it outputs reproduces that
acceleration exactly through the inverse dynamics).

Columns: RMS / max tip error [mm]; the smallest margin to the position
limits [rad], to the velocity limits [rad/s] and to the torque limits as a
fraction of τ_max (−0.00 is a saturated torque; below −1e-6 would be a violation); how many steps were not
``ok``; the median step time [µs].

Usage: ``python examples/tune_qp.py [--seconds 6] [--raw] [--solver auto]``.
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

from robot.limits import JointLimits
from robot.qp import QPConfig, QPController, QPStatus
from robot.smoothing import ReferenceSmoother
from robot.superlimb import SuperLimbParams


def reference(k: int, dt: float) -> np.ndarray:
    """Cutting strokes (±4 cm at 1 Hz) over a plate, jumping 6 cm sideways every 1.5 s [m]."""
    t = k * dt
    stroke = 0.04 * np.sin(2 * np.pi * 1.0 * t)
    side = 0.06 * (int(t / 1.5) % 2)
    return np.array([0.42 + stroke, -0.18 + side, 0.12 - 0.02 * abs(np.sin(np.pi * t))])


def run(cfg: QPConfig, seconds: float, smooth: bool) -> dict:
    params = SuperLimbParams()
    lim = JointLimits.from_superlimb(params)
    ctl = QPController.for_superlimb(params, cfg)
    sm = ReferenceSmoother(3, cfg.dt, max_velocity=0.4, max_acceleration=3.0, max_jerk=40.0)
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    sm.reset(ctl.evaluate(q, v).p)
    errors, times, not_ok = [], [], 0
    margin_q = margin_v = margin_tau = np.inf
    for k in range(int(seconds / cfg.dt)):
        target = reference(k, cfg.dt)
        if smooth:
            s = sm.update(target)
            p_ref, v_ref, a_ref = s.position, s.velocity, s.acceleration
        else:
            p_ref, v_ref, a_ref = target, None, None
        t0 = time.perf_counter()
        r = ctl.step(q, v, p_ref, v_ref, a_ref)
        times.append(time.perf_counter() - t0)
        not_ok += r.status is not QPStatus.OK
        q, v = r.q_next, r.v_next
        errors.append(np.linalg.norm(target - ctl.evaluate(q, v).p) if not smooth else r.tip_error)
        margin_q = min(margin_q, float(np.min(np.minimum(lim.q_max - q, q - lim.q_min))))
        margin_v = min(margin_v, float(np.min(lim.v_max - np.abs(v))))
        margin_tau = min(margin_tau, float(np.min(1.0 - np.abs(r.tau) / lim.tau_max)))
    e = np.asarray(errors[int(0.5 / cfg.dt):]) * 1e3  # skip the first 0.5 s (initial approach)
    return {"rms_mm": float(np.sqrt(np.mean(e**2))), "max_mm": float(e.max()), "margin_q": margin_q,
            "margin_v": margin_v, "margin_tau": margin_tau, "not_ok": not_ok,
            "step_us": float(np.median(times) * 1e6)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--seconds", type=float, default=6.0, help="seconds of the reference per setting")
    ap.add_argument("--raw", action="store_true", help="feed the jumping reference to the QP without ruckig")
    ap.add_argument("--solver", default="auto", help="auto, daqp, osqp or qpsolvers:<name>")
    args = ap.parse_args()

    kps = [100.0, 400.0, 1000.0]
    zetas = [0.7, 1.0]
    posture_weights = [1e-5, 1e-4, 1e-3]
    header = (f"{'kp':>6} {'zeta':>5} {'w_post':>7} | {'rms mm':>7} {'max mm':>7} | "
              f"{'m_q rad':>8} {'m_v rad/s':>9} {'m_tau':>6} {'!ok':>4} | {'step µs':>7}")
    print(f"reference: {'raw (jumps reach the QP)' if args.raw else 'ruckig-smoothed'}; solver {args.solver}")
    print(header)
    print("-" * len(header))
    best = None
    for kp, zeta, wp in itertools.product(kps, zetas, posture_weights):
        cfg = QPConfig(tip_kp=kp, tip_kd=2.0 * zeta * np.sqrt(kp), posture_weight=wp, solver=args.solver)
        res = run(cfg, args.seconds, smooth=not args.raw)
        print(f"{kp:6.0f} {zeta:5.2f} {wp:7.0e} | {res['rms_mm']:7.2f} {res['max_mm']:7.2f} | "
              f"{res['margin_q']:8.3f} {res['margin_v']:9.3f} {res['margin_tau']:6.2f} {res['not_ok']:4d} | "
              f"{res['step_us']:7.1f}")
        if res["not_ok"] == 0 and (best is None or res["rms_mm"] < best[0]):
            best = (res["rms_mm"], kp, zeta, wp)
    if best:
        print(f"\nlowest RMS error with every step ok: kp={best[1]:.0f} 1/s², zeta={best[2]}, "
              f"posture weight={best[3]:.0e} → {best[0]:.2f} mm")


if __name__ == "__main__":
    main()
