"""The spring chain with friction against the published table and the analytic solution."""

import warnings

import numpy as np
import pytest
import qpsolvers
import scipy.sparse
from hypothesis import given, settings
from hypothesis import strategies as st

from contactqp.applications.springs import SpringChain, chain_flexibility
from contactqp.methods.box_qp import solve_box_qp


def analytic(n, c, mu, m, g, F):
    i = np.arange(1, n + 1)
    return np.cumsum(np.maximum(F - (n + 1 - i) * mu * m * g, 0.0) / c)


@pytest.mark.parametrize(
    "force, expected",
    [
        (3, [0, 0, 0]),
        (6, [0, 0, 2]),
        (9, [0, 1, 6]),
        (14, [2, 8, 18]),
    ],
)
def test_published_table(force, expected):
    result = SpringChain(3, 1.0, 0.2, 2.0, 10.0).solve(force)
    assert result.converged
    np.testing.assert_allclose(result.x, expected, atol=1e-12)


@settings(max_examples=20, deadline=None)
@given(
    n=st.integers(1, 300),
    c=st.floats(0.1, 100),
    mu=st.floats(0.0, 1.0),
    m=st.floats(0.1, 10),
    load=st.floats(0.0, 3.0),
)
def test_matches_analytic(n, c, mu, m, load):
    g = 9.81
    F = load * n * max(mu * m * g, 1e-3)  # up to three times the force that moves every body
    result = SpringChain(n, c, mu, m, g).solve(F)
    expected = analytic(n, c, mu, m, g, F)
    assert result.converged
    np.testing.assert_allclose(result.x, expected, atol=1e-9 * max(1.0, np.max(np.abs(expected))))


def test_two_thousand_bodies():
    n, c, mu, m, g, F = 2000, 2.5, 0.3, 1.5, 9.81, 3000.0
    result = SpringChain(n, c, mu, m, g).solve(F)
    expected = analytic(n, c, mu, m, g, F)
    assert result.converged
    np.testing.assert_allclose(result.x, expected, rtol=0, atol=1e-9 * np.max(expected))


def test_primal_energy_formulation_agrees():
    # the method's own statement: min c/2 X^T K X with -mu m g <= F e_N - c K X <= mu m g,
    # solved as a generic QP on displacements (second solver)
    n, c, mu, m, g, F = 12, 3.0, 0.25, 1.2, 9.81, 20.0
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[-1, -1] = 1.0
    pull = np.zeros(n)
    pull[-1] = F
    limit = mu * m * g
    G = np.vstack([-c * K, c * K])
    h = np.concatenate([limit - pull, limit + pull])
    X = qpsolvers.solve_qp(c * K, np.zeros(n), G, h, solver="quadprog")
    np.testing.assert_allclose(SpringChain(n, c, mu, m, g).solve(F).x, X, atol=1e-9)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"n": 0}, "n must"),
        ({"stiffness": -1.0}, "stiffness"),
        ({"mu": -0.1}, "mu"),
        ({"mass": float("nan")}, "mass"),
    ],
)
def test_bad_parameters(kwargs, message):
    from contactqp import InvalidInputError

    params = {"n": 3, "stiffness": 1.0, "mu": 0.2, "mass": 2.0, "g": 10.0, **kwargs}
    with pytest.raises(InvalidInputError, match=message):
        SpringChain(**params)


def test_a_hundred_thousand_bodies_against_the_closed_form_and_equilibrium():
    # the dense flexibility of this chain would take 74.5 GiB; the truth is the closed form and
    # the equilibrium on a stiffness assembled here, independently of the module
    n, c, mu, m, g, F = 100_000, 2.5, 0.3, 1.5, 9.81, 2e5
    result = SpringChain(n, c, mu, m, g).solve(F)
    expected = analytic(n, c, mu, m, g, F)
    assert result.converged and 0 < result.sliding.sum() < n
    np.testing.assert_allclose(result.x, expected, rtol=0, atol=1e-9 * np.max(expected))
    K = scipy.sparse.diags(
        [-np.ones(n - 1), np.r_[2 * np.ones(n - 1), 1.0], -np.ones(n - 1)], [-1, 0, 1]
    )
    pull = np.zeros(n)
    pull[-1] = F
    np.testing.assert_allclose(c * (K @ result.x), pull - result.friction, rtol=0, atol=1e-9 * F)
    limit = mu * m * g  # friction forces are differences of spring forces up to F: 1e-12 F
    assert np.all(np.abs(result.friction) <= limit + 1e-12 * F)
    np.testing.assert_allclose(result.friction[result.x > 0], limit, rtol=0, atol=1e-12 * F)


@pytest.mark.parametrize("n, F", [(40, 50.0), (200, 1500.0), (200, -30.0)])
def test_the_box_qp_of_the_method_agrees(n, F):
    # the method's statement solved by the project's active-set solver on the dense flexibility
    c, mu, m, g = 1.5, 0.25, 2.0, 9.81
    R = chain_flexibility(n, c)
    pull = np.zeros(n)
    pull[-1] = F
    limit = mu * m * g
    solution = solve_box_qp(R, -(R @ pull), lower=-limit, upper=limit, tol=1e-13)
    result = SpringChain(n, c, mu, m, g).solve(F)
    assert solution.converged and result.converged
    scale = np.max(np.abs(R @ pull))
    np.testing.assert_allclose(result.x, R @ (pull - solution.x), rtol=0, atol=1e-9 * scale)


def test_an_overflowing_chain_is_not_converged_and_says_why():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = SpringChain(1000, 1e-305, 0.2, 2.0, 10.0).solve(1e300)
    assert not result.converged and "overflow" in result.message
