"""The exception tree of the library (one root, as python-can's exceptions.py)."""

from __future__ import annotations


class EncoderConformanceError(Exception):
    """Root of every error this library raises on purpose."""


class UsageError(EncoderConformanceError):
    """A bad option, file or combination on the command line: the message names it and says how to fix it
    (one line on stderr, exit code 4)."""


class ProfileError(EncoderConformanceError):
    """A device profile file is missing, malformed or inconsistent.

    ``problems`` holds one line per problem: ``file: key.path: what is wrong; how to fix``.
    """

    def __init__(self, path: str, problems: list[str]) -> None:
        self.path = path
        self.problems = problems
        lines = "\n".join(f"  - {p}" for p in problems)
        super().__init__(f"invalid device profile {path} ({len(problems)} problem(s)):\n{lines}")


class BusSetupError(EncoderConformanceError):
    """The CAN bus could not be opened with the resolved configuration."""


class DutLostError(EncoderConformanceError):
    """The device stopped answering; later tests fail fast with this reason."""


class BusLostError(DutLostError):
    """The tester lost the CAN bus itself (connection closed, interface error): nothing can be tested."""


class RunInterrupted(KeyboardInterrupt):
    """Raised by device calls once the run is stopping (Ctrl-C, SIGTERM): a test's own clean-up must not
    race the restore. A KeyboardInterrupt, so ``except Exception`` in a test cannot swallow it."""
