"""The discharge under a single sheet pile in a finite layer (Harr 1962): the closed form the OpenFOAM
seepage reference is checked against (openfoam_seepage_2d/run.py, its Q_exact column). The other
closed-form seepage references are in verification/analytic/seepage.py; this one lives here because
the reference pipeline needs it and reference_cases imports nothing from verification
(tests/test_import_graph.py). The standard library only.
"""

from __future__ import annotations

import math


def elliptic_k(m: float) -> float:
    """Complete elliptic integral of the first kind K(m), m the modulus (not m^2):
    K = pi / (2 AGM(1, sqrt(1 - m^2))) (arithmetic-geometric mean; Abramowitz & Stegun 17.6)."""
    if not 0.0 <= m < 1.0:
        raise ValueError("modulus must be in [0, 1)")
    a, b = 1.0, math.sqrt(1.0 - m * m)
    while abs(a - b) > 1e-15 * a:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


def sheet_pile_shape_factor(penetration: float, thickness: float) -> float:
    """Q / (k H) for a single sheet pile of zero thickness driven to `penetration` s into a
    homogeneous layer of `thickness` T on an impermeable base, laterally unbounded, with the
    ground surface at heads H apart on either side (the flow-net ratio N_f / N_d).

    Conformal-mapping solution (Pavlovsky; Harr 1962, Groundwater and Seepage, ch. 5;
    Polubarinova-Kochina 1962): Q / (k H) = K(m') / (2 K(m)), m = sin(pi s / (2 T)),
    m' = cos(pi s / (2 T)). Limits: s -> T gives 0 (full cut-off), s -> 0 diverges (a
    zero-width step in head on an unbounded surface), s = T/2 gives exactly 1/2.
    """
    if not 0.0 < penetration < thickness:
        raise ValueError("need 0 < penetration < thickness")
    a = math.pi * penetration / (2.0 * thickness)
    return elliptic_k(math.cos(a)) / (2.0 * elliptic_k(math.sin(a)))
