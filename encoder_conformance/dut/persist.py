"""Make one changed entry survive a reset, the way the device's profile says it is stored.

``persisted_by`` names the mechanism: a 1010h sub-index (CiA 301 §7.5.2.13), a manufacturer store
object (quirk ``manufacturer_store_object``) or nothing at all (``auto``: the device stores by itself).
"""

from __future__ import annotations

from ..parameters import parse_key
from .device import DeviceUnderTest

SAVE = (0x65766173).to_bytes(4, "little")
#: persisted_by -> the 1010h sub-index CiA 301 gives that group (sub 1 stores everything)
STORE_SUB = {"store_all": 1, "store_comm": 2, "store_app": 3, "store_manufacturer": 4}


class CannotPersist(Exception):
    """The profile gives no way to store this entry that a test may use."""


def persist_entry(dut: DeviceUnderTest, index: int, sub: int) -> str:
    """Store the entry's current value; returns how (for the evidence). Raises CannotPersist."""
    profile = dut.profile
    entry = profile.entry(index, sub)
    if entry is None:
        raise CannotPersist(f"{index:04X}h.{sub:02X} is not declared")
    how = entry.persisted_by
    if how == "auto":
        return "stored by the device itself on write (persisted_by: auto)"
    if how in STORE_SUB:
        subs = profile.capabilities.store_subindices
        store_sub = STORE_SUB[how] if STORE_SUB[how] in subs else 1
        if store_sub not in subs:
            raise CannotPersist(f"{index:04X}h.{sub:02X} is {how}, but the profile declares no 1010h sub-index")
        dut.write(0x1010, store_sub, SAVE)
        return f"1010h.{store_sub:02X} 'save'"
    if how == "manufacturer_store":
        found = profile.quirk_with_effect("manufacturer_store_object")
        if found is not None and (index, sub) in {parse_key(k) for k in found[1].params.get("saves", [])}:
            params = found[1].params
            command = (int(params["index"]), int(params.get("subindex", 0)))
            dut.write(*command, int(params.get("signature", 0x65766173)).to_bytes(4, "little"))
            return f"{command[0]:04X}h.{command[1]:02X} 'save' (quirk {found[0]})"
    raise CannotPersist(f"{index:04X}h.{sub:02X} (persisted_by: {how}) has no store command a test can use")
