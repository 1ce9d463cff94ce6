"""Scene input for open boundaries and rigid bodies: `[[inlets]]`, `[[outlets]]`, `[[bodies]]`.

Kept out of solver/scene.py (which imports these models) so that the open-boundary input is one
concept in one file. Every default is in solver/defaults.toml (`[inlet_defaults]`,
`[outlet_defaults]`), filled into each inlet and outlet before validation; the physics is in
solver/physics/inlet.py, outlet.py and bodies.py.
"""

from __future__ import annotations

import copy
from enum import StrEnum
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]


class _Strict(BaseModel):
    # as solver/scene.py's Strict (which imports this module): no bool -> number or number -> str
    # coercion, finite floats only
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class Inlet(_Strict):
    """Water entering through a section at a unit discharge q (m^2/s in 2D, per unit width).

    2D: the section is the segment from `origin` along `across` (a unit vector after normalising)
    of length `width`; the water moves along `direction`. Without `width`, the section is a free
    overfall's critical section: y_c = (q^2/g)^(1/3) (Chow 1959, eq. 3-9), rounded to whole
    particle spacings so that q stays exact; without `speed`, u = q / (width (direction . normal))."""

    name: str
    material: str
    origin: list[float]
    direction: list[float]
    discharge: Positive  # q, m^2/s
    across: list[float] | None = None  # default: direction turned +90 degrees
    width: Positive | None = None  # default: the critical depth, in whole spacings
    speed: Positive | None = None  # default: q / (width * (direction . normal))
    layers: Annotated[int, Field(ge=1)]  # buffer layers (defaults.toml)
    prefill_time: NonNegative  # s of inflow already in free flight at t = 0 (defaults.toml)


class InletDefaults(_Strict):
    """`[inlet_defaults]` (solver/defaults.toml): what every inlet takes unless it sets it."""

    layers: Annotated[int, Field(ge=1)]
    prefill_time: NonNegative


class OutletKind(StrEnum):
    """What an outlet zone does with a particle that enters it (solver/physics/outlet.py)."""

    BUFFER = "buffer"  # frozen velocity and density until it leaves the zone, then removed
    DELETE = "delete"  # removed at once (a free overfall at the zone's face)


class Outlet(_Strict):
    """An outflow zone (a box): particles whose centre enters it are frozen and removed when they
    leave it (kind "buffer"), or removed at once (kind "delete"); the removed mass is counted."""

    name: str
    min: list[float]
    max: list[float]
    kind: Annotated[OutletKind, Field(strict=False)]  # default in defaults.toml ([outlet_defaults])
    materials: list[str] | None = None  # default: every material


class OutletDefaults(_Strict):
    """`[outlet_defaults]` (solver/defaults.toml): what every outlet takes unless it sets it."""

    kind: Annotated[OutletKind, Field(strict=False)]


class Body(_Strict):
    """A rigid obstacle bounded by a polygon (2D), kept impermeable by image particles across its
    edges (free slip, seed sec. 2.5). Vertices in either order."""

    name: str
    vertices: list[list[float]]


def fill_open_defaults(merged: dict) -> dict:
    """Each `[[inlets]]` entry gets the merged `[inlet_defaults]` values it does not set, each
    `[[outlets]]` entry the `[outlet_defaults]` ones (a scene's own defaults tables are honoured).
    Anything of the wrong shape is left for the schema to refuse."""
    merged = copy.deepcopy(merged)
    for entries, table in (("inlets", "inlet_defaults"), ("outlets", "outlet_defaults")):
        items, defaults = merged.get(entries), merged.get(table)
        if not isinstance(items, list) or not isinstance(defaults, dict):
            continue
        for item in items:
            if isinstance(item, dict):
                for key, value in defaults.items():
                    item.setdefault(key, value)
    return merged


def check_open_boundaries(s) -> list[tuple[str, str]]:
    """(key, reason) of the first inconsistency of inlets, outlets and bodies, or []."""
    dim = s.dim
    lo, hi = np.array(s.domain.min, float), np.array(s.domain.max, float)
    eps = 1e-9 * float(np.max(hi - lo))
    names = set(s.materials)
    for k, inlet in enumerate(s.inlets):
        key = f"inlets[{k}]"
        if dim != 2:
            return [(f"{key}", "inlets are implemented in 2D only")]
        if inlet.material not in names or s.materials[inlet.material].model != "water":
            return [(f"{key}.material", f"'{inlet.material}' is not a water material of the scene")]
        for field in ("origin", "direction") + (("across",) if inlet.across is not None else ()):
            vec = getattr(inlet, field)
            if len(vec) != dim:
                return [(f"{key}.{field}", f"needs {dim} components")]
        for field in ("direction",) + (("across",) if inlet.across is not None else ()):
            vec = np.asarray(getattr(inlet, field), float)
            if not np.all(np.isfinite(vec)):
                return [(f"{key}.{field}", "must be finite")]
            if not np.any(vec):
                return [(f"{key}.{field}", "must not be the zero vector")]
        if inlet.across is not None:
            d, a = unit(inlet.direction), unit(inlet.across)
            if abs(d[0] * a[1] - d[1] * a[0]) < 0.1:
                return [(f"{key}.across", "is (nearly) parallel to direction: no flow crosses the section")]
        o = np.asarray(inlet.origin, float)
        if np.any(o < lo - eps) or np.any(o > hi + eps):
            return [(f"{key}.origin", "lies outside the domain")]
        if np.linalg.norm(s.scene.gravity) == 0 and inlet.width is None:
            return [(f"{key}.width", "required without gravity (the critical depth needs g)")]
        bad = _inlet_extent(s, inlet, lo, hi, eps)
        if bad:
            return [(f"{key}.{bad[0]}", bad[1])]
    for k, outlet in enumerate(s.outlets):
        key = f"outlets[{k}]"
        if len(outlet.min) != dim or len(outlet.max) != dim:
            return [(f"{key}.min", f"needs {dim} components")]
        if np.any(np.asarray(outlet.max) <= np.asarray(outlet.min)):
            return [(f"{key}.max", "must be greater than min in every direction")]
        for m in outlet.materials or ():
            if m not in names:
                return [(f"{key}.materials", f"unknown material '{m}'")]
        thinnest = float(np.min(np.asarray(outlet.max, float) - np.asarray(outlet.min, float)))
        support = 2.0 * s.h  # the cubic spline's support radius (seed eq. 5)
        if outlet.kind == OutletKind.BUFFER and thinnest < support * (1 - 1e-9):
            return [
                (
                    f"{key}.max",
                    f"a buffer zone must be at least one kernel support 2h = {support:.4g} m thick in every "
                    f"direction (it is {thinnest:.4g} m): the fluid upstream must see a full kernel of "
                    'buffer particles (Federico et al. 2012); enlarge it or use kind = "delete"',
                )
            ]
    for k, body in enumerate(s.bodies):
        key = f"bodies[{k}]"
        if dim != 2:
            return [(f"{key}", "bodies are implemented in 2D only")]
        if len(body.vertices) < 3 or any(len(p) != 2 for p in body.vertices):
            return [(f"{key}.vertices", "needs three or more [x, y] points")]
        v = np.asarray(body.vertices, float)
        if not np.all(np.isfinite(v)):
            return [(f"{key}.vertices", "must be finite")]
        if abs(polygon_area(v)) < eps * eps:
            return [(f"{key}.vertices", "the polygon has no area")]
        if np.any(np.hypot(*(np.roll(v, -1, axis=0) - v).T) <= eps):
            return [(f"{key}.vertices", "two consecutive vertices coincide (an edge of zero length)")]
    return []


def unit(vector) -> np.ndarray:
    """A direction given as any finite non-zero vector, normalised without overflow (scaled by its
    largest component first: a component of 1e308 squares to inf)."""
    v = np.asarray(vector, float)
    v = v / np.max(np.abs(v))
    return v / np.linalg.norm(v)


def inlet_width(inlet, dx: float, g: float) -> float:
    """The width of an inlet's section as the inlet builds it (solver/physics/inlet.py): `width`, or
    the critical depth (q^2/g)^(1/3) of a free overfall (Chow 1959, eq. 3-9), either in whole spacings,
    at least one (so a tiny q gives one slow layer, never a section of zero width)."""
    if inlet.width is not None:
        return float(inlet.width)
    with np.errstate(over="ignore"):
        layers = round(min((inlet.discharge**2 / g) ** (1.0 / 3.0) / dx, 1e18))
    return max(1, layers) * dx


def _inlet_extent(s, inlet, lo, hi, eps):
    """(key, reason) if the section, its buffer or its prefill does not fit the domain, or the
    inflow is faster than the water's sound speed; else None. These bound the particles an inlet
    creates (a huge q, width, layer count or prefill time is refused, not allocated)."""
    dx = s.scene.spacing
    d = unit(inlet.direction)
    a = np.array([-d[1], d[0]]) if inlet.across is None else unit(inlet.across)
    cos = abs(a[0] * d[1] - a[1] * d[0])  # d . n, n the section's unit normal
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        width = inlet_width(inlet, dx, float(np.hypot(*s.scene.gravity)))
        key = "discharge" if inlet.width is None else "width"
        o = np.asarray(inlet.origin, float)
        ends = np.array([o, o + width * a])
        if not np.all(np.isfinite(ends)) or np.any(ends < lo - eps) or np.any(ends > hi + eps):
            return key, f"the section ({width:.4g} m wide along `across`) must lie inside the domain"
        back = ends - inlet.layers * (dx / cos) * d
        if np.any(back < lo - eps) or np.any(back > hi + eps):
            return "layers", (
                f"the buffer ({inlet.layers} layers of {dx / cos:.4g} m behind the section) must lie inside "
                "the domain"
            )
        speed = inlet.speed if inlet.speed is not None else inlet.discharge / (cos * width)
        water = s.materials[inlet.material]
        if not speed <= water.sound_speed:
            return "speed" if inlet.speed is not None else "discharge", (
                f"gives an inflow speed {speed:.4g} m/s above the water's sound speed "
                f"{water.sound_speed:.4g} m/s (weakly compressible SPH needs the flow well below it)"
            )
        diagonal = float(np.linalg.norm(hi - lo))
        if speed * inlet.prefill_time > diagonal:
            return "prefill_time", (
                f"{inlet.prefill_time:g} s at {speed:.4g} m/s carries the water farther than the domain's "
                f"diagonal ({diagonal:.4g} m)"
            )
    return None


def polygon_area(v) -> float:
    """Signed area (shoelace): positive for counter-clockwise vertices."""
    v = np.asarray(v, float)
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
