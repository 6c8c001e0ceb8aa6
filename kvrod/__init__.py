"""kvrod: the command-line application on top of derive/, generated/ and runtime/.

This package is the only place that may import all three layers (the CLI derives,
generates and simulates); it imports each lazily, per command.
"""

__version__ = "0.1.0"
