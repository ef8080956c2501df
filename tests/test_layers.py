"""Two layers with a Mohr-Coulomb interface: the onset of sliding against the sliding block's
limit c A + mu N, the shape of the load curve, the command line."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from contactqp.applications.layers import Layers


@pytest.fixture(scope="module")
def history():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. no cohesive contact pulled open
        return Layers(steps=30).solve()


def test_sliding_starts_at_cohesion_times_area_plus_mu_times_normal_force(history):
    layers = history.layers
    onset = history.onset
    assert onset is not None and 0 < onset < len(history.load) - 5
    # the soft supports of the upper layer carry 1e-4 of its weight at most: N is the weight
    normal = history.normal_force[onset]
    assert abs(normal - layers.weight) < 1e-4 * layers.weight
    np.testing.assert_allclose(
        history.onset_force, layers.cohesion * layers.area + layers.mu * normal, rtol=1e-9
    )
    np.testing.assert_allclose(history.onset_force, layers.limit, rtol=1e-4)


def test_load_curve_sticks_then_slips_then_plateaus(history):
    load, relative, onset = history.load, history.relative, history.onset
    assert np.all(load[:onset] < history.onset_force * (1 - 1e-6))
    assert np.all(np.diff(load[:onset]) > 0)  # the load grows until the onset
    np.testing.assert_allclose(load[onset:], history.onset_force, rtol=1e-9)  # then stays
    assert np.all(history.sliding[onset:])
    # almost no relative motion under the first increments, then the layer slides: every
    # further increment of travel goes into sliding
    assert relative[1] < 1e-3 * relative[onset]
    steps = np.diff(relative[onset:])
    np.testing.assert_allclose(steps, np.diff(history.travel[onset:]), rtol=1e-6)


def test_without_cohesion_the_onset_is_mu_times_the_normal_force():
    result = Layers(mu=0.3, cohesion=0.0, steps=20).solve()
    np.testing.assert_allclose(
        result.onset_force, 0.3 * result.normal_force[result.onset], rtol=1e-9
    )


def test_cli_json_and_figure(tmp_path, capsys):
    from contactqp.cli import main

    png = tmp_path / "layers.png"
    assert main(["layers", "--json", "--steps", "20", "--plot", str(png)]) == 0
    record = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"mu", "cohesion", "area", "normal_force", "onset_force", "curve"} <= set(record)
    np.testing.assert_allclose(
        record["onset_force"],
        record["cohesion"] * record["area"] + record["mu"] * record["normal_force"],
        rtol=1e-9,
    )
    curve = np.array(record["curve"])
    assert curve.shape == (21, 2) and curve[:, 0].max() == pytest.approx(record["onset_force"])
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert main(["layers", "--mu", "-1"]) == 2


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"cohesion": float("inf")}, "cohesion must be finite"),
        ({"mu": float("nan")}, "mu must be finite"),
        ({"depth": 0.0}, "depth must be finite and > 0"),
        ({"poisson": 0.5}, "poisson must be < 0.5"),
        ({"cells": (20, 0, 4)}, "cells must be 3 integers"),
        ({"steps": 2.5}, "steps an integer"),
    ],
)
def test_bad_layers_are_refused_by_name(kwargs, match):
    from contactqp.errors import InvalidInputError

    with pytest.raises(InvalidInputError, match=match):
        Layers(**kwargs)


def test_cli_infinite_cohesion_is_one_line(capsys):
    from contactqp.cli import main

    assert main(["layers", "--cohesion", "inf"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'--cohesion': inf is not in the range" in err
