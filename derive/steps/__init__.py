"""The derivation steps, one module per part of the paper (docs/design.md, section 2)."""
