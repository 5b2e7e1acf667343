"""Exit codes of a conformance run (`encoder-conformance run` and `pytest suites`), documented in the README.

A bench script must be able to tell a non-conforming device from a run that could not test it,
and both from a device the run could not put back as it was found.
"""

from __future__ import annotations

from enum import IntEnum


class RunExit(IntEnum):
    """What a conformance run's exit status means."""

    PASSED = 0  # every check that may fail a device passed
    NON_CONFORMANT = 1  # at least one check failed: the device does not conform
    INTERNAL_ERROR = 3  # a bug in the tool (pytest's code)
    USAGE_ERROR = 4  # bad options, profile or station file (pytest's code)
    NO_TESTS = 5  # nothing selected (pytest's code)
    INCOMPLETE = 6  # nothing failed, but a check in scope was not testable (the device's state kept it from judging)
    COULD_NOT_TEST = 69  # bus lost, device silent, pre-flight failed: no verdict about the device
    NOT_RESTORED = 70  # the run could not put the device back as found: see the report, run 'restore --from'
    INTERRUPTED = 130  # Ctrl-C (SIGINT); SIGTERM gives 143


def interrupted_by(signum: int) -> int:
    """The shell's convention: 128 + the signal number."""
    return 128 + signum


DESCRIPTIONS: dict[int, str] = {  # keyed by RunExit; looked up with any exit status
    RunExit.PASSED: "passed",
    RunExit.NON_CONFORMANT: "device non-conformant",
    RunExit.INTERNAL_ERROR: "internal error of the tool",
    RunExit.USAGE_ERROR: "usage error (options, profile, station file)",
    RunExit.NO_TESTS: "no tests selected",
    RunExit.INCOMPLETE: "incomplete: no failure, but checks in scope were not testable (see the coverage per area)",
    RunExit.COULD_NOT_TEST: "could not test (bus lost, device silent, pre-flight failed)",
    RunExit.NOT_RESTORED: "device not restored as found (finish with 'encoder-conformance restore --from')",
    RunExit.INTERRUPTED: "interrupted (Ctrl-C; 143 for SIGTERM)",
}
