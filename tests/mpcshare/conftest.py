"""A small trained bundle saved once for the tests of `mpcshare run` and its runtime (real learned parts, ~15 s)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def ros_model(tmp_path_factory):
    """(bundle folder, demonstrations it was trained on)."""
    pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package")
    from mpcshare.bundle import save_bundle
    from tests.mpcshare.control.controller_doubles import real_model_bundle

    demos, bundle = real_model_bundle(0)
    folder = tmp_path_factory.mktemp("ros_model") / "model"
    save_bundle(bundle, folder)
    return folder, demos


@pytest.fixture
def rule_choice_in_process(monkeypatch):
    """`mpcshare train`'s rule choice without worker processes, for one test (:mod:`tests.mpcshare.in_process`)."""
    from tests.mpcshare.in_process import choose_rules_in_process

    choose_rules_in_process(monkeypatch)
