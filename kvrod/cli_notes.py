"""`kvrod reproduce`, `notes-beyond`, `notes-examples`, `notes-maxwell`, `notes-sections`:
the notes that run studies and write Markdown with their figures (the generators are in
reports/).

Wired into `kvrod/cli.py` by ``add_commands(subparsers, parser_class)``.
"""

from __future__ import annotations

from pathlib import Path

from kvrod.progress import progress_bar

# --------------------------------------------------------------------------------------
# kvrod notes-beyond (reports/damping_studies.py)
# --------------------------------------------------------------------------------------


def _notes_paths(args, name: str, notes: str, out: str) -> tuple[Path, Path]:
    """(notes file, results folder) of a notes command: the defaults ``notes``, ``out``;
    ``--out DIR`` alone puts the notes into DIR as well (``DIR/NAME.md``, figures in
    DIR/figures), so only the default run rewrites the committed notes (which quote their
    results folder)."""
    from runtime.io.folder import check_file_argument

    results = Path(args.out or out)
    path = Path(args.out_notes or (results / f"{name}.md" if args.out else notes))
    check_file_argument(path, "--out-notes")
    return path, results


def _notes_names(path: Path, results: Path, *names: str) -> tuple[str, ...]:
    """What a notes command writes into its results folder (removed by --overwrite)."""
    from reports.run_info import FILES

    inside = (path.name,) if path.parent.resolve() == results.resolve() else ()
    return (*names, *FILES, *inside)


def _cmd_notes_beyond(args) -> int:
    from reports.damping_studies import write_beyond_notes
    from runtime.io.folder import results_folder

    path, out = _notes_paths(args, "beyond", "notes/beyond.md", "results/beyond")
    with results_folder(out, "notes-beyond",
                        markers=("compare-damping/compare_damping.json", "modes/modes.json",
                                 "calibration/calibration.json"),
                        overwrite=args.overwrite,
                        names=_notes_names(path, out, "compare-damping", "calibration",
                                           "modes", "modes-deformed")):
        path = write_beyond_notes(path, out, command=getattr(args, "command_line", "kvrod"))
    print(f"wrote {path} (results under {out}/)")
    return 0


def _cmd_notes_examples(args) -> int:
    from reports.examples import DYNAMIC, STATIC, write_examples_notes
    from runtime.io.folder import results_folder

    path, out = _notes_paths(args, "examples", "notes/examples.md", "results/examples")
    names = STATIC + DYNAMIC
    with results_folder(out, "notes-examples",
                        markers=tuple(f"{n}/summary.json" for n in names),
                        overwrite=args.overwrite, names=_notes_names(path, out, *names)):
        path = write_examples_notes(path, out, command=getattr(args, "command_line", "kvrod"))
    print(f"wrote {path} (results under {out}/)")
    return 0


def _cmd_notes_maxwell(args) -> int:
    from kvrod.notices import derivation
    from reports.maxwell import write_maxwell_notes
    from runtime.io.folder import results_folder

    path, out = _notes_paths(args, "maxwell", "notes/maxwell.md", "results/maxwell")
    with results_folder(out, "notes-maxwell",
                        markers=("simulate-mx/summary.json", "dma/fit/dma.json"),
                        overwrite=args.overwrite,
                        names=_notes_names(path, out, "modes-kv", "modes-mx", "simulate-kv",
                                           "simulate-mx", "dma")):
        derivation("kvrod notes-maxwell")       # the notes show derived results
        path = write_maxwell_notes(path, out, command=getattr(args, "command_line", "kvrod"))
    print(f"wrote {path} (results under {out}/)")
    return 0


def _cmd_notes_sections(args) -> int:
    from reports.sections import RESULTS, write_sections_notes
    from runtime.io.folder import results_folder

    path, out = _notes_paths(args, "sections", "notes/sections.md", "results/sections")
    with results_folder(out, "notes-sections",
                        markers=tuple(f"{n}/section.json" for n in RESULTS),
                        overwrite=args.overwrite, names=_notes_names(path, out, *RESULTS)):
        path = write_sections_notes(path, out, command=getattr(args, "command_line",
                                                               "kvrod notes-sections"))
    print(f"wrote {path} (results under {out}/)")
    return 0


# --------------------------------------------------------------------------------------
# kvrod reproduce (reports/reproduction.py)
# --------------------------------------------------------------------------------------


def _cmd_reproduce(args) -> int:
    from reports.reproduction import reproduce

    # --out alone keeps the notes with the results: only the default run rewrites the
    # committed notes/ (the notes quote their results folder)
    out = Path(args.out or "results/reproduce")
    notes = Path(args.notes or (out / "reproduction.md" if args.out else
                                "notes/reproduction.md"))
    from kvrod.notices import DerivationProgress

    out = reproduce(out, n_elements=args.n_elements, t_end=args.t_end,
                    notes=notes, rtol=args.rtol, derive=not args.skip_derive,
                    overwrite=args.overwrite, derive_progress=DerivationProgress(
                        "kvrod reproduce"),
                    command=getattr(args, "command_line", "kvrod reproduce"),
                    progress=progress_bar)
    print(f"wrote {out}")
    return 0


# --------------------------------------------------------------------------------------
# wiring
# --------------------------------------------------------------------------------------


def add_commands(sub, parser_class) -> None:
    """Add `reproduce`, `notes-beyond`, `notes-examples`, `notes-maxwell` and
    `notes-sections` to ``sub``."""
    _ = parser_class
    r = sub.add_parser("reproduce", help="reproduce the paper's Sect. 5 (figures + notes)")
    r.add_argument("--out", help="results folder (default results/reproduce; when given, "
                                 "the notes are written into it unless --notes says where)")
    r.add_argument("--notes", help="notes file to write (default notes/reproduction.md, or "
                                   "DIR/reproduction.md with --out DIR); notes/derivation.md "
                                   "goes beside it")
    r.add_argument("--n-elements", dest="n_elements", type=int, default=100)
    r.add_argument("--t-end", dest="t_end", type=float, default=10.0)
    r.add_argument("--rtol", type=float, default=1e-7,
                   help="relative tolerance (1e-7: energy audits below 1e-5; see the note)")
    r.add_argument("--overwrite", action="store_true",
                   help="replace the results of an earlier reproduction in --out")
    r.add_argument("--skip-derive", action="store_true",
                   help="do not regenerate notes/derivation.md")
    r.set_defaults(func=_cmd_reproduce)
    def notes_parser(name: str, text: str, notes: str, out: str):
        q = sub.add_parser(name, help=text)
        q.add_argument("--out-notes", dest="out_notes",
                       help=f"notes file (default {notes}, or DIR/{Path(notes).name} with --out "
                            "DIR; figures go to its figures/ folder)")
        q.add_argument("--out", help=f"results folder (default {out}; run time, compile time "
                                     "and solver counters go to its run-info.md)")
        q.add_argument("--overwrite", action="store_true",
                       help="replace the results of an earlier run in --out")
        return q

    notes_parser("notes-beyond", "run compare-damping, modes and calibration (modest "
                 "settings) and write notes/beyond.md", "notes/beyond.md",
                 "results/beyond").set_defaults(func=_cmd_notes_beyond)
    x = notes_parser("notes-examples", "run every example in examples/ against its "
                     "reference and write notes/examples.md", "notes/examples.md",
                     "results/examples")
    x.set_defaults(func=_cmd_notes_examples)
    notes_parser("notes-maxwell", "the generalized Maxwell rod: derivation, Kelvin-Voigt "
                 "against Maxwell cantilever, a DMA fit; writes notes/maxwell.md",
                 "notes/maxwell.md", "results/maxwell").set_defaults(func=_cmd_notes_maxwell)
    notes_parser("notes-sections", "composite and anisotropic sections (a cable, a "
                 "fibre-reinforced strip): consistent against naive viscosity, viscous "
                 "couplings; writes notes/sections.md", "notes/sections.md",
                 "results/sections").set_defaults(func=_cmd_notes_sections)
