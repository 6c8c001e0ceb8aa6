"""Notes and reports generated from runs: the paper's reproduction, the examples against their
references, damping studies, the generalized Maxwell rod (each written by a `kvrod` command;
timings and machine facts go to the results folder, not into the tracked notes)."""
