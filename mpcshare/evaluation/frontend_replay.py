"""The controller's observation-only stages computed once per trial and replayed.

In :func:`sim.closed_loop.run_episode` the fork samples are replayed from the trial and the time runs on a
fixed grid, so the stages of :class:`mpcshare.control.controller.SharedController` that read nothing else give
the same outputs in every episode of a trial: the front end (``controller.frontend``), the reactive predictor's
stream and the gate on the model ticks (``controller.bundle.predictor``, ``.gates``), the control-rate forecast
(``controller.fast``) and the tip trajectory the arbitration reads (``controller.forecast``: ``ready``, ``at``).
:class:`FrontEndRecording` holds what each of those calls returned (or raised), in call order, with its control
step (one ``frontend.step``), and the arbitration's observation-only inputs (``controller.arbiter.decide``:
time, gate probability, novelty, prediction finite, available, mode posterior; the arbitration always runs).
The keep-out's zones are given back where their inputs are the recorded ones (:mod:`.keepout_replay`).
:func:`record_front_end` wraps a live controller's parts so that its episode records them;
:func:`replay_front_end` swaps in parts that give the recording back; :func:`simulate_cached` does either, per
process, bundle and trial.

Exactness: each replayed call is checked against the recording (time and fork sample byte for byte, the
trajectory's query time, the arbitration's inputs, the step of every call); at the first difference, or with
recorded calls left at the end, the replay is *diverged* and :func:`simulate_cached` runs the episode again
live, so a replayed episode is the live one to the last bit. Run live: the MPC, a known preview
(``oracle_preview``) and scenarios that transform the trial. What it saves: docs/design.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field, is_dataclass, replace
from typing import Any, Callable

import numpy as np

from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation.episode import simulate_episode, trial_seconds
from mpcshare.evaluation.keepout_replay import RecordedKeepOut, ZoneLog, float_bytes

__all__ = ["FrontEndDiverged", "FrontEndRecording", "decisions", "record_front_end", "replay_front_end", "replayable",
           "simulate_cached"]

#: the recorded calls: name → the controller part's method
_CALLS = ("frontend", "stream", "gate", "fast", "ready", "at", "decide")


class FrontEndDiverged(RuntimeError):
    """A replayed call differs from the recording (the controller's step reports it as an internal error)."""


@dataclass
class FrontEndRecording:
    """Per recorded call name (:data:`_CALLS`): a list of (step, key, outcome); ``outcome`` is
    ``(True, value)`` or ``(False, (exception type, args))``; ``key``: what the replay checks besides the
    step (the front end's (t, sample bytes), the trajectory's query time), else None."""

    calls: dict[str, list[tuple[int, Any, tuple[bool, Any]]]] = field(
        default_factory=lambda: {name: [] for name in _CALLS})
    zones: ZoneLog = field(default_factory=list)  # the keep-out's calls (:mod:`.keepout_replay`)

    @property
    def steps(self) -> int:
        """Control steps recorded."""
        return len(self.calls["frontend"])


def _outcome(fn: Callable[[], Any]) -> tuple[bool, Any]:
    try:
        return True, fn()
    except Exception as exc:  # noqa: BLE001 — recorded and raised again on replay, as the live part did
        return False, (type(exc), exc.args)


def _give(outcome: tuple[bool, Any]) -> Any:
    ok, value = outcome
    if ok:
        return value
    kind, args = value
    raise kind(*args)


class _Recorder:
    """The recording and the current step, shared by one controller's wrapped parts."""

    def __init__(self) -> None:
        self.recording = FrontEndRecording()
        self.step = -1

    def reset(self) -> None:
        self.recording.calls = {name: [] for name in _CALLS}
        self.step = -1

    def call(self, name: str, key: Any, fn: Callable[[], Any]) -> Any:
        if name == "frontend":
            self.step += 1
        out = _outcome(fn)
        self.recording.calls[name].append((self.step, key, out))
        return _give(out)


class _Player:
    """The recording played back to one controller's parts; ``diverged`` says why it no longer matches."""

    def __init__(self, recording: FrontEndRecording) -> None:
        self.recording = recording
        self.step = -1
        self.cursor = {name: 0 for name in _CALLS}
        self.diverged: str | None = None

    def reset(self) -> None:
        self.step = -1
        self.cursor = {name: 0 for name in _CALLS}

    def call(self, name: str, key: Any) -> Any:
        if name == "frontend":
            self.step += 1
        log, i = self.recording.calls[name], self.cursor[name]
        if self.diverged is None:
            if i >= len(log):
                self.diverged = f"{name} call {i} beyond the recording"
            elif log[i][0] != self.step or log[i][1] != key:
                self.diverged = f"{name} call {i} at step {self.step} differs from the recording (step {log[i][0]})"
        if self.diverged is not None:
            raise FrontEndDiverged(self.diverged)
        self.cursor[name] = i + 1
        return _give(log[i][2])

    def finished(self) -> bool:
        """Whether every recorded call was replayed and none differed."""
        if self.diverged is None:
            left = [n for n in _CALLS if self.cursor[n] != len(self.recording.calls[n])]
            if left:
                self.diverged = f"recorded calls not replayed: {', '.join(left)}"
        return self.diverged is None


class _Part:
    """A controller part whose listed methods go through a recorder or a player; the rest are the live part's."""

    def __init__(self, live: Any, via: _Recorder | _Player) -> None:
        self._live, self._via = live, via

    def __getattr__(self, name: str) -> Any:
        return getattr(self._live, name)


class _FrontEnd(_Part):
    def step(self, t: float, obs: Any) -> Any:
        key = float(t), float_bytes(obs)
        if isinstance(self._via, _Recorder):
            return self._via.call("frontend", key, lambda: self._live.step(t, obs))
        return self._via.call("frontend", key)

    def reset(self) -> None:
        self._via.reset()
        if isinstance(self._via, _Recorder):
            self._live.reset()


class _Stream(_Part):
    """The predictor's stream: ``step`` and the ``forecast`` it leaves."""

    def step(self, x: np.ndarray) -> Any:
        if isinstance(self._via, _Recorder):
            out = self._via.call("stream", None, lambda: (self._live.step(x), getattr(self._live, "forecast", None)))
        else:
            out = self._via.call("stream", None)
        self.forecast = out[1]
        return out[0]


class _Predictor(_Part):
    def make_stream(self) -> _Stream:
        live = self._live.make_stream() if isinstance(self._via, _Recorder) else None
        stream = _Stream(live, self._via)
        stream.forecast = getattr(live, "forecast", None)
        return stream


class _Gates(_Part):
    def proba_one(self, window: np.ndarray, mode: int) -> Any:
        if isinstance(self._via, _Recorder):
            return self._via.call("gate", int(mode), lambda: self._live.proba_one(window, mode))
        return self._via.call("gate", int(mode))


class _Fast(_Part):
    """The control-rate forecast: ``step`` recorded; ``on_tick`` and ``reset`` live when recording, nothing on
    replay (the trajectory it feeds is replayed)."""

    def on_tick(self, forecast_std: Any) -> None:
        if isinstance(self._via, _Recorder):
            self._live.on_tick(forecast_std)

    def reset(self) -> None:
        if isinstance(self._via, _Recorder):
            self._live.reset()

    def step(self, *args: Any) -> Any:
        if isinstance(self._via, _Recorder):
            return self._via.call("fast", None, lambda: self._live.step(*args))
        return self._via.call("fast", None)


class _Track(_Part):
    """The tip trajectory the arbitration reads: ``ready`` and ``at``; ``update`` and ``reset`` live when
    recording, nothing on replay."""

    @property
    def ready(self) -> bool:
        if isinstance(self._via, _Recorder):
            return self._via.call("ready", None, lambda: self._live.ready)
        return self._via.call("ready", None)

    def at(self, t: float) -> Any:
        if isinstance(self._via, _Recorder):
            return self._via.call("at", float(t), lambda: self._live.at(t))
        return self._via.call("at", float(t))

    def update(self, t_tick: float, points: np.ndarray) -> None:
        if isinstance(self._via, _Recorder):
            self._live.update(t_tick, points)

    def reset(self) -> None:
        if isinstance(self._via, _Recorder):
            self._live.reset()


def _decide_key(t: float, gate_proba: float | None, novelty: float, prediction_finite: bool, available: bool,
                mode_proba: np.ndarray | None) -> bytes:
    """The arbitration's observation-only inputs as bytes (NaN-safe equality; a :func:`decisions` row)."""
    head = np.array([t, np.nan if gate_proba is None else gate_proba, novelty, prediction_finite, available,
                     gate_proba is None, mode_proba is None], dtype=float)
    return head.tobytes() + (b"" if mode_proba is None else np.asarray(mode_proba, dtype=float).tobytes())


class _Arbiter(_Part):
    """The arbitration, always live: its observation-only inputs recorded, and on replay checked (the wearer's
    and the robot's commands, which the closed loop moves, are passed on but not recorded)."""

    def decide(self, t: float, gate_proba: float | None, novelty: float = 0.0, prediction_finite: bool = True,
               available: bool = True, **inputs: Any) -> Any:
        args = (t, gate_proba, novelty, prediction_finite, available)
        mode_proba = inputs.get("mode_proba")
        key = _decide_key(*args, mode_proba)
        if isinstance(self._via, _Recorder):
            frozen = None if mode_proba is None else np.array(mode_proba, dtype=float)
            self._via.call("decide", key, lambda: (*args, frozen))
        else:
            self._via.call("decide", key)
        return self._live.decide(*args, **inputs)


class _Bundle(_Part):
    """The controller's bundle with its predictor's streams and its gates wrapped."""

    def __init__(self, live: Any, via: _Recorder | _Player) -> None:
        super().__init__(live, via)
        self.predictor = _Predictor(live.predictor, via)
        self.gates = _Gates(live.gates, via)


def replayable(controller: Any) -> bool:
    """Whether ``controller``'s observation-only stages can be recorded and replayed: a
    :class:`~mpcshare.control.controller.SharedController` without an MPC or a known preview."""
    return hasattr(controller, "parts") and hasattr(controller, "reset") and \
        getattr(controller, "mpc", None) is None and not getattr(controller, "oracle", False)


def _wrap(controller: Any, via: _Recorder | _Player) -> None:
    if not replayable(controller):
        raise ValueError("the front end of a controller with an MPC or a known preview is not replayed")
    parts = controller.parts  # built once and frozen (mpcshare.control.builder): replaced whole, then reset
    controller.parts = replace(
        parts, frontend=_FrontEnd(parts.frontend, via), bundle=_Bundle(parts.bundle, via),
        fast=None if parts.fast is None else _Fast(parts.fast, via), forecast=_Track(parts.forecast, via),
        arbiter=_Arbiter(parts.arbiter, via),
        keepout=None if parts.keepout is None else
        RecordedKeepOut(parts.keepout, via.recording.zones, replaying=isinstance(via, _Player)))


def record_front_end(controller: Any) -> FrontEndRecording:
    """Wrap ``controller``'s observation-only parts (module docstring) so that what they give in its next
    episode is recorded into the returned recording; ValueError unless :func:`replayable`."""
    rec = _Recorder()
    _wrap(controller, rec)
    return rec.recording


def replay_front_end(controller: Any, recording: FrontEndRecording) -> Callable[[], str | None]:
    """Put parts in place of ``controller``'s observation-only parts that give ``recording`` back; returns a
    function to call after the episode: None when it replayed exactly, else why not. ValueError unless
    :func:`replayable`."""
    player = _Player(recording)
    _wrap(controller, player)
    return lambda: None if player.finished() else player.diverged


def _factory(make: Callable[..., Any] | None, hook: Callable[[Any], Any], out: list[Any]) -> Callable[..., Any]:
    def build(bundle: Any, **options: Any) -> Any:
        if make is not None:
            controller = make(bundle, **options)
        else:
            from mpcshare.control.controller import SharedController

            controller = SharedController.from_bundle(bundle, **options)
        out.append(hook(controller) if replayable(controller) else None)
        return controller
    return build


def decisions(recording: FrontEndRecording) -> np.ndarray:
    """The arbitration's observation-only inputs at each of its calls in the recorded episode, one float row
    each: t, the gate probability (NaN: None), novelty, prediction finite, available, gate probability None,
    mode posterior None, the mode posterior (K,) (NaN where None); what :func:`decision_trace` replays."""
    rows = [np.frombuffer(key, dtype=float) for _, key, _ in recording.calls["decide"]]
    width = max((r.size for r in rows), default=7)
    out = np.full((len(rows), width), np.nan)
    for i, r in enumerate(rows):
        out[i, :r.size] = r
    return out


#: per process: (the bundle and its models, trial, duration, the controller's options but the strategy's) → (the
#: bundle, the recording of the first replayable episode run here with them); the last few. A bundle's models
#: are not changed in place (a changed bundle is another object: a worker unpickles each digest anew)
_CACHE: dict[tuple[Any, ...], tuple[Any, FrontEndRecording]] = {}
_MAX_CACHED = 8


def _cache_key(bundle: Any, trial: Any, options: dict[str, Any], settings: dict[str, Any]) -> tuple[Any, ...] | None:
    """What the front end's outputs depend on besides the trial: the bundle, the controller's options but the
    strategy's own (``config.strategy_settings``, ``schedule``), the episode's length; None: not cached."""
    if settings.get("scenario") is not None:
        return None
    rest = {k: v for k, v in sorted(options.items()) if k not in ("schedule", "config")}
    config = options.get("config") or ControllerConfig()
    rest["config"] = replace(config, strategy_settings=None) if is_dataclass(config) else config
    parts = tuple(id(getattr(bundle, a, None)) for a in ("predictor", "gates", "fast", "modes", "preprocessor"))
    seconds = trial_seconds(settings.get("duration_s"), trial.trial_id)
    return id(bundle), parts, int(trial.trial_id), seconds, repr(rest)


def simulate_cached(bundle: Any, demos: Any, trial: Any, run: Any, options: dict[str, Any],
                    **settings: Any) -> tuple[Any, dict[str, Any], np.ndarray | None]:
    """:func:`mpcshare.evaluation.episode.simulate_episode`, the same (episode, metrics), with the front end
    replayed from this process's recording of the bundle and trial (:data:`_CACHE`) or, the first time,
    recorded into it; and the :func:`decisions` the arbitration saw (None where not known: a controller that
    is not :func:`replayable`, or a replay that diverged and ran live). Module docstring: where the replay
    diverges, the episode runs again live."""
    key = _cache_key(bundle, trial, options, settings)
    cached = _CACHE.get(key) if key is not None else None
    make = settings.pop("make_controller", None)
    if cached is None or cached[0] is not bundle:
        out: list[Any] = []
        episode, metrics = simulate_episode(bundle, demos, trial, run, options,
                                            make_controller=_factory(make, record_front_end, out), **settings)
        recording = out[0] if out else None
        if recording is None:
            return episode, metrics, None
        if key is not None:
            _CACHE[key] = (bundle, recording)
            while len(_CACHE) > _MAX_CACHED:
                _CACHE.pop(next(iter(_CACHE)))
        return episode, metrics, decisions(recording)
    recording = cached[1]
    checks: list[Any] = []
    episode, metrics = simulate_episode(bundle, demos, trial, run, options,
                                        make_controller=_factory(make, lambda c: replay_front_end(c, recording),
                                                                 checks), **settings)
    if not checks or checks[0] is None:  # not replayable: it ran live
        return episode, metrics, None
    if checks[0]() is None:  # replayed exactly
        return episode, metrics, decisions(recording)
    episode, metrics = simulate_episode(bundle, demos, trial, run, options, make_controller=make, **settings)
    return episode, metrics, None
