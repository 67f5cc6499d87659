"""Reports of the analysis: ``report.json``, a readable ``report.md`` and PNG plots.

Plots (all in the output folder):

- ``data_trial.png`` — a trial of demonstrations: fork, knife, voluntary channel, modes;
- ``quotients_trial.png`` — a trial's signals with its quotients over time, modes coloured;
- ``quotient_hist.png`` — histogram of quotients, with the share of points ≤ each K;
- ``segmentation.png`` — quotients within HMM modes vs within random segmentations;
- ``voluntary_share.png`` — per-trial voluntary share with and without modes;
- ``candidates.png`` — the search for missing information.

Figures are drawn with :class:`matplotlib.figure.Figure` directly (no pyplot, no
backend switch, nothing global): importing this module changes nothing in the process.
The schema of ``report.json`` is documented in ``docs/design.md``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from learning.analysis import AnalysisResult
from learning.analysis.report import AnalysisReport
from learning.atomic import atomic_open, write_json
from learning.data import Demonstrations
from learning.modes import match_modes
from mpcshare.reports.claims import claim_sentences, mixture_advice
from mpcshare.reports.style import legend_outside, mode_colour

__all__ = ["plot_demonstrations", "write_analysis_report", "fmt", "fmt_p", "fmt_p_value"]



def _mode_bands(ax, t: np.ndarray, labels: np.ndarray, names: Sequence[str | None] | None,
                alpha: float = 0.15) -> None:
    """Shade the background of ``ax`` by mode label, each mode in the colour of its name (``style``)."""
    if len(t) == 0:
        return
    change = np.flatnonzero(np.diff(labels) != 0) + 1
    starts = np.r_[0, change]
    ends = np.r_[change, len(labels)]
    for a, b in zip(starts, ends):
        k = int(labels[a])
        if k < 0:
            continue
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color=mode_colour(k, names), alpha=alpha, lw=0)


def _mode_legend(ax, labels: np.ndarray, names: Sequence[str | None] | None, title: str,
                 texts: Sequence[str] | None = None) -> None:
    """A legend of the modes present, outside the data, above the panel ``ax``."""
    from matplotlib.patches import Patch

    ks = [int(k) for k in np.unique(labels) if k >= 0]
    texts = texts or names
    handles = [Patch(color=mode_colour(k, names), alpha=0.4,
                     label=texts[k] if texts is not None and k < len(texts) and texts[k] else f"mode {k}")
               for k in ks]
    if handles:
        ax.legend(handles=handles, title=title, loc="lower left", bbox_to_anchor=(0.0, 1.02), fontsize=7,
                  title_fontsize=7, ncol=len(handles), frameon=False)


def plot_demonstrations(demos: Demonstrations, path: Path, *, mode_names: Sequence[str] | None = None,
                        trial_index: int = 0, seconds: float = 60.0) -> None:
    """Plot the first ``seconds`` of one trial: fork, knife, voluntary channel, modes."""
    tr = demos[trial_index]
    n = min(len(tr), max(2, int(seconds * demos.rate_hz)))
    t = tr.t[:n] - tr.t[0]
    rows = [("fork position [m]", tr.obs[:n, :3], demos.obs_names[:3]),
            ("fork force [N]", tr.obs[:n, 6:9], demos.obs_names[6:9]),
            ("knife position [m]", tr.act[:n, :3], demos.act_names[:3]),
            ("knife orientation [rad]", tr.act[:n, 3:6], demos.act_names[3:6])]
    if tr.voluntary is not None:
        rows.append(("voluntary [rad]", tr.voluntary[:n], demos.vol_names))
    fig = Figure(figsize=(11, 1.9 * len(rows) + 0.5), layout="constrained")
    axes = fig.subplots(len(rows), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (title, y, names) in zip(axes, rows):
        for c in range(y.shape[1]):
            ax.plot(t, y[:, c], lw=0.9, label=names[c] if c < len(names) else str(c))
        if tr.mode is not None:
            _mode_bands(ax, t, tr.mode[:n], mode_names)
        ax.set_ylabel(title, fontsize=8)
        legend_outside(ax)
    if tr.mode is not None:
        _mode_legend(axes[0], tr.mode[:n], mode_names, "true mode")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"trial {tr.trial_id} (subject {tr.subject}), first {t[-1]:.0f} s")
    fig.savefig(path, dpi=110)


def _log_q(q: np.ndarray) -> np.ndarray:
    """log10 of quotients with 0 → the smallest positive and inf → above the largest finite."""
    q = np.asarray(q, dtype=float)
    finite_pos = q[np.isfinite(q) & (q > 0)]
    lo = finite_pos.min() if finite_pos.size else 1e-3
    hi = finite_pos.max() * 10 if finite_pos.size else 1e3
    return np.log10(np.clip(np.where(np.isinf(q), hi, q), lo, hi))


def _plot_trial_quotients(r: AnalysisResult, path: Path, mode_names: Sequence[str] | None,
                          channel_names: tuple[Sequence[str], Sequence[str]] | None = None) -> None:
    """A trial's standardised fork and knife channels (named when ``channel_names`` = (obs, act) is
    given) and its quotients over time; background: HMM modes in the colour of the true mode they match."""
    w = r.windows
    tid = w.trial[0]
    sel = w.trial == tid
    n = min(int(sel.sum()), int(90 * w.rate_hz))
    idx = np.flatnonzero(sel)[:n]
    t = w.t[idx] - w.t[idx[0]]
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    obs_names, act_names = channel_names or ((), ())
    for ax, y, names, what in ((axes[0], w.lag(0)[idx] * math.sqrt(w.lags), obs_names, "fork"),
                               (axes[1], w.Y[idx], act_names, "knife")):
        for c in range(y.shape[1]):
            ax.plot(t, y[:, c], lw=0.8, label=names[c] if c < len(names) else f"{what} {c}")
        ax.set_ylabel(f"{what} (standardised)", fontsize=8)
        legend_outside(ax, fontsize=6)
    axes[2].semilogy(t, np.maximum(r.q[idx], 1e-3), lw=0.9, color="k", label="without modes")
    axes[2].semilogy(t, np.maximum(r.q_modes[idx], 1e-3), lw=0.9, color="tab:purple", label="within HMM modes")
    for K in r.config.K:
        axes[2].axhline(K, ls="--", lw=0.8, color="0.4")
        axes[2].text(t[-1], K, f" K={K:g}", va="center", fontsize=7, color="0.3")
    axes[2].set_ylabel("quotient q", fontsize=8)
    legend_outside(axes[2])
    colour_names: list[str | None] | None = None
    texts = None
    if r.true_modes is not None and mode_names is not None:  # an HMM mode takes its best match's name
        match = match_modes(r.modes, r.true_modes)
        colour_names = [mode_names[match[k]] if match.get(k, -1) >= 0 else None for k in range(r.config.n_modes)]
        texts = [f"{k} ≈ {c}" if c else str(k) for k, c in enumerate(colour_names)]
    for ax in axes:
        _mode_bands(ax, t, r.modes[idx], colour_names)
    _mode_legend(axes[0], r.modes[idx], colour_names, "HMM mode", texts)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"trial {tid}: signals and point-wise Lipschitz quotients (background: HMM modes)")
    fig.savefig(path, dpi=110)


def _plot_histogram(r: AnalysisResult, path: Path) -> None:
    fig = Figure(figsize=(8, 4.5))
    ax = fig.subplots()
    bins = np.linspace(min(_log_q(r.q).min(), _log_q(r.q_modes).min()),
                       max(_log_q(r.q).max(), _log_q(r.q_modes).max()), 80)
    ax.hist(_log_q(r.q), bins=bins, alpha=0.55, label="without modes")
    ax.hist(_log_q(r.q_modes), bins=bins, alpha=0.55, label="within HMM modes")
    top = ax.get_ylim()[1]
    for i, K in enumerate(r.config.K):
        x = math.log10(K)
        ax.axvline(x, ls="--", color="tab:red", lw=1)
        ax.text(x, top * (0.97 - 0.07 * i),
                f" K={K:g}: {100 * np.mean(r.q <= K):.0f}% / {100 * np.mean(r.q_modes <= K):.0f}% ≤ K",
                fontsize=8, color="tab:red", va="top", bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
    ax.set_xlabel("log10 q")
    ax.set_ylabel("points")
    ax.set_title("point-wise Lipschitz quotients (share of points satisfying each K: without / with modes)",
                 fontsize=9)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _plot_segmentation(r: AnalysisResult, path: Path) -> None:
    fig = Figure(figsize=(8, 4.5))
    ax = fig.subplots()
    t = r.summary.segmentation_test
    for q, label in ((r.q, "no segmentation"), (r.q_random.ravel(), "random segmentations"),
                     (r.q_reference, f"reference ({t.reference})"), (r.q_modes, "HMM modes")):
        x = np.sort(_log_q(q))
        ax.plot(x, np.arange(1, len(x) + 1) / len(x), label=label)
    ax.set_title(f"HMM vs {t.reference} reference: median q {t.hmm_median_q:.2f} vs "
                 f"{t.reference_median_q:.2f}; Wilcoxon over {t.n_trials} trials {fmt_p(t.p_value)}",
                 fontsize=9)
    ax.set_xlabel("log10 q")
    ax.set_ylabel("cumulative share of points")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _plot_shares(r: AnalysisResult, path: Path) -> None:
    Ks = sorted(r.shares)
    fig = Figure(figsize=(4.5 * len(Ks), 4))
    axes = fig.subplots(1, len(Ks), squeeze=False)
    for ax, K in zip(axes[0], Ks):
        ids, without, with_modes = r.shares[K]
        for a, b in zip(without, with_modes):
            ax.plot([0, 1], [100 * a, 100 * b], color="0.6", lw=0.8)
        ax.plot([0, 1], [100 * np.mean(without), 100 * np.mean(with_modes)], "o-", color="k", lw=2,
                label="mean")
        ax.set_xticks([0, 1], ["without modes", "with modes"])
        ax.set_ylabel("voluntary share [%]")
        ax.set_title(f"K = {K:g} ({len(ids)} trials)")
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _plot_candidates(r: AnalysisResult, path: Path) -> None:
    c = r.summary.candidates
    fig = Figure(figsize=(8, 0.3 * len(c) + 1.5))
    ax = fig.subplots()
    labels = [f"{x.window_s:g} s, {x.n_modes} modes" for x in c]
    ax.barh(range(len(c)), [x.gain_beyond_reference_log10 for x in c], color="tab:blue")
    ax.set_yticks(range(len(c)), labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("median over trials of log10(median q reference / median q modes)")
    ax.set_title("search for missing information (higher: modes explain more than a time-free grouping)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def fmt(x: float | None) -> str:
    """A quotient for people: 3 significant digits, None (JSON for infinity) as 'inf'."""
    return "inf" if x is None else f"{x:.3g}"


def fmt_p_value(p: float, digits: int = 2) -> str:
    """A p-value for a table cell: ``"3.1e-05"``; an underflowed 0 as ``"< 1e-300"``.

    scipy returns exactly 0 when the p-value is below the smallest float64; "0"
    would claim certainty.
    """
    return "< 1e-300" if p == 0 else f"{p:.{digits}g}"


def fmt_p(p: float, digits: int = 2) -> str:
    """A p-value in a sentence: ``"p = 3.1e-05"``, or ``"p < 1e-300"`` (see ``fmt_p_value``)."""
    value = fmt_p_value(p, digits)
    return f"p {value}" if value.startswith("<") else f"p = {value}"


def _markdown(report: AnalysisReport, mode_names: Sequence[str] | None) -> str:
    q, m, t = report.quotients, report.modes, report.segmentation_test
    lines = [
        "# Predictability report",
        "",
        f"{report.n_samples} samples in {report.n_trials} trials after preprocessing "
        f"({report.rate_hz:g} Hz, {report.scope} scaling, causal window {report.window_s:g} s = "
        f"{report.lags} lags; input dimension {report.input_dim}, output dimension {report.output_dim}).",
        "",
        "## Point-wise Lipschitz quotients without modes",
        "",
        f"median {fmt(q.p50)}, p90 {fmt(q.p90)}, p99 {fmt(q.p99)}, max {fmt(q.max)} "
        f"({q.n_inf} infinite: identical observations, different actions).",
        "",
        "| percentile | K |", "|---|---|",
        *[f"| {p} | {fmt(v)} |" for p, v in (q.K_by_percentile or {}).items()],
        "",
        "![quotients over a trial](quotients_trial.png)",
        "",
        "![histogram](quotient_hist.png)",
        "",
        "## Task modes (HMM)",
        "",
        f"{m.n_modes} modes; occupancy " + ", ".join(f"{100 * o:.0f}%" for o in m.occupancy) + ".",
    ]
    if m.restart_logliks:
        ll = m.restart_logliks
        lines.append(f"EM restarts: {len(ll)}, training log-likelihoods {min(ll):.6g} … {max(ll):.6g} nats "
                     f"(spread {max(ll) - min(ll):.3g}; the best without empty states is kept).")
        if m.restart_ari:
            lines.append(f"Partitions of the restarts against the kept one: adjusted Rand index "
                         f"{min(m.restart_ari):.3f} … {max(m.restart_ari):.3f} (1: the same modes whatever the start).")
    if m.agreement is not None:
        lines.append(f"Agreement with the ground-truth labels: **{100 * m.agreement:.1f} %** "
                     f"(Hungarian matching), adjusted Rand index {m.ari:.3f}.")
    lines += ["", *_claim_lines(t), "", "![segmentation](segmentation.png)", "",
              "## Voluntary share per trial", "",
              f"| K | without modes | with modes | reference ({t.reference}) | random groups | fold | "
              "p (modes < reference) | p (modes < random) |",
              "|---|---|---|---|---|---|---|---|"]
    for K, v in report.voluntary_share.items():
        fold = f"{v.fold_reduction:.2f}×" if v.fold_reduction is not None else "–"
        lines.append(f"| {K} | {100 * v.without_modes:.1f} % | {100 * v.with_modes:.1f} % | "
                     f"{100 * v.reference:.1f} % | {100 * v.random:.1f} % | {fold} | "
                     f"{fmt_p_value(v.p_value)} | {fmt_p_value(v.p_value_vs_random)} |")
    lines += ["", "Shares are means over trials; the tests are one-sided Wilcoxon signed-rank tests over "
              "trials. (Within any grouping quotients can only fall, so the comparison is against another "
              "grouping with the same number of groups, not against the data without modes.)", "",
              "![voluntary share](voluntary_share.png)", ""]
    if report.candidates:
        lines += ["## Search for missing information", "",
                  "Ranked by the gain beyond the time-free reference: the median over trials of "
                  "log10(per-trial median q within the reference / within the modes).", "",
                  "| rank | window [s] | modes | median q (none / modes / reference / random) | "
                  "gain beyond reference (log10) | p | gain beyond random (log10) |",
                  "|---|---|---|---|---|---|---|"]
        for c in report.candidates:
            lines.append(f"| {c.rank} | {c.window_s:g} | {c.n_modes} | "
                         f"{c.median_q_without_modes:.3g} / {c.median_q_modes:.3g} / "
                         f"{c.median_q_reference:.3g} / {c.median_q_random:.3g} | "
                         f"{c.gain_beyond_reference_log10:.3f} | {fmt_p_value(c.p_value)} | "
                         f"{c.gain_beyond_random_log10:.3f} |")
        lines += ["", "![candidates](candidates.png)", ""]
    sel = report.mode_selection
    if sel is not None:
        lines += ["## Number of modes by held-out likelihood", "",
                  "| modes | held-out log-lik per sample | BIC |", "|---|---|---|",
                  *[f"| {k} | {ll:.4g} | {b:.5g} |" for k, ll, b in
                    zip(sel.candidates, sel.heldout_loglik, sel.bic)], "",
                  f"Chosen: {sel.n_modes} ({sel.rule} rule, {sel.n_folds}-fold by trial); "
                  f"held-out maximum {sel.n_modes_max}, BIC minimum {sel.n_modes_bic}.", ""]
    lines += ["", "Time per stage: " + ", ".join(f"{k} {v:.1f} s" for k, v in report.timings_s.items()) + ".", ""]
    return "\n".join(lines)


def _claim_lines(t) -> list[str]:
    """The two claims in words (one line each), the advice they give, then what was compared."""
    seg = t.to_dict()
    lines = ["### What the modes add: two claims, each with its own test", "",
             *[f"- {line}" for line in claim_sentences(seg)]]
    advice = mixture_advice(seg)
    if advice:
        lines += ["", advice]
    return lines + [
        "",
        f"Compared: the median quotient of each trial within the HMM modes against within random groups of "
        f"equal sizes ({t.n_random} groupings, {t.random_method}; the paper's test) and against within the "
        f"*{t.reference}* reference, a grouping of the same per-sample features into as many groups that uses "
        f"no temporal information. Units: the {t.n_trials} trials (one-sided Wilcoxon signed-rank tests of "
        f"ln(reference / HMM) minus the smallest effect of interest). The second claim also needs the modes to "
        f"beat random groups by more than {100 * (np.exp(t.min_effect) - 1):.0f} % "
        f"({fmt_p(t.random_p_value, 3)}; its p is the larger of the two, {fmt_p(t.p_value, 3)}): on confounded "
        "data random thinning can beat a spatial grouping. Any grouping coherent in observation space beats "
        "random groups a little, so the first claim needs a larger effect "
        f"({100 * (np.exp(seg['claims']['modes_help']['min_effect']) - 1):.0f} %).",
        "",
        f"Median q over all windows: {t.hmm_median_q:.3g} within HMM modes, {t.reference_median_q:.3g} within "
        f"the reference, {t.random_median_q:.3g} within random groups of equal sizes.",
    ]


def write_analysis_report(result: AnalysisResult, out: Path, *, mode_names: Sequence[str] | None = None,
                          channel_names: tuple[Sequence[str], Sequence[str]] | None = None) -> None:
    """Write report.json, report.md and the plots of an analysis into ``out`` (``channel_names``:
    the data's obs and act names, to label the plotted channels)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _plot_trial_quotients(result, out / "quotients_trial.png", mode_names, channel_names)
    _plot_histogram(result, out / "quotient_hist.png")
    _plot_segmentation(result, out / "segmentation.png")
    _plot_shares(result, out / "voluntary_share.png")
    if result.summary.candidates:
        _plot_candidates(result, out / "candidates.png")
    md = _markdown(result.summary, mode_names)
    with atomic_open(out / "report.md", "w") as f:
        f.write(md)
    write_json(result.summary.to_dict(), out / "report.json", non_finite="raise")
