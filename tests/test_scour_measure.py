"""The scour measurement rule (solver/output/scour.py) on lattices whose answer is known.

A flat layer of lattice particles (centres (i + 1/2) dx) fills 0 <= z <= top; its surface by the
kernel soil fraction = 1/2 lies at top within dx/2 (half a lattice cell: the rule cannot resolve
finer than the particles it reads), and the same in every bin (the mirrors at the base and the end
walls complete the kernel sums there). A rectangular pit cut out of it has the pit's depth within
dx/2 at its centre and its area within the same half-cell band around its outline. A grain
thrown up out of the top row's kernel support does not move the surface (its fraction, at most
dx^2 W(0) = 0.27, is below 1/2); one resting on it lifts the surface by less than half a cell.
"""

import numpy as np
import pytest

from solver.output.scour import ScourGrid, measure, surface_profile

DX = 0.005
H = 1.3 * DX
LENGTH, TOP = 0.25, 0.095


def layer(pit=None):
    nx, nz = round(LENGTH / DX), round(TOP / DX)
    i, k = np.meshgrid(np.arange(nx), np.arange(nz), indexing="ij")
    x = np.column_stack([(i.ravel() + 0.5) * DX, (k.ravel() + 0.5) * DX])
    if pit is not None:
        (x0, x1), z0 = pit
        x = x[~((x[:, 0] > x0) & (x[:, 0] < x1) & (x[:, 1] > z0))]
    return x


GRID = ScourGrid.for_layer(0.0, LENGTH, 0.0, 0.2, DX, H)


def test_flat_layer_surface_is_its_top_everywhere():
    z = surface_profile(layer(), GRID)
    assert np.all(np.abs(z - TOP) < DX / 2), z
    assert np.ptp(z) < 1e-9  # the same in every bin, the end bins included (mirrors)


def test_a_pit_is_measured_to_within_half_a_cell():
    z0 = surface_profile(layer(), GRID)
    pit = ((0.10, 0.15), 0.05)  # 10 columns wide, 9 rows deep (centres above 0.05 removed)
    z = surface_profile(layer(pit), GRID)
    m = measure(z0, z, GRID, 1.0)
    assert abs(m.depth - (TOP - 0.05)) < DX / 2
    assert 0.10 < m.x_deepest < 0.15
    true_area = 0.05 * (TOP - 0.05)
    band = 2 * (TOP - 0.05) * DX / 2 + 0.05 * DX / 2  # half a cell around the pit's three sides
    assert abs(m.eroded_area - true_area) < band
    assert m.deposited_area < 1e-9


def test_a_grain_thrown_up_does_not_move_the_surface_and_one_resting_on_it_barely():
    """Measured lifts (dx = 5 mm, h = 1.3 dx): a grain resting on the bed (centre dx/2 above it)
    0.41 dx, one a spacing above it 0.26 dx, one beyond a kernel support of the top row 0."""
    x = layer()
    z0 = surface_profile(x, GRID)

    def lift(height):
        grain = np.array([[0.125, TOP + height]])
        return (surface_profile(np.vstack([x, grain]), GRID) - z0).max()

    assert abs(lift(2.6 * DX)) < 1e-12  # in flight, out of the top row's kernel support (round-off)
    assert 0.0 < lift(DX) < DX / 3
    assert 0.0 < lift(DX / 2) < DX / 2  # a fraction of a cell: one grain is not a new row


def test_scoursph_study_scour_is_the_study_script(capsys):
    """`scoursph study scour ...` forwards its arguments to verification/scour_study.py (issue 11
    item 6: the study as a CLI subcommand)."""
    from scoursph.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["study", "scour", "--help"])
    assert exc.value.code == 0
    assert "python -m verification.scour_study" in capsys.readouterr().out
