"""Test-suite configuration.

Property tests run derandomized by default, so the suite (and CI) gives the same verdict on
every run; a failure is a reproducible bug, not luck. Set ``KVROD_HYPOTHESIS=explore`` to draw
fresh random examples (e.g. ``KVROD_HYPOTHESIS=explore pytest --hypothesis-seed=7``) when
hunting for new edge cases; add what it finds as an ``@example``.
"""

import os

# One OpenBLAS thread in the test process and the commands it starts, set before NumPy
# loads. The adversarial cases start their subprocesses from helper threads with a
# preexec_fn, so with fork(): OpenBLAS's fork handler shuts its thread pool down in the
# parent, and a dense product running meanwhile on another thread (an in-process `kvrod
# section`) then waits for the pool forever (seen once: the suite spun at 100 % CPU in
# exec_blas). kvrod's results do not depend on the BLAS thread count.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from hypothesis import settings  # noqa: E402

settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore")
settings.load_profile("explore" if os.environ.get("KVROD_HYPOTHESIS") == "explore"
                      else "deterministic")

# Ctrl-C: the tests that interrupt a run send SIGINT and expect KeyboardInterrupt, which
# Python raises only through the handler it installs at start-up, and it installs none
# when it starts with SIGINT ignored (a background job of a non-interactive shell, as some
# CI runners start their steps). The suite then puts the default handler in place.
import signal  # noqa: E402

if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
