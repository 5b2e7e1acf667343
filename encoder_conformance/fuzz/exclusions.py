"""The objects the SDO fuzzer never sends a download to, each with the reason.

A fuzzer on a bench must not wear the EEPROM (store, restore), move the device to another node-ID or
bit rate, or move a machine's reference point (preset, zeroing). What can be derived is derived from
the profile (CiA 301 store/restore, the quirks that declare node-ID, bit-rate, store and zeroing objects,
the CiA 406 preset); a profile adds its own in ``sdo_fuzz_never_write`` (index -> reason).
"""

from __future__ import annotations

from encoder_conformance.cia.cia301 import RESTORE_DEFAULT_PARAMETERS, STORE_PARAMETERS
from encoder_conformance.models.encoder.objects import HIGH_PRECISION_PRESET, EncoderObjects
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile

#: quirk effects whose object a write must never reach, and why
_QUIRK_OBJECTS: tuple[tuple[type[fx.ObjectAt], str], ...] = (
    (fx.NodeIdObject, "node-ID object: the device would answer at another node-ID"),
    (fx.BitrateObject, "bit-rate object: the device would leave the bus's bit rate"),
    (fx.ManufacturerStoreObject, "manufacturer store command: EEPROM wear, changes what the device keeps"),
    (fx.StoreRebootsWithoutReply, "store command (reboots): EEPROM wear and a restart"),
    (fx.ZeroingObject, "zeroing command: moves the machine's reference point"),
)


def never_write(profile: DeviceProfile) -> dict[int, str]:
    """Object index -> why the fuzzer sends no download (expedited, segmented or truncated) to it."""
    excluded = {
        STORE_PARAMETERS: "1010h store parameters: EEPROM wear, changes what the device keeps (CiA 301 §7.5.2.13)",
        RESTORE_DEFAULT_PARAMETERS: "1011h restore defaults: loses the configuration at the next reset "
                                    "(CiA 301 §7.5.2.14)",
    }
    for effect, why in _QUIRK_OBJECTS:
        for found in profile.quirks_with(effect):
            excluded.setdefault(found.params.index, f"{why} (quirk {found.id})")
    if profile.capabilities.preset:
        preset = EncoderObjects.of(profile).preset
        excluded.setdefault(preset, "preset: moves the machine's reference point (CiA 406)")
        excluded.setdefault(HIGH_PRECISION_PRESET, "64-bit preset: moves the machine's reference point (CiA 406)")
    for index, why in profile.sdo_fuzz_never_write.items():
        excluded.setdefault(index, f"{why} (profile sdo_fuzz_never_write)")
    return dict(sorted(excluded.items()))


def self_storing(profile: DeviceProfile) -> frozenset[tuple[int, int]]:
    """Entries the device writes to its memory on every write (``persisted_by: auto``): EEPROM wear even for
    a refused write on a lenient device, and the run's store watch counts every download to them."""
    return frozenset((i, s) for i, s, _, e in profile.iter_entries() if e.persisted_by == "auto")


def describe(excluded: dict[int, str], entries: frozenset[tuple[int, int]] = frozenset()) -> str:
    """One line per object (and one for the self-storing entries), for the report."""
    lines = [f"{index:04X}h: {why}" for index, why in excluded.items()]
    if entries:
        listed = ", ".join(f"{i:04X}h.{s:02X}" for i, s in sorted(entries))
        lines.append(f"entries the device stores by itself (persisted_by: auto): {listed}")
    return "\n".join(lines)
