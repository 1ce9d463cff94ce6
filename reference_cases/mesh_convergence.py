"""Richardson extrapolation and the grid convergence index of a resolution study: the arithmetic
shared by the SPH verification (verification/common.py and its cases) and the reference runs of other
codes (the interFoam mesh spread, openfoam_lobovsky_impact/compare.py). It knows nothing of either.
"""

from __future__ import annotations

# Roache (1998), "Verification and Validation in Computational Science and Engineering": three-grid GCI
GCI_SAFETY = 1.25


def richardson(spacings, values, orders=(0.5, 4.0)):
    """Observed order p and extrapolated limit f0 of f(dx) = f0 + C dx^p from three spacings
    (any refinement ratios; Celik et al. 2008, J. Fluids Eng. 130:078001, eqs. 3-4, solved here
    by bisection). None if the three values are not monotone in dx or p falls outside `orders`
    (then the sequence is not in its asymptotic range and no extrapolation is defensible; the
    range 0.5-4 is this project's guard, not from the source). Celik et al. recommend refinement
    ratios above 1.3; callers should say when theirs are smaller."""
    (h1, f1), (h2, f2), (h3, f3) = sorted(zip(spacings, values), reverse=True)  # coarse to fine
    d12, d23 = f1 - f2, f2 - f3
    if d12 == 0.0 or d23 == 0.0 or (d12 > 0) != (d23 > 0):
        return None
    target = d12 / d23

    def ratio(p):
        return (h1**p - h2**p) / (h2**p - h3**p)

    lo, hi = orders
    if not min(ratio(lo), ratio(hi)) <= target <= max(ratio(lo), ratio(hi)):
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (ratio(mid) - target) * (ratio(lo) - target) > 0:
            lo = mid
        else:
            hi = mid
    p = 0.5 * (lo + hi)
    f0 = f3 - d23 * h3**p / (h2**p - h3**p)
    return p, f0
