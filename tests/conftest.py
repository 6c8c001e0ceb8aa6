"""Test-suite configuration.

Property tests run derandomized by default, so the suite (and CI) gives the same verdict on
every run; a failure is a reproducible bug, not luck. Set ``KVROD_HYPOTHESIS=explore`` to draw
fresh random examples (e.g. ``KVROD_HYPOTHESIS=explore pytest --hypothesis-seed=7``) when
hunting for new edge cases; add what it finds as an ``@example``.
"""

import os

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore")
settings.load_profile("explore" if os.environ.get("KVROD_HYPOTHESIS") == "explore"
                      else "deterministic")
