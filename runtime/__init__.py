"""kvrod runtime: implicit integrator, static solver, scenarios, analysis and I/O."""
