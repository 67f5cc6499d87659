"""Plot of one closed-loop episode: the knife tip against the wearer's intent, α and β, the shoulder.

Works on an :class:`sim.closed_loop.Episode` or on a run file loaded with
``Episode.load``. Drawn with :class:`matplotlib.figure.Figure` (no pyplot state).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_episode"]


def plot_episode(episode: Any, path: str | Path, title: str = "") -> Path:
    """Four panels over time: tip x/y/z with intent and reference [m], α and β, shoulder angles [rad]."""
    t = np.asarray(episode.t, dtype=float)
    fig = Figure(figsize=(10, 8), constrained_layout=True)
    axes = fig.subplots(5, 1, sharex=True)
    for i, axis in enumerate("xyz"):
        ax = axes[i]
        ax.plot(t, episode.tip_intent[:, i], color="0.3", lw=1.2, label="intent (demonstration)")
        ax.plot(t, episode.tip_reference[:, i], color="#DD8452", lw=0.9, ls="--", label="reference")
        ax.plot(t, episode.tip[:, i], color="#4C72B0", lw=1.0, label="knife tip")
        ax.set_ylabel(f"{axis} [m]")
    axes[0].legend(loc="upper right", fontsize=7, ncol=3)
    axes[3].plot(t, episode.alpha, color="#55A868", label="α (robot)")
    axes[3].plot(t, episode.beta, color="#C44E52", lw=0.8, label="β (wearer)")
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel("weight")
    axes[3].legend(loc="upper right", fontsize=7, ncol=2)
    for i, name in enumerate(("elevation", "protraction", "abduction")):
        axes[4].plot(t, episode.voluntary[:, i], lw=0.8, label=name)
    axes[4].set_ylabel("shoulder [rad]")
    axes[4].set_xlabel("time [s]")
    axes[4].legend(loc="upper right", fontsize=7, ncol=3)
    if title:
        fig.suptitle(title, fontsize=10)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path
