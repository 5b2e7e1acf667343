"""Assertion helpers for the suites: expected, observed, the abort code's name, the last frames."""

from __future__ import annotations

from encoder_conformance.cia.cia301 import ABORT_FOR_SITUATION
from encoder_conformance.coverage import Hold
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link import HostLatency, format_frames
from encoder_conformance.dut.sdo import SdoResponse, abort_name, sdo_words
from encoder_conformance.models.timing import interval_stats, schedule_fit
from encoder_conformance.plugin.evidence import Evidence
from encoder_conformance.plugin.skips import not_applicable, not_judged
from encoder_conformance.profile.quirk_effects import AbortCode, P
from encoder_conformance.profile.schema import HeartbeatTolerance


def expected_aborts(dut: DeviceUnderTest, situation: str, evidence: Evidence) -> set[int]:
    """CiA's code for the situation, or the codes a documented quirk of the profile names."""
    for quirk_id, quirk in dut.profile.quirks.items():
        if isinstance(quirk.params, AbortCode) and quirk.params.situation == situation:
            evidence.deviation(quirk_id, quirk.title)
            return set(quirk.params.codes)
    return {ABORT_FOR_SITUATION[situation]}


def abort_family(code: int) -> int:
    """The family of an abort code: all digits but the last (06090030h, 06090031h, 06090032h: 0609003xh)."""
    return code & ~0xF


def abort_accepted(dut: DeviceUnderTest, response: SdoResponse, expected: set[int]) -> bool:
    """True for an abort with one of ``expected`` codes, or (``dut.abort_codes == "family"``) of their family;
    a family match is noted in the test's evidence."""
    if not response.is_abort or response.abort_code is None:
        return False
    if response.abort_code in expected:
        return True
    if dut.abort_codes == "family" and abort_family(response.abort_code) in {abort_family(c) for c in expected}:
        dut.tester_notes.append(f"abort {abort_name(response.abort_code)} accepted by family for "
                                f"{' or '.join(abort_name(c) for c in sorted(expected))} (--abort-codes family)")
        return True
    return False


def assert_abort(dut: DeviceUnderTest, response: SdoResponse, expected: set[int], what: str) -> None:
    """The response must be an abort with one of ``expected`` codes (or their family, by the run's
    --abort-codes) for the same multiplexer."""
    wanted = " or ".join(abort_name(code) for code in sorted(expected))
    if dut.abort_codes == "family":
        wanted += " (or a code of its family)"
    if not response.is_abort:
        raise AssertionError(
            f"{what}: expected abort {wanted}, observed {response.describe()}\n"
            f"last frames:\n{format_frames(dut.frames.last(6))}"
        )
    if not abort_accepted(dut, response, expected):
        raise AssertionError(f"{what}: expected abort {wanted}, observed abort {abort_name(response.abort_code or 0)}")


def judge_refusal(dut: DeviceUnderTest, response: SdoResponse | None, expected: set[int], tolerated: set[int],
                  what: str, evidence: Evidence) -> None:
    """A request CiA 301 says the server must refuse: no answer or no abort fails (the caller's clause); an abort
    with ``expected`` (CiA's or the manual's code; its family with --abort-codes family) or with a code the CiA
    conformance test tool accepts (``tolerated``) passes; any other code is an inferred problem (a warning)."""
    if response is None:
        raise AssertionError(f"{what}: no SDO response within {dut.sdo_timeout * 1000:.0f} ms (an abort is due)\n"
                             f"last frames:\n{format_frames(dut.frames.last(8))}")
    if not response.is_abort:
        raise AssertionError(f"{what}: accepted ({response.describe()}), expected an abort")
    if abort_accepted(dut, response, expected):
        return
    code = response.abort_code or 0
    wanted = " or ".join(abort_name(c) for c in sorted(expected))
    if code in tolerated:
        evidence.note(f"{what}: abort {abort_name(code)}, accepted as the CiA conformance test tool does "
                      f"(CiA 301 names {wanted})")
        return
    evidence.inferred_problem(f"{what}: abort {abort_name(code)}, expected {wanted}",
                              "the abort code: CiA 301 table 22 names the code; the conformance test tool accepts "
                              + (", ".join(abort_name(c) for c in sorted(tolerated)) or "no other"))


def assert_one_answer(request: bytes, answers: list[bytes], what: str) -> None:
    """CiA 301 §7.2.4.3: a request draws one confirmation or one abort; more fail, naming the request and each
    answer in order with the time between them (a confirmation and then an abort are two answers)."""
    if len(answers) > 1:
        raise AssertionError(f"{what}: {sdo_words.request(request)}: {len(answers)} answers to one request: "
                             f"{sdo_words.replies(answers)} (CiA 301 §7.2.4.3: one confirmation or one abort per "
                             "request)")


def check_periodic(timestamps: list[float], period_ms: float, tolerance: HeartbeatTolerance, what: str,
                   evidence: Evidence, host: HostLatency | None = None, clock: str = "not stated") -> None:
    """Periodic frames: the long-run period (fitted over all frames) within the tolerance, and the frames
    on their schedule.

    At most ``tolerance.late_frames`` of the frames may be further than the tolerance from the
    fitted schedule (a frame delayed by bus arbitration or a busy tester), none by more than half a
    period. With ``host`` (the tester host's own lateness during the capture), a verdict that would fail
    is inconclusive (skipped with the figures) where the host explains it: every frame off the schedule
    came when the host itself ran that late, or the period is off while the host was late throughout.
    Evidence: the measurements, the host's lateness, and the intervals as a timing measurement (statistics and
    plot, stamped by ``clock``).
    """
    allowed = tolerance.allowed_ms(period_ms)
    stats = interval_stats(timestamps, period_ms)
    fit = schedule_fit(timestamps, period_ms)
    late = fit.off_schedule(allowed)
    may_be_late = int(tolerance.late_frames * len(timestamps))
    evidence.measure(f"{what} period fitted over {len(timestamps)} frames", round(fit.fitted_period_ms, 3), "ms",
                     period_ms - allowed, period_ms + allowed)
    evidence.measure(f"{what} mean interval", round(stats.mean_ms, 3), "ms")
    evidence.measure(f"{what} frames off schedule by > {allowed:.1f} ms", len(late), "frames", 0, may_be_late)
    basis = ("inferred: CiA 301 sets the period, no tolerance; profile timing.heartbeat_tolerance "
             f"max({tolerance.abs_ms:g} ms, {tolerance.rel:.0%})")
    evidence.timing(f"{what} interval", stats.intervals_ms, nominal_ms=period_ms, low_ms=period_ms - allowed,
                    high_ms=period_ms + allowed, clock=clock, basis=basis,
                    judged=f"the period fitted over all frames, and at most {may_be_late} frame(s) further than the "
                           "band's half-width from the fitted schedule (one late frame moves two intervals)")
    evidence.note(f"basis of the tolerance: {basis}")
    if host is not None:
        evidence.note(f"tester host during the capture: {host.describe()}")
    if late and len(late) <= may_be_late:
        evidence.note(f"{len(late)} frame(s) off the schedule within the allowed share (timing.heartbeat_tolerance."
                      f"late_frames = {tolerance.late_frames:g}): " + ", ".join(f"#{n}: {o:+.1f} ms" for n, o in late))
    if any(abs(o) > period_ms / 2 for _, o in late):
        may_be_late = 0  # a frame half a period off is a missing or extra one, not a late one
    period_off = abs(fit.fitted_period_ms - period_ms) > allowed
    if host is not None and (period_off or len(late) > may_be_late):
        _inconclusive_if_host_explains(timestamps, period_ms, allowed, late, fit.fitted_period_ms, host, what)
    assert not period_off, (
        f"{what}: period {fit.fitted_period_ms:.2f} ms (fitted over {len(timestamps)} frames; mean interval "
        f"{stats.mean_ms:.2f} ms), expected {period_ms} ms within {allowed:.1f} ms"
    )
    assert len(late) <= may_be_late, (
        f"{what}: {len(late)} of {len(timestamps)} frames further than {allowed:.1f} ms from the {period_ms} ms "
        f"schedule (at most {may_be_late} may be): " + ", ".join(f"#{n}: {o:+.1f} ms" for n, o in late[:8])
        + "; intervals: " + ", ".join(f"#{n}: {i:.1f} ms" for n, i in stats.outside(allowed)[:8])
    )


#: the host's bound on the fitted period (host_period_shift_ms) is taken twice over before a period off while the
#: host was late fails the device: the bound is exact only for a device exactly on its period
HOST_SHIFT_MARGIN = 2.0


def host_period_shift_ms(count: int, worst_ms: float) -> float:
    """The most a host whose lateness stayed within ``worst_ms`` can move the period fitted over ``count`` frames
    (``schedule_fit``: Theil-Sen, the median of the pairwise slopes). A frame stamped late by up to ``worst_ms``
    moves the slope of a pair ``gap`` frames apart by at most ``worst_ms / gap``; more than half of the pairs are at
    least the returned gap apart, so their median moves no further (about 3.4 x ``worst_ms`` / ``count``: 1 ms for
    50 frames stamped up to 15 ms late). The twin's timing thread keeps absolute deadlines, so its own lateness
    does not add up either (sim/engine/scheduler.py)."""
    pairs = count * (count - 1) // 2
    for gap in range(count - 1, 0, -1):
        if (count - gap) * (count - gap + 1) > pairs:  # twice the pairs at least ``gap`` apart: more than half
            return worst_ms / gap
    return worst_ms


def _inconclusive_if_host_explains(timestamps: list[float], period_ms: float, allowed: float,
                                   late: list[tuple[int, float]], fitted_ms: float, host: HostLatency,
                                   what: str) -> None:
    """Skip as inconclusive where the tester's host, not the device, explains what would fail."""
    if host.clock_step_ms > allowed:  # the stamps themselves jumped (CI, stop 49: one interval of 10087 ms)
        not_judged(Hold.HOST_LATE, f"{what} timing cannot be judged, the host's wall clock (the clock of the frame "
                    f"timestamps) was stepped during the capture: {host.describe()}; tolerance {allowed:.1f} ms")
    beyond_ms = abs(fitted_ms - period_ms) - allowed  # how far the fitted period lies outside the band
    period_off = beyond_ms > 0
    window = period_ms / 1000
    unexplained = [(n, o) for n, o in late if host.worst_near(timestamps[n], window) < abs(o) - allowed]
    if period_off and not host.sustained(allowed):
        return  # the period itself is off while the host kept time: the device's
    worst = max(host.worst_ms, host.twin_worst_ms or 0.0)
    if period_off and beyond_ms > HOST_SHIFT_MARGIN * host_period_shift_ms(len(timestamps), worst):
        return  # off by more than any lateness of the host could move the fitted period: the device's
    if unexplained and not period_off:
        return  # a frame off the schedule while the host was on time: the device's
    not_judged(Hold.HOST_LATE, f"{what} timing cannot be judged, the tester's host was overloaded: "
                f"{host.describe()}; tolerance {allowed:.1f} ms. Frames off the schedule: "
                + (", ".join(f"#{n}: {o:+.1f} ms" for n, o in late[:8]) or "none"))


def inconclusive_if_host_late(when: list[float], excess_ms: list[float], host: HostLatency, what: str) -> None:
    """Skip as inconclusive where the tester's host was itself that late at each moment a figure is off."""
    if all(host.worst_near(t, 0.05) >= ms for t, ms in zip(when, excess_ms, strict=True)):
        not_judged(Hold.HOST_LATE, f"{what} cannot be judged, the tester's host was overloaded at each sample "
                    f"off the limit: {host.describe()}")


def describe_value(value: object) -> str:
    if isinstance(value, int):
        return f"{value} (0x{value:X})"
    return repr(value)


def documented_quirk(dut: DeviceUnderTest, effect: type[P], evidence: Evidence, otherwise: str,
                     needs: tuple[str, ...] = ()) -> P:
    """The typed params of the profile's quirk with ``effect``, cited in the evidence; skips if there is none.

    ``otherwise`` says what the device does without the quirk (the skip reason); ``needs`` lists
    params the test cannot do without (e.g. the test_object it may change).
    """
    found = dut.profile.quirk(effect)
    if found is None:
        not_applicable(f"{otherwise} (no quirk {effect.effect})")
    missing = [name for name in needs if getattr(found.params, name, None) is None]
    if missing:
        not_applicable(f"quirk {found.id} names no {', '.join(missing)} the suite may use")
    evidence.deviation(found.id, found.quirk.title)
    return found.params
