"""Trials and data sets in memory (learning.data.model): stacking, summary, renaming, validation."""

from __future__ import annotations

import numpy as np
import pytest

from learning.data import DataFormatError, Demonstrations, Trial
from tests.learning.data_helpers import ACT, OBS, VOL, assert_same, make_demos


def test_from_stacked_matches_stacked() -> None:
    d = make_demos()
    s = d.stacked()
    back = Demonstrations.from_stacked(rate_hz=d.rate_hz, obs_names=OBS, act_names=ACT, vol_names=VOL, **s)
    assert_same(d, back)


def test_summary() -> None:
    d = make_demos()
    s = d.summary()
    assert s["n_trials"] == 3 and s["n_samples"] == 40 + 45 + 50
    assert s["subjects"] == [0, 1]
    assert s["duration_s"] == pytest.approx(1.35)
    assert s["duration_s_per_subject"] == {0: pytest.approx(0.9), 1: pytest.approx(0.45)}
    assert s["rate_hz"] == 100.0 and s["obs_names"] == OBS and s["vol_names"] == VOL
    assert sum(s["mode_counts"].values()) == 135
    assert make_demos(optional=False).summary()["mode_counts"] is None
    import json
    json.dumps(s)


def test_renamed_gives_channels_new_names_and_refuses_what_does_not_fit() -> None:
    d = make_demos()
    r = d.renamed({"knife_x": ACT[0], "shoulder_elevation": VOL[-1]})
    assert r.act_names == ["knife_x", *ACT[1:]] and r.vol_names == [*VOL[:-1], "shoulder_elevation"]
    assert r.obs_names == OBS and r.trials[0] is d.trials[0] and d.act_names == ACT  # the set itself unchanged
    with pytest.raises(ValueError, match="no channel 'nope'"):
        d.renamed({"a": "nope"})
    with pytest.raises(ValueError, match="renamed twice"):
        d.renamed({"a": ACT[0], "b": f"act:{ACT[0]}"})
    with pytest.raises(ValueError, match="twice"):
        d.renamed({OBS[1]: OBS[0]})
    both = Demonstrations(d.trials, d.rate_hz, [str(j) for j in range(len(OBS))],
                          [str(j) for j in range(len(ACT))], VOL)
    with pytest.raises(ValueError, match="obs and act; write knife_x=obs:0 or knife_x=act:0"):
        both.renamed({"knife_x": "0"})
    assert both.renamed({"knife_x": "act:0"}).act_names[0] == "knife_x"


def test_trial_rejects_non_integer_mode() -> None:
    with pytest.raises(DataFormatError, match="integer") as exc:
        Trial(obs=np.zeros((3, 1)), act=np.zeros((3, 1)), t=np.arange(3.0), mode=[0, 1.5, 2])
    assert exc.value.field == "mode" and exc.value.row == 1


def test_validate_catches_problems() -> None:
    d = make_demos()
    assert d.validate() is d
    d.trials[1].trial_id = d.trials[0].trial_id
    with pytest.raises(DataFormatError, match="duplicate trial id"):
        d.validate()
    d = make_demos()
    d.trials[2].mode = None
    with pytest.raises(DataFormatError, match="some trials only"):
        d.validate()
    d = make_demos()
    d.obs_names[1] = "a,b"
    with pytest.raises(DataFormatError, match="channel name"):
        d.validate()
    d = make_demos()
    d.trials[0].act = d.trials[0].act[:, :2]
    with pytest.raises(DataFormatError, match="act channels"):
        d.validate()
    d = make_demos()
    d.trials[1].obs[4, 0] = np.nan
    with pytest.raises(DataFormatError, match="trial 11: non-finite") as exc:
        d.validate()
    assert exc.value.row == 4 and exc.value.field == "obs"
    with pytest.raises(DataFormatError, match="no trials"):
        Demonstrations([], 10.0).validate()
    with pytest.raises(DataFormatError, match="rate_hz"):
        Demonstrations(make_demos().trials, -1.0).validate()
