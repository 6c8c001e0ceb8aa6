"""The one Jinja2 set-up of kvrod (generated code, derivation notes, reproduction and
example notes): templates kept as files, every variable required (StrictUndefined: a
missing one is an error, not an empty string), no HTML escaping (the outputs are C,
Python and Markdown), the final newline kept."""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import jinja2


@cache
def environment(folder: str) -> jinja2.Environment:
    """The environment of the templates in ``folder``."""
    return jinja2.Environment(loader=jinja2.FileSystemLoader(folder),
                              undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
                              autoescape=False)


def render(folder: Path, template: str, **context: Any) -> str:
    """Render ``folder/template`` with ``context``."""
    return environment(str(Path(folder).resolve())).get_template(template).render(**context)
