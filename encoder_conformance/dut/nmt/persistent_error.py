"""An error the device keeps across NMT reset communication, and the states it may then refuse.

CiA 301 v4.2.0 object 1029h (error behaviour, §7.5.2.32): a serious device failure in operational sends the device
to pre-operational by default. A device that finds a failure at every start-up (CANopenNode's Linux demo without its
storage files: EMCY 5000h, 1001h = 01h, at each boot-up) therefore never stays in operational. A test that needs
operational cannot be run on it: where operational was not reached and 1001h stays set after NMT reset
communication, the test says so (``HeldByPersistentError``, a skip) instead of failing the device for a state a
conformant device may be in. An error that the reset clears (one a test left) is no such reason: the test's own
verdict stands (open reading persistent-error-holds-pre-operational).
"""

from __future__ import annotations

from weakref import WeakKeyDictionary

from encoder_conformance.cia.cia301 import ERROR_HISTORY, ERROR_REGISTER, NmtState
from encoder_conformance.dut.link.device import DeviceLink, SdoAborted
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.nmt.commands import send_command
from encoder_conformance.dut.nmt.heartbeat_state import leave_stopped
from encoder_conformance.errors import HeldByPersistentError

CLAUSE = ("CiA 301 v4.2.0 object 1029h (error behaviour, §7.5.2.32): a device failure sends the device from "
          "operational to pre-operational by default")
#: what the kept error means for most tests: the state they need is not reached
OUT_OF_OPERATIONAL = f"and does not stay in operational ({CLAUSE})"


def error_register(dut: DeviceLink) -> int:
    """1001h now (0 where the profile has none)."""
    return dut.read_uint(ERROR_REGISTER) if dut.profile.entry(ERROR_REGISTER, 0) is not None else 0


def _newest_error(dut: DeviceLink) -> str:
    """", newest 1003h entry XXXXXXXXh" where the device has an error history with an entry, else ""."""
    if dut.profile.entry(ERROR_HISTORY, 1) is None:
        return ""
    try:
        if not dut.read_uint(ERROR_HISTORY, 0):
            return ""
        return f", newest 1003h entry {dut.read_uint(ERROR_HISTORY, 1):08X}h"
    except SdoAborted:
        return ""


#: per device, the 1001h value it kept after a reset communication: seen again, it is not reset once more (a device
#: that boots in seconds would spend them on every test that needs operational)
_KEPT: WeakKeyDictionary[DeviceLink, int] = WeakKeyDictionary()


def kept_error(dut: DeviceLink) -> int:
    """1001h as the device kept it after a reset communication in this run (0: none seen)."""
    return _KEPT.get(dut, 0)


def reset_and_read(dut: DeviceLink) -> tuple[Mark, int | None]:
    """NMT reset communication, its boot-up, then 1001h (remembered: ``kept_error``); None where no boot-up came.
    Returns the mark before the reset too, for a caller that names the frames after it."""
    mark = send_command(dut, "reset-communication")
    if dut.wait_bootup(mark) is None:
        return mark, None
    after = error_register(dut)
    if after:
        _KEPT[dut] = after
    else:
        _KEPT.pop(dut, None)
    return mark, after


def persisting_error(dut: DeviceLink) -> int | None:
    """1001h where it is set and stays set after NMT reset communication and its boot-up, else None (1001h is 0,
    the reset cleared it, or no boot-up came: the caller's own verdict stands then). The value the device kept
    after an earlier reset in this run counts without a new one. A device that may be in stopped is brought out of
    it before the first SDO request (``heartbeat_state.leave_stopped``, else the reset)."""
    if not dut.usable:
        return None
    if not leave_stopped(dut):  # no SDO in stopped (CiA 301 §7.3.2.2): reset communication brings it out
        return reset_and_read(dut)[1] or None
    register = error_register(dut)
    if not register:
        return None
    if register == kept_error(dut):
        return register
    return reset_and_read(dut)[1] or None


def describe_hold(dut: DeviceLink, what: str, register: int, consequence: str = OUT_OF_OPERATIONAL) -> str:
    """The skip reason: ``what`` is not testable, the device holding error register ``register`` after a reset."""
    return (f"not testable: {what}: the device keeps an error that NMT reset communication does not clear (1001h = "
            f"{register:02X}h{_newest_error(dut)}) {consequence}")


def raise_if_held_by_error(dut: DeviceLink, what: str, consequence: str = OUT_OF_OPERATIONAL) -> None:
    """``HeldByPersistentError`` where 1001h is set and stays set after NMT reset communication; else returns, the
    device without an error (the reset cleared it). Where operational was not reached, the caller's own verdict
    follows; as a test's precondition, the test then starts with no error active."""
    register = persisting_error(dut)
    if register is not None:
        raise HeldByPersistentError(describe_hold(dut, what, register, consequence))


def raise_if_held_out_of(dut: DeviceLink, expected: int, what: str) -> None:
    """A state was expected and not reached: where it was operational, ``HeldByPersistentError`` if an error the
    device keeps explains it (the caller raises its own verdict otherwise)."""
    if expected == NmtState.OPERATIONAL:
        raise_if_held_by_error(dut, what)
