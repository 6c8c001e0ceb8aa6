"""The version of kvrod as a user should quote it: the package version and the hash of
the generated tree it runs (``kvrod --version``, the notes' run-info)."""

from __future__ import annotations

import json
from pathlib import Path


def version_text() -> str:
    """``kvrod VERSION (generated/ TREE-HASH)``: the package version from its metadata and
    the first 12 hex digits of the sha256 of generated/MANIFEST.json (which holds the hash
    of every generated file); a tree that differs from its manifest is said to."""
    import hashlib
    from importlib import metadata

    import generated

    try:
        version = metadata.version("kvrod")
    except metadata.PackageNotFoundError:  # pragma: no cover - run from a bare source tree
        version = "(not installed)"
    gdir = Path(generated.__file__).resolve().parent
    try:
        text = (gdir / "MANIFEST.json").read_text()
        files = json.loads(text)["files"]
    except (OSError, ValueError, KeyError):
        return f"kvrod {version} (generated/ has no readable MANIFEST.json)"
    tree = hashlib.sha256(text.encode()).hexdigest()[:12]
    changed = []
    for name, entry in sorted(files.items()):
        try:  # the manifest's convention: sha256 of the text followed by NUL
            digest = hashlib.sha256((gdir / name).read_text().encode() + b"\0").hexdigest()
        except OSError:
            digest = None
        if digest != entry.get("sha256"):
            changed.append(name)
    note = (f"; {len(changed)} file(s) differ from it: run `kvrod generate --check`"
            if changed else "")
    return f"kvrod {version} (generated/ {tree}{note})"
