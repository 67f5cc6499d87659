"""learning.predictor's LSTM reactive predictor: learning, its NumPy stream, seeds, masks, persistence, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from sklearn.exceptions import NotFittedError

from learning.predictor import PredictorStream, ReactivePredictor, RidgeWindowBaseline
from learning.preprocessing.preprocess import Preprocessor, Standardizer
from learning.preprocessing.resample import causal_downsample
from sim.demonstrator import generate_demonstrations

SMALL = {"hidden_size": 16, "batch_size": 16, "chunk_len": 25, "burn_in": 10, "max_epochs": 40,
         "patience": 8, "learning_rate": 1e-2}


def memory_task(n_trials: int, T: int, seed: int):
    """Smooth random inputs (AR(1), d_in = 5) and a target that is a known function of the
    last three steps: y_t = [0.8 x_t⁰ − 0.6 x_{t−2}¹, tanh(x_{t−1}²) + 0.5 x_t³]."""
    rng = np.random.default_rng(seed)
    xs, ys = [], []
    for _ in range(n_trials):
        e = rng.standard_normal((T, 5))
        x = np.empty_like(e)
        x[0] = e[0]
        for t in range(1, T):
            x[t] = 0.7 * x[t - 1] + 0.71 * e[t]
        def lag(a, k):
            return np.vstack([np.repeat(a[:1], k, 0), a[:-k]])

        y = np.column_stack([0.8 * x[:, 0] - 0.6 * lag(x, 2)[:, 1], np.tanh(lag(x, 1)[:, 2]) + 0.5 * x[:, 3]])
        xs.append(x)
        ys.append(y)
    return xs, ys


@pytest.fixture(scope="module")
def trained():
    xs, ys = memory_task(8, 150, seed=0)
    model = ReactivePredictor(seed=0, **SMALL).fit(xs, ys, progress=False)
    return model, xs, ys


@pytest.fixture(scope="module")
def demo_sequences():
    """2 subjects × 1 min of the generator, causal 10 Hz, standardised obs + one-hot modes."""
    demos = causal_downsample(generate_demonstrations(2, 1.0, seed=5))
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(demos),
                       act=Standardizer("sensor", field="act").fit(demos), target_hz=10.0, window_s=1.0)
    std = pre.standardize(demos)
    xs = [np.hstack([tr.obs, np.eye(4)[tr.mode]]) for tr in std.trials]
    return xs, [tr.act for tr in std.trials], pre


def test_learns_a_known_function_of_recent_observations(trained):
    model, xs, ys = trained
    xt, yt = memory_task(3, 150, seed=1)
    err = np.vstack([model.predict(x) - y for x, y in zip(xt, yt)])
    Y = np.vstack(yt)
    rmse = np.sqrt((err ** 2).mean(axis=0))
    const = np.sqrt(((Y - np.vstack(ys).mean(axis=0)) ** 2).mean(axis=0))  # best constant from training
    assert np.all(rmse < 0.35 * Y.std(axis=0)), (rmse, Y.std(axis=0))
    assert np.all(rmse < 0.35 * const)
    assert model.val_trials_ is not None and len(model.val_trials_) == 2  # round(8 · 0.2)
    assert 1 <= model.best_epoch_ <= model.n_epochs_ <= SMALL["max_epochs"]
    assert len(model.history_["val_loss"]) == model.n_epochs_
    # the ridge baseline on a 3-step window can fit the linear part but not tanh
    base = RidgeWindowBaseline(lags=3).fit(xs, ys)
    err_b = np.vstack([base.predict(x) - y for x, y in zip(xt, yt)])
    assert np.sqrt((err_b[:, 0] ** 2).mean()) < 0.05  # exactly linear channel


def test_stream_equals_batch_prediction(trained, demo_sequences):
    model, xs, _ = trained
    stream = model.make_stream()
    out = np.array([stream.step(x) for x in xs[0]])
    np.testing.assert_allclose(out, model.predict(xs[0]), rtol=0, atol=1e-5)
    stream.reset()
    out2 = np.array([stream.step(x) for x in xs[1]])
    np.testing.assert_allclose(out2, model.predict(xs[1]), rtol=0, atol=1e-5)
    # on the generator's data (other structure: 9 + 4 inputs, 9 outputs)
    dx, dy, _ = demo_sequences
    m2 = ReactivePredictor(**{**SMALL, "max_epochs": 3}).fit(dx, dy, progress=False)
    s2 = m2.make_stream()
    np.testing.assert_allclose(np.array([s2.step(x) for x in dx[-1]]), m2.predict(dx[-1]), rtol=0, atol=1e-5)
    # the float64 batch path follows the float32 torch network to float32 precision
    with torch.no_grad():
        ref = m2.net_(torch.as_tensor(dx[-1], dtype=torch.float32)[None])[0].numpy()
    np.testing.assert_allclose(m2.predict(dx[-1]), ref, rtol=0, atol=1e-4)


def test_same_seed_same_weights_other_seed_differs():
    xs, ys = memory_task(4, 80, seed=2)
    kw = {**SMALL, "max_epochs": 4}
    a = ReactivePredictor(seed=3, **kw).fit(xs, ys, progress=False).state_dict()
    torch.manual_seed(12345)  # the global RNG state must not matter
    b = ReactivePredictor(seed=3, **kw).fit(xs, ys, progress=False).state_dict()
    c = ReactivePredictor(seed=4, **kw).fit(xs, ys, progress=False).state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert not all(torch.equal(a[k], c[k]) for k in a)


def test_masked_steps_do_not_change_the_fit():
    xs, ys = memory_task(5, 90, seed=4)
    rng = np.random.default_rng(0)
    masks = [rng.random(90) < 0.6 for _ in xs]
    masks[0][:] = False  # a trial with no loss step at all
    kw = {**SMALL, "max_epochs": 5}
    vx, vy = memory_task(2, 90, seed=5)
    vm = [rng.random(90) < 0.5 for _ in vx]
    a = ReactivePredictor(**kw).fit(xs, ys, masks, vx, vy, vm, progress=False)
    ys2 = [np.where(m[:, None], y, 1e3 * rng.standard_normal(y.shape)) for y, m in zip(ys, masks)]
    vy2 = [np.where(m[:, None], y, -50.0) for y, m in zip(vy, vm)]
    b = ReactivePredictor(**kw).fit(xs, ys2, masks, vx, vy2, vm, progress=False)
    sa, sb = a.state_dict(), b.state_dict()
    assert all(torch.equal(sa[k], sb[k]) for k in sa)
    assert a.history_ == b.history_
    # and the targets at masked steps do matter when the mask lets them in
    c = ReactivePredictor(**kw).fit(xs, ys2, None, vx, vy2, vm, progress=False)
    assert not torch.equal(c.state_dict()["head.bias"], sa["head.bias"])


def test_persistence_round_trip(trained, tmp_path):
    model, xs, _ = trained
    torch.save(model.state_dict(), tmp_path / "w.pt")
    (tmp_path / "c.json").write_text(json.dumps(model.get_config()))
    again = ReactivePredictor.from_config(json.loads((tmp_path / "c.json").read_text()))
    again.load_state_dict(torch.load(tmp_path / "w.pt", weights_only=True))
    np.testing.assert_array_equal(again.predict(xs[0]), model.predict(xs[0]))
    s1, s2 = model.make_stream(), again.make_stream()
    assert all(np.array_equal(s1.step(x), s2.step(x)) for x in xs[1][:20])
    assert again.get_config()["params"] == model.get_config()["params"]
    assert again.best_epoch_ == model.best_epoch_
    # refusals
    sd = model.state_dict()
    with pytest.raises(ValueError, match="missing keys"):
        again.load_state_dict({k: v for k, v in sd.items() if k != "head.bias"})
    with pytest.raises(ValueError, match="hidden_size=28"):
        ReactivePredictor().load_state_dict(sd)
    cfg = model.get_config()
    cfg["input_dim"] = 7
    with pytest.raises(ValueError, match="5 inputs .* config says 7"):
        ReactivePredictor.from_config(cfg).load_state_dict(sd)
    with pytest.raises(ValueError, match="unknown predictor parameter"):
        ReactivePredictor.from_config({"params": {"hidden": 3}})
    with pytest.raises(TypeError):
        ReactivePredictor.from_config([1, 2])
    with pytest.raises(NotFittedError):
        ReactivePredictor.from_config(cfg).predict(xs[0])


def test_stream_rejects_bad_input_and_keeps_state(trained):
    model, xs, _ = trained
    s = model.make_stream()
    assert isinstance(s, PredictorStream)
    s.step(xs[0][0])
    h, c = s.h.copy(), s.c.copy()
    bad = xs[0][1].copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        s.step(bad)
    with pytest.raises(ValueError, match=r"shape \(5,\)"):
        s.step(xs[0][1][:4])
    assert np.array_equal(s.h, h) and np.array_equal(s.c, c)
    s.reset()
    assert not s.h.any() and not s.c.any()


def test_bad_input_errors():
    xs, ys = memory_task(3, 40, seed=6)
    m = ReactivePredictor(**{**SMALL, "max_epochs": 1})
    with pytest.raises(NotFittedError):
        m.predict(xs[0])
    with pytest.raises(NotFittedError):
        m.make_stream()
    with pytest.raises(TypeError, match="list of"):
        m.fit(xs[0], ys[0])
    with pytest.raises(ValueError, match=r"sequences\[1\] has 4 input channels, expected 5"):
        m.fit([xs[0], xs[1][:, :4]], ys[:2])
    with pytest.raises(ValueError, match=r"targets\[1\] of sequences must have shape \(40, 2\)"):
        m.fit(xs[:2], [ys[0], ys[1][:30]])
    with pytest.raises(ValueError, match=r"masks\[0\] of sequences must be a bool array"):
        m.fit(xs[:2], ys[:2], [np.ones(40), np.ones(40, bool)])
    nan = xs[0].copy()
    nan[17, 1] = np.inf
    with pytest.raises(ValueError, match=r"sequences\[0\] row 17 is not finite"):
        m.fit([nan, xs[1]], ys[:2])
    with pytest.raises(ValueError, match="no training step has mask True"):
        m.fit(xs, ys, [np.zeros(40, bool)] * 3)
    with pytest.raises(ValueError, match="both val_sequences and val_targets"):
        m.fit(xs, ys, val_sequences=xs)
    with pytest.raises(ValueError, match="device must be one of"):
        ReactivePredictor(device="tpu").fit(xs, ys, progress=False)
    with pytest.raises(ValueError, match="hidden_size must be an integer"):
        ReactivePredictor(hidden_size=0).fit(xs, ys, progress=False)
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="no CUDA device"):
            ReactivePredictor(device="cuda").fit(xs, ys, progress=False)
    with pytest.raises(ValueError, match="val_masks given without val_sequences"):
        m.fit(xs, ys, val_masks=[np.ones(40, bool)])
    with pytest.raises(ValueError, match=r"targets\[2\] row 5 has a value beyond ±1e\+06"):
        m.fit(xs, [ys[0], ys[1], np.where(np.arange(40)[:, None] == 5, 1e7, ys[2])])
    assert not hasattr(m, "net_") and not hasattr(m, "input_dim_")  # failed fits leave nothing
    with pytest.warns(UserWarning, match="one training trial"):
        one = ReactivePredictor(**{**SMALL, "max_epochs": 2}).fit(xs[:1], ys[:1], progress=False)
    assert one.n_epochs_ == 2 and one.val_trials_ is None
    fitted = ReactivePredictor(**{**SMALL, "max_epochs": 1}).fit(xs, ys, progress=False)
    with pytest.raises(ValueError, match="has 3 input channels, expected 5"):
        fitted.predict(xs[0][:, :3])


def test_divergence_is_reported(monkeypatch):
    import learning.predictor.lstm as lp
    xs, ys = memory_task(2, 30, seed=9)
    monkeypatch.setattr(lp, "_masked_mse", lambda out, y, w: (out * float("nan")).sum())
    m = ReactivePredictor(**{**SMALL, "max_epochs": 3})
    with pytest.raises(RuntimeError, match="loss is not finite at epoch 1"):
        m.fit(xs, ys, progress=False)
    assert not hasattr(m, "net_")
