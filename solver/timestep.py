"""Time step from the constraints a scene activates: seed eqs. (28)-(30).

    sound     dt <= C_s  min(h / c)            eq. (28), every scene
    force     dt <= C_f  min sqrt(h / |f|)     eq. (29), every scene
    viscous   dt <= C_v  min(h^2 / nu)         eq. (30), only when the viscous stress term is on
nu = mu / rho0 is the kinematic viscosity. Other physics (soil) adds its own constraint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Constraint:
    name: str
    equation: str
    constant_dt: float | None  # None: depends on the state (force)


class TimeStepper:
    def __init__(self, constraints: list[Constraint], h: float, cfl_force: float):
        self.constraints = constraints
        self.h = h
        self.cfl_force = cfl_force
        self.fixed = min((c.constant_dt for c in constraints if c.constant_dt is not None), default=math.inf)
        self.fixed_name = next((c.name for c in constraints if c.constant_dt == self.fixed), None)

    def __call__(self, max_acc: float, dynamic=()):
        """(dt, name of the limiting constraint); `dynamic`: (name, dt) of state-dependent limits."""
        dt_force = self.cfl_force * math.sqrt(self.h / max_acc) if max_acc > 0 else math.inf
        dt, name = (dt_force, "force") if dt_force < self.fixed else (self.fixed, self.fixed_name)
        for other, value in dynamic:
            if value < dt:
                dt, name = value, other
        return dt, name
