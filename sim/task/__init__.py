"""The task: everything specific to what the wearer and the robot do together, one module a task.

- :mod:`sim.task.protocol` — :class:`~sim.task.protocol.Task`, what the simulator, the reports and the
  commands read from a task;
- :mod:`sim.task.metrics` — the figures a task's metrics are made of (lag, strokes, per mode, pick-ups);
- :mod:`sim.task.eating` — the task shipped (:data:`EATING`).

Another task is one module beside :mod:`sim.task.eating` whose ``TASK`` is a :class:`Task`;
:func:`task_named` finds it by the module's name, :func:`task_names` lists them. A task outside this
package is named ``package.module:ATTR`` (or ``package.module``, whose ``TASK`` is taken): a user's own
task needs no edit here.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Any, Mapping

from .eating import TASK as EATING
from .protocol import Task

__all__ = ["DEFAULT_TASK", "EATING", "Task", "recorded_task", "task_named", "task_names"]

#: the task the commands run unless told otherwise
DEFAULT_TASK = "eating"
_NOT_TASKS = frozenset({"eating", "metrics", "protocol"})


def task_names() -> list[str]:
    """The names of the task modules in this package (each has a ``TASK``), sorted."""
    others = [m.name for m in pkgutil.iter_modules(__path__) if m.name not in _NOT_TASKS and not m.name.startswith("_")]
    return sorted([EATING.name] + [n for n in others if isinstance(getattr(_module(n), "TASK", None), Task)])


def task_named(name: str) -> Task:
    """The task ``name`` names: the ``TASK`` of module ``sim.task.<name>``; with a dot or a colon, the object
    ``ATTR`` of ``package.module:ATTR`` (``package.module``: its ``TASK``), imported from ``sys.path``.
    Raises ValueError naming the valid choices for an unknown name, and saying why for a module that does not
    import or an object that is not a :class:`Task`."""
    if name == EATING.name:
        return EATING
    if "." in name or ":" in name:
        return _outside(name)
    names = task_names()
    if name not in names:
        raise ValueError(f"unknown task {name!r}; valid choices: {', '.join(names)} (or package.module:ATTR)")
    return _module(name).TASK


def recorded_task(config: Mapping[str, Any] | None) -> Task:
    """The task a model bundle's configuration records (``config["task"]``, a name for :func:`task_named`);
    :data:`DEFAULT_TASK`'s where it records none (a bundle from before tasks were named). Raises ValueError as
    :func:`task_named` does."""
    return task_named(str((config or {}).get("task") or DEFAULT_TASK))


def _outside(spec: str) -> Task:
    """The task of ``package.module[:ATTR]`` (:func:`task_named`)."""
    module_name, _, attr = spec.partition(":")
    attr = attr or "TASK"
    if not module_name or not attr.isidentifier():
        raise ValueError(f"task {spec!r}: expected package.module or package.module:ATTR")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # any failure of the user's module is the user's to see, in one line
        raise ValueError(f"task {spec!r}: cannot import {module_name} ({type(exc).__name__}: {exc})") from None
    task = getattr(module, attr, None)
    if task is None:
        raise ValueError(f"task {spec!r}: module {module_name} has no {attr}")
    if isinstance(task, type):
        raise ValueError(f"task {spec!r}: {module_name}.{attr} is a class; name an instance of it (TASK = {attr}())")
    if not isinstance(task, Task):
        raise ValueError(f"task {spec!r}: {module_name}.{attr} is a {type(task).__name__}, not a sim.task.Task "
                         "(its attributes and methods: sim/task/protocol.py)")
    return task


def _module(name: str) -> object:
    return importlib.import_module(f"{__name__}.{name}")
