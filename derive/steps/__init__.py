"""The derivation steps, one module per part of the paper (design section 2)."""
