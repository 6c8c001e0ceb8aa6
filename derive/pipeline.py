"""The derivation's step records for this process: derived once from the catalogue
(:mod:`derive.catalogue`) or, between processes, taken from the derivation cache
(:mod:`derive.cache`: the user's cache folder, keyed by the content of derive/ and the tool
versions, never the checkout). The catalogue's names are available from here too.
"""

from __future__ import annotations

from derive.catalogue import (  # noqa: F401 - the pipeline's public names
    PIPELINE,
    STEP_NAMES,
    PipelineEntry,
    Progress,
    UnknownStepError,
    derive_all,
    entry,
)
from derive.step import Step

_memo: dict[str, Step] | None = None


def run(progress: Progress | None = None) -> dict[str, Step]:
    """All step records by name, in pipeline order.

    Derived once per process; between processes they come from the derivation cache
    (:func:`derive.cache.load_or_derive`: rebuilt when anything in derive/ or a tool
    version changed; ``KVROD_DERIVE_CACHE=0`` derives from scratch and writes nothing).
    ``progress`` is called only when the steps are actually derived.
    """
    global _memo
    if _memo is None:
        from derive import cache

        _memo = cache.load_or_derive(progress)
    return dict(_memo)


def forget() -> None:
    """Drop the records kept for this process (the disk cache is left alone; the formula
    table has its own: :func:`derive.formulas.forget`)."""
    global _memo
    _memo = None


def step(name: str) -> Step:
    """The record of one step (see :func:`run`)."""
    entry(name)
    return run()[name]
