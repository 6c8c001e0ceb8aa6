"""The files of a section analysis (``kvrod section``, the sections notes): ``section.json``
(:meth:`runtime.section.analysis.SectionResult.to_dict` with the command and the kvrod
version) and ``section.png`` (:func:`runtime.io.section_figure.draw_section`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

#: what a section analysis writes into its results folder
SECTION_FILES = ("section.json", "section.png")


def write_section(res: Any, out: Path, spec: Any, command: str) -> list[Path]:
    """Write ``res`` (the analysis of ``spec``, a
    :class:`runtime.problem.section_analysis.SectionSpec`) into folder ``out``; returns the
    paths. ``command``: the command line quoted in section.json."""
    from runtime.io.atomic import write_text
    from runtime.io.section_figure import draw_section
    from runtime.version import version_text

    regions, _ = spec.regions_and_materials()
    doc = {"command": command, "kvrod": version_text(), **res.to_dict()}
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_text(out / "section.json", json.dumps(doc, indent=1) + "\n")]
    paths.append(draw_section(res, regions, out / "section.png",
                              title=f"{spec.name}: {res.n_elements} six-node triangles"))
    return paths
