"""The TPDO a test configures, its communication parameter written field by field (named as canopen's PDO ``Map``:
cob_id, trans_type, inhibit_time, event_timer, sync_start_value; the mapping read as the device has it) through
the test's settings journal, so that it is put back after the test. Shared by the TPDO, SYNC, NMT, CAM and encoder
suites and the periodic capture, so they configure a TPDO the same way."""

from __future__ import annotations

from dataclasses import dataclass

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.custody.settings_journal import SettingsJournal
from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.sdo.sdo_frames import abort_name
from encoder_conformance.dut.tpdo.pdo_mapping import Entry, read_mapping
from encoder_conformance.dut.tpdo.tpdo import TpdoParameters
from encoder_conformance.dut.tpdo.tpdo_choice import TpdoChoice
from encoder_conformance.dut.tpdo.tpdo_while_invalid import WhileInvalid
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.schema import DeviceProfile


@dataclass
class TpdoUnderTest(TpdoParameters):
    """One TPDO of the device, configured for a test; every write goes through ``journal``."""

    dut: DeviceLink
    journal: SettingsJournal
    comm: int  # its communication parameter (18xxh)
    trans_type: int  # the transmission type the test uses (the device's own where sub 2 is read-only)

    @classmethod
    def chosen(cls, dut: DeviceLink, journal: SettingsJournal, choice: TpdoChoice) -> TpdoUnderTest:
        """The TPDO ``choice`` names (``choose_tpdo``), enabled for the test where it is disabled."""
        tpdo = cls(dut, journal, choice.comm, choice.transmission_type)
        if choice.enable_cob_id is not None:
            tpdo.configure(cob_id=choice.enable_cob_id)
        return tpdo

    def configure(self, *, cob_id: int | None = None, trans_type: int | None = None,
                  event_timer: int | None = None) -> None:
        """Write the fields given, in the order of their sub-indices: sub 1 COB-ID, sub 2 transmission type (only
        where sub 2 is writable: a read-only one holds the type the choice took), sub 5 event timer (ms)."""
        if cob_id is not None:
            self.journal.write(self.comm, 1, cob_id.to_bytes(4, "little"))
        if trans_type is not None and self.writable(2):
            try:
                self.journal.write(self.comm, 2, bytes([trans_type]))
            except SdoAbortedError as exc:  # the profile's claim, not the test's subject: say which claim failed
                if trans_type not in self.dut.profile.capabilities.tpdo_transmission_types:
                    raise
                raise AssertionError(
                    f"{self.comm:04X}h.02 = {trans_type} refused with {abort_name(exc.code)}, although the profile "
                    "lists it in capabilities.tpdo_transmission_types: the device differs from its profile (check "
                    "the profile against the manual)") from None
        if event_timer is not None:
            self.journal.write(self.comm, 5, event_timer.to_bytes(2, "little"))

    def configure_while_invalid(self, writer: WhileInvalid, *, inhibit_time: int | None = None,
                                sync_start_value: int | None = None) -> None:
        """Write sub 3 inhibit time (100 us) and sub 6 SYNC start value with the TPDO not valid (``writer``: put
        back the same way before the journal puts back the rest)."""
        if inhibit_time is not None:
            writer.write(self.comm, 3, inhibit_time.to_bytes(2, "little"))
        if sync_start_value is not None:
            writer.write(self.comm, 6, bytes([sync_start_value]))

    def writable(self, sub: int) -> bool:
        """The profile declares the communication parameter's ``sub`` writable."""
        entry = self.dut.profile.entry(self.comm, sub)
        return entry is not None and entry.writable

    def mapping(self) -> list[Entry]:
        """Its mapping as the device reads it now."""
        return read_mapping(self.dut, self.comm)

    def mapped_bytes_of(self, index: int, sub: int = 0) -> slice | None:
        """Where object ``index``/``sub`` lies in its payload (the mapping as the device reads it now), or None
        where it is not mapped on byte boundaries."""
        offset = 0
        for mapped_index, mapped_sub, bits in self.mapping():
            if (mapped_index, mapped_sub) == (index, sub):
                return slice(offset // 8, (offset + bits) // 8) if offset % 8 == 0 and bits % 8 == 0 else None
            offset += bits
        return None

    def maps_position(self) -> bool:
        """It maps a position value (its mapping objects, or the fixed layout a quirk gives)."""
        profile = self.dut.profile
        if profile.entry(self.mapping_index, 0) is None:
            found = profile.params_of(fx.FixedTpdoMapping)
            entries = found.mapping.get(self.comm, []) if found is not None else []
            return any(index in position_objects(profile) for index, _, _ in entries)
        return any(index in position_objects(profile) for index, _, _ in self.mapping())


def position_objects(profile: DeviceProfile) -> set[int]:
    """Objects whose value a turning shaft changes: 6004h/6008h, or a manufacturer object standing for one."""
    found = profile.params_of(fx.ManufacturerEncoderObjects)
    equivalents = found.equivalents if found is not None else {}
    return {0x6004, 0x6008} | {obj for obj, cia in equivalents.items() if cia in (0x6004, 0x6008)}
