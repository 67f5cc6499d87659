"""Tune the SuperLimb QP controller: sweep gains and weights, print tracking error, limit margins, step time.

Scenario: a knife-tip reference that follows a cutting stroke over a plate
and jumps 6 cm every 1.5 s (control passing between robot and wearer).  The
jumps go through the ruckig smoother (as in the real pipeline) or, with
``--raw``, straight to the QP.  The arm is integrated with the controller's
own constant-acceleration step (the torque it outputs reproduces that
acceleration exactly through the inverse dynamics).

The table (printed, and written as ``tune_qp.md`` and ``tune_qp.json`` into ``--out``, default
``examples-out/tune-qp``) has one row per setting: the tip gain kp [1/s²], the damping ratio ζ
(kd = 2ζ√kp), the posture weight; the RMS and largest tip error [mm] after the first 0.5 s;
the smallest margin to the position limits [rad], to the velocity limits [rad/s] and to the
torque limits as a share of τ_max (0 is a saturated torque; below −1e-6 would be a violation);
how many steps the QP did not solve ``ok``; the median step time [µs].

Usage: ``python examples/tune_qp.py [--seconds 6] [--raw] [--solver auto] [--out DIR]``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

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


#: the table's columns: (key of :func:`run`'s result, header, what it means)
COLUMNS = (("rms_mm", "rms mm", "RMS tip error after the first 0.5 s [mm]"),
           ("max_mm", "max mm", "largest tip error after the first 0.5 s [mm]"),
           ("margin_q", "m_q rad", "smallest margin to the joint position limits [rad]"),
           ("margin_v", "m_v rad/s", "smallest margin to the joint velocity limits [rad/s]"),
           ("margin_tau", "m_tau", "smallest torque margin, share of tau_max (0: saturated, < 0: violated)"),
           ("not_ok", "!ok", "steps the QP did not solve ok"),
           ("step_us", "step µs", "median QP step time [µs]"))


def main(argv: list[str] | None = None) -> list[dict]:
    """Sweep the settings, print the table with its legend, write it into ``--out``; returns the rows."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--seconds", type=float, default=6.0, help="seconds of the reference per setting")
    ap.add_argument("--raw", action="store_true", help="feed the jumping reference to the QP without ruckig")
    ap.add_argument("--solver", default="auto", help="auto, daqp, osqp or qpsolvers:<name>")
    ap.add_argument("--out", default="examples-out/tune-qp", help="output folder (git ignores examples-out/)")
    args = ap.parse_args(argv)
    if not args.seconds > 0.5:
        ap.error(f"--seconds must be more than 0.5 (the first 0.5 s are not scored), got {args.seconds:g}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"writing into {out.resolve()}")

    kps = [100.0, 400.0, 1000.0]
    zetas = [0.7, 1.0]
    posture_weights = [1e-5, 1e-4, 1e-3]
    reference_kind = "raw (jumps reach the QP)" if args.raw else "ruckig-smoothed"
    legend = ["kp: tip gain [1/s²]; zeta: damping ratio (kd = 2·zeta·√kp); w_post: posture weight",
              *[f"{head}: {meaning}" for _, head, meaning in COLUMNS]]
    header = (f"{'kp':>6} {'zeta':>5} {'w_post':>7} | {'rms mm':>7} {'max mm':>7} | "
              f"{'m_q rad':>8} {'m_v rad/s':>9} {'m_tau':>6} {'!ok':>4} | {'step µs':>7}")
    print(f"reference: {reference_kind}; solver {args.solver}; {args.seconds:g} s per setting")
    print("\n".join(legend) + "\n")
    print(header)
    print("-" * len(header))
    rows, best = [], None
    for kp, zeta, wp in itertools.product(kps, zetas, posture_weights):
        cfg = QPConfig(tip_kp=kp, tip_kd=2.0 * zeta * np.sqrt(kp), posture_weight=wp, solver=args.solver)
        res = run(cfg, args.seconds, smooth=not args.raw)
        rows.append({"kp": kp, "zeta": zeta, "posture_weight": wp, **res})
        print(f"{kp:6.0f} {zeta:5.2f} {wp:7.0e} | {res['rms_mm']:7.2f} {res['max_mm']:7.2f} | "
              f"{res['margin_q']:8.3f} {res['margin_v']:9.3f} {res['margin_tau']:6.2f} {res['not_ok']:4d} | "
              f"{res['step_us']:7.1f}")
        if res["not_ok"] == 0 and (best is None or res["rms_mm"] < best["rms_mm"]):
            best = rows[-1]
    verdict = (f"lowest RMS error with every step ok: kp={best['kp']:.0f} 1/s², zeta={best['zeta']}, "
               f"posture weight={best['posture_weight']:.0e} → {best['rms_mm']:.2f} mm" if best else
               "no setting solved every step ok")
    print(f"\n{verdict}")
    (out / "tune_qp.json").write_text(json.dumps({"reference": reference_kind, "solver": args.solver,
                                                  "seconds": args.seconds, "rows": rows, "best": best},
                                                 indent=2) + "\n")
    md = ["# QP settings on a jumping cutting reference", "",
          f"Reference {reference_kind}, solver {args.solver}, {args.seconds:g} s per setting.", "",
          *[f"- {line}" for line in legend], "",
          "| kp | zeta | w_post | " + " | ".join(head for _, head, _ in COLUMNS) + " |",
          "|---|---|---|" + "---|" * len(COLUMNS),
          *[f"| {r['kp']:.0f} | {r['zeta']:g} | {r['posture_weight']:.0e} | "
            + " | ".join(f"{r[key]:.3g}" for key, _, _ in COLUMNS) + " |" for r in rows],
          "", verdict[:1].upper() + verdict[1:] + ".", ""]
    (out / "tune_qp.md").write_text("\n".join(md))
    print(f"table: {out / 'tune_qp.md'}")
    return rows


if __name__ == "__main__":
    main()
