"""Project error classes (design section 5)."""

from __future__ import annotations

from generated import constitutive


class ParameterError(constitutive.ParameterError):
    """A bad parameter value; the message names the parameter, its value and the range.

    A subclass of the generated module's ParameterError (a ValueError), so one
    ``except ParameterError`` catches bad input from every layer.
    """

    def __init__(self, name: str, value: object, allowed: str) -> None:
        self.name, self.value, self.allowed = name, value, allowed
        super().__init__(f"parameter {name!r} = {value!r} is outside the allowed range: "
                         f"{allowed}")


class GeneratedCodeError(RuntimeError):
    """generated/ is inconsistent with its manifest (regenerate with `kvrod generate`)."""
