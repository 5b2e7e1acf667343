"""A PDO's mapping on the device: read it, change it by the CiA 301 procedure, and give it back in that order.

CiA 301 §7.5.2.38 (TPDO; §7.5.2.36 RPDO): a mapping changes only with the PDO invalid (COB-ID bit 31 set),
sub 0 = 0, then the entries, then sub 0 = n, then the COB-ID valid again. A journal that writes the old
values back one by one would write sub 0 before the entries and the COB-ID first: a device that follows
CiA 301 refuses that. ``MappingCustody`` remembers a PDO's COB-ID and mapping and puts them back through
``write_plan`` (the run's restore uses the same plan), also when the test failed. After Ctrl-C the device
is no longer usable for the test's clean-up; the run's restore puts the mapping back from its snapshot.
"""

from __future__ import annotations

from types import TracebackType

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import COB_ID_INVALID, cob_id_valid, mapping_fields, mapping_word, pdo_mapping_of
from encoder_conformance.dut.custody.write_plan import Key, plan_writes
from encoder_conformance.dut.link.device import DeviceLink

Entry = tuple[int, int, int]  # (index, sub-index, length in bits)
U8, U32 = 1, 4


def mapping_object(comm: int) -> int:
    mapping = pdo_mapping_of(comm)
    if mapping is None:
        raise ValueError(f"{comm:04X}h is no PDO communication object")
    return mapping


def read_mapping(dut: DeviceLink, comm: int) -> list[Entry]:
    """The entries the PDO maps now (sub 1 .. sub 0)."""
    mapping = mapping_object(comm)
    return [mapping_fields(dut.read_uint(mapping, sub)) for sub in range(1, dut.read_uint(mapping, 0) + 1)]


def invalidate(dut: DeviceLink, comm: int) -> int:
    """Step 1: COB-ID bit 31 set (where it is clear); returns the COB-ID found."""
    cob_id = dut.read_uint(comm, 1)
    if not cob_id & COB_ID_INVALID:
        dut.write_uint(comm, 1, cob_id | COB_ID_INVALID, U32)
    return cob_id


def apply_mapping(dut: DeviceLink, comm: int, entries: list[Entry], enable: bool = True) -> None:
    """The CiA 301 procedure: PDO invalid, sub 0 = 0, the entries, sub 0 = n, then the COB-ID valid
    (``enable``) or as found. A refused step raises SdoAbortedError (the caller's custody puts it back)."""
    mapping = mapping_object(comm)
    found = invalidate(dut, comm)
    dut.write_uint(mapping, 0, 0, U8)
    for sub, entry in enumerate(entries, start=1):
        dut.write_uint(mapping, sub, mapping_word(*entry), U32)
    dut.write_uint(mapping, 0, len(entries), U8)
    final = cob_id_valid(found) if enable else found
    if final != dut.read_uint(comm, 1):
        dut.write_uint(comm, 1, final, U32)


def describe(entries: list[Entry]) -> str:
    return "[" + ", ".join(f"{mapping_word(*e):08X}h" for e in entries) + "]"


class MappingCustody:
    """A PDO's COB-ID and mapping (sub 0 and every entry the profile lets write) as found, put back on exit
    in the CiA 301 order. Give the device back in pre-operational before the exit where a device allows
    mapping changes only there."""

    def __init__(self, dut: DeviceLink, comm: int) -> None:
        self.dut = dut
        self.comm = comm
        mapping = mapping_object(comm)
        keys = [(comm, 1), *((mapping, sub) for sub in sorted(dut.profile.objects[mapping].entries()))]
        self.found: dict[Key, bytes] = {}
        for key in keys:
            entry = dut.profile.entry(*key)
            value = self._read(key) if entry is not None and entry.writable and entry.readable else None
            if value is not None:
                self.found[key] = value

    def _read(self, key: Key) -> bytes | None:
        try:
            return self.dut.read(*key)
        except SdoAbortedError:
            return None

    def __enter__(self) -> MappingCustody:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if not self.dut.usable:
            return  # gone or interrupted: the run's restore gives the mapping back from its snapshot
        problems = self.restore()
        if problems and kind is None:
            raise AssertionError(f"could not put back the mapping of {self.comm:04X}h: " + "; ".join(problems))

    def restore(self) -> list[str]:
        """Write back what differs, in the procedure's order; what the device refused."""
        current = {key: self._read(key) for key in self.found}
        if current == self.found:
            return []
        problems = []
        for step in plan_writes(self.dut.profile, self.found, current):
            try:
                self.dut.write(*step.key, step.value)
            except (SdoAbortedError, AssertionError) as exc:
                if not self.dut.usable:
                    break
                problems.append(f"{step.label}: {exc}")
        return problems
