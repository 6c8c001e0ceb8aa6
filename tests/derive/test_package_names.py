"""The package's public functions keep their names when a derivation imports the step
modules (importing the subpackage derive.steps for the first time would rebind
``derive.steps`` to it)."""

from __future__ import annotations

import subprocess
import sys


def test_steps_stays_the_function_after_the_step_modules_are_imported():
    code = ("import importlib, derive\n"
            "importlib.import_module('derive.steps.biot')\n"      # as a derivation does
            "from derive import formulas, step, steps\n"
            "assert callable(steps) and steps.__module__ == 'derive', steps\n"
            "assert callable(formulas) and callable(step)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
