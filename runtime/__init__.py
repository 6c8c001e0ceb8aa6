"""kvrod runtime: problems, the rod model over the generated kernels, integrator and static
solver, simulation, analyses, studies and I/O (floors: docs/design.md, tests/test_layering.py)."""
