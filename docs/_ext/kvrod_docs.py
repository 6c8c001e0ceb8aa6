"""Pages rendered from the code at docs build time (so they cannot drift):

* ``_generated/derivation.md``: the derivation, from the same step records as
  ``kvrod derive`` (:func:`derive.notes.render_derivation_notes`);
* ``_generated/problem_keys.md``: every problem-file key (:mod:`runtime.problem.keys`);
* ``_generated/cli.md``: every command and flag, from the argument parser
  (:func:`kvrod.cli.build_parser`);
* ``_generated/first_rod.md``: the getting-started commands with the output they print,
  produced by running them (in a temporary folder);
* ``_generated/validation.md``: the tables and figures of the generated notes, each with
  the command that regenerates it;
* ``_generated/notes/*.md`` and ``_generated/bench.md``: the generated notes and the
  benchmark tables, with their figures;
* ``_generated/commands.md``: the README's commands;
* ``_generated/examples/``: the example files the pages include.

The two expensive pages (the derivation, the command outputs) are rebuilt only when what
they depend on changes: each carries a ``.key`` file with the hash of its inputs (the
sources of kvrod's packages and the library versions, see :func:`source_key`). The same
kind of key names the tutorials' jupyter-cache folder (:func:`_set_notebook_cache`), so a
notebook executes again when its cells change or when kvrod's code does.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

from sphinx.errors import ExtensionError

import kvrod

ROOT = Path(kvrod.__file__).resolve().parents[1]
NOTES = ("reproduction", "examples", "beyond", "maxwell", "sections")

#: what the executed pages (tutorials, command outputs) depend on: kvrod's packages and
#: the example problems (built-in problem names resolve to examples/*.toml)
SOURCE_DIRS = ("derive", "generated", "runtime", "kvrod", "references", "examples")
#: libraries whose version changes numbers or rendering in the executed pages
LIBRARIES = ("numpy", "scipy", "sympy", "casadi", "matplotlib", "jinja2")

#: the getting-started commands (run at build time in a temporary folder that holds a
#: copy of examples/; written with the README's `.venv/bin/kvrod`)
FIRST_ROD = (
    "simulate cantilever --tau 0.04 --n-elements 50 --out results/cantilever",
    "static examples/rollup.toml --out results/rollup",
    "static examples/bathe_bolourchi.toml --out results/bend45",
    "modes cantilever --count 6",
)

#: the validation page: (note, section title)
VALIDATION = (
    ("reproduction", "The paper's Sect. 5: the damped large-deflection cantilever"),
    ("examples", "Rod problems against independent references"),
    ("beyond", "Consistent against naive damping, damped modes, calibration"),
    ("maxwell", "Generalized Maxwell rods"),
    ("sections", "Composite and anisotropic sections: consistent against naive viscosity"),
)


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:   # unchanged pages stay unchanged
        path.write_text(text)


def source_key(dirs: tuple[str, ...] = SOURCE_DIRS,
               libraries: tuple[str, ...] = LIBRARIES, root: Path = ROOT) -> str:
    """sha256 of the files under ``root/dir`` for each of ``dirs`` (paths and contents;
    caches and build products excluded), the Python version and the versions of
    ``libraries``."""
    h = hashlib.sha256(sys.version.encode() + b"\0")
    for lib in libraries:
        try:
            version = metadata.version(lib)
        except metadata.PackageNotFoundError:
            version = "absent"
        h.update(f"{lib}=={version}\0".encode())
    for d in dirs:
        for path in sorted((root / d).rglob("*")):
            if (not path.is_file() or "__pycache__" in path.parts
                    or path.suffix in (".pyc", ".so", ".o", ".tmp")):
                continue
            h.update(path.relative_to(root).as_posix().encode() + b"\0")
            h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def _cached(path: Path, key: str, make: Callable[[], str]) -> None:
    """Write ``make()`` to ``path`` unless the page there was made from the same ``key``."""
    stamp = path.with_name(path.name + ".key")
    if path.exists() and stamp.exists() and stamp.read_text() == key:
        return
    _write(path, make())
    stamp.write_text(key)


def _subcommands(parser: argparse.ArgumentParser, prefix: str):
    for action in parser._actions:          # argparse keeps subparsers here only
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield f"{prefix} {name}", sub
                yield from _subcommands(sub, f"{prefix} {name}")


def cli_markdown() -> str:
    from kvrod.cli import build_parser

    parser = build_parser()
    out = ["# Command-line reference", "",
           "Generated from kvrod's argument parser at every docs build "
           "(`kvrod COMMAND --help` prints the same).", "",
           "```text", parser.format_help().rstrip(), "```", ""]
    for name, sub in _subcommands(parser, "kvrod"):
        sub.prog = name
        out += [f"## `{name}`", "", "```text", sub.format_help().rstrip(), "```", ""]
    return "\n".join(out)


def keys_markdown() -> str:
    from runtime.problem import keys

    return ("# Problem file reference\n\n"
            "Every key of a problem file (TOML), generated at every docs build from "
            "`runtime/problem/keys.py`, which a test checks against the parsers: the keys "
            "each parser accepts and the ranges it enforces. `kvrod problem-keys` prints "
            "the same. The kinds column names the `kind` (or material `model`, or whether "
            "a named material is isotropic or anisotropic) a key belongs to. Examples: "
            "`examples/*.toml`.\n\n" + keys.markdown())


def _repo_links_as_code(text: str) -> str:
    # links to files of the repository become code text (they are not pages here)
    return re.sub(r"\[([^\]]*)\]\((?!figures/|https?:)([^)]+)\)", r"\1 (`\2`)", text)


def _copy_note(name: str, dest: Path) -> None:
    text = _repo_links_as_code((ROOT / "notes" / f"{name}.md").read_text())
    _write(dest / "notes" / f"{name}.md", text)
    for fig in sorted(set(re.findall(r"\]\((figures/[^)]+)\)", text))):
        target = dest / "notes" / fig
        target.parent.mkdir(parents=True, exist_ok=True)
        data = (ROOT / "notes" / fig).read_bytes()
        if not target.exists() or target.read_bytes() != data:   # keep the mtime otherwise
            target.write_bytes(data)


def readme_commands() -> str:
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    setup_run, tests = blocks[0].strip(), blocks[1].strip()
    return ("Set up and run the paper's reproduction (the main job):\n\n```bash\n"
            f"{setup_run}\n```\n\nSet up and run the test suite:\n\n```bash\n{tests}\n```\n")


def _kvrod_command() -> list[str]:
    """The `kvrod` console script of this environment (else `python -m kvrod`)."""
    script = Path(sys.executable).with_name("kvrod")
    return [str(script)] if script.exists() else [sys.executable, "-m", "kvrod"]


def command_outputs(commands: tuple[str, ...]) -> str:
    """Markdown: each ``kvrod`` command and everything it prints (stdout and stderr, in
    order), run in a temporary folder with a copy of examples/; a failing command fails
    the build."""
    out = []
    with tempfile.TemporaryDirectory(prefix="kvrod-docs-") as tmp:
        shutil.copytree(ROOT / "examples", Path(tmp) / "examples")
        env = {**os.environ, "COLUMNS": "100", "NO_COLOR": "1"}
        for cmd in commands:
            proc = subprocess.run([*_kvrod_command(), *shlex.split(cmd)], cwd=tmp, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True, timeout=600, check=False)
            if proc.returncode != 0:
                raise ExtensionError(f"kvrod_docs: `kvrod {cmd}` exited with "
                                     f"{proc.returncode}:\n{proc.stdout[-2000:]}")
            out += ["```console", f"$ .venv/bin/kvrod {cmd}", proc.stdout.rstrip(), "```", ""]
    return "\n".join(out)


_COMMAND_SPAN = re.compile(r"`(kvrod [^`]+)`")
# a command on a line of its own, after "Regenerate:" / "regenerate with", or in a fence
_REGENERATE = re.compile(r"^\s*`(kvrod [^`]+)`\s*$|[Rr]egenerate(?: with)?:? `(kvrod [^`]+)`")


def _sections(lines: list[str]) -> list[tuple[str, list[str]]]:
    """(heading, body lines) of every ## / ### section of a note."""
    out: list[tuple[str, list[str]]] = []
    fenced = False
    for line in lines:
        if line.startswith("```"):
            fenced = not fenced
        m = None if fenced else re.match(r"#{2,3} (.*)", line)
        if m:
            out.append((m.group(1).strip(), []))
        elif out:
            out[-1][1].append(line)
    return out


def _section_commands(body: list[str]) -> list[str]:
    cmds, fenced = [], False
    for line in body:
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            if line.strip().startswith("kvrod "):
                cmds.append(line.strip())
            continue
        for m in _REGENERATE.finditer(line):
            cmds.append(m.group(1) or m.group(2))
    return list(dict.fromkeys(cmds))


def _tables(body: list[str]) -> list[list[str]]:
    tables: list[list[str]] = []
    previous = False
    for line in body:
        is_row = line.startswith("|")
        if is_row and not previous:
            tables.append([])
        if is_row:
            tables[-1].append(line)
        previous = is_row
    return [t for t in tables if len(t) >= 3]       # header, rule and at least one row


def validation_markdown() -> str:
    """The tables and figures of the generated notes, section by section, each with the
    command that regenerates it (the notes' own commands, copied from them)."""
    out = []
    for name, title in VALIDATION:
        text = _repo_links_as_code((ROOT / "notes" / f"{name}.md").read_text())
        lines = text.splitlines()
        top = _COMMAND_SPAN.search("\n".join(lines[:6]))
        if top is None:
            raise ExtensionError(f"kvrod_docs: notes/{name}.md names no command at its top")
        out += [f"## {title}", "",
                f"Regenerated by `{top.group(1)}`; the whole note, with its discussion: "
                f"{{doc}}`/_generated/notes/{name}`.", ""]
        found = 0
        for heading, body in _sections(lines):
            tables = _tables(body)
            figures = re.findall(r"!\[([^\]]*)\]\((figures/[^)]+)\)", "\n".join(body))
            if not tables and not figures:
                continue
            found += len(tables) + len(figures)
            out += [f"### {heading}", ""]
            cmds = _section_commands(body)
            if cmds:
                out += ["Regenerate: " + "; ".join(f"`{c}`" for c in cmds) + ".", ""]
            for table in tables:
                out += [*table, ""]
            for alt, src in figures:
                out += [f"![{alt}](notes/{src})", ""]
        if not found:
            raise ExtensionError(f"kvrod_docs: notes/{name}.md has no table or figure")
    return "\n".join(out)


def _compile_kernels() -> None:
    """Load (compiling on first use) the C kernels and the compiled BDF step loop, as a
    sweep worker does (runtime.study.worker_boot.warm_up)."""
    from runtime.model import build

    build.load_library()
    from runtime.solvers.native import loader

    loader.load()


def render(srcdir: Path) -> None:
    from derive.notes import render_derivation_notes

    dest = srcdir / "_generated"
    # On an empty compile cache the C kernels take ~20 s of compiler time; compile them
    # (in a compiler subprocess) while this process renders the derivation, before the
    # command outputs and the tutorials need them.
    compiling = threading.Thread(target=_compile_kernels, name="kvrod-compile", daemon=True)
    compiling.start()
    derivation_key = source_key(("derive", "generated"), ("sympy", "jinja2", "casadi"))
    _cached(dest / "derivation.md", derivation_key, render_derivation_notes)
    _write(dest / "problem_keys.md", keys_markdown())
    _write(dest / "cli.md", cli_markdown())
    _write(dest / "commands.md", readme_commands())
    for name in NOTES:
        _copy_note(name, dest)
    _write(dest / "validation.md", validation_markdown())
    bench = (ROOT / "bench" / "results" / "README.md").read_text()
    _write(dest / "bench.md", bench)
    for name in ("study_tau.toml", "maxwell_cantilever.toml"):
        _write(dest / "examples" / name, (ROOT / "examples" / name).read_text())
    compiling.join()
    _cached(dest / "first_rod.md", source_key() + repr(FIRST_ROD),
            lambda: command_outputs(FIRST_ROD))


#: jupyter-cache folders kept besides the current one (switching back to a recent branch
#: or revision reuses its executed notebooks)
KEEP_CACHES = 2


def _set_notebook_cache(app, config) -> None:
    """Execute the tutorials through a jupyter-cache folder named by :func:`source_key`
    (next to the HTML output: docs/_build/.jupyter_cache/KEY for the README's command), so
    a cached notebook is only ever reused with the code it ran against. A changed key
    changes this configuration value, so Sphinx reads every page again. Only the
    ``KEEP_CACHES`` most recently used other folders are kept."""
    root = Path(app.outdir).resolve().parent / ".jupyter_cache"
    current = root / source_key()[:20]
    current.mkdir(parents=True, exist_ok=True)
    os.utime(current)                                   # most recently used
    entries = [p for p in root.iterdir() if p != current]
    for p in entries:
        if not p.is_dir():                              # a cache from before the keys
            p.unlink()
    older = sorted((p for p in entries if p.is_dir()), key=lambda p: p.stat().st_mtime,
                   reverse=True)
    for p in older[KEEP_CACHES:]:
        shutil.rmtree(p, ignore_errors=True)
    config.nb_execution_cache_path = str(current)


def _on_builder_inited(app) -> None:
    render(Path(app.srcdir))


def _napoleon_without_attributes(app) -> None:
    """napoleon reads the first line of an attribute's or property's docstring as
    ``type: description`` (Google style) and turns the "type" into a cross-reference;
    kvrod's attribute comments are prose with colons ("per held end: the support's force
    ...") and their types come from the annotations. Attribute, data and property
    docstrings therefore bypass napoleon (which only does that type split for them);
    everything else is converted as before."""
    from sphinx.ext import napoleon

    for listener in list(app.events.listeners.get("autodoc-process-docstring", [])):
        if listener.handler is napoleon._process_docstring:
            app.disconnect(listener.id)

            def process(app, what, name, obj, options, lines, _convert=listener.handler):
                if what not in ("attribute", "data", "property"):
                    _convert(app, what, name, obj, options, lines)

            app.connect("autodoc-process-docstring", process, priority=listener.priority)


def setup(app):
    app.setup_extension("sphinx.ext.napoleon")
    _napoleon_without_attributes(app)
    app.connect("config-inited", _set_notebook_cache)
    app.connect("builder-inited", _on_builder_inited)
    return {"version": "1", "parallel_read_safe": True}
