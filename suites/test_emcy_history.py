"""The error history 1003h (CiA 301 §7.5.2 object 1003h): each error signalled by EMCY is entered, the newest at
sub 1; sub 0 counts the entries up to the number the list has; writing 0 to sub 0 clears it, other values are
refused (06090030h).

The entries' bits 0-15 are the error code (bits 16-31 are manufacturer-specific: FAULHABER puts its error register
there, quirk error-history-layout), so only those are compared. A bench run adds entries to the device's history
with each error; only test_error_history_cleared_by_zero_only clears it (its purpose; the history as found is in
its evidence). The WDGA's manual says its list keeps the first errors (quirk error_history_keeps_first, which its
twin plays): there the order is not judged, the count and the clear are.
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import ERROR_HISTORY, SdoAbortCode
from encoder_conformance.dut.emcy import BENCH_OTHER_CODE, BenchError
from encoder_conformance.dut.sdo import abort_name, sdo_frames
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import abort_accepted
from encoder_conformance.profile import quirk_effects as fx

pytestmark = [pytest.mark.spec("CiA 301 §7.5.2 object 1003h (pre-defined error field)"), pytest.mark.requires("emcy")]

CLAUSE = "CiA 301 §7.5.2 object 1003h (pre-defined error field)"


@pytest.fixture
def depth(dut) -> int:
    """The number of entries the profile declares for 1003h; skips where it has none."""
    entry = dut.profile.objects.get(ERROR_HISTORY)
    subs = [sub for sub in (entry.subs if entry is not None and entry.subs else {}) if sub > 0]
    if not subs:
        not_applicable("the profile has no error history 1003h")
    return len(subs)


def _history(dut) -> list[int]:
    """The error codes (bits 0-15) of the entries sub 0 counts, sub 1 first."""
    count = dut.read_uint(ERROR_HISTORY, 0)
    return [dut.read_uint(ERROR_HISTORY, sub) & 0xFFFF for sub in range(1, count + 1)]


def _errors(emcy, count: int) -> list[int]:
    """``count`` errors, each waited for by its EMCY (on the bench: two codes in turn, the cause taken away
    between them, so that each is a new error); the codes signalled, in order."""
    trigger = emcy.trigger()
    codes = []
    for n in range(count):
        code = BENCH_OTHER_CODE if isinstance(trigger, BenchError) and n % 2 else trigger.code
        mark = trigger.fire(code) if isinstance(trigger, BenchError) else trigger.fire()
        emcy.wait(mark, trigger, f"error {n + 1} of {count}", code=None if code == trigger.code else code)
        codes.append(code)
        if trigger.clears:
            trigger.clear()
    return codes


def test_error_history_records_newest_first(dut, emcy, depth, evidence):
    """Two errors are entered: sub 0 counts them (up to the list's size), the newer at sub 1, the older entries
    moved on by two. Where the manual keeps the first errors (quirk), not applicable: its list has another order
    (test_error_history_limited_to_its_size still checks its count)."""
    evidence.rests_on("cia", CLAUSE)
    found = dut.profile.quirk(fx.ErrorHistoryKeepsFirst)
    if found is not None:
        evidence.deviation(found.id, found.quirk.title)
        not_applicable(f"quirk {found.id}: the manual's list keeps the first errors, not the newest")
    before = _history(dut)
    codes = _errors(emcy, 2)
    after = _history(dut)
    evidence.note(f"1003h before: {_codes(before)}; errors {_codes(codes)}; after: {_codes(after)}")
    newest_first = ([*reversed(codes), *before])[:depth]
    assert len(after) == len(newest_first), (
        f"1003h sub 0 = {len(after)} after two errors; it counted {len(before)} before (the list has {depth})")
    assert after == newest_first, f"1003h reads {_codes(after)}, expected {_codes(newest_first)} (newest at sub 1)"


def test_error_history_limited_to_its_size(dut, emcy, depth, evidence):
    """Errors past the list's size: sub 0 stays at the number of entries the list has."""
    evidence.rests_on("cia", CLAUSE + ": sub 0 = the number of errors recorded, at most the entries the list has")
    before = len(_history(dut))
    _errors(emcy, depth - before + 1)
    count = dut.read_uint(ERROR_HISTORY, 0)
    evidence.measure("1003h sub 0 after the list was overfilled", count, "entries", depth, depth)
    assert count == depth, f"1003h sub 0 = {count} after {depth - before + 1} errors on {before}; the list has {depth}"


def test_error_history_cleared_by_zero_only(dut, emcy, depth, evidence):
    """1003h sub 0: 1 and the current count are refused (06090030h) and change nothing; 0 clears the history
    (sub 0 reads 0), and the next error is entered again. This test clears the device's history on purpose."""
    evidence.rests_on("cia", CLAUSE + ": writing 0 to sub 0 deletes the history, other values abort 06090030h")
    if not dut.profile.entry(ERROR_HISTORY, 0).writable:
        not_applicable("the profile declares 1003h sub 0 read-only")
    found = _history(dut)
    if not found:
        _errors(emcy, 1)
        found = _history(dut)
    evidence.note(f"1003h as found before the clear: {_codes(found)} (cleared by this test: its purpose)")
    accepted = []
    for value in sorted({1, len(found)}):
        what = f"1003h sub 0 = {value}"
        response = dut.expect_abort(sdo_frames.expedited_download_request(ERROR_HISTORY, 0, bytes([value])))
        if not response.is_abort:
            accepted.append(what)
        elif not abort_accepted(dut, response, {SdoAbortCode.VALUE_INVALID}):
            evidence.inferred_problem(f"{what}: aborted with {abort_name(response.abort_code or 0)}, expected "
                                      "06090030h", "06090030h, the code CiA 301 gives for 1003h sub 0")
    assert not accepted, "accepted: " + "; ".join(accepted)
    assert _history(dut) == found, f"1003h changed by the refused writes: {_codes(_history(dut))}"
    dut.write(ERROR_HISTORY, 0, b"\x00")
    count = dut.read_uint(ERROR_HISTORY, 0)
    assert count == 0, f"1003h sub 0 = 0 confirmed, but sub 0 reads {count}"
    codes = _errors(emcy, 1)
    after = _history(dut)
    assert after == codes, f"after the clear and one error 1003h reads {_codes(after)}, expected {_codes(codes)}"


def _codes(codes: list[int]) -> str:
    return "[" + ", ".join(f"{c:04X}h" for c in codes) + "]"
