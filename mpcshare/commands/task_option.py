"""``--task NAME``: the task a command runs (:mod:`sim.task`), for the commands that read one.

NAME is a task module of :mod:`sim.task` (:func:`sim.task.task_names`) or a task outside the package,
``package.module:ATTR`` (``package.module``: its ``TASK``). A name that finds no task is a usage error
(exit status 2) naming the valid choices. ``mpcshare train`` records the name in the bundle
(``config["task"]``, :func:`bundle_task`); ``mpcshare sim`` runs the bundle's task unless told otherwise and
refuses another (:func:`task_for_bundle`).
"""

from __future__ import annotations

import argparse
from typing import Any

from mpcshare.commands.base import CommandError
from sim.task import DEFAULT_TASK, Task, task_named, task_names

__all__ = ["add_task_argument", "bundle_task", "chosen_task", "task_for_bundle", "task_spec"]


def task_spec(text: str) -> str:
    """argparse type: a name :func:`sim.task.task_named` finds a task by (returned as given)."""
    try:
        task_named(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def add_task_argument(p: argparse.ArgumentParser, default: str | None = DEFAULT_TASK, default_words: str = "") -> None:
    """``--task NAME`` (module docstring); ``default_words`` says what None (no ``--task``) means."""
    p.add_argument("--task", type=task_spec, default=default, metavar="NAME",
                   help=f"the task: {', '.join(task_names())}, or package.module:ATTR of your own "
                        f"(sim.task.Task; default {default_words or default})")


def chosen_task(args: argparse.Namespace) -> Task:
    """The task of ``args.task`` (:func:`add_task_argument`; :data:`sim.task.DEFAULT_TASK` where None)."""
    return task_named(getattr(args, "task", None) or DEFAULT_TASK)


def bundle_task(bundle: Any) -> str:
    """The name of the task ``bundle`` was trained for (``config["task"]``; a bundle that does not record one
    was trained for :data:`sim.task.DEFAULT_TASK`, the only task then)."""
    return str((getattr(bundle, "config", None) or {}).get("task") or DEFAULT_TASK)


def task_for_bundle(given: str | None, bundle: Any) -> Task:
    """The task to run ``bundle`` on: ``given`` (a ``--task``) or else the bundle's (:func:`bundle_task`).
    Raises :class:`CommandError` in one line where the bundle's task cannot be found or ``given`` names
    another task than the bundle's."""
    recorded = bundle_task(bundle)
    try:
        trained_for = task_named(recorded)
    except ValueError as exc:
        raise CommandError(f"the bundle was trained for task {recorded!r}, which cannot be loaded here: {exc}"
                           ) from None
    if given is None or given == recorded:
        return trained_for
    task = task_named(given)
    if task.name != trained_for.name:
        raise CommandError(f"--task {given}: the bundle was trained for task {recorded!r} "
                           f"(modes {', '.join(trained_for.mode_names)}); leave --task out, or train it again "
                           f"with --task {given}")
    return task
