"""ScourSPH: a validated SPH solver for soil-water interaction."""

__version__ = "0.1.0"
