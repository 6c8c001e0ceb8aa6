"""Generated files with provenance: the one mechanism behind `kvrod generate`.

Every generator in derive/ returns :class:`Artifact` records. :func:`write_tree` prefixes
each file with the provenance header of docs/design.md, section 3 (template or CasADi function it
came from, derivation step, hash of the inputs, tool versions, "do not edit") and writes
``MANIFEST.json``. Nothing here carries a timestamp, so regeneration is byte-identical;
:func:`check_tree` regenerates into a temporary folder and reports every difference.
"""

from __future__ import annotations

import difflib
import json
import tempfile
from collections.abc import Callable, Iterable
from importlib import metadata
from pathlib import Path

from derive.artifact import Artifact, sha256_text

__all__ = ["Artifact", "check_tree", "generated_dir", "render", "sha256_text", "write_tree"]

HEADER_TOOLS = ("sympy", "casadi", "jinja2")
MANIFEST_NAME = "MANIFEST.json"

#: comment syntax by file suffix; files whose format admits no comment (CasADi
#: serialisations) get no header and are described by their manifest entry alone.
_COMMENT = {".py": "# ", ".c": "// ", ".h": "// ", ".jinja": "# "}


def tool_versions() -> dict[str, str]:
    """Versions of the code-generating tools (pinned in pyproject.toml)."""
    return {name: metadata.version(name) for name in HEADER_TOOLS}


def header(artifact: Artifact) -> str:
    """The provenance banner for ``artifact`` in the comment syntax of its file type."""
    prefix = _COMMENT.get(Path(artifact.path).suffix)
    if prefix is None:
        return ""
    versions = ", ".join(f"{k} {v}" for k, v in tool_versions().items())
    lines = [
        "GENERATED FILE - do not edit; regenerate with `kvrod generate`.",
        f"source: {artifact.source}",
        f"derivation step: {artifact.step}",
        f"inputs sha256: {artifact.inputs_hash}",
        f"tools: {versions}",
    ]
    return "".join(prefix + line + "\n" for line in lines) + "\n"


def render(artifact: Artifact) -> str:
    """Full file content: header followed by body, ending in exactly one newline."""
    return header(artifact) + artifact.text.rstrip("\n") + "\n"


def _generators() -> list[Callable[[], Iterable[Artifact]]]:
    # Imported lazily: each generator pulls in SymPy or CasADi work of its own.
    from derive import codegen_constitutive

    gens: list[Callable[[], Iterable[Artifact]]] = [codegen_constitutive.artifacts]
    try:
        from derive import codegen_rod
    except ImportError:  # pragma: no cover - only while the rod generator does not exist
        return gens
    gens.append(codegen_rod.artifacts)
    return gens


def collect() -> list[Artifact]:
    """All artifacts of all generators, sorted by path (duplicate paths are an error)."""
    arts = [a for gen in _generators() for a in gen()]
    paths = [a.path for a in arts]
    dup = {p for p in paths if paths.count(p) > 1}
    if dup:
        raise RuntimeError(f"two generators write the same file(s): {sorted(dup)}")
    return sorted(arts, key=lambda a: a.path)


def manifest(artifacts: list[Artifact]) -> str:
    """MANIFEST.json text: tool versions and, per file, content hash and provenance."""
    files = {}
    for a in artifacts:
        files[a.path] = {
            "sha256": sha256_text(render(a)),
            "source": a.source,
            "step": a.step,
            "inputs_sha256": a.inputs_hash,
            **({"signature": a.signature} if a.signature else {}),
        }
    doc = {
        "generator": "kvrod generate",
        "note": "do not edit; regenerate with `kvrod generate`",
        "tools": tool_versions(),
        "files": files,
    }
    return json.dumps(doc, indent=2, sort_keys=True) + "\n"


def generated_dir() -> Path:
    """The ``generated/`` package folder of this checkout."""
    import generated

    return Path(generated.__file__).resolve().parent


def write_tree(outdir: Path | None = None, artifacts: list[Artifact] | None = None) -> list[Path]:
    """Write every artifact and the manifest into ``outdir`` (default: ``generated/``).

    Files are written via a temporary name and renamed, so a crash never leaves half a file.
    Returns the written paths.
    """
    outdir = Path(outdir) if outdir is not None else generated_dir()
    outdir.mkdir(parents=True, exist_ok=True)
    arts = collect() if artifacts is None else artifacts
    contents = {a.path: render(a) for a in arts}
    contents[MANIFEST_NAME] = manifest(arts)
    written = []
    for rel, text in contents.items():
        dest = outdir / rel
        tmp = dest.with_name(dest.name + ".tmp")
        tmp.write_text(text)
        tmp.replace(dest)
        written.append(dest)
    for stale in stale_files(outdir, contents):  # outputs of an earlier generator version
        stale.unlink()
    return written


#: files of generated/ that are not generator outputs
KEPT = ("__init__.py",)
#: endings of generator outputs (anything else in the folder is left alone)
OUTPUT_SUFFIXES = (".py", ".c", ".h", ".casadi", ".json")


def stale_files(outdir: Path, contents) -> list[Path]:
    """Generator-output files in ``outdir`` that a fresh generation does not write."""
    return sorted(p for p in Path(outdir).iterdir()
                  if p.is_file() and p.suffix in OUTPUT_SUFFIXES and p.name not in KEPT
                  and p.name not in contents)


def check_tree(outdir: Path | None = None) -> list[str]:
    """Differences between the committed tree and a fresh generation ([] when up to date).

    Each entry is a human-readable line (missing file, unexpected diff with the first
    differing lines). Only files listed in a fresh manifest are compared.
    """
    outdir = Path(outdir) if outdir is not None else generated_dir()
    problems: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        fresh = write_tree(Path(tmp))
        for stale in stale_files(outdir, {p.name for p in fresh}):
            problems.append(f"{stale.name}: not written by a fresh generation (stale; run "
                            "`kvrod generate`)")
        for path in fresh:
            committed = outdir / path.name
            if not committed.exists():
                problems.append(f"{path.name}: missing (run `kvrod generate`)")
                continue
            new, old = path.read_text(), committed.read_text()
            if new != old:
                diff = list(difflib.unified_diff(old.splitlines(), new.splitlines(), lineterm="",
                                                 fromfile=f"committed/{path.name}",
                                                 tofile=f"fresh/{path.name}", n=0))
                problems.append(f"{path.name}: differs from a fresh generation\n"
                                + "\n".join(diff[:12]))
    return problems
