"""Pages rendered from the code at every docs build (so they cannot drift):

* ``_generated/derivation.md``: the derivation, from the same step records as
  ``kvrod derive`` (:func:`derive.notes.render_derivation_notes`);
* ``_generated/problem_keys.md``: every problem-file key (:mod:`runtime.problem.keys`);
* ``_generated/cli.md``: every command and flag, from the argument parser
  (:func:`kvrod.cli.build_parser`);
* ``_generated/notes/*.md`` and ``_generated/bench.md``: the generated notes and the
  benchmark tables, with their figures;
* ``_generated/commands.md``: the README's two commands;
* ``_generated/examples/``: the example files the pages include.
"""

from __future__ import annotations

import argparse
import re
import shutil
from pathlib import Path

import kvrod

ROOT = Path(kvrod.__file__).resolve().parents[1]
NOTES = ("reproduction", "examples", "beyond", "maxwell")


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:   # unchanged pages stay unchanged
        path.write_text(text)


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
            "the same. The kinds column names the `kind` (or material `model`) a key "
            "belongs to. Examples: `examples/*.toml`.\n\n" + keys.markdown())


def _copy_note(name: str, dest: Path) -> None:
    text = (ROOT / "notes" / f"{name}.md").read_text()
    # links to files of the repository become code text (they are not pages here)
    text = re.sub(r"\[([^\]]*)\]\((?!figures/|https?:)([^)]+)\)", r"\1 (`\2`)", text)
    _write(dest / "notes" / f"{name}.md", text)
    for fig in sorted(set(re.findall(r"\]\((figures/[^)]+)\)", text))):
        target = dest / "notes" / fig
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / "notes" / fig, target)


def readme_commands() -> str:
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    setup_run, tests = blocks[0].strip(), blocks[1].strip()
    return ("Set up and run the paper's reproduction (the main job):\n\n```bash\n"
            f"{setup_run}\n```\n\nSet up and run the test suite:\n\n```bash\n{tests}\n```\n")


def render(srcdir: Path) -> None:
    from derive.notes import render_derivation_notes

    dest = srcdir / "_generated"
    _write(dest / "derivation.md", render_derivation_notes())
    _write(dest / "problem_keys.md", keys_markdown())
    _write(dest / "cli.md", cli_markdown())
    _write(dest / "commands.md", readme_commands())
    for name in NOTES:
        _copy_note(name, dest)
    bench = (ROOT / "bench" / "results" / "README.md").read_text()
    _write(dest / "bench.md", bench)
    for name in ("study_tau.toml", "maxwell_cantilever.toml"):
        _write(dest / "examples" / name, (ROOT / "examples" / name).read_text())


def _on_builder_inited(app) -> None:
    render(Path(app.srcdir))


def setup(app):
    app.connect("builder-inited", _on_builder_inited)
    return {"version": "1", "parallel_read_safe": True}
