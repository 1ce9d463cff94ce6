"""Verification cases: each is a scene, references, metrics with sourced tolerances and a figure."""
