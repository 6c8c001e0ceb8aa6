"""The record of one generated file (:class:`Artifact`) and the inputs hash.

The generators (``codegen_*.py``) return artifacts; :mod:`derive.artifacts` writes them with
their provenance headers and the manifest. Kept apart so that the generators and the
writer do not import each other.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Artifact:
    """One generated file.

    path: file name relative to ``generated/``.
    text: the file body (without the provenance header).
    source: the Jinja2 template or CasADi function the body came from.
    step: the derivation step(s) (``derive list``) whose results it renders.
    inputs_hash: sha256 of everything the body was generated from (expressions, options).
    signature: optional description of the functions in the file (names, inputs, outputs).
    """

    path: str
    text: str
    source: str
    step: str
    inputs_hash: str
    signature: dict = field(default_factory=dict)


def sha256_text(*parts: str) -> str:
    """sha256 hex digest of the concatenated parts (each followed by a NUL separator)."""
    h = hashlib.sha256()
    for part in parts:
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()
