"""Self-affine random surfaces: the requested rms, the power law of the spectrum, the seed."""

import numpy as np
import pytest

from contactqp.applications.rough.surface import (
    rms_height,
    rms_slope,
    self_affine_surface,
    wavenumbers,
)
from contactqp.errors import InvalidInputError

CELL = 1e-6  # m


def spectral_gradient_rms(heights, cell):
    """The rms of |grad h| in real space, the gradient taken by the FFT (no Nyquist modes)."""
    ny, nx = heights.shape
    qx = 2 * np.pi * np.fft.fftfreq(nx, d=cell)[np.newaxis, :]
    qy = 2 * np.pi * np.fft.fftfreq(ny, d=cell)[:, np.newaxis]
    spectrum = np.fft.fft2(heights)
    gx = np.fft.ifft2(1j * qx * spectrum)
    gy = np.fft.ifft2(1j * qy * spectrum)
    assert np.abs(gx.imag).max() < 1e-12 * np.abs(gx.real).max()  # a real field's gradient
    return np.sqrt(np.mean(gx.real**2 + gy.real**2))


def test_rms_slope_of_a_sinusoid_is_its_amplitude_times_wavenumber_over_root_two():
    n, mode, amplitude = 64, 5, 2e-7
    x = np.arange(n) * CELL
    heights = np.tile(amplitude * np.cos(2 * np.pi * mode * x / (n * CELL)), (48, 1))
    heights = heights[:, :n]
    q = 2 * np.pi * mode / (n * CELL)
    assert rms_slope(heights, CELL) == pytest.approx(amplitude * q / np.sqrt(2), rel=1e-12)
    assert rms_height(heights) == pytest.approx(amplitude / np.sqrt(2), rel=1e-12)


@pytest.mark.parametrize("hurst", [0.3, 0.8, 1.0])
def test_the_requested_rms_slope_holds_and_matches_the_real_space_gradient(hurst):
    heights = self_affine_surface(128, CELL, hurst=hurst, rms_slope=0.1, short_cutoff=32, seed=3)
    # rounding only: one rescaling of a sum of 128^2 squares
    assert rms_slope(heights, CELL) == pytest.approx(0.1, rel=1e-12)
    assert spectral_gradient_rms(heights, CELL) == pytest.approx(0.1, rel=1e-12)
    assert abs(heights.mean()) < 1e-12 * rms_height(heights)  # no q = 0 mode


def test_the_requested_rms_height_holds_on_a_rectangular_grid():
    heights = self_affine_surface(96, CELL, ny=64, hurst=0.7, rms_height=3e-7, rolloff=4, seed=9)
    assert heights.shape == (64, 96)
    assert np.std(heights) == pytest.approx(3e-7, rel=1e-12)


@pytest.mark.parametrize("hurst", [0.4, 0.9])
def test_the_spectrum_is_the_power_law_between_the_rolloff_and_the_cutoff(hurst):
    n, q_l, q_r, q_s = 128, 2, 8, 40
    heights = self_affine_surface(
        n,
        CELL,
        hurst=hurst,
        rms_height=1e-6,
        long_cutoff=q_l,
        rolloff=q_r,
        short_cutoff=q_s,
        seed=1,
    )
    power = np.abs(np.fft.fft2(heights)) ** 2
    mode = wavenumbers(n, n, CELL) * n * CELL / (2 * np.pi)
    law = (mode >= q_r * (1 - 1e-9)) & (mode <= q_s * (1 + 1e-9))  # mode numbers, rounded
    slope, intercept = np.polyfit(np.log(mode[law]), np.log(power[law]), 1)
    # every mode's amplitude is set exactly (random phase only): the fit is exact to rounding
    assert slope == pytest.approx(-2 * (1 + hurst), abs=1e-9)
    plateau = (mode >= q_l * (1 - 1e-9)) & (mode < q_r * (1 - 1e-9))
    assert plateau.sum() > 100
    np.testing.assert_allclose(power[plateau], np.exp(intercept) * q_r**slope, rtol=1e-9)
    outside = (mode < q_l * (1 - 1e-9)) | (mode > q_s * (1 + 1e-9))
    assert power[outside].max() < 1e-20 * power.max()


def test_the_same_seed_gives_the_same_surface_and_another_seed_another():
    first = self_affine_surface(64, CELL, hurst=0.8, rms_slope=0.2, seed=42)
    again = self_affine_surface(64, CELL, hurst=0.8, rms_slope=0.2, seed=42)
    other = self_affine_surface(64, CELL, hurst=0.8, rms_slope=0.2, seed=43)
    generator = self_affine_surface(
        64, CELL, hurst=0.8, rms_slope=0.2, seed=np.random.default_rng(42)
    )
    np.testing.assert_array_equal(first, again)
    np.testing.assert_array_equal(first, generator)
    assert np.abs(first - other).max() > 0.1 * np.abs(first).max()


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"hurst": 0.0, "rms_slope": 0.1}, "hurst"),
        ({"hurst": 1.5, "rms_slope": 0.1}, "hurst"),
        ({"hurst": 0.8}, "exactly one"),
        ({"hurst": 0.8, "rms_slope": 0.1, "rms_height": 1e-6}, "exactly one"),
        ({"hurst": 0.8, "rms_slope": -0.1}, "rms_slope"),
        ({"hurst": 0.8, "rms_slope": 0.1, "short_cutoff": 40}, "Nyquist"),
        ({"hurst": 0.8, "rms_slope": 0.1, "rolloff": 20, "short_cutoff": 10}, "rolloff"),
        ({"hurst": 0.8, "rms_slope": 0.1, "long_cutoff": 1.2, "short_cutoff": 1.3}, "no mode"),
        ({"hurst": 0.8, "rms_slope": 0.1, "ny": 1}, "ny"),
    ],
)
def test_bad_arguments_are_one_line_errors(options, words):
    with pytest.raises(InvalidInputError, match=words) as caught:
        self_affine_surface(64, CELL, **options)
    assert "\n" not in str(caught.value)
