"""One family of errors: every error class of the project under one of the roots in PROJECT_ERRORS."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from learning.errors import LearningError
from mpcshare.errors import PROJECT_ERRORS, ControllerSetupError, ControllerTypeError, MpcshareError
from robot.errors import RobotError
from sim.errors import SimError

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("learning", "robot", "sim", "mpcshare")
OWN_ROOT = {"learning": LearningError, "robot": RobotError, "sim": SimError, "mpcshare": MpcshareError}


def _exception_classes() -> list[tuple[str, str]]:
    """(module, class name) of every class in the packages whose name ends in Error, Missing or Exception."""
    found = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            tree = ast.parse(path.read_text())
            for node in tree.body:
                if isinstance(node, ast.ClassDef) and node.name.endswith(("Error", "Missing", "Exception")):
                    module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
                    found.append((module, node.name))
    return found


def test_every_error_class_derives_from_its_packages_root():
    classes = _exception_classes()
    assert len(classes) >= 14, classes  # the scan sees the project's errors
    bad = []
    for module, name in classes:
        cls = getattr(importlib.import_module(module), name)
        root = OWN_ROOT[module.split(".")[0]]
        if not (isinstance(cls, type) and issubclass(cls, Exception) and issubclass(cls, root)):
            bad.append(f"{module}.{name} does not derive from {root.__name__}")
        else:
            assert issubclass(cls, PROJECT_ERRORS)
    assert not bad, "\n".join(bad)


def test_the_roots_are_distinct_and_errors_keep_their_builtin_bases():
    from learning.data import DataFormatError
    from mpcshare.bundle.bundle import BundleError
    from mpcshare.commands.base import CommandError
    from robot.errors import FrameNotFoundError

    assert len(set(PROJECT_ERRORS)) == 4
    assert issubclass(DataFormatError, ValueError) and issubclass(BundleError, ValueError)
    assert issubclass(CommandError, RuntimeError) and issubclass(FrameNotFoundError, KeyError)
    assert issubclass(ControllerTypeError, TypeError) and issubclass(ControllerTypeError, ControllerSetupError)


@pytest.mark.parametrize("options,error,match", [
    ({"strategy": "nope"}, ControllerSetupError, "valid choices"),
    ({"beta": 1.2}, ControllerSetupError, "beta must be in"),
    ({"tip_channels": ("x",)}, ControllerSetupError, "must name 3 channels"),
    ({"preview": object()}, ControllerTypeError, "preview must be"),
])
def test_shared_controller_construction_misuse_raises_the_family(options, error, match):
    from mpcshare.control.controller import SharedController
    from tests.mpcshare.control.controller_doubles import demos_and_bundle

    _, bundle = demos_and_bundle(0)
    with pytest.raises(error, match=match) as caught:
        SharedController.from_bundle(bundle, use_mpc=False, **options)
    assert isinstance(caught.value, MpcshareError) and isinstance(caught.value, (ValueError, TypeError))
