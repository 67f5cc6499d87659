"""Settings of training a model bundle: :class:`TrainConfig`, validated on construction.

JSON-able (:meth:`TrainConfig.to_dict`, stored in the bundle); read by
:func:`mpcshare.training.train_bundle`, :func:`mpcshare.training.sweep.run_sweep` and the
``train`` and ``demo`` commands.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from learning.predictor import defaults as lstm

__all__ = ["DEFAULT_PERCENTILES", "MODES_FROM", "RULE_DURATION_S", "TrainConfig"]

#: sources of the task modes (``TrainConfig.modes_from``, ``mpcshare train --modes-from``)
MODES_FROM: tuple[str, ...] = ("hmm", "mixture")

#: percentiles of the K trade-off sweep (``mpcshare train --sweep``, :func:`~mpcshare.training.sweep.run_sweep`)
DEFAULT_PERCENTILES: tuple[float, ...] = (100.0, 90.0, 80.0, 70.0, 60.0, 50.0)


#: seconds simulated per held-out trial for the closed-loop choice of the hand-over rule
#: (``mpcshare.calibration.rule_choice``; 30 s of one trial chose by noise)
RULE_DURATION_S = 60.0

@dataclass(frozen=True)
class TrainConfig:
    """Settings of :func:`~mpcshare.training.train_bundle` (JSON-able; stored in the bundle).

    Attributes:
        percentile: K is this percentile of the within-mode quotients of the training
            trials (100: every windowed point is reactive).
        model_hz: rate of the models after causal downsampling [Hz].
        window_s: causal window of the gates [s].
        n_modes, hmm_restarts: HMM task modes and EM restarts.
        modes_from: where the modes come from, "hmm" (the HMM task modes) or "mixture" (the
            time-free Gaussian mixture of the same observations, as an HMM whose rows of A
            equal the weights: ``TaskModes(temporal=False)``; the analysis's advice where
            modes help but the temporal model adds nothing).
        heldout_fraction: share of trials held out for evaluation (at least one).
        val_fraction: share of the training trials used for the LSTM's early stopping.
        hidden_size, batch_size, max_epochs, patience, learning_rate: LSTM settings
            (the paper's 28 hidden units, batch 64).
        chunk_len, burn_in: training chunks of the LSTM (steps with loss, warm-up steps).
        torch_threads: torch CPU threads while training the LSTM.
        The LSTM's defaults (and ``val_fraction``'s) are :mod:`learning.predictor.defaults`,
        with the reasons for them; ``ReactivePredictor`` reads the same.
        gate_kernel, gate_max_samples: gate classifier ("rbf" SVM or "nystroem") and
            the per-mode subsample it is fitted on.
        lstm_baseline: also train the LSTM on all points (baseline; doubles LSTM time).
        device: torch device of the LSTM ("cpu", "cuda").
        zero_phase_targets: the actions (quotients' outputs, the LSTM's targets) are
            downsampled with a zero-phase filter, the observations causally (see
            :func:`learning.preprocessing.resample.causal_downsample`): the model learns the knife at
            t, not the knife a filter delay earlier. False: both causal.
        forecast_s: the reactive predictor forecasts the action over this horizon [s]
            (``round(forecast_s·model_hz)`` model steps beyond the current one; 0: the
            current action only): the controller cancels its latency with it and gives it
            to the MPC as its preview (docs/design.md, "Online control").
        fast_forecast: also fit the control-rate forecast (:mod:`learning.predictor.fast`: a ridge
            correction of the LSTM's forecast from the fork's Kalman state, run every control step);
            needs the knife tip channels and ``forecast_s`` > 0.
        fast_alpha: its ridge penalty; fast_lags: its fork position lags [raw steps].
        seed: seed of everything random.
    """

    percentile: float = 90.0
    model_hz: float = 10.0
    window_s: float = 1.0
    n_modes: int = 4
    hmm_restarts: int = 3
    modes_from: str = "hmm"
    heldout_fraction: float = 0.25
    val_fraction: float = lstm.VAL_FRACTION
    hidden_size: int = lstm.HIDDEN_SIZE
    batch_size: int = lstm.BATCH_SIZE
    max_epochs: int = lstm.MAX_EPOCHS
    patience: int = lstm.PATIENCE
    learning_rate: float = lstm.LEARNING_RATE
    chunk_len: int = lstm.CHUNK_LEN
    burn_in: int = lstm.BURN_IN
    torch_threads: int = lstm.NUM_THREADS
    gate_kernel: str = "rbf"
    gate_max_samples: int | None = 2000
    lstm_baseline: bool = False
    device: str = "cpu"
    zero_phase_targets: bool = True
    forecast_s: float = 0.5
    fast_forecast: bool = True
    fast_alpha: float = 1.0
    fast_lags: tuple[int, ...] = (5, 10, 20)
    seed: int = 0

    def __post_init__(self) -> None:
        if not 0.0 <= self.percentile <= 100.0:
            raise ValueError(f"percentile must be in [0, 100], got {self.percentile!r}")
        if not (math.isfinite(self.model_hz) and self.model_hz > 0):
            raise ValueError(f"model_hz must be > 0, got {self.model_hz!r}")
        if not (math.isfinite(self.window_s) and self.window_s >= 0):
            raise ValueError(f"window_s must be >= 0, got {self.window_s!r}")
        for name in ("n_modes", "hmm_restarts", "hidden_size", "batch_size", "max_epochs", "patience",
                     "chunk_len", "torch_threads"):
            if int(getattr(self, name)) != getattr(self, name) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {getattr(self, name)!r}")
        if int(self.burn_in) != self.burn_in or self.burn_in < 0:
            raise ValueError(f"burn_in must be an integer >= 0, got {self.burn_in!r}")
        for name in ("heldout_fraction", "val_fraction"):
            if not 0.0 < getattr(self, name) < 1.0:
                raise ValueError(f"{name} must be in (0, 1), got {getattr(self, name)!r}")
        if self.modes_from not in MODES_FROM:
            raise ValueError(f"modes_from must be one of {MODES_FROM}, got {self.modes_from!r}")
        if self.gate_kernel not in ("rbf", "nystroem"):
            raise ValueError(f"gate_kernel must be 'rbf' or 'nystroem', got {self.gate_kernel!r}")
        if self.gate_max_samples is not None and (int(self.gate_max_samples) != self.gate_max_samples
                                                  or self.gate_max_samples < 40):
            raise ValueError(f"gate_max_samples must be None or an integer >= 40, got {self.gate_max_samples!r}")
        if self.device not in ("cpu", "cuda", "auto"):
            raise ValueError(f"device must be 'cpu', 'cuda' or 'auto', got {self.device!r}")
        if not (math.isfinite(self.forecast_s) and 0.0 <= self.forecast_s <= 5.0):
            raise ValueError(f"forecast_s must be in [0, 5] s, got {self.forecast_s!r}")
        object.__setattr__(self, "fast_lags", tuple(self.fast_lags))
        if not all(int(v) == v and v >= 1 for v in self.fast_lags):
            raise ValueError(f"fast_lags must be integers >= 1 (raw steps), got {self.fast_lags!r}")
        if not (math.isfinite(self.fast_alpha) and self.fast_alpha >= 0):
            raise ValueError(f"fast_alpha must be finite and >= 0, got {self.fast_alpha!r}")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate!r}")

    @property
    def forecast_steps(self) -> int:
        """H: model steps forecast beyond the current one."""
        return int(round(self.forecast_s * self.model_hz))

    def to_dict(self) -> dict[str, Any]:
        """The settings as a JSON-able dict (field name → value; tuples as lists, as JSON reads them back)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}
