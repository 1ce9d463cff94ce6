"""Output field names (what a user asks for) and the particle arrays behind them."""

OUTPUT_TO_ARRAY = {
    "position": "x",
    "velocity": "v",
    "density": "rho",
    "pressure": "p",
    "mass": "mass",
    "material": "material",
    "acceleration": "acc",
    "id": "id",
    "suspended": "suspended",
    "shields": "shields",
    "eroded_share": "eroded_share",
}
ALWAYS = ("position", "id", "material", "rank")  # rank: which process owned it (MPI)


def requested_fields(scene, particles):
    """Output names to write, in a stable order; fields the plan did not allocate are skipped."""
    names = list(ALWAYS) + [f for f in scene.output.fields if f not in ALWAYS]
    return [n for n in names if n == "rank" or OUTPUT_TO_ARRAY[n] in particles]
