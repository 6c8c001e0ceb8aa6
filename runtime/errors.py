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


class Terminated(BaseException):
    """SIGTERM turned into an exception (by the command line), so that a run can record
    where it stopped, like Ctrl-C (KeyboardInterrupt)."""


#: exceptions that interrupt a run: it records "interrupted" and re-raises them
INTERRUPTS: tuple[type[BaseException], ...] = (KeyboardInterrupt, Terminated)
