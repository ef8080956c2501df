"""The part/assembly model shared by riveting and riveting_friction: one Part, one stacked
model, plate flexibilities computed once per assembly object (no process-wide cache)."""

from __future__ import annotations

import numpy as np
import pytest

from contactqp.applications import riveting
from contactqp.applications.assembly import Part, StackedModel
from contactqp.applications.riveting import Assembly
from contactqp.applications.riveting_friction import FrictionAssembly
from contactqp.errors import InvalidInputError


@pytest.fixture
def counted(monkeypatch):
    """Calls of riveting.plate_flexibility, by plate."""
    calls = []
    compute = riveting.plate_flexibility

    def counting(plate, *args, **kwargs):
        calls.append(plate)
        return compute(plate, *args, **kwargs)

    monkeypatch.setattr(riveting, "plate_flexibility", counting)
    return calls


def test_flexibility_is_computed_once_per_assembly_and_kept_on_it(counted):
    small = dict(grid=(5, 3), refine=1, fasteners=((2, 1),))
    assembly = Assembly(**small)
    first, second = assembly.build(), assembly.build()
    assert len(counted) == 1  # equal plates: one flexibility for both, once
    np.testing.assert_array_equal(first.model.flexibility, second.model.flexibility)
    assert assembly.flexibilities[0] is assembly.flexibilities[1]
    assert not assembly.flexibilities[0].flags.writeable
    # an equal assembly made anew computes its own: nothing is kept between objects
    Assembly(**small).build()
    assert len(counted) == 2
    thinner = Assembly(upper=Part(thickness=0.0015), **small)
    lower, upper = thinner.flexibilities
    assert len(counted) == 4  # two different plates
    np.testing.assert_allclose(upper, lower * (0.002 / 0.0015) ** 3, rtol=1e-12)


def test_riveting_and_friction_assemblies_share_one_part_and_model():
    plate = Assembly().lower
    block = FrictionAssembly().lower
    assert type(plate) is type(block) is Part
    assert (block.length, block.width) == (0.100, 0.040)  # the friction case's smaller parts
    assert FrictionAssembly().thickness == 0.0012
    np.testing.assert_allclose(plate.rigidity, 70e9 * 0.002**3 / (12 * (1 - 0.33**2)))
    for assembly in (
        Assembly(upper=Part(width=0.2)),
        FrictionAssembly(upper=Part(length=0.3, width=0.040)),
    ):
        with pytest.raises(
            InvalidInputError, match="lower and upper parts must have the same length and width"
        ):
            assembly.build()


def test_the_friction_model_refuses_absurd_gaps_like_the_plates():
    # was: any finite gaps, even an overlap of 1 m through 1.2 mm parts
    model = FrictionAssembly(cells=(3, 1)).build()
    assert isinstance(model, StackedModel) and model.grid == (2, 2) and model.n_pairs == 4
    assert model.pair(1, 1) == 3
    pairs = model.obstacles(np.full(4, 1e-4))[0]
    np.testing.assert_array_equal(pairs.pairs, [[0, 4], [1, 5], [2, 6], [3, 7]])
    with pytest.raises(
        InvalidInputError,
        match=r"^gaps: an overlap of 1000 mm is deeper than "
        r"the 1\.2 mm plates",
    ):
        model.obstacles(np.full(4, -1.0))
    with pytest.raises(InvalidInputError, match="gaps must have 4 values, got 3"):
        model.obstacles(np.zeros(3))
    with pytest.raises(InvalidInputError, match=r"pair \(2, 0\) is outside the 2 x 2 grid"):
        model.pair(2, 0)
