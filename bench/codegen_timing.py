"""Time of the derivation, of ``kvrod generate`` and of compiling the generated C.

Every stage runs in a fresh Python process (nothing cached in memory; the derivation's
``lru_cache`` starts empty), timed inside the child, and separately the child's start-up
and imports:

- derivation: ``derive.pipeline.run()`` (all SymPy steps);
- generate: ``derive.artifacts.write_tree(tmp)`` (derivation, templates, CasADi kernels and
  C code into an empty temporary folder, as ``kvrod generate --out tmp``);
- compile: ``runtime.model.build.load_library()`` with ``KVROD_CACHE_DIR`` set to an empty
  temporary folder (gcc on the generated C, then loading it).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

_CHILD = {
    "derivation": (
        "import time; t0 = time.perf_counter(); from derive import pipeline; "
        "t1 = time.perf_counter(); pipeline.run(); t2 = time.perf_counter(); "
        "print(t1 - t0, t2 - t1)"),
    "generate": (
        "import sys, time; t0 = time.perf_counter(); from derive import artifacts; "
        "t1 = time.perf_counter(); paths = artifacts.write_tree(sys.argv[1]); "
        "t2 = time.perf_counter(); print(t1 - t0, t2 - t1, sum(p.stat().st_size "
        "for p in paths))"),
    "compile": (
        "import time; t0 = time.perf_counter(); from runtime.model import build; "
        "t1 = time.perf_counter(); lib = build.load_library(); t2 = time.perf_counter(); "
        "assert lib is not None, 'no library'; print(t1 - t0, t2 - t1)"),
}


def _child(stage: str, tmp: str) -> dict:
    env = dict(os.environ)
    if stage == "compile":
        env["KVROD_CACHE_DIR"] = tmp
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _CHILD[stage], tmp], capture_output=True,
                       text=True, env=env, timeout=1800)
    total = time.perf_counter() - t0
    if p.returncode != 0:
        return {"stage": stage, "ok": False, "message": p.stderr.strip()[-400:]}
    vals = [float(v) for v in p.stdout.split()[-3:]] if stage == "generate" else [
        float(v) for v in p.stdout.split()[-2:]]
    out = {"stage": stage, "ok": True, "import_seconds": vals[0], "seconds": vals[1],
           "process_seconds": total}
    if stage == "generate":
        out["bytes_written"] = int(vals[2])
    return out


def run(log=print) -> dict:
    rows = []
    for stage in ("derivation", "generate", "compile"):
        with tempfile.TemporaryDirectory(prefix=f"kvrod_{stage}_") as tmp:
            r = _child(stage, tmp)
        rows.append(r)
        if r["ok"]:
            log(f"  {stage}: {r['seconds']:.2f} s (imports {r['import_seconds']:.2f} s, "
                f"process {r['process_seconds']:.2f} s)")
        else:
            log(f"  {stage}: failed: {r['message']}")
    from bench.meta import metadata

    return {"rows": rows, "targets": [], "meta": metadata()}


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
