"""Closed-form references for the verification cases (NumPy only; no solver imports)."""
