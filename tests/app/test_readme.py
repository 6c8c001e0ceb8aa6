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


def readme_commands() -> list[str]:
    text = README.read_text()
    body = text.split("## The three uses", 1)[1]
    cmds = []
    for block in re.findall(r"```bash\n(.*?)```", body, flags=re.S):
        for line in block.splitlines():
            line = line.split("#", 1)[0].strip()
            if line:
                cmds.append(line)
    return cmds


def test_readme_has_commands_for_the_three_uses():
    cmds = readme_commands()
    assert any(" generate" in c for c in cmds)
    assert any(" derive show" in c for c in cmds)
    assert any(" simulate" in c for c in cmds)


@pytest.mark.parametrize("cmd", readme_commands())
def test_readme_command(cmd, tmp_path):
    argv = shlex.split(cmd)
    assert argv[0] == ".venv/bin/kvrod", f"not a .venv/bin/kvrod command: {cmd}"
    r = subprocess.run([sys.executable, "-m", "kvrod", *argv[1:]], cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"{cmd}\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}"
