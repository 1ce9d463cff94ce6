"""Which soils erode in a scene: the switch the erosion terms share (issue 24; docs/erosion.md).

A soil erodes when the scene runs the Shields law (numerics.erosion = "shields"), has water, and the
soil has a grain size. The pick-up (shields_pickup.py), the bed surface (bed_surface.py), the bed
shear (bed_shear.py), the seepage drag, the soil rates and the soil stress all ask the same question,
so the answer lives here, below all of them (none of them imports another to ask it).
"""

from __future__ import annotations

from ..materials import Phase
from ..scene import Soil


def erosion_materials(scene, materials):
    """Material ids of the soils that erode in this scene (none without water or with erosion off)."""
    if scene.numerics.erosion != "shields" or not materials.has_phase(Phase.WATER):
        return []
    return [
        k
        for k, name in enumerate(materials.names)
        if isinstance(scene.materials[name], Soil) and scene.materials[name].grain_size is not None
    ]
