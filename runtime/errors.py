"""Project error classes (docs/design.md, section 5)."""

from __future__ import annotations

from generated import constitutive


class ParameterError(constitutive.ParameterError):
    """A bad parameter value; the message names the parameter, its value and the range.

    A subclass of the generated module's ParameterError (a ValueError), so one
    ``except ParameterError`` catches bad input from every layer.
    """

    def __init__(self, name: str, value: object, allowed: str, where: str = "") -> None:
        self.name, self.value, self.allowed, self.where = name, value, allowed, where
        shown = value if not isinstance(value, str) or len(value) < 80 else value[:77] + "..."
        prefix = f"{where}: " if where else ""
        super().__init__(f"{prefix}parameter {name!r} = {shown!r} is outside the allowed "
                         f"range: {allowed}")


class IllPosedError(ValueError):
    """A problem that is valid key by key but has no solution to compute as posed (a
    free-free rod under a net load in statics, a rod too soft for its loads); the message
    says why and ``key`` names the problem key that fixes it. Raised before any work."""

    def __init__(self, message: str, key: str = "") -> None:
        super().__init__(message)
        self.key = key


class GeneratedCodeError(RuntimeError):
    """generated/ is inconsistent with its manifest (regenerate with `kvrod generate`)."""


class Terminated(BaseException):
    """SIGTERM turned into an exception (by the command line), so that a run can record
    where it stopped, like Ctrl-C (KeyboardInterrupt)."""


#: the exceptions that interrupt a run (it records "interrupted" and re-raises them)
INTERRUPTS: tuple[type[BaseException], ...] = (KeyboardInterrupt, Terminated)
