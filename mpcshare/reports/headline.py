"""The four answers a person wants first, one line each with its figure and a word of verdict.

1. **The task** — did the knife saw while cutting (stroke correlation and amplitude against
   the intended stroke, :data:`SAWING_TARGET`)?
2. **Sharing** — did the shared strategy track the wearer's intent better than the wearer
   alone (``voluntary``), the robot alone (``reactive``) and mixing the two (the *line ratio*:
   tracking RMS over the straight ``reactive``–``voluntary`` line at the same effort, below 1
   beats mixing)?
3. **Effort** — how much of the wearer's effort did it save (against ``voluntary``)?
4. **Keep-out** — did the knife stay out of the wearer's body zones?

Read from ``comparison.json``'s ``strategies`` (name → metrics). Keys that newer versions add
are used when present: ``line_ratio`` (else computed here from ``voluntary`` and ``reactive``
with the same definition), the clearance figures (any key with ``clearance`` in its name, in
metres, and any with ``driven_in`` or ``intrusion``: control steps the knife was driven into a
zone); without them the keep-out line says it was not measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mpcshare.line_ratio import add_line_ratios
from sim.task_metrics import SAWING_MIN_AMPLITUDE, SAWING_MIN_CORRELATION

__all__ = ["SAWING_TARGET", "SHARED_STRATEGIES", "Headline", "headline_lines", "headlines", "line_ratio",
           "shared_strategy"]

SAWING_TARGET = (SAWING_MIN_AMPLITUDE, SAWING_MIN_CORRELATION)  # amplitude ratio and correlation that count as sawing
EFFORT_TARGET = 0.75  # the shared strategy's effort, at most this share of the wearer's alone (docs/design.md)
#: which run is "sharing" in the headline: the first of these present
SHARED_STRATEGIES = ("gate", "paper_gate", "blend")
_TIE = 0.02  # relative difference in tracking RMS read as a tie


@dataclass(frozen=True)
class Headline:
    """One answer: ``topic`` (The task, Sharing, Effort, Keep-out), its ``verdict`` word(s) and the ``text``."""

    topic: str
    verdict: str
    text: str

    def markdown(self) -> str:
        return f"**{self.topic}: {self.verdict}.** {self.text[:1].upper()}{self.text[1:]}"

    def plain(self) -> str:
        """The line for a terminal: no Markdown."""
        return f"{self.topic}: {self.verdict}. {self.text[:1].upper()}{self.text[1:]}".replace("`", "")


def _finite(x: Any) -> bool:
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x)


def shared_strategy(strategies: dict[str, dict[str, Any]]) -> str | None:
    """The run the headline calls *sharing*: the first of :data:`SHARED_STRATEGIES` present."""
    return next((s for s in SHARED_STRATEGIES if s in strategies), None)


def line_ratio(strategies: dict[str, dict[str, Any]], name: str) -> float | None:
    """``name``'s tracking RMS over the voluntary–reactive line's at ``name``'s effort.

    The metrics' own ``line_ratio`` when they have one, else :func:`mpcshare.line_ratio.add_line_ratios`
    from the ``voluntary`` and ``reactive`` runs (the definition, ends included); None when an end
    of the line is missing.
    """
    m = strategies.get(name, {})
    if _finite(m.get("line_ratio")):
        return float(m["line_ratio"])
    if "voluntary" not in strategies or "reactive" not in strategies or name not in strategies:
        return None
    ratios = add_line_ratios({k: dict(strategies[k]) for k in ("voluntary", "reactive", name)})
    return ratios[name]["line_ratio"]


def _task(name: str, m: dict[str, Any]) -> Headline:
    amp, corr, lag = m.get("saw_amplitude_ratio"), m.get("saw_correlation"), m.get("lag_s")
    lag_text = f" The knife follows the wearer's intent {lag * 1e3:.0f} ms late." if _finite(lag) else ""
    if not (_finite(amp) and _finite(corr)):
        return Headline("The task", "not shown", f"no cutting in these trials, so no sawing to judge.{lag_text}")
    cut = amp >= SAWING_TARGET[0] and corr >= SAWING_TARGET[1]
    return Headline("The task", "yes, it cut" if cut else "NO, it did not saw",
                    f"while cutting, the knife's stroke under `{name}` correlates {corr:.2f} with the intended "
                    f"stroke at {amp:.2f} of its amplitude (sawing needs a correlation of at least "
                    f"{SAWING_TARGET[1]:g} and an amplitude of at least {SAWING_TARGET[0]:g}).{lag_text}")


def _compare(mine: float, other: float) -> str:
    rel = mine / other if other > 0 else math.inf
    return "tie" if abs(rel - 1) <= _TIE else ("beat" if rel < 1 else "lost")


def _sharing(name: str, s: dict[str, dict[str, Any]]) -> Headline:
    mine = s[name]["tracking_rmse_m"]
    parties = [(label, key) for label, key in (("the wearer alone", "voluntary"), ("the robot alone", "reactive"))
               if key in s and _finite(s[key].get("tracking_rmse_m"))]
    outcome = {label: _compare(mine, s[key]["tracking_rmse_m"]) for label, key in parties}
    ratio = line_ratio(s, name)
    if ratio is not None:
        outcome["mixing them"] = "tie" if abs(ratio - 1) <= _TIE else ("beat" if ratio < 1 else "lost")
    figures = "; ".join(f"{label} {s[key]['tracking_rmse_m'] * 1e3:.1f} mm" for label, key in parties)
    line = "" if ratio is None else (f" Line ratio {ratio:.2f} (tracking RMS over mixing the two at the same "
                                     "effort; below 1 beats mixing).")
    lost = [k for k, v in outcome.items() if v == "lost"]
    beat = [k for k, v in outcome.items() if v == "beat"]
    if not outcome:
        verdict = "not measured"
    elif lost:
        verdict = "NO, it loses to " + " and ".join(lost)
    elif len(beat) == len(outcome):
        verdict = "yes, it beats " + ", ".join(beat)
    else:
        verdict = "partly: it ties with " + " and ".join(k for k, v in outcome.items() if v == "tie")
    return Headline("Sharing", verdict, f"`{name}` tracks the wearer's intent at {mine * 1e3:.1f} mm RMS"
                    + (f" ({figures})." if figures else ".") + line)


def _effort(name: str, s: dict[str, dict[str, Any]]) -> Headline | None:
    if "voluntary" not in s or not _finite(s["voluntary"].get("voluntary_effort")):
        return None
    alone, mine = s["voluntary"]["voluntary_effort"], s[name]["voluntary_effort"]
    if not (_finite(mine) and alone > 0):
        return Headline("Effort", "not measured", "the wearer's effort alone is zero in these runs.")
    r = mine / alone
    verdict = (f"{1 - r:.0%} saved" if r <= EFFORT_TARGET else
               (f"only {1 - r:.0%} saved" if r < 1 else "NONE saved"))
    return Headline("Effort", verdict, f"under `{name}` the wearer works {r:.0%} as hard as alone "
                    f"({mine:.3f} against {alone:.3f} rad, mean shoulder angle from rest; the target is at most "
                    f"{EFFORT_TARGET:.0%}).")


def _keepout(s: dict[str, dict[str, Any]]) -> Headline:
    clear = [v for m in s.values() for k, v in m.items() if "clearance" in k and k.endswith("_m") and _finite(v)]
    driven = [v for m in s.values() for k, v in m.items()
              if ("driven_in" in k or "intrusion" in k) and _finite(v)]
    if not clear and not driven:
        return Headline("Keep-out", "not measured", "these runs have no keep-out zones around the wearer's body, "
                        "so no clearance was recorded.")
    n = int(sum(driven))
    closest = f" The knife came no closer than {min(clear) * 1e3:.0f} mm to a body zone." if clear else ""
    if n == 0:
        return Headline("Keep-out", "yes, it kept out",
                        f"the knife was driven into a body zone in 0 control steps, under every strategy.{closest}")
    return Headline("Keep-out", "NO", f"the knife was driven into a body zone in {n} control step(s).{closest}")


def headlines(strategies: dict[str, dict[str, Any]]) -> list[Headline]:
    """The four answers (module docstring) for the runs present; [] when no shared strategy was run."""
    name = shared_strategy(strategies)
    if name is None:
        return []
    out = [_task(name, strategies[name]), _sharing(name, strategies)]
    effort = _effort(name, strategies)
    if effort is not None:
        out.append(effort)
    out.append(_keepout(strategies))
    return out


def headline_lines(strategies: dict[str, dict[str, Any]], markdown: bool = True) -> list[str]:
    """:func:`headlines` as Markdown (bold topic and verdict) or plain text lines."""
    return [h.markdown() if markdown else h.plain() for h in headlines(strategies)]
