"""The reactive predictor π̂: an LSTM from (observation, mode posterior) to the knife action.

At every 10 Hz step t of a trial the input is ``x_t = concat(o_t, p_t)`` (standardised
observation, causal mode posterior); one LSTM layer (PyTorch gate order i, f, g, o) and a linear
read-out give the standardised action:

    i, f, g, o = σ(W_i x + U_i h + b_i), σ(·_f), tanh(·_g), σ(·_o)
    c_t = f ⊙ c_{t−1} + i ⊙ g,   h_t = o ⊙ tanh(c_t),   û_t = W_y h_t + b_y

With ``horizons = H > 0`` the read-out gives ``[û_t, û_{t+1}, …, û_{t+H}]`` (targets: the trial's
actions shifted by h steps, the last sample repeated). Training: masked MSE over the steps where
the mask (the reactive subset R) is True, on chunks of ``chunk_len`` steps after up to ``burn_in``
warm-up steps without loss; Adam; early stopping on the masked MSE of whole validation trials,
the best epoch kept. Online, :meth:`ReactivePredictor.make_stream` applies the same equations in
NumPy one step at a time (:class:`learning.predictor.stream.PredictorStream`, equal to
:meth:`ReactivePredictor.predict` to 1e-5). The same ``seed`` gives the same weights on the CPU
(torch's global RNG is left alone). Bad settings, shapes, values beyond ``MAX_ABS_VALUE`` or an
empty mask raise ``ValueError``; a loss that turns non-finite raises ``RuntimeError``.
"""

from __future__ import annotations

import copy
import math
import numbers
import time
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted
from torch import nn

from learning.predictor import defaults as D
from learning.predictor.sequences import check_sequence_set, chunk_sequences, pad_sequences, shifted_targets
from learning.predictor.stream import PredictorStream
from learning.progress import progress_bar
from learning.torch_threads import torch_threads

__all__ = ["DEVICES", "ReactivePredictor"]

DEVICES = ("cpu", "cuda", "auto")


class _Net(nn.Module):
    """One LSTM layer and a linear read-out (module docstring)."""

    def __init__(self, d_in: int, hidden: int, d_out: int) -> None:
        super().__init__()
        self.lstm = nn.LSTM(d_in, hidden, batch_first=True)
        self.head = nn.Linear(hidden, d_out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h, _ = self.lstm(x)
        return self.head(h)


def _resolve_device(device: str) -> torch.device:
    if device not in DEVICES:
        raise ValueError(f"device must be one of {DEVICES}, got {device!r}")
    if device == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if device == "cuda" and not torch.cuda.is_available():
        raise ValueError("device='cuda' was asked for but torch sees no CUDA device; use 'cpu' or 'auto'")
    return torch.device(device)


MAX_ABS_VALUE = 1e6


def _check_magnitude(arrays: list[np.ndarray], what: str) -> None:
    """Training runs in float32 on standardised data; refuse values beyond ±MAX_ABS_VALUE
    (squared errors of such values lose all precision or overflow float32)."""
    for i, a in enumerate(arrays):
        big = np.flatnonzero(np.abs(a).max(axis=1) > MAX_ABS_VALUE)
        if big.size:
            raise ValueError(f"{what}[{i}] row {big[0]} has a value beyond ±{MAX_ABS_VALUE:g}: the "
                             f"predictor expects standardised inputs and targets")


def _masked_mse(out: torch.Tensor, y: torch.Tensor, w: torch.Tensor) -> torch.Tensor:
    """Σ w_t ‖out_t − y_t‖² / (Σ w_t · d_u): mean squared error over the masked steps."""
    return ((out - y) ** 2 * w.unsqueeze(-1)).sum() / (w.sum() * y.shape[-1])


class ReactivePredictor(BaseEstimator):
    """LSTM reactive predictor (module docstring); defaults in :mod:`learning.predictor.defaults`, with reasons.

    Args:
        hidden_size: LSTM units (paper: 28).
        batch_size: chunks per gradient step (paper: 64).
        chunk_len: steps per training chunk that carry loss; burn_in: earlier steps
            prepended to warm the state (no loss).
        learning_rate, weight_decay: Adam settings; grad_clip: max gradient norm (0 = none).
        max_epochs, patience: early stopping stops after ``patience`` epochs without a
            validation improvement; the best epoch's weights are kept.
        lr_patience: halve the learning rate after this many epochs without a validation
            improvement (``ReduceLROnPlateau``); 0 = constant rate.
        val_fraction: share of trials held out for early stopping when ``fit`` gets no
            validation sequences (at least 1 trial, split with ``seed``).
        num_threads: torch CPU threads during ``fit`` (None = torch's setting).
        seed: weight initialisation, validation split and chunk order.
        horizons: H, the number of future model steps forecast beyond the current one
            (0: the current action only, as Song & Asada's predictor).
        device: ``"cpu"`` (default), ``"cuda"`` or ``"auto"`` (CUDA when present).

    Fitted attributes: ``input_dim_``, ``output_dim_``, ``net_`` (the torch module, on
    ``device_``), ``history_`` ({"train_loss", "val_loss"} per epoch), ``best_epoch_``,
    ``n_epochs_``, ``fit_time_s_``, ``val_trials_`` (indices used for validation, or
    None when validation sequences were given).
    """

    def __init__(self, hidden_size: int = D.HIDDEN_SIZE, batch_size: int = D.BATCH_SIZE,
                 chunk_len: int = D.CHUNK_LEN, burn_in: int = D.BURN_IN, learning_rate: float = D.LEARNING_RATE,
                 weight_decay: float = 0.0, grad_clip: float = 1.0, max_epochs: int = D.MAX_EPOCHS,
                 patience: int = D.PATIENCE, lr_patience: int = 5, val_fraction: float = D.VAL_FRACTION,
                 num_threads: int | None = D.NUM_THREADS, seed: int = 0, device: str = "cpu",
                 horizons: int = 0) -> None:
        self.hidden_size = hidden_size
        self.batch_size = batch_size
        self.chunk_len = chunk_len
        self.burn_in = burn_in
        self.learning_rate = learning_rate
        self.weight_decay = weight_decay
        self.grad_clip = grad_clip
        self.max_epochs = max_epochs
        self.patience = patience
        self.lr_patience = lr_patience
        self.val_fraction = val_fraction
        self.num_threads = num_threads
        self.seed = seed
        self.device = device
        self.horizons = horizons

    # ------------------------------------------------------------------ checks

    def _check_params(self) -> None:
        for name, lo in (("hidden_size", 1), ("batch_size", 1), ("chunk_len", 1), ("burn_in", 0),
                         ("max_epochs", 1), ("patience", 1), ("lr_patience", 0),
                         ("horizons", 0)):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Integral) and v >= lo):
                raise ValueError(f"{name} must be an integer ≥ {lo}, got {v!r}")
        for name in ("learning_rate",):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Real) and v > 0 and math.isfinite(v)):
                raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
        for name in ("weight_decay", "grad_clip"):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Real) and v >= 0 and math.isfinite(v)):
                raise ValueError(f"{name} must be a finite number ≥ 0, got {v!r}")
        if not (isinstance(self.val_fraction, numbers.Real) and 0 < self.val_fraction < 1):
            raise ValueError(f"val_fraction must be in (0, 1), got {self.val_fraction!r}")
        if self.num_threads is not None and not (isinstance(self.num_threads, numbers.Integral)
                                                 and self.num_threads >= 1):
            raise ValueError(f"num_threads must be None or an integer ≥ 1, got {self.num_threads!r}")
        _resolve_device(self.device)

    # ----------------------------------------------------------------- fitting

    def fit(self, sequences: Sequence[np.ndarray], targets: Sequence[np.ndarray],
            masks: Sequence[np.ndarray] | None = None, val_sequences: Sequence[np.ndarray] | None = None,
            val_targets: Sequence[np.ndarray] | None = None, val_masks: Sequence[np.ndarray] | None = None,
            progress: bool = True) -> ReactivePredictor:
        """Train on trials ``sequences[i]`` (T_i, d_in) → ``targets[i]`` (T_i, d_u), loss where
        ``masks[i]`` (T_i,) is True (None: everywhere). Validation trials: ``val_*`` or, if not
        given, ``val_fraction`` of the trials (by trial, seeded). ``progress`` shows a tqdm bar."""
        self._check_params()
        xs, ys, ms = check_sequence_set(sequences, targets, masks)
        ms = ms if ms is not None else [np.ones(x.shape[0], bool) for x in xs]
        if not any(m.any() for m in ms):
            raise ValueError("no training step has mask True: nothing to fit")
        _check_magnitude(xs, "sequences")
        _check_magnitude(ys, "targets")
        if (val_sequences is None) != (val_targets is None):
            raise ValueError("give both val_sequences and val_targets, or neither")
        if val_masks is not None and val_sequences is None:
            raise ValueError("val_masks given without val_sequences")
        val_trials: list[int] | None = None
        if val_sequences is not None:
            vx, vy, vm = check_sequence_set(val_sequences, val_targets, val_masks, what="val_sequences",
                                            d_in=xs[0].shape[1], d_out=ys[0].shape[1])
            vm = vm if vm is not None else [np.ones(x.shape[0], bool) for x in vx]
            _check_magnitude(vx, "val_sequences")
            _check_magnitude(vy, "val_targets")
        elif len(xs) >= 2:
            n_val = min(max(round(len(xs) * self.val_fraction), 1), len(xs) - 1)
            val = set(np.random.default_rng(self.seed).permutation(len(xs))[:n_val].tolist())
            val_trials = sorted(val)
            vx, vy, vm = ([a[i] for i in sorted(val)] for a in (xs, ys, ms))
            xs, ys, ms = ([a[i] for i in range(len(xs)) if i not in val] for a in (xs, ys, ms))
            if not any(m.any() for m in ms):
                raise ValueError("after holding out validation trials no training step has mask True")
        else:
            vx = vy = vm = None
            warnings.warn("one training trial and no validation trials: training for max_epochs "
                          "without early stopping", UserWarning, stacklevel=2)
        if vm is not None and not any(m.any() for m in vm):
            warnings.warn("the validation trials have no step with mask True: no early stopping",
                          UserWarning, stacklevel=2)
            vx = vy = vm = None
        H = int(self.horizons)
        d_u = int(ys[0].shape[1])
        ys = [shifted_targets(y, H) for y in ys]
        vy = None if vy is None else [shifted_targets(y, H) for y in vy]
        device = _resolve_device(self.device)
        t0 = time.perf_counter()
        with torch_threads(self.num_threads), torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(self.seed))
            net, history, best_epoch = self._train(xs, ys, ms, vx, vy, vm, device, progress)
        # fitted attributes only once training has succeeded (nothing half-written)
        self.input_dim_, self.output_dim_ = int(xs[0].shape[1]), d_u
        self.device_, self.net_, self.history_ = device, net, history
        self.best_epoch_, self.n_epochs_ = best_epoch, len(history["train_loss"])
        self.val_trials_ = val_trials
        self.fit_time_s_ = time.perf_counter() - t0
        self._cache_numpy()
        return self

    def _train(self, xs: list[np.ndarray], ys: list[np.ndarray], ms: list[np.ndarray],
               vx: list[np.ndarray] | None, vy: list[np.ndarray] | None, vm: list[np.ndarray] | None,
               dev: torch.device, progress: bool) -> tuple[_Net, dict[str, list[float]], int]:
        """Adam on shuffled chunks, early stopping on the validation loss; returns the best
        network (eval mode), the loss history and the best epoch."""
        net = _Net(int(xs[0].shape[1]), int(self.hidden_size), int(ys[0].shape[1])).to(dev)
        X, Y, W = (torch.from_numpy(a).to(dev) for a in chunk_sequences(xs, ys, ms, int(self.chunk_len),
                                                                 int(self.burn_in)))
        val = None if vx is None else tuple(torch.from_numpy(a).to(dev) for a in pad_sequences(vx, vy, vm))
        opt = torch.optim.Adam(net.parameters(), lr=float(self.learning_rate),
                               weight_decay=float(self.weight_decay))
        sched = (torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=int(self.lr_patience))
                 if self.lr_patience else None)
        gen = torch.Generator().manual_seed(int(self.seed))
        history: dict[str, list[float]] = {"train_loss": [], "val_loss": []}
        best, best_epoch, best_state = math.inf, 0, copy.deepcopy(net.state_dict())
        bar = progress_bar(range(1, int(self.max_epochs) + 1), enabled=progress, desc="predictor", unit="epoch",
                           leave=False)
        for epoch in bar:
            net.train()
            order = torch.randperm(X.shape[0], generator=gen).to(dev)
            tot, wsum = 0.0, 0.0
            for k in range(0, X.shape[0], int(self.batch_size)):
                b = order[k:k + int(self.batch_size)]
                loss = _masked_mse(net(X[b]), Y[b], W[b])
                opt.zero_grad()
                loss.backward()
                if self.grad_clip > 0:
                    nn.utils.clip_grad_norm_(net.parameters(), float(self.grad_clip))
                opt.step()
                ws = float(W[b].sum())
                tot, wsum = tot + loss.item() * ws, wsum + ws
            history["train_loss"].append(tot / wsum)
            if not math.isfinite(tot / wsum):
                bar.close()
                raise RuntimeError(f"training diverged: the loss is not finite at epoch {epoch}; lower "
                                   f"learning_rate (now {self.learning_rate})")
            if val is not None:
                net.eval()
                with torch.no_grad():
                    v = float(_masked_mse(net(val[0]), val[1], val[2]))
                history["val_loss"].append(v)
                if sched is not None:
                    sched.step(v)
                if v < best:
                    best, best_epoch, best_state = v, epoch, copy.deepcopy(net.state_dict())
                elif epoch - best_epoch >= int(self.patience):
                    break
                bar.set_postfix(train=f"{tot / wsum:.4f}", val=f"{v:.4f}", best=best_epoch)
            else:
                best_epoch, best_state = epoch, net.state_dict()
                bar.set_postfix(train=f"{tot / wsum:.4f}")
        bar.close()
        net.load_state_dict(best_state)
        net.eval()
        return net, history, best_epoch

    def _cache_numpy(self) -> None:
        """float64 copies of the weights for :meth:`predict` and the stream."""
        sd = {k: v.detach().cpu().double() for k, v in self.net_.state_dict().items()}
        n_out = self.output_dim_ * (int(self.horizons) + 1)
        self._cpu64 = _Net(self.input_dim_, int(self.hidden_size), n_out).double()
        self._cpu64.load_state_dict(sd)
        self._cpu64.eval()
        self._np = {k: v.numpy().copy() for k, v in sd.items()}

    # --------------------------------------------------------------- inference

    def predict(self, sequence: np.ndarray) -> np.ndarray:
        """(T, d_u) standardised actions for one trial (T, d_in), from the zero state (float64, CPU)."""
        check_is_fitted(self, "net_")
        (x,), _, _ = check_sequence_set([sequence], what="sequence", d_in=self.input_dim_)
        with torch.no_grad():
            return self._cpu64(torch.from_numpy(x)[None])[0].numpy()[:, :self.output_dim_]

    def forecast(self, sequence: np.ndarray) -> np.ndarray:
        """(T, H+1, d_u) standardised actions: row t, horizon h forecasts û_{t+h} (module docstring)."""
        check_is_fitted(self, "net_")
        (x,), _, _ = check_sequence_set([sequence], what="sequence", d_in=self.input_dim_)
        with torch.no_grad():
            out = self._cpu64(torch.from_numpy(x)[None])[0].numpy()
        return out.reshape(x.shape[0], int(self.horizons) + 1, self.output_dim_)

    def make_stream(self) -> PredictorStream:
        """A new :class:`PredictorStream` (zero state) with this model's weights."""
        check_is_fitted(self, "net_")
        p = self._np
        return PredictorStream(p["lstm.weight_ih_l0"], p["lstm.weight_hh_l0"],
                               p["lstm.bias_ih_l0"] + p["lstm.bias_hh_l0"], p["head.weight"], p["head.bias"],
                               horizons=int(self.horizons))

    # ------------------------------------------------------------- persistence

    def get_config(self) -> dict[str, Any]:
        """JSON-able: the constructor parameters and, once fitted, the dimensions and training record."""
        cfg: dict[str, Any] = {"params": self.get_params()}
        if hasattr(self, "net_"):
            cfg["input_dim"], cfg["output_dim"] = self.input_dim_, self.output_dim_
            cfg["training"] = {"best_epoch": getattr(self, "best_epoch_", None),
                               "n_epochs": getattr(self, "n_epochs_", None),
                               "fit_time_s": getattr(self, "fit_time_s_", None),
                               "history": getattr(self, "history_", None)}
        return cfg

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> ReactivePredictor:
        """A predictor with ``config``'s parameters; load the weights with :meth:`load_state_dict`."""
        if not isinstance(config, dict) or not isinstance(config.get("params"), dict):
            raise TypeError("predictor config must be a dict with a 'params' dict (from get_config())")
        valid = set(cls().get_params())
        unknown = sorted(set(config["params"]) - valid)
        if unknown:
            raise ValueError(f"unknown predictor parameter(s) {unknown}; valid: {sorted(valid)}")
        model = cls(**config["params"])
        model._check_params()
        model._config_dims = (config.get("input_dim"), config.get("output_dim"))
        tr = config.get("training") or {}
        model._config_training = tr
        return model

    def state_dict(self) -> dict[str, torch.Tensor]:
        """The network's weights as CPU float32 tensors (for ``torch.save``; loads with ``weights_only=True``)."""
        check_is_fitted(self, "net_")
        return {k: v.detach().cpu().float().clone() for k, v in self.net_.state_dict().items()}

    def load_state_dict(self, state_dict: dict[str, torch.Tensor]) -> ReactivePredictor:
        """Restore the weights (shapes checked against ``hidden_size`` and the config's dimensions)."""
        if not isinstance(state_dict, dict):
            raise TypeError(f"state_dict must be a dict of tensors, got {type(state_dict).__name__}")
        need = ("lstm.weight_ih_l0", "lstm.weight_hh_l0", "lstm.bias_ih_l0", "lstm.bias_hh_l0",
                "head.weight", "head.bias")
        missing = [k for k in need if k not in state_dict]
        extra = sorted(set(state_dict) - set(need))
        if missing or extra:
            raise ValueError(f"predictor state_dict: missing keys {missing}, unexpected keys {extra}")
        H = int(self.hidden_size)
        d_in, n_out = state_dict["lstm.weight_ih_l0"].shape[1], state_dict["head.weight"].shape[0]
        n_h = int(self.horizons) + 1
        if n_out % n_h:
            raise ValueError(f"predictor state_dict has {n_out} outputs, not a multiple of horizons + 1 = {n_h}")
        d_out = n_out // n_h
        if tuple(state_dict["lstm.weight_hh_l0"].shape) != (4 * H, H):
            raise ValueError(f"predictor state_dict has lstm.weight_hh_l0 of shape "
                             f"{tuple(state_dict['lstm.weight_hh_l0'].shape)}, hidden_size={H} needs {(4 * H, H)}")
        cfg_in, cfg_out = getattr(self, "_config_dims", (None, None))
        if (cfg_in is not None and cfg_in != d_in) or (cfg_out is not None and cfg_out != d_out):
            raise ValueError(f"predictor state_dict is for {d_in} inputs → {d_out} outputs, the config says "
                             f"{cfg_in} → {cfg_out}")
        net = _Net(int(d_in), H, int(n_out))
        try:
            net.load_state_dict({k: torch.as_tensor(v, dtype=torch.float32) for k, v in state_dict.items()})
        except RuntimeError as e:
            raise ValueError(f"predictor state_dict does not fit the network: {e}") from None
        net.eval()
        self.input_dim_, self.output_dim_ = int(d_in), int(d_out)
        self.device_ = torch.device("cpu")
        self.net_ = net
        tr = getattr(self, "_config_training", {}) or {}
        self.best_epoch_, self.n_epochs_ = tr.get("best_epoch"), tr.get("n_epochs")
        self.history_, self.fit_time_s_ = tr.get("history"), tr.get("fit_time_s")
        self._cache_numpy()
        return self
