"""Goods-in judges working order: a device that reports an error at start-up that no test caused, or that does not
reach operational on NMT start, is not a good one.

This rests on the device's own error report, not on an inference: the error register 1001h (CiA 301 v4.2.0
§7.5.2.2: a set bit is an error present, bit 0 any error), the EMCY it sent (§7.2.7: a device signals an error by
EMCY; table 21 names the code) and NMT start (§7.3.2.2: NMT start makes the device operational). CiA 301 lets a
device with an error leave operational (1029h; open reading persistent-error-holds-pre-operational): that makes such
behaviour conformant, not the device in working order. Where the manual documents an error at start-up as normal,
the quirk ``error_at_start_up_documented`` names the codes and its section.

Only ``encoder-conformance accept`` runs these: a full run judges each error by the test that causes it, and one the
device keeps makes the tests that need operational not testable (the run is INCOMPLETE, never PASS).
"""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import EMCY_BASE, ERROR_HISTORY, NmtState, emcy_meaning
from encoder_conformance.dut.emcy import emcy_code
from encoder_conformance.dut.link import Mark, format_frames
from encoder_conformance.dut.nmt import error_register
from encoder_conformance.errors import NotJudged
from encoder_conformance.plugin import acceptance
from encoder_conformance.plugin.skips import not_selected
from encoder_conformance.profile import quirk_effects as fx

ERROR_CLAUSE = ("CiA 301 v4.2.0 §7.5.2.2 (1001h error register: a set bit is an error present) and §7.2.7 "
                "(EMCY: the device signals an error; table 21 names its code)")
START_CLAUSE = "CiA 301 v4.2.0 §7.3.2.2 (NMT start: the device enters operational)"
RUN_START = Mark(0, 0.0)  # every frame the tester has seen since it opened the bus
pytestmark: list[pytest.MarkDecorator] = []  # each test names its clause


@pytest.fixture
def goods_in(pytestconfig: pytest.Config) -> None:
    """Only an acceptance run judges working order (see the module's docstring)."""
    if not acceptance.is_acceptance(pytestconfig):
        not_selected("a goods-in check: 'encoder-conformance accept' runs it; a full run judges each error by the "
                     "test that causes it")


def _documented(dut) -> tuple[set[int], str | None]:
    """The EMCY codes the manual documents at start-up, and the quirk's id (none: empty, None)."""
    found = dut.profile.quirk(fx.ErrorAtStartUpDocumented)
    if found is None:
        return set(), None
    return set(found.params.codes), found.id


def _newest_history_code(dut) -> int | None:
    """Bits 0-15 of 1003h sub 1 where the device has an error history with an entry."""
    if dut.profile.entry(ERROR_HISTORY, 1) is None or not dut.read_uint(ERROR_HISTORY, 0):
        return None
    return dut.read_uint(ERROR_HISTORY, 1) & 0xFFFF


def _named(code: int) -> str:
    return f"{code:04X}h ({emcy_meaning(code)})"


@pytest.mark.spec(ERROR_CLAUSE)
def test_no_error_reported_at_start_up(dut, goods_in, evidence):
    """At goods-in, before any test, the device reports no error of its own: no EMCY with an error code since the
    tester opened the bus, and 1001h = 0."""
    documented, quirk = _documented(dut)
    own_emcy = EMCY_BASE + dut.node_id
    emcys = [m for m in dut.frames.since(RUN_START, lambda m: m.is_rx and m.arbitration_id == own_emcy)
             if len(m.data) >= 2 and emcy_code(m) != 0]
    register = error_register(dut)
    newest = _newest_history_code(dut) if register else None
    codes = {emcy_code(m) for m in emcys} | ({newest} if newest is not None else set())
    if codes and codes <= documented:
        evidence.deviation(quirk or "", f"errors at start-up the manual documents as normal: "
                                        f"{', '.join(_named(c) for c in sorted(codes))}")
        return
    problems = []
    if emcys:
        problems.append(f"EMCY {', '.join(_named(emcy_code(m)) for m in emcys[:4])} before any test\n"
                        f"{format_frames(emcys[:4])}")
    if register:
        history = f", newest 1003h entry {_named(newest)}" if newest is not None else ""
        problems.append(f"1001h = {register:02X}h (an error is present){history}")
    assert not problems, "the device reports an error at start-up that no test caused: " + "; ".join(problems)


@pytest.mark.spec(START_CLAUSE)
@pytest.mark.requires("heartbeat_producer")
def test_nmt_start_reaches_operational(dut, goods_in, settings_journal, back_to_preoperational, evidence):
    """At goods-in, NMT start brings the device into operational (its heartbeat reports 05h)."""
    try:
        dut.nmt.transition("operational", settings_journal, evidence)
    except NotJudged as held:  # staying out of operational may be conformant; a device in working order does not
        pytest.fail(f"NMT start: the device does not stay in operational ({NmtState.OPERATIONAL:02X}h): {held}",
                    pytrace=False)  # back_to_preoperational gives the device back to pre-operational
