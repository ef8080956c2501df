"""Suite-wide settings: property tests draw the same examples on every run and machine.

Hypothesis otherwise draws new examples on each run (and replays failures from a local
database), so a fresh clone could meet a case no earlier run met: the suite must give the same
verdict every time. ``HYPOTHESIS_PROFILE=explore`` draws at random, to look for new cases.
"""

import os

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))
