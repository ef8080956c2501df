"""Static condensation against the unit-load procedure and against a closed form."""

import numpy as np
import pytest
import scipy.sparse as sp

from contactqp.compliance.condensation import RigidBodyModeError, condense
from contactqp.errors import InvalidInputError
from contactqp.model import unit_load_compliance


def bar_stiffness(n, k=3.0, fixed=True):
    """Chain of ``n`` springs ``k``; the first attached to a wall when ``fixed``."""
    main = np.full(n, 2 * k)
    main[-1] = k
    if not fixed:
        main[0] = k
    return sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, -1, 1], format="csr")


def test_spring_chain_flexibility_is_the_closed_form():
    k, n = 3.0, 40
    chosen = np.array([0, 7, 19, 39])
    R = condense(bar_stiffness(n, k), chosen)
    expected = (np.minimum.outer(chosen, chosen) + 1) / k
    np.testing.assert_allclose(R, expected, rtol=1e-12)


def test_equals_the_unit_load_procedure_on_a_random_sparse_model():
    rng = np.random.default_rng(1)
    n = 300
    B = sp.random(n, n, density=0.02, random_state=rng)
    K = (B @ B.T + sp.eye(n) * 0.5).tocsr()
    chosen = rng.choice(n, size=60, replace=False)
    Kd = K.toarray()

    def _embed(load):
        full = np.zeros(n)
        full[chosen] = load
        return full

    unit = unit_load_compliance(lambda p: np.linalg.solve(Kd, _embed(p))[chosen], chosen.size)
    R = condense(K, chosen)
    np.testing.assert_allclose(R, unit.flexibility, rtol=1e-10, atol=1e-10 * np.abs(R).max())
    assert np.array_equal(R, R.T)


def test_rigid_body_mode_is_a_clear_error():
    with pytest.raises(RigidBodyModeError, match="rigid-body modes"):
        condense(bar_stiffness(10, fixed=False), [3])


def test_bad_freedoms_are_named():
    with pytest.raises(InvalidInputError, match="freedoms must lie in"):
        condense(bar_stiffness(5), [5])
    with pytest.raises(InvalidInputError, match="repeated"):
        condense(bar_stiffness(5), [1, 1])
    with pytest.raises(InvalidInputError, match="stiffness contains NaN"):
        condense(sp.csr_matrix(np.full((2, 2), np.nan)), [0])
