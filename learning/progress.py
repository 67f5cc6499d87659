"""Progress bars for a person at a terminal: the one rule every bar of the project follows.

A bar draws only when it is asked for and its stream (stderr unless ``file=`` says otherwise)
is a terminal, or in a notebook (``tqdm.auto``'s widget writes no control codes). Output
redirected to a file or a pipe gets no bar: a log holds lines, never carriage returns.
"""

from __future__ import annotations

import sys
from typing import Any, Iterable

__all__ = ["progress_bar", "shows_progress"]


def shows_progress(file: Any = None) -> bool:
    """Whether a bar on ``file`` (None: ``sys.stderr``) would be seen: a terminal, or a notebook."""
    from tqdm.auto import tqdm as auto
    from tqdm.notebook import tqdm as notebook

    if issubclass(auto, notebook):  # a notebook's widget
        return True
    stream = sys.stderr if file is None else file
    isatty = getattr(stream, "isatty", None)
    return bool(isatty is not None and isatty())


def progress_bar(iterable: Iterable[Any] | None = None, *, enabled: bool = True, **kwargs: Any) -> Any:
    """A ``tqdm.auto`` bar over ``iterable`` (or with ``total=``), drawn only when ``enabled`` and
    :func:`shows_progress`; otherwise a silent one that still counts and iterates."""
    from tqdm.auto import tqdm

    on = enabled and shows_progress(kwargs.get("file"))
    return tqdm(iterable, disable=not on, **kwargs)
