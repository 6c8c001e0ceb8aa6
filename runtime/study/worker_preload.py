"""Imported by the fork server of a sweep's workers (:mod:`runtime.study.worker_boot`):
imports what a worker runs and loads the compiled kernels once, so that every worker
forked from it has them, then
freezes the heap (``gc.freeze``): a worker's collections then leave the objects it
inherited alone, so their pages stay shared instead of being copied into every worker.

A module, because a fork server preloads modules by name. Its import must not fail: the
fork server would die and no worker could start. It loads kernels that are compiled
already, and never compiles: a first sweep on a machine (an empty kernel cache) would
otherwise keep its cluster from starting for the compile's tens of seconds, while the
sweep ignores Ctrl-C (runtime.study.sweep_dask.start_local_cluster); then the workers'
own :class:`runtime.study.sweep_dask.KvrodWorkerSetup` compiles, as it always did, with
the cluster up and Ctrl-C heard. An exception here is likewise left for each worker's
set-up to meet again and report.
"""

import gc

from runtime.study.worker_boot import kernels_built, warm_up

try:
    if kernels_built():
        warm_up()
    else:
        import runtime.simulate.simulate  # noqa: F401 - the imports, without the kernels
except Exception:  # noqa: BLE001 - reported by the workers' own set-up (module docstring)
    pass
gc.freeze()
