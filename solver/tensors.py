"""Symmetric tensors are stored as 6 components in every dimension:

    0: xx   1: yy   2: zz   3: xy   4: yz   5: xz

A 2D scene is plane strain: zz is kept (soil needs s_zz for the yield criterion) and the
out-of-plane shears stay zero. Mirroring a tensor across walls flips the sign of each
component by s_a s_b (seed eq. 23); SYM_AXES lists (a, b) per component for that.
"""

import numpy as np

XX, YY, ZZ, XY, YZ, XZ = range(6)
N_SYM = 6
SYM_AXES = np.array([[0, 0], [1, 1], [2, 2], [0, 1], [1, 2], [0, 2]], dtype=np.int64)
