"""Model bundles: everything the online controller needs, in one folder (docs/training.md, "Bundle format").

A bundle (format :data:`FORMAT_VERSION`) holds ``manifest.json`` (bytes and SHA-256 of every other file,
so a missing, truncated or altered file is detected); ``bundle.json`` (format, channel names, rates [Hz],
window [s], the threshold K (``null`` = +∞), its percentile, the novelty threshold, trial ids, training
configuration, library versions); ``metrics.json`` (training and held-out metrics, no NaN);
``preprocessor.json`` (the two standardizers as exact JSON numbers); ``predictor.pt`` (the predictor's
state dict, read with ``torch.load(weights_only=True)``); ``fast.json`` (format 2: the control-rate
forecast, :class:`learning.predictor.fast.FastForecaster`, ``{"model": null}`` when not trained);
``rule.json`` (format 3: the calibrated rule, :class:`~mpcshare.bundle.rule.CalibratedRule`,
``{"rule": null}`` before calibration); ``modes.joblib``, ``gates.joblib`` (:class:`~learning.modes.TaskModes`,
:class:`~learning.gates.gate.ModeGates`; joblib files are pickles: load bundles you made or trust).
A format-1 bundle loads with ``fast = None``; formats 1 and 2 have their rule moved out of ``metrics.json``
(:func:`~mpcshare.bundle.rule.rule_from_metrics`).

:func:`save_bundle` writes into a temporary folder beside the target, fsyncs every file and the folder,
then renames it onto the target: the bundle is complete or absent. :func:`load_bundle` checks the
manifest before reading anything and raises one :class:`BundleError` whose message starts with the
offending file. JSON encodings, checksums and fsync: :mod:`mpcshare.bundle.files`.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from learning.atomic import default_dir_mode, write_json
from learning.preprocessing.preprocess import Preprocessor
from mpcshare.bundle.files import (
    file_sha256,
    from_json_number,
    fsync_path,
    json_number,
    library_versions,
    standardizer_from_json,
    standardizer_to_json,
)
from mpcshare.bundle.manifest import (
    BUNDLE_FILES,
    FORMAT_VERSION,
    MANIFEST,
    BundleError,
    read_json,
    verify_manifest,
)
from mpcshare.bundle.rule import CalibratedRule, rule_from_json, rule_from_metrics, rule_to_json

if TYPE_CHECKING:  # pragma: no cover - imported lazily (torch and sklearn are slow to import)
    from learning.gates.gate import ModeGates
    from learning.modes import TaskModes
    from learning.predictor import ReactivePredictor

__all__ = ["FORMAT_VERSION", "BUNDLE_FILES", "ModelBundle", "BundleError", "save_bundle",
           "load_bundle", "check_bundle_target", "is_bundle"]

@dataclass
class ModelBundle:
    """Fitted models and settings of the shared controller (see module docstring).

    Attributes:
        obs_names, act_names, vol_names: channel names of the training data, in order.
        rate_hz: rate of the raw data [Hz]; model_hz: rate of the models [Hz];
        window_s: causal window of the gates [s].
        preprocessor: fitted obs/act standardizers (``scope="sensor"``).
        modes: HMM task modes fitted on standardised 10 Hz obs samples.
        gates: one classifier per mode, P(predictable | window, mode).
        predictor: LSTM over concat(standardised obs, mode posterior) → standardised act.
        K: threshold on the within-mode quotients (+∞ allowed); percentile: its percentile.
        novelty_threshold: 99.9th percentile of −log p(o_t | o_<t) on the training trials.
        train_trials, heldout_trials: trial ids of each side.
        metrics: JSON-able training and held-out metrics.
        config: JSON-able training configuration.
        fast: the control-rate forecast (``learning.predictor.fast.FastForecaster``) or None.
        rule: the calibrated hand-over rule (:class:`~mpcshare.bundle.rule.CalibratedRule`) or None (not
            calibrated: the strategies' defaults).
    """

    obs_names: tuple[str, ...]
    act_names: tuple[str, ...]
    vol_names: tuple[str, ...]
    rate_hz: float
    model_hz: float
    window_s: float
    preprocessor: Preprocessor
    modes: "TaskModes"
    gates: "ModeGates"
    predictor: "ReactivePredictor"
    K: float
    percentile: float
    novelty_threshold: float
    train_trials: list[int]
    heldout_trials: list[int]
    metrics: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    fast: Any = None
    rule: CalibratedRule | None = None
    format_version: int = FORMAT_VERSION

    def __post_init__(self) -> None:
        self.obs_names = tuple(str(n) for n in self.obs_names)
        self.act_names = tuple(str(n) for n in self.act_names)
        self.vol_names = tuple(str(n) for n in self.vol_names)

    @property
    def n_modes(self) -> int:
        """Number of HMM task modes."""
        return int(self.modes.n_modes)

    @property
    def window_lags(self) -> int:
        """Samples per window at ``model_hz`` (L = max(1, round(window_s · model_hz)))."""
        from learning.preprocessing.preprocess import window_lags
        return window_lags(self.window_s, self.model_hz)


def is_bundle(folder: str | os.PathLike) -> bool:
    """True when ``folder`` is a folder with a bundle manifest (not checked further)."""
    p = Path(folder)
    return p.is_dir() and (p / MANIFEST).is_file()


def check_bundle_target(folder: str | os.PathLike) -> Path:
    """Check that a bundle may be written to ``folder``; return it as a Path.

    Allowed: an absent path whose parent exists or can be created, an empty folder, or
    an existing bundle (replaced as a whole). Refused (:class:`BundleError`): a file,
    a non-empty folder that is not a bundle, an unwritable parent.
    """
    p = Path(folder)
    if p.exists():
        if not p.is_dir():
            raise BundleError(p, "exists and is not a folder; refusing to overwrite it with a bundle")
        if any(p.iterdir()) and not is_bundle(p):
            raise BundleError(p, "is a non-empty folder that is not a model bundle (no manifest.json); "
                                 "refusing to overwrite it")
    parent = p.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BundleError(parent, f"cannot create the folder ({exc.strerror or exc})") from exc
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BundleError(parent, "folder is not writable")
    return p


# -------------------------------------------------------------------- save

def _write_files(bundle: ModelBundle, tmp: Path) -> None:
    import joblib
    import torch

    info = {
        "format_version": FORMAT_VERSION,
        "obs_names": list(bundle.obs_names), "act_names": list(bundle.act_names),
        "vol_names": list(bundle.vol_names),
        "rate_hz": float(bundle.rate_hz), "model_hz": float(bundle.model_hz),
        "window_s": float(bundle.window_s), "n_modes": bundle.n_modes,
        "K": json_number(bundle.K), "percentile": float(bundle.percentile),
        "novelty_threshold": float(bundle.novelty_threshold),
        "train_trials": [int(i) for i in bundle.train_trials],
        "heldout_trials": [int(i) for i in bundle.heldout_trials],
        "predictor_config": bundle.predictor.get_config(),
        "config": bundle.config, "library_versions": library_versions(),
    }
    write_json(info, tmp / "bundle.json", non_finite="raise", fsync=False)
    write_json(bundle.metrics, tmp / "metrics.json", non_finite="raise", fsync=False)
    write_json({"obs": standardizer_to_json(bundle.preprocessor.obs),
                "act": standardizer_to_json(bundle.preprocessor.act),
                "target_hz": float(bundle.preprocessor.target_hz),
                "window_s": float(bundle.preprocessor.window_s)}, tmp / "preprocessor.json", non_finite="raise",
               fsync=False)
    torch.save(bundle.predictor.state_dict(), tmp / "predictor.pt")
    joblib.dump(bundle.modes, tmp / "modes.joblib")
    joblib.dump(bundle.gates, tmp / "gates.joblib")
    write_json({"model": None if bundle.fast is None else bundle.fast.to_json()}, tmp / "fast.json")
    write_json(rule_to_json(bundle.rule), tmp / "rule.json", non_finite="raise", fsync=False)
    files = {}
    for name in BUNDLE_FILES:
        path = tmp / name
        fsync_path(path)
        files[name] = {"bytes": path.stat().st_size, "sha256": file_sha256(path)}
    write_json({"format_version": FORMAT_VERSION, "files": files}, tmp / MANIFEST, non_finite="raise", fsync=False)
    fsync_path(tmp / MANIFEST)
    os.chmod(tmp, default_dir_mode())
    fsync_path(tmp)


def save_bundle(bundle: ModelBundle, folder: str | os.PathLike) -> Path:
    """Write ``bundle`` to ``folder`` atomically; return the folder.

    The files are written into a temporary folder beside ``folder``, fsynced, and the
    temporary folder is renamed onto ``folder`` (an existing bundle or empty folder
    there is replaced; anything else is refused, see :func:`check_bundle_target`).
    On any failure the temporary folder is removed and ``folder`` is left as it was.
    """
    target = check_bundle_target(folder)
    parent = target.absolute().parent
    tmp = Path(tempfile.mkdtemp(dir=parent, prefix=f".{target.name}.", suffix=".tmp"))
    old: Path | None = None
    try:
        _write_files(bundle, tmp)
        if target.exists():
            old = Path(tempfile.mkdtemp(dir=parent, prefix=f".{target.name}.", suffix=".old"))
            os.replace(target, old / "b")  # moves the old bundle (or empty folder) aside
        try:
            os.replace(tmp, target)
        except BaseException:
            if old is not None:
                os.replace(old / "b", target)
            raise
        fsync_path(parent)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and not (old / "b").exists():
            shutil.rmtree(old, ignore_errors=True)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return target


# -------------------------------------------------------------------- load

def _load_fast(root: Path, version: int) -> Any:
    """The fast forecaster of ``fast.json`` (None in a version-1 bundle or when not trained)."""
    from learning.predictor.fast import FastForecaster

    if version == 1:
        return None
    path = root / "fast.json"
    d = read_json(path)
    if not isinstance(d, dict) or "model" not in d:
        raise BundleError(path, "expected a JSON object with key 'model'")
    if d["model"] is None:
        return None
    try:
        return FastForecaster.from_json(d["model"])
    except (KeyError, TypeError, ValueError) as exc:
        raise BundleError(path, f"not a valid fast forecaster ({exc!r})") from None


def _load_rule(root: Path, version: int, metrics: dict[str, Any]) -> CalibratedRule | None:
    """The rule of ``rule.json``, or of ``metrics`` in a format-1/2 bundle or where ``rule.json`` has none and
    ``metrics`` says why the choice was skipped (moved out of it)."""
    path = root / ("rule.json" if version >= 3 else "metrics.json")
    try:
        rule = rule_from_json(read_json(path)) if version >= 3 else None
        return rule if rule is not None else rule_from_metrics(metrics)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, BundleError):
            raise
        raise BundleError(path, f"not a valid hand-over rule ({exc})") from None


def _check_names(path: Path, kind: str, have: Sequence[str], expect: Sequence[str] | None) -> None:
    if expect is None:
        return
    expect = [str(n) for n in expect]
    if list(have) != expect:
        raise BundleError(path, f"{kind} channels do not match: the bundle was trained on "
                                f"{list(have)}, the data has {expect}")


def _read_preprocessor(ppath: Path) -> Preprocessor:
    """The two standardizers of ``preprocessor.json``, or a :class:`BundleError` naming the file."""
    try:
        p = read_json(ppath)
        return Preprocessor(obs=standardizer_from_json(p["obs"]), act=standardizer_from_json(p["act"]),
                            target_hz=float(p["target_hz"]), window_s=float(p["window_s"]))
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, BundleError):
            raise
        raise BundleError(ppath, f"not a valid preprocessor ({exc!r})") from None


def load_bundle(folder: str | os.PathLike, expect_obs_names: Sequence[str] | None = None,
                expect_act_names: Sequence[str] | None = None) -> ModelBundle:
    """Read a bundle written by :func:`save_bundle`.

    ``expect_obs_names`` / ``expect_act_names``: channel names of the data the bundle
    will run on; a different list (names or order) is refused.

    Raises:
        BundleError: a missing folder or file, a truncated or corrupt file, another
            format version, channels that do not match; the message names the file.
    """
    import joblib
    import torch

    from learning.gates.gate import ModeGates
    from learning.modes import TaskModes
    from learning.predictor import ReactivePredictor

    root = Path(folder)
    if not root.exists():
        raise BundleError(root, "no such bundle folder")
    if not root.is_dir():
        raise BundleError(root, "is not a folder (a bundle is a folder with manifest.json)")
    version = verify_manifest(root)
    info_path = root / "bundle.json"
    info = read_json(info_path)
    if not isinstance(info, dict):
        raise BundleError(info_path, "expected a JSON object")
    if info.get("format_version") != version:
        raise BundleError(info_path, f"format version {info.get('format_version')!r}, the manifest says {version}")
    _check_names(info_path, "obs", info.get("obs_names", []), expect_obs_names)
    _check_names(info_path, "act", info.get("act_names", []), expect_act_names)
    metrics = read_json(root / "metrics.json")
    if not isinstance(metrics, dict):
        raise BundleError(root / "metrics.json", "expected a JSON object")
    rule = _load_rule(root, version, metrics)

    ppath = root / "preprocessor.json"
    pre = _read_preprocessor(ppath)
    loaded: dict[str, Any] = {}
    for name, cls in (("modes.joblib", TaskModes), ("gates.joblib", ModeGates)):
        try:
            obj = joblib.load(root / name)
        except Exception as exc:  # unpickling can fail in many ways (library versions)
            raise BundleError(root / name, f"cannot be loaded ({type(exc).__name__}: {exc}); written "
                                           f"with {info.get('library_versions')}") from None
        if not isinstance(obj, cls):
            raise BundleError(root / name, f"holds a {type(obj).__name__}, expected {cls.__name__}")
        loaded[name] = obj

    wpath = root / "predictor.pt"
    try:
        state = torch.load(wpath, map_location="cpu", weights_only=True)
        predictor = ReactivePredictor.from_config(info["predictor_config"])
        predictor.load_state_dict(state)
    except Exception as exc:  # torch raises RuntimeError, pickle errors, KeyError …
        raise BundleError(wpath, f"cannot restore the predictor ({type(exc).__name__}: {exc})") from None

    try:
        bundle = ModelBundle(
            obs_names=tuple(info["obs_names"]), act_names=tuple(info["act_names"]),
            vol_names=tuple(info.get("vol_names", [])), rate_hz=float(info["rate_hz"]),
            model_hz=float(info["model_hz"]), window_s=float(info["window_s"]), preprocessor=pre,
            modes=loaded["modes.joblib"], gates=loaded["gates.joblib"], predictor=predictor,
            K=from_json_number(info["K"]), percentile=float(info["percentile"]),
            novelty_threshold=float(info["novelty_threshold"]),
            train_trials=[int(i) for i in info["train_trials"]],
            heldout_trials=[int(i) for i in info["heldout_trials"]],
            metrics=metrics, config=dict(info.get("config", {})), fast=_load_fast(root, version),
            rule=rule, format_version=int(info["format_version"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise BundleError(info_path, f"missing or invalid field ({exc!r})") from None
    if pre.obs.n_features_in_ != len(bundle.obs_names) or pre.act.n_features_in_ != len(bundle.act_names):
        raise BundleError(ppath, f"standardizers for {pre.obs.n_features_in_} obs / {pre.act.n_features_in_} "
                                 f"act channels, bundle.json names {len(bundle.obs_names)} / "
                                 f"{len(bundle.act_names)}")
    return bundle
