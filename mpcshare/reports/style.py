"""How every plot of the project looks: one colour per task mode and per strategy, legends outside
the data, strategy names a person can read (horizontal bars).

One mapping in one place: a mode has the same colour in the data plot, the quotient plot, the
trial plot of the closed loop and the video; a strategy the same colour in the comparison, the
effort–error plot and ``tune``'s Pareto plot. Modes are coloured by *name*, from the
``mode_colours`` of the :class:`sim.task.Task` (the task shipped: :data:`sim.task.eating.MODE_COLOURS`,
which the video in ``sim`` draws with too); a mode without a colour (an HMM mode no true mode matches)
gets a grey of its own.
"""

from __future__ import annotations

from typing import Any, Sequence

from mpcshare.run_table import RUN_COLORS
from sim.task import EATING, Task

__all__ = ["number", "STRATEGY_COLOURS", "legend_outside", "mode_colour", "strategy_colour",
           "strategy_ticks"]

_UNNAMED = ("#8C8C8C", "#B0B0B0", "#6E6E6E", "#C8C8C8", "#5A5A5A", "#A0A0A0", "#7C7C7C", "#BEBEBE")

#: strategy (run) name → colour: the registry's colours (``mpcshare.run_table.RUN_COLORS``), one table
STRATEGY_COLOURS: dict[str, str] = RUN_COLORS


def mode_colour(label: int, names: Sequence[str] | None = None, task: Task = EATING) -> str:
    """The colour of mode ``label``: by its name in ``names`` (``task.mode_colours``), else a grey."""
    k, colours = int(label), task.mode_colours
    if names is not None and 0 <= k < len(names) and names[k] in colours:
        return colours[names[k]]
    return _UNNAMED[k % len(_UNNAMED)]


def strategy_colour(name: str) -> str:
    """The colour of a strategy (run) name (the registry's); anything else black."""
    return STRATEGY_COLOURS.get(name, "#222222")


def strategy_ticks(ax: Any, names: Sequence[str]) -> None:
    """Legible strategy names on the y axis of a horizontal bar chart (one a row, underscores as spaces)."""
    ax.set_yticks(range(len(names)), [n.replace("_", " ") for n in names], fontsize=8)


def legend_outside(ax: Any, **kwargs: Any) -> Any:
    """A legend to the right of ``ax``, outside the data (the figure should use a constrained layout)."""
    kwargs.setdefault("fontsize", 7)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False, **kwargs)


def number(x: Any, spec: str = ".1f", scale: float = 1.0) -> str:
    """``x·scale`` formatted by ``spec`` for a table or sentence: "–" for None or non-finite, and never
    "-0.0" (a value that rounds to zero is written without a sign)."""
    import math

    if x is None or not isinstance(x, (int, float)) or not math.isfinite(x):
        return "–"
    text = format(float(x) * scale, spec)
    return text.lstrip("-") if text.startswith("-") and float(text) == 0.0 else text
