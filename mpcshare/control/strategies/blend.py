"""``blend`` (policy blending, Dragan & Srinivasa 2013): α continuous in the gate's calibrated
probability p, a linear ramp α = clip((p − p₀)/(p₁ − p₀), 0, 1) with (p₀, p₁) = ``blend_range``
(default (0.5, 0.9): no robot share below even odds, the whole share from 90 % confidence up);
β = 1 − α·(1 − β_user), the paper's β at α ∈ {0, 1}. The gate's overrides apply."""

from __future__ import annotations

from dataclasses import dataclass

from mpcshare.control.strategies.base import ArbiterView, StepInputs, StrategySpec, Target

__all__ = ["Blend", "BlendSettings", "SPECS"]


@dataclass(frozen=True)
class BlendSettings:
    """blend_range (p₀, p₁): the ramp's ends in the gate probability. ValueError unless 0 ≤ p₀ < p₁ ≤ 1."""

    blend_range: tuple[float, float] = (0.5, 0.9)

    def __post_init__(self) -> None:
        try:
            p0, p1 = (float(x) for x in self.blend_range)
        except (TypeError, ValueError):
            raise ValueError(f"blend_range must be two probabilities (p0, p1), got {self.blend_range!r}") from None
        if not 0.0 <= p0 < p1 <= 1.0:
            raise ValueError(f"blend_range must satisfy 0 <= p0 < p1 <= 1, got {self.blend_range!r}")
        object.__setattr__(self, "blend_range", (p0, p1))


class Blend:
    """α = clip((p − p₀)/(p₁ − p₀), 0, 1) (module docstring)."""

    overrides = True

    def __init__(self, blend_range: tuple[float, float]) -> None:
        self.p0, self.p1 = blend_range

    def reset(self) -> None:
        """No state."""

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        p = float(inputs.gate_proba)  # type: ignore[arg-type]  # finite: the overrides ran first
        a = min(max((p - self.p0) / (self.p1 - self.p0), 0.0), 1.0)
        return Target(a, f"blend of gate probability {p:.2f}")


SPECS = (StrategySpec("blend", "Policy blending: alpha rises linearly with the gate's probability.", tunable=True,
                      color="#ff7f0e", factory=lambda ctx: Blend(ctx.settings.blend_range), order=6, role="shared",
                      settings=BlendSettings),)
