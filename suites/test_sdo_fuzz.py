"""SDO robustness under generated requests (hypothesis): at most one well-formed answer, never a crash.

CiA 301 §7.2.4.3 (SDO protocol). Each example is a few request frames: initiates with any index,
sub-index and size bits, reserved command specifiers, frames shorter than 8 bytes, segments without
or out of order, interleaved transfers. After every example (``encoder_conformance.fuzz``): one reply
to each request that owes one and none to a client's abort (each reply paired with its request by the bus order
and the frames' stamps, a short frame's answer waited for: ``fuzz.runner``; a failure names the request and every
reply it drew), none, one abort or the served answer to a frame under 8 bytes (open readings sdo-short-frame,
sdo-short-frame-served), DLC 8, the server command that answers the request or an abort, the multiplexer echoed
(an initiate with reserved bits set may instead be refused with 05040001h naming any: open reading
sdo-initiate-reserved-bits), 1000h still readable, the heartbeat's NMT state
unchanged (an EMCY is a warning: ``watch.EMCY_RULE``); over the whole test the heartbeat keeps coming. Downloads
never reach the exclusion list (store, restore, node-ID, bit rate, preset, self-storing entries:
``fuzz.exclusions``) and write nothing: they go to entries that must refuse them, or open a segmented
transfer that is never completed. ``--fuzz-budget`` bounds each test.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from encoder_conformance.cia.cia301 import COB_ID_INVALID, EMCY_BASE, SDO_REQUEST_BASE, SdoAbortCode, can_id_of
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.fuzz import exclusions, replay, rounds
from encoder_conformance.fuzz import strategies as fz
from encoder_conformance.fuzz.runner import Failure, FuzzRunner
from encoder_conformance.fuzz.watch import EMCY_RULE, DeviceWatch
from encoder_conformance.plugin.suite_helpers import abort_accepted

pytestmark = pytest.mark.spec("CiA 301 §7.2.4.3 (SDO protocol)")

#: No shrinking: against a device that stopped answering, every shrink step costs an SDO timeout, and
#: the failing example (a few frames, shown as a replay) is short already.
FUZZ_SETTINGS = settings(
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.filter_too_much],
    deadline=None,
    phases=[Phase.explicit, Phase.reuse, Phase.generate],
    report_multiple_bugs=False,
)


def _emcy_cob_id(dut) -> int | None:
    """The EMCY COB-ID the device uses (1014h where declared), None without a valid EMCY."""
    if not dut.profile.capabilities.emcy:
        return None
    if dut.profile.entry(0x1014, 0) is None:
        return EMCY_BASE + dut.node_id
    value = dut.read_uint(0x1014, 0)
    return None if value & COB_ID_INVALID else can_id_of(value)


def _heartbeat_ms(dut, settings_journal) -> int:
    """The heartbeat period the watch checks: the running one, else the profile's test period (put back after)."""
    if not dut.profile.capabilities.heartbeat_producer:
        return 0
    period = dut.read_uint(0x1017, 0)
    if period == 0:
        period = dut.profile.timing.heartbeat_test_period_ms
        settings_journal.write(0x1017, 0, period.to_bytes(2, "little"))
    return period


@pytest.fixture
def targets(dut, evidence) -> fz.Targets:
    """What the fuzzer may address; the exclusion list goes into the evidence."""
    excluded, self_storing = exclusions.never_write(dut.profile), exclusions.self_storing(dut.profile)
    evidence.note("never written by the fuzzer:\n" + exclusions.describe(excluded, self_storing))
    return fz.Targets.of(dut.profile, excluded, self_storing)


@pytest.fixture
def fuzz(dut, settings_journal, evidence, request) -> FuzzRunner:
    """A runner with the device's heartbeat and EMCY watched; the figures go into the evidence."""
    watch = DeviceWatch(dut, _heartbeat_ms(dut, settings_journal), _emcy_cob_id(dut))
    problem = watch.begin()
    assert problem is None, problem
    if not watch.period_s:
        evidence.note("no heartbeat producer: the NMT state is watched through boot-up messages only")
    runner = FuzzRunner(dut, watch, request.config.getoption("--ec-fuzz-budget"))
    return runner


def _figures(fuzz: FuzzRunner, evidence) -> None:
    evidence.measure("fuzz examples", fuzz.examples, "examples")
    evidence.measure("fuzz exchanges per second", round(fuzz.rate), "exchanges/s")
    evidence.note(f"{fuzz.examples} examples: {fuzz.exchanges} request frames ({fuzz.round_trips} waited for a reply) "
                  f"in {fuzz.busy_s:.2f} s of sending, {fuzz.rate:.0f} exchanges/s ({fuzz.wall_rate:.0f}/s over the "
                  "test's wall-clock, example generation included); 1000h read and heartbeat/EMCY checked after every "
                  "example, the heartbeat's continuity over the whole test"
                  + (f"; --fuzz-budget spent, {fuzz.skipped} examples not sent" if fuzz.skipped else ""))


def _how_to_rerun(request, base: int | None, budget_s: float | None) -> str:
    profile = settings.get_current_profile_name()
    if FUZZ_SETTINGS.derandomize:
        return (f"hypothesis profile {profile}: derandomized, every run sends the same examples in the same order "
                "(run it again to repeat; --hypothesis-seed has no effect)")
    device = request.getfixturevalue("dut").profile.id
    budget = f" --fuzz-budget {budget_s:g}" if budget_s is not None else ""
    return (f"rerun: HYPOTHESIS_PROFILE={profile} encoder-conformance run --profile {device} -- "
            f"-k {request.node.name} --hypothesis-seed={base}{budget}")


def _fuzz(fuzz: FuzzRunner, strategy: st.SearchStrategy[fz.Example], evidence, request,
          extra: Callable[[fz.Example], list[str]] | None = None) -> None:
    """Run ``strategy``'s examples through ``fuzz``; on failure the replay goes into the message and evidence."""

    def make_test(max_examples: int) -> Callable[[], None]:
        @settings(FUZZ_SETTINGS, max_examples=max_examples)
        @given(strategy)
        def check(example: fz.Example) -> None:
            problems = fuzz.run(example)
            if not problems and extra is not None:
                problems = extra(example)
            assert not problems, "\n".join(problems)

        return check

    forced = request.config.getoption("--hypothesis-seed", None)
    base = rounds.base_seed(FUZZ_SETTINGS, None if forced is None else int(forced), fuzz.budget_s)
    rerun = _how_to_rerun(request, base, fuzz.budget_s)
    try:
        rounds.run_rounds(make_test, FUZZ_SETTINGS.max_examples, base, fuzz.budget_s, lambda: fuzz.spent)
        problems = fuzz.final_check()
        assert not problems, "\n".join(problems)
    except AssertionError as exc:
        if fuzz.failure is None:
            raise
        text = _replay(fuzz, fuzz.failure, evidence, rerun)
        raise AssertionError("\n".join(fuzz.failure.problems) + "\n" + text) from exc
    finally:
        _figures(fuzz, evidence)
    if fuzz.first_emcy is not None:  # the replay goes into a note, the warning stays one line
        _replay(fuzz, fuzz.first_emcy, evidence, rerun)
        sent = ", ".join(str(r) for r in fuzz.first_emcy.requests)
        evidence.inferred_problem(f"{len(fuzz.watch.emcy)} EMCY frame(s) while fuzzed, the first "
                                  f"({fuzz.first_emcy.problems[0]}) after {sent}", EMCY_RULE)


def _replay(fuzz: FuzzRunner, failure: Failure, evidence, rerun: str) -> str:
    """The failing example as text (also a note) and, next to the bus trace, as a file canplayer takes."""
    cob_id = SDO_REQUEST_BASE + fuzz.dut.node_id
    text = replay.describe(cob_id, failure.requests, failure.window, failure.before, rerun)
    if evidence.trace_path is not None:
        path = evidence.trace_path.with_suffix(".replay.log")
        path.write_text(replay.candump_lines(cob_id, failure.requests) + "\n", encoding="utf-8")
        text += f"\nrequests as a canplayer file: {path}"
    evidence.note(text)
    return text


def test_initiate_requests_answered_once(fuzz, targets, evidence, request):
    """Upload and download initiates with any index, sub-index and size bits: one reply each, echoing the
    multiplexer; a write to a read-only entry or a reserved index aborted. An upload with reserved bits set (41h-5Fh)
    is served as 40h or refused with 05040001h naming any multiplexer (open reading sdo-initiate-reserved-bits)."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.3-§7.2.4.3.9 (initiate SDO download/upload), §7.2.4.3.17 (abort)")
    examples = st.lists(fz.initiates(targets), min_size=1, max_size=3).map(tuple)
    _fuzz(fuzz, examples, evidence, request)


def test_reserved_command_specifiers_abort(fuzz, targets, evidence, request):
    """Reserved command specifiers (and block transfer where the profile has none) are aborted with 05040001h
    (CTT SDO 07), once, echoing nothing else."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.17 (abort: command specifier not valid or unknown)")
    dut = fuzz.dut

    def right_code(example: fz.Example) -> list[str]:
        replies = fuzz.last_exchanges[0].replies
        reply = sdo_frames.SdoResponse(replies[0]) if replies else None
        if reply is None or not abort_accepted(dut, reply, {SdoAbortCode.COMMAND_SPECIFIER}):
            return [f"{example[0]}: expected abort {sdo_frames.abort_name(SdoAbortCode.COMMAND_SPECIFIER)}, got "
                    f"{reply.describe() if reply else 'no reply'}"]
        return []

    _fuzz(fuzz, st.tuples(fz.reserved_commands(targets)), evidence, request, extra=right_code)


def test_short_frames_ignored_or_aborted(fuzz, targets, evidence, request):
    """A frame shorter than 8 bytes is not answered, answered with one abort (naming any multiplexer), or served as
    the request its bytes carry (open readings sdo-short-frame, sdo-short-frame-served); never answered twice or
    with another multiplexer, and the device goes on serving. Its answer is waited for before the next request."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.1 (SDO frames carry 8 data bytes; no rule for a shorter one)")
    harmless = st.one_of(fz.initiates(targets), fz.reserved_commands(targets))
    _fuzz(fuzz, st.tuples(fz.truncated(harmless)), evidence, request)


def test_segments_out_of_order_aborted(fuzz, targets, evidence, request):
    """Segments without an open transfer, of the other direction, with the toggle bit not alternated, or after
    the client's abort are aborted; in-order segments are answered with the toggle bit echoed."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3.4-§7.2.4.3.10 (segments, toggle bit), §7.2.4.3.17 (abort)")
    _fuzz(fuzz, fz.segment_sequences(targets), evidence, request)


def test_interleaved_transfers_answered_once(fuzz, targets, evidence, request):
    """A second initiate while a segmented transfer is open, then segments meant for the first: one reply to
    each, and segments the open transfer cannot take are aborted."""
    evidence.rests_on("cia", "CiA 301 §7.2.4.3 (one transfer per SDO channel), §7.2.4.3.17 (abort)")
    _fuzz(fuzz, fz.interleaved_transfers(targets), evidence, request)
