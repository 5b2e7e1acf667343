"""Make changed entries survive a reset, the way the device's profile says they are stored.

``persisted_by`` names the mechanism: a 1010h sub-index (CiA 301 §7.5.2.13), a manufacturer store
object (quirk ``manufacturer_store_object``), a store command that reboots instead of answering
(quirk ``store_reboots_without_reply``, e.g. POSITAL 2300h), or nothing at all (``auto``: the device
stores by itself). The tests and the run's restore use the same commands.
"""

from __future__ import annotations

from dataclasses import dataclass

from encoder_conformance.cia.cia301 import SAVE, STORE_PARAMETERS, STORE_SUB_OF_GROUP
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.errors import CannotPersist
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile

__all__ = ["SAVE", "STORE_SUB", "CannotPersist", "StoreCommand", "persist_entry", "store_commands_for"]

STORE_SUB = STORE_SUB_OF_GROUP  # persisted_by -> the 1010h sub-index CiA 301 gives that group


@dataclass(frozen=True)
class StoreCommand:
    """One command that stores: an SDO download of ``signature`` to ``index``/``sub``."""

    index: int
    sub: int
    signature: bytes
    reboots: bool = False  # no SDO reply; the device reboots and sends a boot-up (store_reboots_without_reply)
    quirk: str | None = None

    @property
    def label(self) -> str:
        via = f" (quirk {self.quirk})" if self.quirk else ""
        return f"{self.index:04X}h.{self.sub:02X} 'save'{via}"

    def request(self) -> bytes:
        """The raw download frame; a reboot store uses the manual's 'size not indicated' form (22h)."""
        frame = sdo_frames.expedited_download_request(self.index, self.sub, self.signature)
        return bytes([0x22]) + frame[1:] if self.reboots else frame

    def issue(self, dut: DeviceLink) -> None:
        """Send it; for a rebooting store, wait for the boot-up (AssertionError if none comes)."""
        if not self.reboots:
            dut.write(self.index, self.sub, self.signature)
            return
        mark = dut.frames.mark()
        dut.sdo_request(self.request())
        if dut.wait_bootup(mark, timeout=dut.profile.timing.store_max_ms / 1000) is None:
            raise AssertionError(f"no boot-up within {dut.profile.timing.store_max_ms:.0f} ms after {self.label}")


def _reboot_store(profile: DeviceProfile) -> StoreCommand | None:
    found = profile.quirk(fx.StoreRebootsWithoutReply)
    if found is None:
        return None
    params = found.params
    return StoreCommand(params.index, params.subindex, params.signature_bytes, True, found.id)


def _manufacturer_store(profile: DeviceProfile, index: int, sub: int) -> StoreCommand | None:
    found = profile.quirk(fx.ManufacturerStoreObject)
    if found is None:
        return None
    params = found.params
    if (index, sub) not in params.saves:
        return None
    return StoreCommand(params.index, params.subindex, params.signature_bytes, quirk=found.id)


def _store_command(profile: DeviceProfile, index: int, sub: int) -> StoreCommand | None:
    """The command that stores this entry; None for entries the device stores by itself."""
    entry = profile.entry(index, sub)
    if entry is None:
        raise CannotPersist(f"{index:04X}h.{sub:02X} is not declared")
    how = entry.persisted_by
    if how == "auto":
        return None
    if how in STORE_SUB:
        subs = profile.capabilities.store_subindices
        store_sub = STORE_SUB[how] if STORE_SUB[how] in subs else 1
        if store_sub not in subs:
            raise CannotPersist(f"{index:04X}h.{sub:02X} is {how}, but the profile declares no 1010h sub-index")
        return StoreCommand(STORE_PARAMETERS, store_sub, SAVE)
    if how == "manufacturer_store":
        command = _manufacturer_store(profile, index, sub) or _reboot_store(profile)
        if command is not None:
            return command
    raise CannotPersist(f"{index:04X}h.{sub:02X} (persisted_by: {how}) has no store command a test can use")


def store_commands_for(profile: DeviceProfile, keys: list[tuple[int, int]]) -> list[StoreCommand]:
    """The fewest commands that store all ``keys`` (1010h sub 1 covers every 1010h group); raises CannotPersist."""
    commands: list[StoreCommand] = []
    for index, sub in keys:
        command = _store_command(profile, index, sub)
        if command is not None and command not in commands:
            commands.append(command)
    if any(c.index == STORE_PARAMETERS and c.sub == 1 for c in commands):
        commands = [c for c in commands if c.index != STORE_PARAMETERS or c.sub == 1]
    return sorted(commands, key=lambda c: c.reboots)  # a rebooting store last: it resets the device


def persist_entry(dut: DeviceLink, index: int, sub: int) -> str:
    """Store the entry's current value; returns how (for the evidence). Raises CannotPersist."""
    command = _store_command(dut.profile, index, sub)
    if command is None:
        return "stored by the device itself on write (persisted_by: auto)"
    command.issue(dut)
    return command.label
