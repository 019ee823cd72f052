"""Errors raised for bad user input.

Every input problem becomes a :class:`SceneError` whose message is one sentence naming the
field (a dotted path such as ``bents[1].x.stiffness``), the value, the unit and what is
allowed. The CLI prints that sentence and exits with status 2; nothing else is caught there.
"""

from __future__ import annotations


class SceneError(ValueError):
    """Bad scene, record or option given by the user.

    Parameters
    ----------
    field:
        Dotted path of the offending field, e.g. ``"contact.restitution"`` (may be empty).
    message:
        What is wrong and what is allowed, e.g. ``"must be in [0, 1], got 1.3"``.
    """

    def __init__(self, field: str, message: str):
        self.field = field
        self.reason = message
        super().__init__(f"{field}: {message}" if field else message)

    def prefixed(self, prefix: str) -> SceneError:
        """The same error with ``prefix`` prepended to its field path."""
        if not prefix:
            return self
        joined = (
            prefix
            if not self.field
            else (
                f"{prefix}{self.field}" if self.field.startswith("[") else f"{prefix}.{self.field}"
            )
        )
        return SceneError(joined, self.reason)


class EngineFailure(RuntimeError):
    """An engine could not finish a run (raised only when the caller asks for exceptions)."""


class DoubtfulResult(EngineFailure):
    """A run finished but failed a quality check (energy created by a contact, a work–energy
    balance that does not close): its answer is not to be trusted as it stands. The CLI exits
    with the engine-failure status unless ``run.accept_doubtful`` is set."""
