"""The exception tree of the library: one root, drawn here (as python-can's ``can/exceptions.py``).

Every exception class the library defines is in this picture, and each but one derives from
``EncoderConformanceError``, so ``except EncoderConformanceError`` catches whatever the library raises on
purpose. Each is defined below, and the module that raises it imports it from here (and keeps it importable
under its old name, e.g. ``encoder_conformance.dut.custody.custody.PreflightError``). Where a class also needs a base of
a library this package builds on, it derives from both; ``SdoAborted`` is defined beside the code that raises
it (``dut/link/device.py``), so that this module, at the bottom of every layer, imports no third-party package.
The exit code a class leads to is set where it is caught (``exit_codes.py`` names them)::

    Exception
     +-- EncoderConformanceError        the root of every error the library raises on purpose
          |   the command line and its files
          +-- UsageError                a bad option, file or combination (exit 4)
          +-- ProfileError              a device profile is missing, malformed or inconsistent
          +-- StationError              a station file is missing or invalid (config/station.py)
          +-- LssStop                   an expected end of an ``lss`` command, with its exit code (cli/lss_actions.py)
          |   the bus and the device
          +-- BusSetupError             the CAN bus could not be opened
          +-- DutLostError              the device stopped answering (a finding about the device)
          |    +-- BusLostError         the tester lost its bus: nothing can be tested
          +-- PreflightError            the run cannot start: pre-flight (dut/custody/custody.py)
          |    +-- IdentityMismatch     the node is plainly another product than the profile's
          +-- SdoAborted                the device refused an SDO request (dut/link/device.py); also canopen's
          |                             SdoAbortedError (-> SdoError), so a finding about the device
          +-- PowerSwitchError          the bench's power switch failed (dut/bench/power.py)
          +-- CannotPersist             the profile gives no way to store an entry (dut/store/persist.py)
          +-- NoUsableTpdo              no TPDO of the profile can serve a test: a skip (dut/tpdo/tpdo_choice.py)
          +-- NotJudged                 a check in scope could not judge the device (coverage.Hold says why): a
          |    |                        skip that makes the verdict INCOMPLETE or at most PASS WITH WARNINGS
          |    +-- HeldByPersistentError  an error no reset clears keeps the device out of the state a test needs
          |                             (dut/nmt/persistent_error.py)
          |   the simulator (control flow of its SDO server, never seen by a test)
          +-- SdoAbort                  makes the twin's SDO server answer with an abort (sim/engine/sdo_server.py)
          +-- SdoNoReply                makes the twin's SDO server send nothing (sim/engine/sdo_server.py)
          |   the run's history
          +-- HistoryError              the history database cannot be used (history/db.py)
          |   the user-space SocketCAN bus
          +-- BuildError                the preload library cannot be built; also a RuntimeError (vcan/build.py)
          +-- HubError                  the hub cannot be started or reached; also a RuntimeError (vcan/runtime.py)
          +-- HubStop                   SIGTERM/SIGINT: the hub process leaves its loop (vcan/hub.py)
          |   the simulator process
          +-- SimulatorStop             SIGTERM: the simulator leaves its wait, no lock taken in the handler
                                        (sim/engine/serve.py)

    BaseException
     +-- TypedSkip                      pytest's skip (its Skipped, an outcome, not an error) that says why: a scope
     |                                  kind or a coverage.Hold (plugin/skips.py)
     +-- KeyboardInterrupt
          +-- RunInterrupted            device calls once the run is stopping (Ctrl-C, SIGTERM); by design not an
                                        EncoderConformanceError: ``except Exception`` must not swallow it
"""

from __future__ import annotations

from encoder_conformance.coverage import Hold


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


class StationError(EncoderConformanceError):
    """The station file is missing or invalid; the message names file, key and fix."""


class LssStop(EncoderConformanceError):
    """An expected end of an ``lss`` command: ``str(exc)`` for the user, ``code`` the exit code."""

    def __init__(self, text: str, code: int) -> None:
        super().__init__(text)
        self.code = code


class BusSetupError(EncoderConformanceError):
    """The CAN bus could not be opened with the resolved configuration."""


class DutLostError(EncoderConformanceError):
    """The device stopped answering; later tests fail fast with this reason."""


class BusLostError(DutLostError):
    """The tester lost the CAN bus itself (connection closed, interface error): nothing can be tested."""


class PreflightError(EncoderConformanceError):
    """The run cannot start: one line saying what failed and what to check."""


class IdentityMismatch(PreflightError):
    """The node answers but is plainly another product than the profile's (a verdict about the device)."""


class PowerSwitchError(EncoderConformanceError):
    """The switch could not do what it was asked (the message names the command and its output)."""


class CannotPersist(EncoderConformanceError):
    """The profile gives no way to store this entry that a test may use."""


class NoUsableTpdo(EncoderConformanceError):
    """No TPDO of the profile can be used for the test; the message says why (a skip reason)."""

    def __init__(self, reason: str, deviations: list[tuple[str, str]], hold: Hold | None = None) -> None:
        super().__init__(reason)
        self.deviations = deviations
        self.hold = hold  # where the device's configuration, not the profile, left none usable


class NotJudged(EncoderConformanceError):
    """A check in scope could not judge the device; ``hold`` says why (a closed set, ``coverage.Hold``). The test
    becomes a skip that makes its area INCOMPLETE (not testable) or at most PASS WITH WARNINGS (inconclusive): never
    a pass, never a finding."""

    def __init__(self, hold: Hold, detail: str) -> None:
        self.hold = hold
        prefix = f"{hold.kind.value}: "
        super().__init__(detail if detail.startswith(prefix) else prefix + detail)


class HeldByPersistentError(NotJudged):
    """The device keeps an error that NMT reset communication does not clear and, as CiA 301 allows (1029h), stays
    out of the state the test needs (operational): the test cannot be run; the message says why (a skip)."""

    def __init__(self, detail: str) -> None:
        super().__init__(Hold.PERSISTENT_ERROR, detail)


class SdoAbort(EncoderConformanceError):
    """Raised by the simulator's ObjectAccess to make its SDO server answer with an abort frame."""

    def __init__(self, code: int) -> None:
        super().__init__(f"SDO abort 0x{code:08X}")
        self.code = code


class SdoNoReply(EncoderConformanceError):
    """Raised by the simulator's ObjectAccess when the device sends no response at all (e.g. it reboots)."""


class HistoryError(EncoderConformanceError):
    """The history database cannot be used (unreadable, not a database, newer schema, locked too long)."""


class BuildError(EncoderConformanceError, RuntimeError):
    """The vcan preload library cannot be built here; the message says why and what to do. Also a RuntimeError,
    as it was before it joined this tree."""


class HubError(EncoderConformanceError, RuntimeError):
    """The vcan hub could not be started or reached; the message says why. Also a RuntimeError, as it was before
    it joined this tree."""


class HubStop(EncoderConformanceError):
    """SIGTERM or SIGINT reached the vcan hub process: leave the relay loop and clean up."""


class SimulatorStop(EncoderConformanceError):
    """SIGTERM reached a simulator process: raised in its main thread out of its wait (an ``Event.set()`` in the
    handler deadlocked a twin whose main thread held that Event's lock inside the wait)."""


class RunInterrupted(KeyboardInterrupt):
    """Raised by device calls once the run is stopping (Ctrl-C, SIGTERM): a test's own clean-up must not
    race the restore. A KeyboardInterrupt, so ``except Exception`` in a test cannot swallow it."""
