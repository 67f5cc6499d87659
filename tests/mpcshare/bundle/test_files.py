"""The bundle's pieces as files (mpcshare.bundle.files): +∞ through JSON, standardizers exact through
JSON, checksums, fsync and the recorded library versions."""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np
import pytest

from learning.preprocessing.preprocess import Standardizer
from mpcshare.bundle.files import (
    file_sha256,
    from_json_number,
    fsync_path,
    json_number,
    library_versions,
    standardizer_from_json,
    standardizer_to_json,
)


def test_infinity_is_stored_as_null_and_nan_is_refused():
    assert json_number(math.inf) is None and from_json_number(None) == math.inf
    assert from_json_number(json_number(0.1)) == 0.1
    for bad in (math.nan, -math.inf):
        with pytest.raises(ValueError, match="cannot store"):
            json_number(bad)


@pytest.mark.parametrize("scope, sensors", [("channel", None), ("sensor", 3), ("sensor", [[0, 4], [1, 2, 3], [5]])])
def test_a_standardizer_comes_back_exactly_through_json(scope, sensors):
    x = np.random.default_rng(0).normal(size=(200, 6)) * [0.01, 3.0, 1e3, 1.0, 7.0, 0.2] + 1 / 3
    s = Standardizer(scope, sensors=sensors).fit(x)
    back = standardizer_from_json(json.loads(json.dumps(standardizer_to_json(s))))
    assert np.array_equal(back.transform(x), s.transform(x))  # bit for bit
    assert [g.tolist() for g in back.groups_] == [g.tolist() for g in s.groups_]


def test_an_unfitted_or_invalid_standardizer_is_refused():
    with pytest.raises(ValueError, match="fitted"):
        standardizer_to_json(Standardizer("channel"))
    d = standardizer_to_json(Standardizer("channel").fit(np.arange(12.0).reshape(6, 2)))
    with pytest.raises(ValueError, match="scale > 0"):
        standardizer_from_json({**d, "scale": [1.0, 0.0]})


def test_checksum_fsync_and_versions(tmp_path):
    data = np.random.default_rng(1).bytes(3 * (1 << 20) + 5)  # more than one 1 MiB chunk
    path = tmp_path / "f.bin"
    path.write_bytes(data)
    assert file_sha256(path) == hashlib.sha256(data).hexdigest()
    fsync_path(path)
    fsync_path(tmp_path)  # a folder too
    assert set(library_versions()) == {"numpy", "scikit-learn", "hmmlearn", "torch"}
