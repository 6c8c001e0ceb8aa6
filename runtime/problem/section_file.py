"""``section.file``: a problem's section taken from a section file.

A problem file may write ``[section] file = "cable_section.toml"`` instead of its section:
the file is a *section file*, what ``kvrod section`` reads (``[section]`` with
``[materials.NAME]``: a composite section; or a closed-form shape with ``[material]``;
besides ``name`` and ``description``), its path relative to the problem file (as
``rod.geometry.file`` is). :func:`with_section_file` puts the file's ``[section]`` and its
material tables into the problem's table; the problem then reads as if it had written them
itself, and :meth:`~runtime.problem.schema.Problem.to_mapping` writes them out in full (a
problem written into a results folder does not depend on the section file any more).

How the tables combine (decision; ambiguity is refused, naming both keys):

* beside ``file`` the problem's ``[section]`` may give only ``damping`` and
  ``shear_correction``, how the rod takes the section (they replace the file's); any
  other key is the section's own and belongs in the file;
* a composite section file's ``[materials]`` are the section's: the problem gives no
  ``[materials]`` and no ``[material]`` of its own;
* a shape's ``[material]`` in the section file is the rod's material: the problem gives
  none beside it; a section file with a shape and no ``[material]`` leaves the problem's
  ``[material]`` (or the default) to the rod.

Errors inside the section file name its key and the file (``materials.pvc.tau_S (in
section.file 'cable_section.toml')``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from runtime.errors import ParameterError
from runtime.problem import coerce as C

#: the tables and keys of a section file
SECTION_FILE_KEYS = ("name", "description", "section", "materials", "material")
#: the keys a problem's [section] may give beside ``file`` (how the rod takes the section)
BESIDE_FILE = ("damping", "shear_correction")


def read_section_file(name: Any, base: Path | None) -> tuple[dict[str, Any], Path]:
    """(the table, its path) of the section file ``name`` (``section.file``), relative to
    ``base`` (the problem file's folder) unless absolute; ParameterError naming
    ``section.file`` when it cannot be read or is no section file."""
    from runtime.problem.registry import ProblemFileError, read_toml

    name = C.string("section.file", name)
    path = Path(name) if Path(name).is_absolute() or base is None else Path(base) / name
    try:
        doc, _ = read_toml(path, what="section file")
    except ProblemFileError as exc:
        raise ParameterError("section.file", name, f"a readable section file, relative to "
                             f"the problem file ({exc})") from None
    extra = [k for k in doc if k not in SECTION_FILE_KEYS]
    if extra or not isinstance(doc.get("section"), Mapping):
        held = ("[" + "], [".join(extra) + "]") if extra else "no [section] table"
        raise ParameterError("section.file", name, "a section file, as kvrod section reads "
                             "it: [section] with [materials.NAME], or a shape with "
                             f"[material], besides name and description (it holds {held})")
    if "file" in doc["section"]:
        raise ParameterError("section.file", name, "a section file that holds its section "
                             "itself (its own section.file = "
                             f"{doc['section']['file']!r} is not followed)")
    return doc, path


def with_section_file(m: Mapping[str, Any], base: Path | None) -> Mapping[str, Any]:
    """The problem table ``m`` with ``section.file`` replaced by the section file's
    ``[section]`` and material tables (see the module docstring); ``m`` itself when its
    section names no file. The file's own tables are checked first, so an error in them
    names the file."""
    sec = m.get("section")
    if not isinstance(sec, Mapping):
        return m
    # the key this step reads from [section] (every other one is the section parsers')
    C.no_unknown_keys("section", {k: v for k, v in sec.items() if k == "file"}, ("file",))
    if "file" not in sec:
        return m
    doc, path = read_section_file(sec["file"], base)
    name = sec["file"]
    from runtime.problem.schema import section_and_material

    try:
        section_and_material(doc)
    except ParameterError as exc:
        raise ParameterError(f"{exc.name} (in section.file {name!r})", exc.value,
                             exc.allowed) from None
    for key in sec:
        if key != "file" and key not in BESIDE_FILE:
            raise ParameterError(f"section.{key}", sec[key], f"absent beside section.file = "
                                 f"{name!r}: the section file gives the whole section (beside "
                                 f"file only {', '.join(BESIDE_FILE)})")
    composite = doc["section"].get("kind") == "composite"
    for key in ("materials", "material"):
        own = m.get(key) is not None
        if own and (composite or key in doc):
            theirs = "[materials.NAME]" if composite else "[material]"
            raise ParameterError(key, m[key], f"absent beside section.file = {name!r}, whose "
                                 f"{theirs} {'are' if composite else 'is'} the section's: "
                                 "one place for a material (edit the section file, or "
                                 "write the section into the problem)")
    out = {k: v for k, v in m.items() if k not in ("section",)}
    out["section"] = {**doc["section"], **{k: v for k, v in sec.items() if k != "file"}}
    for key in ("materials", "material"):
        if key in doc:
            out[key] = doc[key]
    return out
