"""The benchmarks' worlds by name: ``family:<seed>`` (:mod:`sim.world_family`), a data kind of
``benchmarks/bench_task.py`` (``default``, ``other_seed``, ``other_structure``) or ``default:<seed>`` (the default
data of another seed), shared by ``bench_family.py``, ``bench_choice_gap.py`` and ``bench_splice_bound.py``."""

from __future__ import annotations

from typing import Any


def world_data(world: str, quick: bool) -> tuple[Any, tuple[str, ...], dict[str, Any]]:
    """(demonstrations, mode names, description) of ``family:<seed>``, ``default:<seed>`` or a bench_task data
    kind."""
    if world.startswith("family:"):
        from sim.world_family import world_demonstrations

        demos, spec = world_demonstrations(int(world.split(":")[1]), n_trials=12 if quick else 16,
                                           trial_s=40.0 if quick else 60.0)
        info = {"kinds": list(spec.kinds), "stroke_hz": spec.stroke_hz, "stroke_amp_mm": 1e3 * spec.stroke_amp_m,
                "knife_delay_s": spec.knife_delay_s, "act_noise_mm": 1e3 * spec.act_noise_m}
        return demos, spec.mode_names, info
    from sim.task.eating import MODE_NAMES

    if world.startswith("default:"):  # the default data of another seed (the demo's --data-seed)
        from sim.demonstrator import generate_demonstrations

        return generate_demonstrations(seed=int(world.split(":")[1])), MODE_NAMES, {}
    from bench_task import make_data

    return make_data(world), MODE_NAMES, {}
