"""Value domains: a write outside the values an entry declares is refused, and the entry keeps its value.

CiA 301 §7.2.4.3.17: 06090030h (value range of parameter exceeded), 06090031h (value too high),
06090032h (value too low). The declared domain is the type range ∩ [min, max] ∩ ``allowed`` (and the
accepted transmission types for 18xxh sub 2, capabilities.tpdo_transmission_types); the test writes
the values just outside each of its boundaries (encoder_conformance/value_domain.py).
"""

from __future__ import annotations

import contextlib

import pytest
from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import SdoAbortCode
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.plugin.skips import skip_text
from encoder_conformance.plugin.suite_helpers import abort_accepted, assert_abort, describe_value, expected_aborts
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.value_domain import declared_domain, probe_values, refusal_basis

pytestmark = pytest.mark.spec("CiA 301 §7.2.4.3.17 (abort codes 06090030h..06090032h)")

VALUE_INVALID = SdoAbortCode.VALUE_INVALID  # value range of parameter exceeded
STORE_RESTORE = {0x1010: "store parameters", 0x1011: "restore default parameters"}


def _skip_reason(profile, index: int, entry) -> str | None:
    """Why writes to this entry cannot be probed here (a gate the test cannot open), or None."""
    if index in STORE_RESTORE:
        return (f"not applicable: {index:04X}h ({STORE_RESTORE[index]}) takes signatures; writing other values "
                "is the store/restore suite's business")
    size = datatypes.size_bytes(entry.type)
    if size is None or size > 4:
        # the suite's own limit, not the device's state: out of scope, and said so (a segmented probe is still to do)
        return (f"not applicable: {entry.type} does not fit an expedited download (this suite probes value domains "
                "by expedited download only)")
    found = profile.quirk(fx.WritesNeedScalingBit)
    if found and index in found.params.indices:
        return (f"not applicable: writes to {index:04X}h are refused unless 6000h bit 2 (scaling) is set "
                f"(quirk {found.id}); this test does not switch scaling on")
    reboots = profile.quirk(fx.StoreRebootsWithoutReply)
    if reboots and index == reboots.params.index:
        return f"not applicable: a write to {index:04X}h makes the device store and reboot (quirk {reboots.id})"
    return None


def _gap_codes(dut, evidence) -> set[int]:
    """06090030h, plus what a documented quirk sends for a value too high or too low."""
    codes = {VALUE_INVALID}
    for quirk_id, quirk in dut.profile.quirks.items():
        if isinstance(quirk.params, fx.AbortCode) and quirk.params.situation in ("value_high", "value_low"):
            evidence.deviation(quirk_id, quirk.title)
            codes |= set(quirk.params.codes)
    return codes


def _read(dut, index: int, sub: int) -> bytes:
    try:
        return dut.read(index, sub)
    except SdoAbortedError as exc:
        raise AssertionError(f"{index:04X}h.{sub:02X} declared readable but the read aborted: {exc}") from None


def _put_back(dut, settings_journal, index: int, sub: int, original: bytes | None) -> None:
    """After a wrongly accepted write: the original value again now, and once more at teardown."""
    if original is None:
        return
    settings_journal.remember(index, sub, original)
    with contextlib.suppress(SdoAbortedError, AssertionError):  # the journal retries at teardown and reports
        dut.write(index, sub, original)


def _report(problems: list[str] | None, evidence, text: str, rests_on: str) -> None:
    """A problem for the verdict (``problems``), or, where None, one that breaks only an inferred rule."""
    if problems is None:
        evidence.inferred_problem(text.split("\n")[0], rests_on)
    else:
        problems.append(text)


def test_write_outside_declared_domain_is_refused(dut, value_domain_entry, settings_journal, evidence):
    """Each value just outside the declared domain is refused with 06090030h/31h/32h; the entry keeps its value."""
    index, sub, _, entry = value_domain_entry
    reason = _skip_reason(dut.profile, index, entry)
    if reason:
        skip_text(reason)
    domain = declared_domain(dut.profile, index, sub)
    probes = probe_values(dut.profile, index, sub)
    assert domain, "the parametrisation only selects entries with probe values"
    size = datatypes.size_bytes(entry.type) or 4
    signed = datatypes.is_signed(entry.type)
    where = f"{index:04X}h.{sub:02X} {entry.name}"
    evidence.note(f"{where}: declared domain {domain}; probe values {', '.join(map(str, probes))}")

    def situation(value: int) -> str:
        if value > domain.maximum:
            return "value_high"
        return "value_low" if value < domain.minimum else "gap"

    wanted: dict[str, set[int]] = {}
    for kind in sorted({situation(p) for p in probes}):
        wanted[kind] = _gap_codes(dut, evidence) if kind == "gap" else (
            expected_aborts(dut, kind, evidence) | {VALUE_INVALID}
        )
    label = {"value_high": "above the maximum", "value_low": "below the minimum", "gap": "between allowed values"}

    basis_of = {probe: refusal_basis(dut.profile, index, sub, probe) for probe in probes}  # what says "refuse"
    original = _read(dut, index, sub) if entry.readable else None
    problems: list[str] = []
    refused = 0
    for probe in probes:
        kind = situation(probe)
        what = f"write of {describe_value(probe)} ({label[kind]}) to {where}"
        request = sdo_frames.expedited_download_request(index, sub, probe.to_bytes(size, "little", signed=signed))
        response = dut.sdo_request(request)
        if response is None:
            _put_back(dut, settings_journal, index, sub, original)
            problems.append(f"{what}: no SDO response within {dut.sdo_timeout * 1000:.0f} ms")
            evidence.note(f"{describe_value(probe)}: no answer")
            break
        evidence.note(f"{describe_value(probe)} ({label[kind]}): {response.describe()}")
        # a value accepted against a domain that only our inference draws is a warning, not a failure
        basis, rests_on = basis_of[probe]
        found = problems if response.is_abort or basis != "inferred" else None
        if abort_accepted(dut, response, wanted[kind]):
            refused += 1
        else:
            try:
                assert_abort(dut, response, wanted[kind], what)
            except AssertionError as exc:
                _report(found, evidence, str(exc), rests_on)
        if original is None:
            continue
        after = _read(dut, index, sub)
        if after != original:
            _report(found, evidence, (
                f"after the {what}: the entry reads {describe_value(int.from_bytes(after, 'little', signed=signed))}"
                f", before it read {describe_value(int.from_bytes(original, 'little', signed=signed))}"
            ), rests_on)
        if not response.is_abort or after != original:
            _put_back(dut, settings_journal, index, sub, original)
    bases = {basis for basis, _ in basis_of.values()}
    firm = [b for b in ("manual", "cia") if b in bases]
    clause = next((text for basis, text in basis_of.values() if basis == "cia" and text.startswith("CiA")), None)
    evidence.rests_on(firm[0] if firm else "inferred",
                      clause if firm == ["cia"] and clause else entry.manual or where)
    required = sum(1 for basis, _ in basis_of.values() if basis != "inferred")
    evidence.measure("probe values refused", refused, "", low=required, high=len(probes))
    if required < len(probes):
        evidence.note(f"{len(probes) - required} of the probe values are refused only by our inference "
                      "(a warning if accepted; --strict-inferred fails it)")
    if original is None:
        evidence.note(f"{where} is write-only: the value after the refused writes is not read back")
    if problems:
        raise AssertionError(f"{where}: {len(problems)} problem(s)\n" + "\n".join(problems))
