"""SDO robustness under generated requests (hypothesis): one well-formed answer per request, never a crash.

CiA 301 §7.2.4.3 (SDO protocol): every initiate request gets exactly one response from the
server, an abort echoes the request's multiplexer, and an unknown command specifier aborts with
05040001h. Only harmless requests are generated: uploads of anything, and downloads to objects
that must refuse them (absent objects, read-only entries), so the device keeps its settings.
"""

from __future__ import annotations

import struct

import pytest
from hypothesis import HealthCheck, Phase, given, note, settings
from hypothesis import strategies as st

from encoder_conformance.checks import abort_accepted
from encoder_conformance.cia301 import SdoAbortCode
from encoder_conformance.dut import sdo_frames

pytestmark = pytest.mark.spec("CiA 301 §7.2.4.3 (SDO protocol)")

#: No shrinking: against a device that stops answering, every shrink step costs an SDO timeout, and
#: the first failing request (shown with note()) is already a single frame.
FUZZ_SETTINGS = settings(
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    deadline=None,
    phases=[Phase.explicit, Phase.reuse, Phase.generate],
    report_multiple_bugs=False,
)


def _declared(profile) -> list[tuple[int, int]]:
    return [(index, sub) for index, sub, _, _ in profile.iter_entries()]


def _read_only(profile) -> list[tuple[int, int]]:
    return [(i, s) for i, s, _, e in profile.iter_entries() if e.access in ("ro", "const")]


def _absent_indices(profile) -> st.SearchStrategy[int]:
    return st.integers(0x1000, 0xFFFF).filter(lambda index: index not in profile.objects)


def _multiplexers(profile) -> st.SearchStrategy[tuple[int, int]]:
    declared = _declared(profile)
    return st.one_of(
        st.sampled_from(declared),
        st.tuples(st.sampled_from(sorted(profile.objects)), st.integers(0, 0xFF)),
        st.tuples(st.integers(0x0000, 0xFFFF), st.integers(0, 0xFF)),
    )


def _check_reply(dut, request: bytes, response, allowed_scs: set[int]) -> None:
    note(f"request {request.hex(' ')} -> {response.describe() if response else 'no response'}")
    assert response is not None, f"no SDO response to {request.hex(' ').upper()}"
    assert len(response.raw) == 8, f"SDO response with DLC {len(response.raw)}: {response.raw.hex(' ')}"
    if response.is_abort:
        assert response.raw[1:4] == request[1:4], (
            f"abort for {response.index:04X}h.{response.sub:02X} does not echo the request's "
            f"{request[2]:02X}{request[1]:02X}h.{request[3]:02X}"
        )
        return
    assert response.scs in allowed_scs, f"unexpected server command {response.raw[0]:02X}h to {request.hex(' ')}"
    assert response.raw[1:4] == request[1:4], "response does not echo the request's index/sub-index"


@pytest.fixture
def alive_after(dut):
    """After the examples, the device still answers a plain read of 1000h."""
    yield
    assert dut.responds(), "the device stopped answering SDO after the generated requests"


def test_uploads_of_any_object_answered(dut, alive_after):
    """Any upload request (declared or not) gets one response: data or an abort echoing the multiplexer."""

    @FUZZ_SETTINGS
    @given(_multiplexers(dut.profile))
    def check(mux):
        request = sdo_frames.upload_request(*mux)
        response = dut.sdo_request(request)
        _check_reply(dut, request, response, {2})
        if response.segmented_size is not None:  # a segmented upload was started: end it politely
            dut.send_sdo(struct.pack("<BHBI", 0x80, *mux, SdoAbortCode.TIMEOUT))

    check()


def test_refused_downloads_answered_with_abort(dut, alive_after):
    """Expedited writes to absent objects or read-only entries always abort, echoing the multiplexer."""
    read_only = _read_only(dut.profile)
    targets = st.one_of(
        st.tuples(_absent_indices(dut.profile), st.integers(0, 0xFF)),
        *([st.sampled_from(read_only)] if read_only else []),
    )

    @FUZZ_SETTINGS
    @given(targets, st.binary(min_size=1, max_size=4))
    def check(mux, data):
        request = sdo_frames.expedited_download_request(*mux, data)
        response = dut.sdo_request(request)
        _check_reply(dut, request, response, set())

    check()


def test_unknown_command_specifiers_abort(dut, alive_after):
    """Reserved command specifiers and orphan segments are refused with abort 05040001h (CTT SDO 07)."""
    block = dut.profile.capabilities.block_sdo

    @FUZZ_SETTINGS
    @given(
        st.sampled_from([0, 3, 7] if block else [0, 3, 5, 6, 7]),
        st.integers(0, 0x1F),
        st.binary(min_size=7, max_size=7),
    )
    def check(ccs, low_bits, rest):
        request = bytes([(ccs << 5) | low_bits]) + rest
        response = dut.sdo_request(request)
        note(f"request {request.hex(' ')} -> {response.describe() if response else 'no response'}")
        assert response is not None, f"no response to command specifier {ccs} ({request.hex(' ').upper()})"
        expected = f"command specifier {ccs}: expected abort {sdo_frames.abort_name(SdoAbortCode.COMMAND_SPECIFIER)}"
        assert response.is_abort, f"{expected}, got {response.describe()}"
        assert abort_accepted(dut, response, {SdoAbortCode.COMMAND_SPECIFIER}), f"{expected}, got {response.describe()}"

    check()
