"""Communication services the EDS cannot vouch for: TPDO transmission types, block and segmented transfer,
SYNC producer, node guarding, which 1010h/1011h sub-indices store and restore."""

from __future__ import annotations

import struct
from typing import Any

from encoder_conformance.cia.cia301 import COB_ID_INVALID, COB_ID_SYNC_GENERATE, HEARTBEAT_BASE, SdoAbortCode
from encoder_conformance.probe.findings import Findings, TpdoTypes
from encoder_conformance.probe.link import Answer, ProbeLink, download
from encoder_conformance.probe.put_back import PutBack

GUARD_WINDOW_S = 0.2
#: entries a segmented download is tried on first: plain communication parameters any device takes back
PREFERRED_SEGMENTED = ((0x1017, 0), (0x1005, 0), (0x1006, 0), (0x100C, 0), (0x1014, 0))


def _u32(data: bytes | None) -> int | None:
    return struct.unpack_from("<I", data.ljust(4, b"\x00"))[0] if data else None


def tpdo_transmission_types(link: ProbeLink, put_back: PutBack, objects: dict[int, dict[str, Any]],
                            findings: Findings) -> None:
    """Every value 0..255 written to the first TPDO's 18xxh sub 2, the PDO made invalid first (as CiA 301 asks
    before its parameters change); all put back."""
    comm = next((i for i in sorted(objects) if 0x1800 <= i <= 0x19FF and 2 in objects[i].get("subs", {})), None)
    if comm is None:
        return
    if objects[comm]["subs"][2].get("access") not in ("rw", "rww", "rwr"):
        fixed = findings.value((comm, 2))
        if fixed is not None and len(fixed) == 1:  # a fixed type: the one the device has
            findings.tpdo_types = TpdoTypes(comm, [fixed[0]], {})
        return
    cob_id = _u32(findings.value((comm, 1)))
    if cob_id is not None and not cob_id & COB_ID_INVALID:
        invalid = put_back.write(comm, 1, struct.pack("<I", cob_id | COB_ID_INVALID))
        if not invalid.ok:
            frame = download(comm, 1, struct.pack("<I", cob_id | COB_ID_INVALID), invalid)
            findings.notes.append(f"probe: {comm:04X}h sub 1 (valid bit) could not be cleared ({frame}); "
                                  "transmission types were tried on the valid PDO")
    accepted: list[int] = []
    refused: dict[int, list[int]] = {}
    frames: dict[int, str] = {}
    for value in range(256):
        answer = put_back.write(comm, 2, bytes([value]))
        frames[value] = download(comm, 2, bytes([value]), answer)
        if answer.ok:
            accepted.append(value)
        else:
            refused.setdefault(answer.abort or 0, []).append(value)
    findings.tpdo_types = TpdoTypes(comm, accepted, refused, frames)


def block_and_segmented(link: ProbeLink, put_back: PutBack, objects: dict[int, dict[str, Any]],
                        findings: Findings) -> None:
    """A block upload of 1018h sub 1 (block_sdo); for segmented transfer, the upload of a value longer than 4 bytes,
    else a segmented download of a writable value with the value it has."""
    if (0x1018, 1) in findings.readings:
        answer = link.block_read(0x1018, 1)
        findings.block_sdo = answer.ok
        if not answer.ok and answer.abort not in (SdoAbortCode.COMMAND_SPECIFIER, None):
            findings.notes.append(f"probe: a block upload of 1018h sub 1 was answered with {answer.describe()} "
                                  f"(block upload 1018h.01 -> {answer.describe()}) "
                                  "(CiA 301: 05040001h where block transfer is not supported); block_sdo set false")
    longest = max(((key, len(reads[0].data)) for key, reads in findings.readings.items()
                   if reads and reads[0].data is not None), key=lambda item: item[1], default=None)
    if longest is not None and longest[1] > 4:
        findings.segmented_sdo = True  # canopen read it segmented: an expedited answer holds 4 bytes at most
        return
    candidates = sorted(findings.readings, key=lambda key: (key not in PREFERRED_SEGMENTED, key))
    key = next((key for key in candidates if _stable_writable(objects, key, findings.readings[key])), None)
    if key is None:
        return
    value = findings.value(key)
    assert value is not None
    answer = put_back.write(*key, value, force_segment=True)
    if answer.ok or answer.abort == SdoAbortCode.COMMAND_SPECIFIER:
        findings.segmented_sdo = answer.ok
    else:
        findings.notes.append(f"probe: a segmented download of {key[0]:04X}h sub {key[1]} with its own value got "
                              f"{answer.describe()} (segmented {download(*key, value, answer)}; CiA 301: 05040001h "
                              "where segmented transfer is not supported); segmented_sdo not settled")


def _stable_writable(objects: dict[int, dict[str, Any]], key: tuple[int, int], reads: list[Answer]) -> bool:
    """A communication entry the device lets be written whose reads all agree (writing it back changes nothing)."""
    index, sub = key
    obj = objects.get(index, {})
    entry = obj.get("subs", {}).get(sub) if "subs" in obj else obj
    values = {r.data for r in reads}
    return (0x1000 <= index < 0x2000 and index not in (0x1003, 0x1010, 0x1011) and entry is not None
            and entry.get("access") in ("rw", "rww") and len(values) == 1 and None not in values)


def sync_producer(link: ProbeLink, put_back: PutBack, findings: Findings) -> None:
    """1005h bit 30 written (only with 1006h = 0 or absent, so no SYNC goes out) and put back: accepted means
    the device can generate SYNC; 06090030h (or any refusal) that it cannot."""
    cob_id = _u32(findings.value((0x1005, 0)))
    if cob_id is None:
        return
    period = _u32(findings.value((0x1006, 0)))
    if period:
        findings.notes.append(f"capabilities.sync_producer: not probed, 1006h = {period} us would make SYNC go out")
        return
    if cob_id & COB_ID_SYNC_GENERATE:
        findings.sync_producer = True
        return
    answer = put_back.write(0x1005, 0, struct.pack("<I", cob_id | COB_ID_SYNC_GENERATE))
    findings.sync_producer = answer.ok
    if answer.silent:
        findings.sync_producer = None
        frame = download(0x1005, 0, struct.pack("<I", cob_id | COB_ID_SYNC_GENERATE), answer)
        findings.notes.append(f"capabilities.sync_producer: 1005h with bit 30 got no answer ({frame}); not settled")


def node_guarding(link: ProbeLink, objects: dict[int, dict[str, Any]], findings: Findings) -> None:
    """A guarding request answered (only asked with the heartbeat off: CiA 301 §7.2.8.3.2 uses one or the other)."""
    heartbeat = findings.value((0x1017, 0))
    if heartbeat and any(heartbeat):
        findings.notes.append("capabilities.node_guarding: not probed, the heartbeat (1017h) is on and a device "
                              "answers guarding only without it")
        return
    if link.guard(GUARD_WINDOW_S) is not None:
        findings.node_guarding = True
    elif 0x100C in objects or 0x100D in objects:  # a device may answer only once guarding is configured
        frame = f"remote frame {HEARTBEAT_BASE + link.node_id:03X}h -> none within {GUARD_WINDOW_S * 1000:.0f} ms"
        findings.notes.append(f"capabilities.node_guarding: a guarding request got no answer ({frame}); the EDS has "
                              "100Ch/100Dh, so the draft keeps node_guarding; check the manual")
    else:
        findings.node_guarding = False


def store_restore_subindices(findings: Findings) -> None:
    """1010h/1011h sub-indices whose value has bit 0 set: the device stores / restores on command (CiA 301
    §7.5.2.13-14). Where every sub reads 0 the device says nothing either way: the draft's guess stays."""
    for index, attribute in ((0x1010, "store_subindices"), (0x1011, "restore_subindices")):
        values = {sub: reads[0].data for (i, sub), reads in findings.readings.items()
                  if i == index and sub > 0 and reads and reads[0].data}
        empty = [sub for (i, sub), reads in findings.readings.items()
                 if i == index and sub > 0 and reads and reads[0].abort == SdoAbortCode.NO_DATA]
        if not values and empty:  # sub 0 counts no command (an EDS without its default): none to give
            setattr(findings, attribute, [])
            continue
        if not values:
            continue
        if not any(any(data) for data in values.values()):
            frames = "; ".join(f"upload {index:04X}h.{sub:02X} -> {data.hex(' ').upper()}"
                               for sub, data in sorted(values.items()))
            findings.notes.append(f"capabilities.{attribute}: every {index:04X}h sub-index reads 0 ({frames}; CiA 301: "
                                  "bit 0 says the device does it on command); the draft keeps the EDS's sub-indices")
            continue
        setattr(findings, attribute, sorted(sub for sub, data in values.items() if data[0] & 1))
