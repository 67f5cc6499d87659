"""Train a shared controller from demonstrations and run it beside a simulated wearer.

    python examples/run_eating_sim.py                 # trains a small model first; writes examples-out/eating-sim/
    python examples/run_eating_sim.py --model mpcshare-out/model --out my-run   # reuse `mpcshare demo`'s model

Steps, each one call:
1. demonstrations: the synthetic bimanual eating data (fork = observation, knife = action);
2. a model bundle: HMM task modes, per-mode gates, the LSTM reactive predictor;
3. the online controller: gate → α, β; û = α·û_r + β·û_v; ruckig → MPC → QP;
4. one held-out trial in MuJoCo: the SuperLimb holds the knife, the simulated wearer's
   intent is the demonstration's knife, the fork replays the demonstration's fork;
5. the metrics, a plot of the trial and (with --video) a video.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from learning.data import load
from mpcshare.bundle import load_bundle, save_bundle
from mpcshare.control.arbitration import STRATEGIES
from mpcshare.control.controller import SharedController
from mpcshare.reports.episode_plot import plot_episode
from mpcshare.training import train_bundle
from mpcshare.training.config import TrainConfig
from sim.closed_loop import run_episode
from sim.demonstrator import CUTTING, generate_demonstrations
from sim.metrics import episode_metrics


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--out", default="examples-out/eating-sim", help="output folder (git ignores examples-out/)")
    p.add_argument("--model", default=None, help="a bundle from `mpcshare train` / `mpcshare demo` (else train one)")
    p.add_argument("--minutes", type=float, default=4.0, help="minutes of demonstrations per subject to train on")
    p.add_argument("--seconds", type=float, default=30.0, help="seconds of the held-out trial to simulate")
    p.add_argument("--strategy", default="gate", choices=STRATEGIES,
                   help="who leads (default gate): " + ", ".join(STRATEGIES))
    p.add_argument("--video", action="store_true", help="render a video (needs offscreen OpenGL)")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"writing into {out.resolve()}")

    # 1-2. demonstrations and a model bundle
    if args.model:
        bundle = load_bundle(args.model)
        demos = load(bundle.config["data_path"])  # the data it was trained on (recorded by `mpcshare train`)
    else:
        demos = generate_demonstrations(n_subjects=3, minutes=args.minutes, seed=0)
        bundle = train_bundle(demos, TrainConfig(max_epochs=40), progress=True)
        save_bundle(bundle, out / "model")
    print(f"K = {bundle.K:.3g}; held-out trials {bundle.heldout_trials}")

    # 3. the online controller
    controller = SharedController.from_bundle(bundle, strategy=args.strategy)

    # 4. one held-out trial in the closed loop
    trial = next(tr for tr in demos.trials if tr.trial_id == bundle.heldout_trials[0])
    episode = run_episode(controller, trial, duration_s=args.seconds, progress=True,
                          render=out / "trial.mp4" if args.video else None)
    episode.save(out / "run.npz")

    # 5. what happened
    metrics = episode_metrics(episode)
    cutting = None if trial.mode is None else trial.mode[:len(episode.t)] == CUTTING  # the sawing close-up's steps
    plot_episode(episode, out / "trial.png", title=f"{args.strategy}, trial {trial.trial_id}", cutting=cutting)
    print(f"tracking error against the wearer's intent: RMS {metrics['tracking_rmse_m'] * 1e3:.1f} mm, "
          f"p95 {metrics['tracking_p95_m'] * 1e3:.1f} mm")
    print(f"robot in control {metrics['reactive_share']:.0%} of the time, {metrics['handovers']} hand-overs; "
          f"wearer's effort {metrics['voluntary_effort']:.3f} rad; limit violations {metrics['limit_violations']}")
    if args.video:
        print(f"video: {episode.info.get('video') or episode.info.get('render_message')}")
    print(f"plot: {out / 'trial.png'}; run file: {out / 'run.npz'}")
    return metrics


if __name__ == "__main__":
    main()
