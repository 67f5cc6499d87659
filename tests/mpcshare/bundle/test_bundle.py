"""Model bundles: round trip, every refusal (naming the file), atomic writes."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

import mpcshare
from mpcshare.bundle import (
    BUNDLE_FILES,
    FORMAT_VERSION,
    RULE_VERSION,
    BundleError,
    CalibratedRule,
    load_bundle,
    save_bundle,
)
from mpcshare.bundle.rule import skipped_rule
from mpcshare.training import train_bundle
from mpcshare.training.config import TrainConfig
from sim.demonstrator import GeneratorConfig, generate_demonstrations

SMALL = TrainConfig(percentile=80, n_modes=3, hmm_restarts=1, max_epochs=3, patience=2,
                    gate_max_samples=200, seed=0)


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(2, 1.5, seed=3, config=GeneratorConfig(trial_minutes=0.5))


@pytest.fixture(scope="module")
def bundle(demos):
    return train_bundle(demos, SMALL, progress=False)


@pytest.fixture(scope="module")
def saved(bundle, tmp_path_factory):
    return save_bundle(bundle, tmp_path_factory.mktemp("b") / "model")


def _copy(src: Path, dst: Path) -> Path:
    import shutil
    shutil.copytree(src, dst)
    return dst


def _rewrite_manifest(folder: Path) -> None:
    """Make the manifest consistent with the files again (a genuine other bundle)."""
    import hashlib
    m = json.loads((folder / "manifest.json").read_text())
    for name in m["files"]:
        data = (folder / name).read_bytes()
        m["files"][name] = {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    (folder / "manifest.json").write_text(json.dumps(m))


def test_round_trip_gives_identical_predictions(bundle, saved, demos):
    back = mpcshare.load_bundle(saved, expect_obs_names=demos.obs_names, expect_act_names=demos.act_names)
    assert back.format_version == FORMAT_VERSION
    assert back.obs_names == tuple(demos.obs_names) and back.act_names == tuple(demos.act_names)
    assert back.vol_names == tuple(demos.vol_names)
    for name in ("rate_hz", "model_hz", "window_s", "K", "percentile", "novelty_threshold"):
        assert getattr(back, name) == getattr(bundle, name), name
    assert back.train_trials == bundle.train_trials and back.heldout_trials == bundle.heldout_trials
    assert not set(back.train_trials) & set(back.heldout_trials)
    assert back.metrics == json.loads(json.dumps(bundle.metrics))
    assert back.config == bundle.config
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(40, len(demos.obs_names)))
    np.testing.assert_array_equal(back.preprocessor.obs.transform(obs), bundle.preprocessor.obs.transform(obs))
    np.testing.assert_array_equal(back.preprocessor.act.inverse_transform(obs),
                                  bundle.preprocessor.act.inverse_transform(obs))
    np.testing.assert_array_equal(back.modes.filter_proba(obs, [40]), bundle.modes.filter_proba(obs, [40]))
    L = bundle.window_lags
    win = rng.normal(size=(25, L * len(demos.obs_names)))
    m = rng.integers(0, bundle.n_modes, 25)
    np.testing.assert_array_equal(back.gates.predict_proba(win, m), bundle.gates.predict_proba(win, m))
    seq = rng.normal(size=(30, len(demos.obs_names) + bundle.n_modes))
    np.testing.assert_array_equal(back.predictor.predict(seq), bundle.predictor.predict(seq))


def test_manifest_lists_every_file_with_size_and_checksum(saved):
    m = json.loads((saved / "manifest.json").read_text())
    assert m["format_version"] == FORMAT_VERSION
    assert set(m["files"]) == set(BUNDLE_FILES)
    assert sorted(os.listdir(saved)) == sorted([*BUNDLE_FILES, "manifest.json"])
    for name, entry in m["files"].items():
        assert entry["bytes"] == (saved / name).stat().st_size and len(entry["sha256"]) == 64


def test_missing_folder_is_refused(tmp_path):
    with pytest.raises(BundleError, match="no such bundle folder") as e:
        load_bundle(tmp_path / "nope")
    assert str(tmp_path / "nope") in str(e.value)
    (tmp_path / "file").write_text("x")
    with pytest.raises(BundleError, match="not a folder"):
        load_bundle(tmp_path / "file")


@pytest.mark.parametrize("name", ["manifest.json", *BUNDLE_FILES])
def test_missing_file_is_refused_naming_it(saved, tmp_path, name):
    b = _copy(saved, tmp_path / "b")
    (b / name).unlink()
    with pytest.raises(BundleError, match="missing") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / name))


@pytest.mark.parametrize("name", ["predictor.pt", "gates.joblib", "bundle.json", "modes.joblib"])
def test_truncated_file_is_refused_naming_it(saved, tmp_path, name):
    b = _copy(saved, tmp_path / "b")
    data = (b / name).read_bytes()
    (b / name).write_bytes(data[: len(data) // 2])
    with pytest.raises(BundleError, match="truncated") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / name))


def test_corrupt_file_of_the_same_size_is_refused(saved, tmp_path):
    b = _copy(saved, tmp_path / "b")
    data = bytearray((b / "predictor.pt").read_bytes())
    data[len(data) // 2] ^= 0xFF
    (b / "predictor.pt").write_bytes(bytes(data))
    with pytest.raises(BundleError, match="checksum") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / "predictor.pt"))


def test_truncated_manifest_is_refused(saved, tmp_path):
    b = _copy(saved, tmp_path / "b")
    text = (b / "manifest.json").read_text()
    (b / "manifest.json").write_text(text[: len(text) // 2])
    with pytest.raises(BundleError, match="not valid JSON") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / "manifest.json"))


def test_other_format_version_is_refused(saved, tmp_path):
    b = _copy(saved, tmp_path / "b")
    info = json.loads((b / "bundle.json").read_text())
    info["format_version"] = FORMAT_VERSION + 1
    (b / "bundle.json").write_text(json.dumps(info))
    _rewrite_manifest(b)
    with pytest.raises(BundleError, match=f"format version {FORMAT_VERSION + 1}") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / "bundle.json"))
    m = json.loads((b / "manifest.json").read_text())
    m["format_version"] = 7
    (b / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(BundleError, match="format version 7") as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / "manifest.json"))


def test_the_fast_forecaster_round_trips(bundle, saved):
    back = load_bundle(saved)
    assert bundle.fast is not None and back.fast is not None
    rng = np.random.default_rng(1)
    phi = rng.normal(size=(5, bundle.fast.n_features_in_))
    slow = rng.normal(size=(5, bundle.fast.n_horizons_, 3))
    np.testing.assert_array_equal(back.fast.predict(phi, slow), bundle.fast.predict(phi, slow))
    np.testing.assert_array_equal(back.fast.preview_skill_, bundle.fast.preview_skill_)
    assert back.fast.channels_ == ("knife_x", "knife_y", "knife_z")


def _as_version_2(b: Path, metrics_extra: dict) -> None:
    """Rewrite the bundle folder ``b`` as format 2: no ``rule.json``, ``metrics_extra`` added to the metrics."""
    (b / "rule.json").unlink()
    for name in ("bundle.json", "manifest.json"):
        d = json.loads((b / name).read_text())
        d["format_version"] = 2
        d.get("files", {}).pop("rule.json", None)
        (b / name).write_text(json.dumps(d))
    m = json.loads((b / "metrics.json").read_text())
    (b / "metrics.json").write_text(json.dumps({**m, **metrics_extra}))
    _rewrite_manifest(b)


def test_the_rule_round_trips_and_a_version_2_bundles_rule_is_moved_out_of_its_metrics(bundle, tmp_path):
    import dataclasses

    rule = CalibratedRule("gate", {"wearer_modes": [1], "share_on": 0.5}, {"why": "measured"})
    back = load_bundle(save_bundle(dataclasses.replace(bundle, rule=rule), tmp_path / "b"))
    assert back.rule == CalibratedRule("gate", {"wearer_modes": (1,), "share_on": 0.5}, {"why": "measured"})
    assert back.rule.version == RULE_VERSION and load_bundle(save_bundle(bundle, tmp_path / "none")).rule is None
    old = _copy(tmp_path / "none", tmp_path / "v2")
    _as_version_2(old, {"rule_settings": {"wearer_modes": [0], "lead_s": 1.5}, "rule_choice": {"why": "old"}})
    migrated = load_bundle(old)
    assert migrated.format_version == 2 and "rule_settings" not in migrated.metrics
    assert migrated.rule == CalibratedRule("gate", {"wearer_modes": (0,), "lead_s": 1.5}, {"why": "old"}, 1)


def test_a_skipped_rule_round_trips_and_an_older_bundles_skipped_metric_becomes_one(bundle, tmp_path):
    import dataclasses

    skipped = skipped_rule("closed-loop choice was skipped: no knife")
    back = load_bundle(save_bundle(dataclasses.replace(bundle, rule=skipped), tmp_path / "b"))
    assert back.rule == skipped and "rule_choice_skipped" not in back.metrics
    old = _copy(tmp_path / "b", tmp_path / "old")  # as written before the rule could say so: in the metrics
    (old / "rule.json").write_text(json.dumps({"rule": None}))
    m = json.loads((old / "metrics.json").read_text())
    (old / "metrics.json").write_text(json.dumps({**m, "rule_choice_skipped": skipped.skipped}))
    _rewrite_manifest(old)
    migrated = load_bundle(old)
    assert migrated.rule == skipped and "rule_choice_skipped" not in migrated.metrics


@pytest.mark.parametrize("rule,match", [({"version": 1, "strategy": "gate", "settings": {"lead_s": "1"}},
                                         "rule setting 'lead_s' must be a finite number"),
                                        ({"version": 9, "strategy": "gate", "settings": {}}, "rule version 9"),
                                        ({"strategy": "gate", "settings": {}}, r"lacks \['version'\]")])
def test_a_wrong_rule_is_refused_naming_the_file_and_field(saved, tmp_path, rule, match):
    b = _copy(saved, tmp_path / "b")
    (b / "rule.json").write_text(json.dumps({"rule": rule}))
    _rewrite_manifest(b)
    with pytest.raises(BundleError, match=match) as e:
        load_bundle(b)
    assert str(e.value).startswith(str(b / "rule.json"))


def test_a_version_1_bundle_still_loads_without_the_fast_forecaster(saved, tmp_path):
    b = _copy(saved, tmp_path / "b")
    (b / "fast.json").unlink()
    (b / "rule.json").unlink()
    info = json.loads((b / "bundle.json").read_text())
    info["format_version"] = 1
    (b / "bundle.json").write_text(json.dumps(info))
    m = json.loads((b / "manifest.json").read_text())
    m["format_version"] = 1
    del m["files"]["fast.json"], m["files"]["rule.json"]
    (b / "manifest.json").write_text(json.dumps(m))
    _rewrite_manifest(b)
    old = load_bundle(b)
    assert old.format_version == 1 and old.fast is None
    info["format_version"] = 2  # a version-2 bundle.json beside a version-1 manifest: refused
    (b / "bundle.json").write_text(json.dumps(info))
    _rewrite_manifest(b)
    with pytest.raises(BundleError, match="the manifest says 1"):
        load_bundle(b)


def test_channel_mismatch_is_refused(saved, demos):
    obs = list(demos.obs_names)
    with pytest.raises(BundleError, match="obs channels do not match") as e:
        load_bundle(saved, expect_obs_names=obs[::-1])
    assert str(e.value).startswith(str(saved / "bundle.json"))
    with pytest.raises(BundleError, match="act channels do not match"):
        load_bundle(saved, expect_obs_names=obs, expect_act_names=["a", "b"])


def test_a_failure_mid_write_leaves_no_folder(bundle, tmp_path, monkeypatch):
    import joblib

    calls = []

    def failing_dump(obj, path, *a, **k):
        calls.append(path)
        if str(path).endswith("gates.joblib"):
            raise OSError("disk full (simulated)")
        return real(obj, path, *a, **k)

    real = joblib.dump
    monkeypatch.setattr(joblib, "dump", failing_dump)
    with pytest.raises(OSError, match="disk full"):
        save_bundle(bundle, tmp_path / "model")
    assert calls, "the failure must happen while writing"
    assert not (tmp_path / "model").exists()
    assert os.listdir(tmp_path) == []  # no temporary folder left either


def test_failed_rewrite_keeps_the_old_bundle(bundle, saved, tmp_path, monkeypatch):
    import joblib

    b = _copy(saved, tmp_path / "b")
    before = (b / "manifest.json").read_bytes()
    monkeypatch.setattr(joblib, "dump", lambda *a, **k: (_ for _ in ()).throw(OSError("boom")))
    with pytest.raises(OSError):
        save_bundle(bundle, b)
    assert (b / "manifest.json").read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["b"]
    load_bundle(b)


def test_overwrites_a_bundle_or_empty_folder_but_never_other_folders(bundle, saved, tmp_path):
    b = _copy(saved, tmp_path / "b")
    save_bundle(bundle, b)  # an existing bundle is replaced
    load_bundle(b)
    (tmp_path / "empty").mkdir()
    save_bundle(bundle, tmp_path / "empty")
    load_bundle(tmp_path / "empty")
    other = tmp_path / "results"
    other.mkdir()
    (other / "notes.txt").write_text("keep me")
    with pytest.raises(BundleError, match="not a model bundle"):
        save_bundle(bundle, other)
    assert (other / "notes.txt").read_text() == "keep me"
    (tmp_path / "afile").write_text("x")
    with pytest.raises(BundleError, match="not a folder"):
        save_bundle(bundle, tmp_path / "afile")
