"""The robot alone (``reactive``) and the wearer alone (``voluntary``) on a world's held-out trials, with
the controller's internals per step, cached as NPZ files.

:func:`world_bundle` trains a bundle on ``family:<seed>`` or a ``benchmarks/bench_task.py`` data kind
with the defaults (``quick``: at most 20 LSTM epochs) and caches it; :func:`record_world` runs both
parties on the held-out trials and writes per trial ``<strategy>_<trial>.npz`` with, per control step
(100 Hz): ``t`` [s], ``tip``, ``intent``, ``reference`` (N, 3) [m, plate frame], ``shoulder`` (N, n) [rad],
``u_v`` (N, 3) [m/s] the tip velocity the shoulder map gives the wearer's deflection, ``mode_proba`` (N, K),
``novelty`` (N,), and with the control-rate forecast ``fast`` and ``slow`` (N, H+1, 3) [m]: the fast
path's forecast and the LSTM's (interpolated to the step) it was made from, NaN before the first.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path("/tmp/coming-error")
STRATEGIES = ("reactive", "voluntary")


def world_data(world: str, quick: bool = True, extra_trials: int = 0) -> tuple[Any, tuple[str, ...], list[Any]]:
    """(demonstrations, mode names, further trials) of ``family:<seed>`` (quick: 12 trials × 40 s) or a data
    kind. ``extra_trials`` (family worlds only): that many more trials of the same world, drawn after the
    data's own (the data's trials are the same with or without them), never seen by training."""
    if world.startswith("family:"):
        from learning.data import Demonstrations
        from sim.world_family import world_demonstrations

        n = 12 if quick else 16
        demos, spec = world_demonstrations(int(world.split(":")[1]), n_trials=n + extra_trials,
                                           trial_s=40.0 if quick else 60.0)
        own = Demonstrations(demos.trials[:n], demos.rate_hz, list(demos.obs_names), list(demos.act_names),
                             list(demos.vol_names))
        return own, tuple(spec.mode_names), list(demos.trials[n:])
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_task import make_data

    from sim.task.eating import MODE_NAMES

    return make_data(world), tuple(MODE_NAMES), []


def world_dir(world: str, root: Path = ROOT) -> Path:
    """The cache folder of a world."""
    return root / world.replace(":", "_")


def world_bundle(world: str, demos: Any, quick: bool = True, root: Path = ROOT) -> Any:
    """The world's bundle, trained with the defaults (quick: ``max_epochs=20``) or loaded from the cache."""
    from mpcshare.bundle import is_bundle, load_bundle

    folder = world_dir(world, root) / "bundle"
    if is_bundle(folder):
        return load_bundle(folder)
    from mpcshare.bundle.bundle import save_bundle
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig

    bundle = train_bundle(demos, TrainConfig(max_epochs=20) if quick else TrainConfig(), progress=False)
    folder.parent.mkdir(parents=True, exist_ok=True)
    save_bundle(bundle, folder)
    return bundle


class _Recorder:
    """A controller factory that keeps, per step, the command's mode posterior and novelty and the fast
    path's inputs and output (the LSTM's forecast at the step and the control-rate forecast)."""

    def __init__(self) -> None:
        self.controller: Any = None
        self.rows: dict[str, list[Any]] = {}

    def __call__(self, bundle: Any, **options: Any) -> Any:
        from mpcshare.control.controller import SharedController

        ctl = SharedController.from_bundle(bundle, **options)
        self.controller, self.rows = ctl, {"mode_proba": [], "novelty": [], "fast": [], "slow": []}
        fast, step = ctl.fast, ctl.step
        current: dict[str, Any] = {"fast": None, "slow": None}
        if fast is not None:
            fast_step = fast.step

            def recorded_fast(*args: Any, **kw: Any) -> Any:
                F = fast_step(*args, **kw)
                if F is not None and fast._slow is not None:
                    slow = fast._interpolate(fast._slow[None], np.array([fast._since_tick / fast.factor]))[0]
                    current["fast"], current["slow"] = np.array(F), slow * fast._scale + fast._mean
                return F

            fast.step = recorded_fast

        def recorded_step(*args: Any, **kw: Any) -> Any:
            current["fast"] = current["slow"] = None
            cmd = step(*args, **kw)
            self.rows["mode_proba"].append(np.array(cmd.mode_proba, dtype=float))
            self.rows["novelty"].append(float(cmd.novelty))
            self.rows["fast"].append(current["fast"])
            self.rows["slow"].append(current["slow"])
            return cmd

        ctl.step = recorded_step
        return ctl

    def arrays(self) -> dict[str, np.ndarray]:
        """The recorded rows as arrays (forecasts NaN where none was made)."""
        out = {"mode_proba": np.stack(self.rows["mode_proba"]), "novelty": np.array(self.rows["novelty"])}
        shape = next((f.shape for f in self.rows["fast"] if f is not None), None)
        if shape is not None:
            for k in ("fast", "slow"):
                out[k] = np.stack([np.full(shape, np.nan) if f is None else f for f in self.rows[k]])
        return out


def record_episode(bundle: Any, demos: Any, trial: Any, strategy: str, duration_s: float | None,
                   mode_names: tuple[str, ...], seed: int = 0) -> dict[str, np.ndarray]:
    """One closed-loop episode of ``strategy`` (β 0.5, the default wearer) with the module docstring's arrays."""
    from mpcshare.evaluation.episode import simulate_episode
    from mpcshare.run_table import StrategyRun

    rec = _Recorder()
    ep, m = simulate_episode(bundle, demos, trial, StrategyRun(strategy, strategy), {}, beta=0.5,
                             duration_s=duration_s, seed=seed, wearer=None, mode_names=mode_names,
                             make_controller=rec)
    theta = np.asarray(ep.voluntary, dtype=float)
    shoulder = rec.controller.shoulder
    u_v = np.stack([shoulder.tip_velocity(th) for th in theta])
    out = {"t": np.asarray(ep.t, dtype=float), "tip": np.asarray(ep.tip, dtype=float),
           "intent": np.asarray(ep.tip_intent, dtype=float), "reference": np.asarray(ep.tip_reference, dtype=float),
           "shoulder": theta, "u_v": u_v, "true_mode": np.asarray(trial.mode[:len(ep.t)]) if trial.mode is not None
           else np.full(len(ep.t), -1), **rec.arrays()}
    n = len(out["t"])
    if out["mode_proba"].shape[0] != n:
        raise RuntimeError(f"recorded {out['mode_proba'].shape[0]} controller steps for {n} episode steps")
    out["rms_m"] = np.array(m["tracking_rmse_m"])
    return out


def record_world(world: str, quick: bool = True, duration_s: float | None = 40.0, max_trials: int = 8,
                 extra_trials: int = 5, root: Path = ROOT, log: Any = print) -> Path:
    """Train (or load) the world's bundle and record both parties on its held-out trials and ``extra_trials``
    further trials of a family world, at most ``max_trials`` in all (module docstring); the estimated modes
    on the training trials too (:func:`training_dwells`). Cached."""
    import torch

    torch.set_num_threads(1)
    folder = world_dir(world, root)
    demos, mode_names, extra = world_data(world, quick, extra_trials)
    bundle = world_bundle(world, demos, quick, root)
    by_id = {t.trial_id: t for t in list(demos.trials) + extra}
    trials = (list(bundle.heldout_trials) + [t.trial_id for t in extra])[:max_trials]
    dwell = folder / "dwells.npz"
    if not dwell.exists():
        np.savez(dwell, **training_dwells(bundle, [by_id[i] for i in bundle.train_trials]))
    for tid in trials:
        for strategy in STRATEGIES:
            path = folder / f"{strategy}_{tid}.npz"
            if path.exists():
                continue
            arrays = record_episode(bundle, demos, by_id[tid], strategy, duration_s, mode_names)
            np.savez_compressed(path, **arrays)
            log(f"{world} trial {tid} {strategy}: {1e3 * float(arrays['rms_m']):.1f} mm RMS")
    (folder / "meta.json").write_text(json.dumps({"world": world, "trials": trials, "quick": quick,
                                                  "duration_s": duration_s, "mode_names": list(mode_names)}))
    return folder


def training_dwells(bundle: Any, trials: list[Any]) -> dict[str, np.ndarray]:
    """The estimated mode (argmax of the controller's front end's posterior, run on each training trial's
    recorded fork as the loop would see it) per model tick: ``mode`` (M,) and ``trial`` (M,), at
    ``model_hz`` (``dt`` [s])."""
    from mpcshare.control.frontend import StreamingFrontEnd

    fe = StreamingFrontEnd(bundle.preprocessor.obs, bundle.modes, rate_hz=bundle.rate_hz,
                           model_hz=bundle.model_hz, window_s=bundle.window_s)
    modes, ids = [], []
    for trial in trials:
        fe.reset()
        for t, o in zip(trial.t, trial.obs):
            out = fe.step(float(t), o)
            if out.tick is not None:
                modes.append(int(np.argmax(out.tick.mode_proba)))
                ids.append(trial.trial_id)
    return {"mode": np.array(modes), "trial": np.array(ids), "dt": np.array(1.0 / float(bundle.model_hz))}
