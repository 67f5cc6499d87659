"""Does mode discovery depend on the seed? Agreement with the true modes over seeds and generators,
for the ways of choosing among EM restarts and of shaping the fit. Prints JSON.

    PYTHONPATH=. python benchmarks/bench_mode_discovery.py [--seeds 20] [--restarts 5]

Generators (preprocessed as :func:`learning.analysis.analyze` does: 10 Hz, standardised):

- ``demonstrations``: the default demonstrator (``sim.demonstrator``), 3 subjects × 4 min
  (6 trials of 2 min), 4 modes, ``scope="sensor"``; ``demonstrations, overlap 0.9``: its
  weaker-cue variant (not run by default);
- ``hidden regime, cue/noise 2`` and ``1``: ``sim.hidden_regime`` (three regimes visible in
  one sample, less so at 1), 12 trials × 2 min, 3 modes, ``scope="channel"``.

Strategies, each on the same data (agreement after Hungarian matching, per sample):

- ``default``: ``TaskModes(n_restarts)``, the best training likelihood (the analysis's);
- ``sticky``: the same with a strong self-transition prior, ``sticky`` = 5 % of the samples
  (pseudo-counts; mean dwell of the prior's A about 20 samples / K);
- ``heldout``: each restart seed fitted on two thirds of the trials and scored on the rest
  (3 folds by trial); the seed with the best total held-out log-likelihood is refitted on
  all data (choosing among restarts by held-out likelihood over trials);
- ``window_init``: k-means of the initialisation on the features averaged over a centred
  window of 21 samples (2 s), the per-sample features for the statistics and EM (a
  ``TaskModes`` subclass: an experiment, not an option of the package);
- ``mixture``: the time-free Gaussian mixture (``TaskModes(temporal=False)``), as a baseline.

For every data set also the spread of the restarts' training log-likelihoods [nats a sample],
the agreement of each single restart, and whether the restart with the best likelihood has
the best agreement (where not, the best likelihood is the wrong partition, and no choice
among restarts by likelihood helps). (Supersedes ``bench_mode_agreement.py`` of issue 13.)
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings

import numpy as np
from scipy.ndimage import uniform_filter1d
from sklearn.cluster import KMeans

from learning.modes import TaskModes, mode_agreement
from learning.preprocessing.preprocess import Standardizer, downsample
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from sim.hidden_regime import HiddenRegimeConfig, generate_hidden_regime

STRATEGIES = ("default", "sticky", "heldout", "window_init", "mixture")
INIT_WINDOW = 21  # samples (2 s at 10 Hz)


class WindowInitModes(TaskModes):
    """TaskModes whose k-means initialisation runs on features averaged over ``INIT_WINDOW`` samples."""

    def _init_hmm(self, hmm, Z, lengths, seed) -> None:
        super()._init_hmm(hmm, Z, lengths, seed)
        K, D = int(self.n_modes), Z.shape[1]
        smooth = np.concatenate([uniform_filter1d(z, INIT_WINDOW, axis=0, mode="nearest")
                                 for z in np.split(Z, np.cumsum(lengths)[:-1])])
        labels = KMeans(n_clusters=K, n_init=1, random_state=seed).fit_predict(smooth)
        if min(np.bincount(labels, minlength=K)) <= D:
            return  # a cluster too small for a covariance: keep the per-sample initialisation
        hmm.means_ = np.stack([Z[labels == k].mean(axis=0) for k in range(K)])
        hmm.covars_ = np.stack([np.cov(Z[labels == k].T) + self.min_covar * np.eye(D) for k in range(K)])


def _data(name: str, seed: int):
    if name.startswith("demonstrations"):
        gen = GeneratorConfig(overlap=float(name.rsplit(" ", 1)[1])) if "overlap" in name else GeneratorConfig()
        demos, K, scope = generate_demonstrations(3, 4, seed=seed, config=gen), 4, "sensor"
    else:
        ratio = float(name.rsplit(" ", 1)[1])
        cfg = HiddenRegimeConfig(cue=0.3 * ratio, trial_s=120.0)
        demos, K, scope = generate_hidden_regime(cfg, seed=seed), 3, "channel"
    demos = downsample(demos, 10.0)
    std = Standardizer(scope, field="obs").fit(demos)
    Zs = [std.transform(t.obs) for t in demos.trials]
    return Zs, np.concatenate([t.mode for t in demos.trials]), K


def _heldout_choice(Zs: list[np.ndarray], K: int, restarts: int, seed: int) -> tuple[int, list[float]]:
    """The restart seed whose fits on 2/3 of the trials score best on the held-out third (3 folds)."""
    folds = np.arange(len(Zs)) % 3
    seeds = np.random.SeedSequence(seed).generate_state(restarts)
    scores = []
    for s in seeds:
        total = 0.0
        for f in range(3):
            tr = [z for z, g in zip(Zs, folds) if g != f]
            te = [z for z, g in zip(Zs, folds) if g == f]
            m = TaskModes(K, n_restarts=1, seed=int(s)).fit(np.concatenate(tr), [len(z) for z in tr])
            total += m.score(np.concatenate(te), [len(z) for z in te])
        scores.append(total)
    return int(seeds[int(np.argmax(scores))]), scores


def run(name: str, seed: int, restarts: int) -> dict:
    Zs, true, K = _data(name, seed)
    Z, L = np.concatenate(Zs), [len(z) for z in Zs]
    out = {}
    fits = {"default": TaskModes(K, n_restarts=restarts, seed=seed),
            "sticky": TaskModes(K, n_restarts=restarts, seed=seed, sticky=0.05 * len(Z)),
            "window_init": WindowInitModes(K, n_restarts=restarts, seed=seed),
            "mixture": TaskModes(K, n_restarts=restarts, seed=seed, temporal=False)}
    for key, m in fits.items():
        m.fit(Z, L)
        out[key] = float(mode_agreement(m.predict(Z, L), true)[0])
        if key == "default":
            ll = np.array(m.restart_logliks_) / len(Z)
            out["loglik_spread_per_sample"] = float(ll.max() - ll.min())
            out["restart_agreement"] = [float(mode_agreement(
                TaskModes(K, n_restarts=1, seed=int(s)).fit(Z, L).predict(Z, L), true)[0])
                for s in np.random.SeedSequence(seed).generate_state(restarts)]
            out["best_loglik_has_best_agreement"] = bool(
                out["restart_agreement"][int(np.argmax(ll))] >= max(out["restart_agreement"]) - 1e-3)
    s, _ = _heldout_choice(Zs, K, restarts, seed)
    out["heldout"] = float(mode_agreement(TaskModes(K, n_restarts=1, seed=s).fit(Z, L).predict(Z, L), true)[0])
    return out


def summary(x) -> dict:
    x = np.asarray(x, dtype=float)
    q = np.quantile(x, [0.0, 0.05, 0.5, 0.95, 1.0])
    return {"min": round(q[0], 3), "p5": round(q[1], 3), "median": round(q[2], 3), "p95": round(q[3], 3),
            "max": round(q[4], 3), "below_0.8": int(np.sum(x < 0.8))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--restarts", type=int, default=5)
    ap.add_argument("--generators", nargs="+",
                    default=["demonstrations", "hidden regime, cue/noise 2", "hidden regime, cue/noise 1"])
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    out = {}
    for name in a.generators:
        runs = []
        for s in range(a.seeds):
            runs.append(run(name, s, a.restarts))
            print(f"{name} seed {s}: " + " ".join(f"{k} {runs[-1][k]:.3f}" for k in STRATEGIES),
                  file=sys.stderr, flush=True)
        out[name] = {"agreement": {k: {**summary([r[k] for r in runs]), "values": [round(r[k], 3) for r in runs]}
                                   for k in STRATEGIES},
                     "restart_agreement_spread": summary([max(r["restart_agreement"]) - min(r["restart_agreement"])
                                                          for r in runs]),
                     "loglik_spread_per_sample": summary([r["loglik_spread_per_sample"] for r in runs]),
                     "best_loglik_has_best_agreement": float(np.mean([r["best_loglik_has_best_agreement"]
                                                                      for r in runs]))}
    print(json.dumps({"seeds": a.seeds, "restarts": a.restarts, "generators": out}, indent=1))


if __name__ == "__main__":
    main()
