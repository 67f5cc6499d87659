"""The task: everything specific to what the wearer and the robot do together, one module a task.

- :mod:`sim.task.protocol` — :class:`~sim.task.protocol.Task`, what the simulator, the reports and the
  commands read from a task;
- :mod:`sim.task.metrics` — the figures a task's metrics are made of (lag, strokes, per mode, pick-ups);
- :mod:`sim.task.eating` — the task shipped (:data:`EATING`).

Another task is one module beside :mod:`sim.task.eating` whose ``TASK`` is a :class:`Task`;
:func:`task_named` finds it by the module's name, :func:`task_names` lists them.
"""

from __future__ import annotations

import importlib
import pkgutil

from .eating import TASK as EATING
from .protocol import Task

__all__ = ["DEFAULT_TASK", "EATING", "Task", "task_named", "task_names"]

#: the task the commands run unless told otherwise
DEFAULT_TASK = "eating"
_NOT_TASKS = frozenset({"eating", "metrics", "protocol"})


def task_names() -> list[str]:
    """The names of the task modules in this package (each has a ``TASK``), sorted."""
    others = [m.name for m in pkgutil.iter_modules(__path__) if m.name not in _NOT_TASKS and not m.name.startswith("_")]
    return sorted([EATING.name] + [n for n in others if isinstance(getattr(_module(n), "TASK", None), Task)])


def task_named(name: str) -> Task:
    """The ``TASK`` of module ``sim.task.<name>``. Raises ValueError naming the valid choices for any other name."""
    if name == EATING.name:
        return EATING
    names = task_names()
    if name not in names:
        raise ValueError(f"unknown task {name!r}; valid choices: {', '.join(names)}")
    return _module(name).TASK


def _module(name: str) -> object:
    return importlib.import_module(f"{__name__}.{name}")
