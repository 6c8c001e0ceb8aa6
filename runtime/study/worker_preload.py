"""Imported by the fork server of a sweep's workers (:mod:`runtime.study.worker_boot`):
loads the compiled kernels once, so that every worker forked from it has them.

A module, because a fork server preloads modules by name. Its import must not fail: the
fork server would die and no worker could start. A failure here (say, no C compiler and
no CasADi) is left for each worker's own :class:`runtime.study.sweep_dask.KvrodWorkerSetup`
to meet again and report.
"""

from runtime.study.worker_boot import warm_up

try:
    warm_up()
except Exception:  # noqa: BLE001 - reported by the workers' own set-up (module docstring)
    pass
