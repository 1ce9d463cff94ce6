"""A sand with a state: the scene table `[materials.NAME.state]` and its consistency checks.

The void ratio e is a material property (e0 at the start; afterwards de / (1 + e) is the plastic
volumetric strain: the grains' rearrangement, not the elastic strain of the skeleton, which the seed
makes softer than sand's). The sand carries a critical-state
line e_c(p') = e_Gamma - lambda_c (p' / p_a)^xi (Li & Wang 1998), its state parameter is
psi_s = e - e_c(p') (Been & Jefferies 1985), and its peak friction and dilatancy follow Bolton's
(1986) relative dilatancy index referred to that line (solver/physics/sand_state.py, docs/sand.md).
Defaults: Toyoura sand (Li & Wang 1998; Cubrinovski & Ishihara 2002) and Bolton's Q = 10.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, model_validator

Positive = Annotated[float, Field(gt=0)]


class SandState(BaseModel):
    """The state of a critical-state sand; every key but void_ratio has Toyoura sand's value."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    void_ratio: Positive  # e0, the void ratio at the start
    min_void_ratio: Positive = 0.616  # e_min, Toyoura sand (Cubrinovski & Ishihara 2002)
    max_void_ratio: Positive = 0.988  # e_max, Toyoura sand (Cubrinovski & Ishihara 2002)
    # critical-state line e_c = e_Gamma - lambda_c (p' / p_a)^xi: Toyoura sand (Li & Wang 1998, fitted to
    # Verdugo & Ishihara 1996)
    critical_void_ratio: Positive = 0.934  # e_Gamma, e_c at p' = 0
    critical_lambda: Annotated[float, Field(ge=0.0)] = 0.019
    critical_xi: Positive = 0.7
    reference_pressure: Positive = 101.0e3  # p_a (Pa)
    # Bolton (1986): I_R = I_D (Q - ln p'[kPa]) - R, Q = 10 for quartz and feldspar sands (ln of the grains'
    # crushing stress in kPa); R is replaced by the critical-state line above (docs/sand.md)
    bolton_q: Positive = 10.0

    @model_validator(mode="after")
    def _consistent(self):
        if self.min_void_ratio >= self.max_void_ratio:
            raise ValueError(
                f"min_void_ratio ({self.min_void_ratio:g}) must be below max_void_ratio "
                f"({self.max_void_ratio:g})"
            )
        if not self.min_void_ratio <= self.void_ratio <= self.max_void_ratio:
            raise ValueError(
                f"void_ratio {self.void_ratio:g} lies outside the sand's e_min-e_max "
                f"[{self.min_void_ratio:g}, {self.max_void_ratio:g}]: no packing of this sand has it "
                "(cap it at the limit and say so in the scene)"
            )
        crushing = crushing_pressure(self)
        e_c = critical_void_ratio(self, crushing)
        if e_c <= 0.0:
            raise ValueError(
                f"the critical-state line crosses zero below the crushing stress exp(Q) kPa = "
                f"{crushing / 1e6:.3g} MPa (e_c = {e_c:.3g} there): a void ratio cannot be negative"
            )
        return self


def crushing_pressure(state: SandState) -> float:
    """Bolton's Q is ln of the grains' crushing stress in kPa: p'_crush = exp(Q) kPa (Pa here)."""
    return 1e3 * math.exp(state.bolton_q)


def critical_void_ratio(state: SandState, p: float) -> float:
    """e_c(p') = e_Gamma - lambda_c (p'/p_a)^xi (Li & Wang 1998), p' in Pa."""
    return state.critical_void_ratio - state.critical_lambda * (max(p, 0.0) / state.reference_pressure) ** (
        state.critical_xi
    )


def void_ratio_of_porosity(n: float) -> float:
    """e = n / (1 - n)."""
    return n / (1.0 - n)
