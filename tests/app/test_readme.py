"""The README's copy-paste commands work (issue 6, item 7).

Every command in a ```bash block after the set-up section is run as written, with
`.venv/bin/kvrod` replaced by this interpreter's `python -m kvrod` and in a temporary
working directory (so results and notes land there). The two set-up commands themselves
are what CI (.ci/run) and the main job run.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def readme_blocks() -> list[list[str]]:
    """The commands of each ```bash block after the set-up section (comments dropped)."""
    text = README.read_text()
    body = text.split("## The three uses", 1)[1]
    blocks = []
    for block in re.findall(r"```bash\n(.*?)```", body, flags=re.S):
        cmds = [line.split("#", 1)[0].strip() for line in block.splitlines()]
        blocks.append([c for c in cmds if c])
    return blocks


def readme_commands() -> list[str]:
    return [c for b in readme_blocks() for c in b]


def redirect_into(argv: list[str], tmp_path: Path) -> list[str]:
    """``kvrod generate`` (which rewrites the checkout's generated/) writes into the temporary
    directory instead, so the suite never touches tracked files and the staleness tests keep
    seeing the committed tree. Every other command already writes relative to the cwd."""
    if argv[1:2] == ["generate"] and "--out" not in argv and "--check" not in argv:
        return [*argv, "--out", str(tmp_path / "regenerated")]
    return argv


def test_generate_is_redirected(tmp_path):
    assert redirect_into([".venv/bin/kvrod", "generate"], tmp_path)[-1] == str(
        tmp_path / "regenerated")
    # --check only reads the checkout
    assert redirect_into([".venv/bin/kvrod", "generate", "--check"], tmp_path)[-1] == "--check"


def test_readme_commands_do_not_collide_with_the_main_job():
    """The main job writes results/reproduce and notes/; a README command run after it must
    not need that folder empty (it would exit 2: the folder holds a result)."""
    for cmd in readme_commands():
        argv = shlex.split(cmd.split("#", 1)[0])
        if argv[1:2] == ["reproduce"]:
            assert "--out" in argv, cmd
            assert argv[argv.index("--out") + 1].rstrip("/") != "results/reproduce", cmd


def test_readme_has_commands_for_the_three_uses():
    cmds = readme_commands()
    assert any(" generate" in c for c in cmds)
    assert any(" derive show" in c for c in cmds)
    assert any(" simulate" in c for c in cmds)


@pytest.mark.parametrize("block", readme_blocks(), ids=lambda b: b[0][:60])
def test_readme_block(block, tmp_path):
    """The commands of one block run in order in one fresh working directory."""
    for cmd in block:
        argv = shlex.split(cmd)
        assert argv[0] == ".venv/bin/kvrod", f"not a .venv/bin/kvrod command: {cmd}"
        # inputs shipped with the checkout (examples/*.toml) are read from the repo; every
        # other path stays relative to the temporary working directory
        repo = README.parent
        argv = [str(repo / a) if a.startswith("examples/") else a for a in argv]
        argv = redirect_into(argv, tmp_path)
        r = subprocess.run([sys.executable, "-m", "kvrod", *argv[1:]], cwd=tmp_path,
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, f"{cmd}\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}"


def test_readme_problem_file_and_python_snippet(tmp_path):
    """The abridged problem file of the README is a valid problem, and the Python snippet
    runs as written from any folder (it names a built-in problem)."""
    import tomllib

    from runtime.problem.schema import Problem

    text = README.read_text()
    (toml_block,) = re.findall(r"```toml\n(.*?)```", text, flags=re.S)
    problem = Problem.from_mapping(tomllib.loads(toml_block))
    assert problem.name == "my_rod" and problem.section.kind == "circle"
    (py_block,) = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    r = subprocess.run([sys.executable, "-c", py_block], cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and r.stdout.startswith("finished"), r.stderr[-2000:]
