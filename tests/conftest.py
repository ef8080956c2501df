"""Suite-wide settings: property tests draw the same examples on every run and machine.

Where the compiled kernels were not built (no C compiler), the suite asks for the pure-numpy
kernels by name (``CONTACTQP_PURE_NUMPY=1``, inherited by the processes it starts): they are
what would be used anyway, and chosen so they give no warning on every import, which would add
a line to the one-line errors the command-line tests check.

Hypothesis otherwise draws new examples on each run (and replays failures from a local
database), so a fresh clone could meet a case no earlier run met: the suite must give the same
verdict every time. ``HYPOTHESIS_PROFILE=explore`` draws at random, to look for new cases.
"""

import importlib.machinery
import importlib.util
import os
from pathlib import Path

from hypothesis import settings


def compiled_kernels_built() -> bool:
    """Whether contactqp.kernels.compiled exists as a built extension (found without importing)."""
    package = importlib.util.find_spec("contactqp")
    if package is None or not package.submodule_search_locations:
        return False
    kernels = Path(next(iter(package.submodule_search_locations))) / "kernels"
    return any(
        (kernels / f"compiled{suffix}").exists()
        for suffix in importlib.machinery.EXTENSION_SUFFIXES
    )


if not compiled_kernels_built():
    os.environ.setdefault("CONTACTQP_PURE_NUMPY", "1")

settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))
