"""The `scoursph` command: the layer above the solver and its verification suite.

`solver` is the SPH solver and knows nothing of `verification`; this package dispatches the
command line to both (`scoursph run`, `scoursph verify`).
"""
