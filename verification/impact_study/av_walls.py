"""The Lobovsky tank with the artificial viscosity (and XSPH) reading the no-slip image velocity, v' = -v,
as the viscous stress does; only the continuity reads the free-slip mirror. A study variant, not a
scheme: it is the wall friction of DualSPHysics' dynamic boundaries, where the artificial viscosity
acts between fluid and wall particles (Crespo et al. 2015, Comput. Phys. Commun. 187:204), and shows
what a numerical wall viscosity nu_AV = alpha h c / 8 (Monaghan 2005) does to the plateau
(verification/results/impact_pressure/README.md, "No-slip walls").

python -m verification.impact_study.av_walls OUT.npz RESOLUTION   (the walls are no_slip)
"""

import sys

from solver.physics.fluid_rates import FluidRates

from . import fields

if __name__ == "__main__":
    FluidRates.slip_image_velocity = False
    sys.argv = sys.argv[:3] + ["no_slip"]
    fields.main()
