"""Layer setting services (CiA 305 v3.0.0): every service the profile declares, in the LSS and NMT states it
allows, the node-ID life cycle (pending, active, stored, unconfigured) and fastscan.

Sources: CiA 305 v3.0.0, cited by the heading of each service (``cia305.CLAUSE_*``); the device manuals for
their quirks; where a text allows more than one behaviour, every reading it allows is accepted
(``encoder_conformance/open_points/lss.py`` lists them with their sentences). Devices without LSS (switch-configured)
skip every test with that reason. Every test starts in pre-operational, waits what the device owes (its LSS
answer window, its boot-up time) and checks it got there; the lss fixture puts the device back wherever the test
left it, also when it fails.
"""

from __future__ import annotations

import time
from contextlib import nullcontext

import pytest

from encoder_conformance.cia import cia305
from encoder_conformance.cia.cia301 import HEARTBEAT_BASE
from encoder_conformance.cia.cia305 import (
    AUTO_BIT_RATE_INDEX,
    FASTSCAN_RESET_BIT,
    MAX_NODE_ID,
    UNCONFIGURED_NODE_ID,
    LssCommand,
    LssState,
)
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link import format_frames
from encoder_conformance.dut.lss import (
    SWITCH_DELAY_MS,
    LssAddress,
    LssDevice,
    activate,
    cob_ids_not_reset,
    expect_success,
    manual_excludes,
    stored_node_id_survives_power_cycle,
)
from encoder_conformance.plugin.skips import not_applicable, not_equipped
from encoder_conformance.plugin.suite_helpers import destructive_if_self_stored, documented_quirk, require_service
from encoder_conformance.profile import quirk_effects as fx

pytestmark = pytest.mark.spec(cia305.CIA305)
#: the WDGA manual's "new boot-up" after LSS changes (M §8.2.4): open readings lss-node-id-activation and
#: lss-unconfigured-start (open_points/lss.py)
NEW_BOOT_UP = "Wachendorff WDGA manual M §8.2.4 (a new boot-up after LSS configuration) and M §4.2"
#: CiA 305 leaves open when an unconfigured slave given a node-ID starts (open reading lss-unconfigured-start)
UNCONFIGURED_START_READINGS = ("CiA 305 v3.0.0, configure node-ID and the LSS slave states: an unconfigured slave "
                               "given a node-ID starts when switched to the waiting state (CANopenNode) or at the "
                               "next NMT reset (lely-core); both accepted")

NMT_STATES = {"pre-operational": ("pre-operational", 0x7F), "operational": ("start", 0x05),
              "stopped": ("stop", 0x04)}


# -- LSS states and addressing ---------------------------------------------------------------------------
@pytest.mark.spec(cia305.CLAUSE_FSA)
def test_switch_global_enters_and_leaves_configuration(lss: LssDevice):
    """Switch state global 1 -> inquire node-ID is answered with the active node-ID; 0 -> not answered (inquire
    belongs to the configuration state)."""
    require_service(lss, "switch_global", "inquire_node_id")
    lss.master.switch_global(LssState.CONFIGURATION)
    assert lss.master.inquire_node_id() == lss.node_id, "inquire node-ID in configuration state"
    lss.leave()
    with lss.master.no_answer_expected(cia305.CLAUSE_FSA):
        assert lss.master.inquire_node_id() is None, "inquire node-ID answered in the waiting state"


@pytest.mark.spec(cia305.CLAUSE_SWITCH_SELECTIVE)
def test_switch_selective_only_own_address(lss: LssDevice):
    """Switch state selective: the device answers 44h to its own LSS address (1018h sub 1..4), not to one
    that differs in the serial number."""
    require_service(lss, "switch_selective")
    other = LssAddress(*lss.address.parts()[:3], (lss.address.serial + 1) & 0xFFFFFFFF)
    with lss.master.no_answer_expected(cia305.CLAUSE_SWITCH_SELECTIVE):
        assert not lss.master.switch_selective(other), f"answered 44h to another serial number: {other.describe()}"
    assert lss.master.switch_selective(lss.address), f"no 44h to its own address {lss.address.describe()}"


@pytest.mark.spec(cia305.CLAUSE_INQUIRE)
def test_inquire_identity_equals_1018h(lss: LssDevice):
    """Inquire vendor-ID, product code, revision and serial number (5Ah-5Dh) answer 1018h sub 1..4."""
    require_service(lss, "inquire_identity")
    lss.transition("configuration")
    found = lss.master.inquire_address()
    assert found == lss.address, f"inquired {found.describe() if found else 'no answer'}, 1018h holds " \
                                 f"{lss.address.describe()}"


@pytest.mark.spec(cia305.CLAUSE_FSA)
@pytest.mark.parametrize("service", ["configure_node_id", "inquire_identity", "inquire_node_id"])
def test_configuration_services_not_answered_in_waiting_state(lss: LssDevice, service: str):
    """Configure and inquire services belong to the configuration state: unanswered in the waiting state."""
    require_service(lss, service)
    lss.transition("waiting")
    with lss.master.no_answer_expected(cia305.CLAUSE_FSA):
        answer = {"configure_node_id": lambda: lss.master.configure_node_id(lss.node_id),
                  "inquire_identity": lambda: lss.master.inquire("serial"),
                  "inquire_node_id": lss.master.inquire_node_id}[service]()
    assert answer is None, f"{service} answered in the LSS waiting state: {answer}"


@pytest.mark.spec(cia305.CLAUSE_FSA)
@pytest.mark.parametrize("state", list(NMT_STATES))
def test_lss_in_nmt_state(lss: LssDevice, state: str, evidence, request: pytest.FixtureRequest, dut: DeviceUnderTest):
    """LSS works in every NMT state (the LSS FSA is independent of the NMT state); a device whose manual allows it
    only in some (quirk lss_only_in_states, e.g. WDGA M §8.2.1) must ignore it in the others."""
    require_service(lss, "inquire_node_id")
    command, code = NMT_STATES[state]
    beats = lss.dut.profile.capabilities.heartbeat_producer
    period = request.getfixturevalue("heartbeat") / 1000 if beats else 0.0  # set up while SDO still works,
    request.getfixturevalue("back_to_preoperational")  # and put back after the device is pre-operational again
    mark = dut.nmt.command(command)
    quirk = lss.dut.profile.params_of(fx.LssOnlyInStates)
    allowed = quirk is None or state in quirk.states
    if quirk is not None:
        documented_quirk(lss.dut, fx.LssOnlyInStates, evidence, "")
    settle = lss.dut.profile.timing.nmt_settle_ms / 1000
    if beats:  # the state is reached when the heartbeat says so (a kept error may hold it in pre-operational)
        dut.nmt.confirm(mark, code, period * 1000, f"NMT {command}, so that LSS in {state} can be judged")
    else:
        lss.dut.frames.quiet_period(lambda m: False, settle)  # nothing shows the state: the profile's settle time
    with lss.master.no_answer_expected() if not allowed else nullcontext():
        lss.select()
        answer = lss.master.inquire_node_id()
    lss.transition("waiting")
    assert (answer is not None) == allowed, (f"in NMT {state} the device {'ignored' if allowed else 'obeyed'} LSS "
                                             f"({'allowed' if allowed else 'not allowed'} here)")
    if allowed:
        assert answer == lss.node_id, f"inquire node-ID in NMT {state}: {answer}, the device is {lss.node_id}"


# -- configure node-ID and bit timing ----------------------------------------------------------------------
NODE_ID_CASES = [(1, 0), (MAX_NODE_ID, 0), (UNCONFIGURED_NODE_ID, 0), (0, 1), (128, 1), (254, 1)]


@pytest.mark.spec(cia305.CLAUSE_CONFIGURE_NODE_ID)
@pytest.mark.parametrize(("node_id", "error"), NODE_ID_CASES, ids=[f"{n}->{e}" for n, e in NODE_ID_CASES])
def test_configure_node_id_range(lss: LssDevice, node_id: int, error: int, pytestconfig):
    """Configure node-ID: 1..127 and 255 (unconfigured) accepted (error 0), 0 and 128..254 refused (error 1).
    The value is only pending: the test configures the device's own node-ID again before leaving."""
    require_service(lss, "configure_node_id")
    manual_range = lss.dut.profile.params_of(fx.LssNodeIdRange)
    if manual_range is not None and (manual_excludes(lss, node_id) is None) != (error == 0):
        not_applicable(f"not judged here: the manual's node-ID range {manual_range.node_id_range} and CiA 305 disagree "
                    f"on node-ID {node_id} (quirk lss_node_id_range)")
    if error == 0 and node_id != lss.node_id:
        destructive_if_self_stored(lss, pytestconfig, "node_id")
    lss.transition("configuration")
    if error == 0:
        lss.moving_to(node_id)  # pending only; custody looks there too should a reset apply it
    answer = lss.master.configure_node_id(node_id)  # the lss fixture configures the node-ID in use again
    assert answer is not None, \
        f"configure node-ID {node_id}: no answer within {lss.master.answer_timeout_s * 1000:.0f} ms"
    assert answer.error == error, f"configure node-ID {node_id}: error {answer.error}, expected {error}"


@pytest.mark.spec(cia305.CLAUSE_CONFIGURE_BIT_TIMING)
@pytest.mark.parametrize("index", [*range(0, 11)], ids=[f"index {i}" for i in range(11)])
def test_configure_bit_timing_table_0(lss: LssDevice, index: int, evidence, pytestconfig):
    """Configure bit timing, table 0: the indices of the bit rates the profile lists (and 9, automatic
    detection, where the device has it) are accepted; indices past 9, which table 0 does not have, are refused
    (error 1 or FFh). A table-0 rate the profile does not list, automatic detection (9, optional) and the
    reserved index 5 (100 kbit/s in older LSS tables) are taken as not supported: our inference from the profile
    (open reading lss-bit-timing-beyond-profile), a warning. The bit rate in use is configured again afterwards."""
    require_service(lss, "configure_bit_timing")
    bus = lss.dut.profile.bus
    expected_ok = index in bus.lss_bit_indices()
    if expected_ok and index != lss.bit_index:
        destructive_if_self_stored(lss, pytestconfig, "bit_timing")
    if expected_ok and lss.bit_index is None and "bit_timing" in lss.auto_stored:
        not_equipped("the bit rate in use is unknown and the device stores a configured bit rate by itself")
    lss.transition("configuration")
    answer = lss.master.configure_bit_timing(index)  # the lss fixture configures the rate in use again
    assert answer is not None, f"configure bit timing {index}: no answer"
    if (answer.error == 0) == expected_ok:
        return
    observed = (f"configure bit timing table 0 index {index} ({bus.lss_table().get(index, 'reserved / auto')}): "
                f"error {answer.error}; the profile's bit rates are {bus.bitrates}")
    if not expected_ok and (index in bus.lss_table() or index in (5, AUTO_BIT_RATE_INDEX)):
        evidence.inferred_problem(observed, "a table-0 index the profile does not list is taken as not supported "
                                            "(CiA 305 v3.0.0 table 0 leaves auto-detection optional and reserves "
                                            "index 5; older LSS tables give it 100 kbit/s)")
        return
    raise AssertionError(observed)


@pytest.mark.spec(cia305.CLAUSE_ACTIVATE_BIT_TIMING)
def test_activate_bit_timing_silent_for_the_switch_delay(lss: LssDevice, heartbeat: int):
    """Activate bit timing (the rate in use again): the device sends nothing for the switch delay before
    and after the switch, then its heartbeat comes again. One frame per COB-ID that crossed the request (sent
    within the LSS response window after it) is not held against the device (``sent_after_request``)."""
    require_service(lss, "configure_bit_timing", "activate_bit_timing")
    if lss.bit_index is None:
        not_equipped("the bit rate in use is unknown: activating a configured one could move the device off the bus")
    mark, delay = activate(lss, lss.bit_index)
    silent = lss.sent_after_request(mark, 2 * delay * 0.9)
    beat = lss.dut.wait_heartbeat(mark, 2 * delay + 3 * heartbeat / 1000)
    lss.transition("waiting")
    assert not silent, f"frames within the 2 x {SWITCH_DELAY_MS} ms switch delay:\n{format_frames(silent)}"
    assert beat is not None, "no heartbeat after the switch"


@pytest.mark.spec(cia305.CLAUSE_ACTIVATE_BIT_TIMING)
def test_activated_bit_rate_leaves_the_old_rate(lss: LssDevice, heartbeat: int, power_cycle, pytestconfig):
    """Activate another bit rate: the device is no longer heard at the old one. The tester's interface cannot
    follow a bit-rate change during a run, so the test stops there; a power cycle brings back the stored rate
    (nothing was stored)."""
    require_service(lss, "configure_bit_timing", "activate_bit_timing")
    destructive_if_self_stored(lss, pytestconfig, "bit_timing")
    others = sorted(lss.dut.profile.bus.lss_bit_indices() - {lss.bit_index, AUTO_BIT_RATE_INDEX})
    if lss.bit_index is None or not others:
        not_applicable("the bit rate in use is unknown, or the device has no other bit rate")
    mark, delay = activate(lss, others[0])
    heard = lss.sent_after_request(mark, 2 * delay + 3 * heartbeat / 1000)
    power_cycle()
    assert not heard, (f"still heard at the old bit rate after activating table index {others[0]}:\n"
                       f"{format_frames(heard[-5:])}")


# -- the node-ID life cycle ----------------------------------------------------------------------------------
@pytest.mark.spec(cia305.CLAUSE_CONFIGURE_NODE_ID)
def test_configured_node_id_pending_until_reset(lss: LssDevice, evidence, pytestconfig):
    """A configured node-ID is pending: the device keeps answering at its node-ID (and inquire node-ID says so)
    until NMT reset communication, after which it boots with the new one. A device whose manual asks for a new
    boot-up (quirk lss_only_in_states, WDGA M §8.2.4) may boot at either node-ID after the reset: at the old one
    (it applies the node-ID only at power-on) or at the new one (M §4.2: "power reset or NMT reset"; open reading
    lss-node-id-activation), never at neither."""
    require_service(lss, "configure_node_id")
    destructive_if_self_stored(lss, pytestconfig, "node_id")
    new_id = lss.free_node_id()
    expect_success(lss.configure_for(new_id), f"configure node-ID {new_id}")
    if "inquire_node_id" in lss.services:
        assert lss.master.inquire_node_id() == lss.node_id, "inquire node-ID: the pending node-ID is active at once"
    lss.transition("waiting")
    assert lss.answers_at(lss.node_id), f"after configure node-ID {new_id} the device no longer answers at " \
                                        f"{lss.node_id}: the new node-ID was active at once"
    assert not lss.answers_at(new_id, timeout=lss.dut.sdo_silence_s), f"answers at {new_id} before any reset"
    mark = lss.reset_communication(lss.node_id)
    boot_ids = (HEARTBEAT_BASE + new_id, HEARTBEAT_BASE + lss.node_id)
    boot = lss.dut.frames.wait_for(lambda m: m.is_rx and m.arbitration_id in boot_ids
                                   and bytes(m.data) == b"\x00", lss.dut.profile.timing.bootup_max_ms / 1000, mark)
    booted_at = None if boot is None else boot.arbitration_id - HEARTBEAT_BASE
    if not lss.applies_on_reset:
        documented_quirk(lss.dut, fx.LssOnlyInStates, evidence, "")
        evidence.rests_on("manual", NEW_BOOT_UP)
        assert booted_at is not None, (f"no boot-up at {lss.node_id} nor at {new_id} within "
                                       f"{lss.dut.profile.timing.bootup_max_ms:.0f} ms after NMT reset communication")
        evidence.note(f"after NMT reset communication the device booted at {booted_at}: "
                      + ("the configured node-ID waits for power-on" if booted_at == lss.node_id else
                         "the configured node-ID became active at the reset (M §4.2: power or NMT reset)"))
        assert lss.answers_at(booted_at), f"boot-up at {booted_at}, but no SDO answer there"
        return
    if booted_at != new_id:
        evidence.inferred_problem(
            f"no boot-up at the new node-ID {new_id} after NMT reset communication\n"
            f"{format_frames(lss.dut.frames.since(mark)) or '  no frames'}",
            "CiA 305 v3.0.0, configure node-ID: the configured node-ID is pending and becomes active at NMT reset "
            "communication (as CANopenNode and lely-core implement it; TR-Electronic CM-36 manual §3.7.6)")
        return
    assert lss.answers_at(new_id), f"boot-up at {new_id}, but no SDO answer there"


@pytest.mark.spec(cia305.CLAUSE_IDENTIFY)
def test_identify_remote_slave_by_ranges(lss: LssDevice):
    """Identify remote slave: answered (4Fh) when the device's revision and serial lie in the ranges, not
    when the serial range excludes it."""
    require_service(lss, "identify_remote_slave")
    address = lss.address
    low = LssAddress(address.vendor, address.product, 0, max(address.serial - 1, 0))
    high = LssAddress(address.vendor, address.product, 0xFFFFFFFF, address.serial)
    assert lss.master.identify_remote(low, high) >= 1, "no 4Fh although the ranges contain the device"
    above = LssAddress(address.vendor, address.product, 0, address.serial + 1)
    top = LssAddress(address.vendor, address.product, 0xFFFFFFFF, 0xFFFFFFFF)
    if address.serial < 0xFFFFFFFF:
        with lss.master.no_answer_expected(cia305.CLAUSE_IDENTIFY):
            assert lss.master.identify_remote(above, top) == 0, "4Fh although the serial range excludes the device"


@pytest.mark.spec(cia305.CLAUSE_IDENTIFY)
def test_configured_device_not_identified_as_non_configured(lss: LssDevice):
    """Identify non-configured remote slave (4Ch) is answered only by a device with node-ID FFh."""
    require_service(lss, "identify_non_configured")
    with lss.master.no_answer_expected(cia305.CLAUSE_IDENTIFY):
        assert lss.master.identify_non_configured() == 0, f"a configured device (node-ID {lss.node_id}) answered 50h"


@pytest.mark.spec(cia305.CLAUSE_CONFIGURE_NODE_ID)
def test_unconfigured_start_up(unconfigured: LssDevice, evidence):
    """Node-ID 255: no boot-up and no SDO until LSS gives a node-ID; then the device boots with it when it leaves
    the configuration state, or at the NMT reset communication the suite then sends to all nodes (both readings of
    CiA 305, open reading lss-unconfigured-start-at-nmt-reset). A device whose manual asks for a new boot-up (quirk
    lss_only_in_states, WDGA M §8.2.4: store, leave, then e.g. a power reset) is given the node-ID that way: stored,
    and, where leaving does not start it, switched off and on (open reading lss-unconfigured-start)."""
    lss = unconfigured
    quiet = lss.unconfigured_since or lss.dut.frames.mark()
    # node-ID 255 stored by the device itself: its delivery state, checked after power-on below (a legacy
    # device was made unconfigured by a power cycle already); one boot-up window is enough
    power_on_check = lss.power_cycle is not None and lss.applies_on_reset and "node_id" in lss.auto_stored
    if not power_on_check:  # the boot-up it would owe comes within the boot-up time after the reset
        rest = Deadline(lss.dut.profile.timing.bootup_max_ms / 1000, since=quiet.time).remaining()
        assert lss.wait_bootup_at(lss.node_id, quiet, rest) is None, \
            "unconfigured, but a boot-up at the old node-ID"
    assert not lss.answers_at(lss.node_id, timeout=lss.dut.sdo_silence_s), "unconfigured, but answers SDO"
    if "identify_non_configured" in lss.services:
        assert lss.master.identify_non_configured() == 1, "unconfigured, but no answer to identify non-configured"
    frames = lss.dut.frames.since(quiet, lambda m: m.is_rx and m.arbitration_id in (0x7FF, 0x77F, 0x6FF, 0x5FF))
    assert not frames, f"an unconfigured device sent frames as node 127 or 255:\n{format_frames(frames)}"
    if power_on_check:
        mark = lss.power_cycle()
        assert lss.wait_bootup_at(lss.node_id, mark) is None, "node-ID 255 stored, but a boot-up after power-on"
        if "identify_non_configured" in lss.services:
            assert lss.master.identify_non_configured() == 1, "after power-on not identified as non-configured"
    new_boot_up = lss.dut.profile.params_of(fx.LssOnlyInStates) is not None
    lss.transition("configuration")
    mark = lss.dut.frames.mark()
    expect_success(lss.master.configure_node_id(lss.node_id), f"configure node-ID {lss.node_id}")
    if new_boot_up and "node_id" not in lss.auto_stored and "store_configuration" in lss.services:
        expect_success(lss.master.store_configuration(), "store configuration (the manual's step 1, M §8.2.4)")
    lss.transition("waiting")
    boot = lss.wait_bootup_at(lss.node_id, mark)
    if boot is None and new_boot_up and lss.power_cycle is not None:
        evidence.rests_on("manual", NEW_BOOT_UP)
        evidence.note("no boot-up on leaving the configuration state: the new boot-up the manual asks for, by a "
                      "power cycle")
        mark = lss.power_cycle()
        boot = lss.wait_bootup_at(lss.node_id, mark)
    if boot is None and not new_boot_up:
        evidence.rests_on("cia", UNCONFIGURED_START_READINGS)
        evidence.note("no boot-up on leaving the configuration state: NMT reset communication to all nodes (the "
                      "device has no node-ID to be addressed by yet; open reading lss-unconfigured-start-at-nmt-reset)")
        mark = lss.reset_communication(0)
        boot = lss.wait_bootup_at(lss.node_id, mark)
    assert boot is not None, (
        f"no boot-up at {lss.node_id} after the unconfigured device got its node-ID\n"
        f"{format_frames(lss.dut.frames.since(mark)) or '  no frames'}")
    if lss.dut.profile.params_of(fx.UnconfiguredNodeId) is not None:
        documented_quirk(lss.dut, fx.UnconfiguredNodeId, evidence, "")
        problems = cob_ids_not_reset(lss)
        assert not problems, "; ".join(problems)


@pytest.mark.spec(cia305.CLAUSE_FASTSCAN)
def test_fastscan_finds_exact_identity(scannable: LssDevice, evidence):
    """Fastscan (no part known) finds the unconfigured device's exact LSS address, which is then in the
    configuration state (inquire node-ID answers FFh). Each step waits the window learned from the device's
    own answers (3 x the slowest, at least 10 ms, at most timing.lss_response_ms), and the whole scan again
    with the profile's window if that found nothing."""
    lss = scannable
    window = lss.master.learned_window()
    steps, start = lss.master.steps, time.perf_counter()
    found = lss.master.fastscan_learned()
    evidence.measure("fastscan time", time.perf_counter() - start, "s")
    evidence.measure("fastscan step window", window * 1000, "ms", None, lss.dut.profile.timing.lss_response_ms)
    evidence.measure("fastscan frames", lss.master.steps - steps, "frames")
    assert found == lss.address, f"fastscan found {found.describe() if found else 'nothing'}, the device is " \
                                 f"{lss.address.describe()}"
    if "inquire_node_id" in lss.services:
        assert lss.master.inquire_node_id() == UNCONFIGURED_NODE_ID


@pytest.mark.spec(cia305.CLAUSE_FASTSCAN)
def test_fastscan_reset_restarts_a_partial_scan(scannable: LssDevice):
    """BitChecked 80h restarts the scan: after the vendor-ID was confirmed, a reset and a full fastscan
    still find the device."""
    lss = scannable
    lss.master.request(LssCommand.FASTSCAN, bytes(4) + bytes([FASTSCAN_RESET_BIT, 0, 0]))
    lss.master.request(LssCommand.FASTSCAN, lss.address.vendor.to_bytes(4, "little") + bytes([0, 0, 1]))
    known = (*lss.address.parts()[:3], None)  # vendor-ID confirmed again first: a scan that was not restarted fails
    found = lss.master.fastscan_learned(known)
    assert found == lss.address, "after a reset (BitChecked 80h) the fastscan did not find it"


@pytest.mark.spec(cia305.CLAUSE_FASTSCAN)
def test_fastscan_no_configuration_before_serial(scannable: LssDevice):
    """The device enters the configuration state only after the serial number was confirmed: a master that
    confirms vendor-ID and product code and then sends LSSNext back to the vendor-ID does not select it
    (CANopenNode PR#647)."""
    require_service(scannable, "inquire_node_id")
    lss = scannable
    lss.master.request(LssCommand.FASTSCAN, bytes(4) + bytes([FASTSCAN_RESET_BIT, 0, 0]))
    lss.master.request(LssCommand.FASTSCAN, lss.address.vendor.to_bytes(4, "little") + bytes([0, 0, 1]))
    mark = lss.master.request(LssCommand.FASTSCAN, lss.address.product.to_bytes(4, "little") + bytes([0, 1, 0]))
    assert lss.master.answer(LssCommand.IDENTIFY_SLAVE, mark) is not None, "product code confirm not answered"
    with lss.master.no_answer_expected():
        assert lss.master.inquire_node_id() is None, "in the configuration state before its serial number was checked"


@pytest.mark.spec(cia305.CLAUSE_STORE)
@pytest.mark.destructive
def test_store_configuration_survives_power_cycle(lss: LssDevice, power_cycle):
    """Store configuration (17h) keeps a configured node-ID over a power cycle."""
    require_service(lss, "configure_node_id", "store_configuration")
    stored_node_id_survives_power_cycle(lss, store=True)


@pytest.mark.spec(cia305.CLAUSE_CONFIGURE_NODE_ID)
@pytest.mark.destructive
def test_self_stored_node_id_survives_power_cycle(lss: LssDevice, power_cycle, evidence):
    """A device that stores a configured node-ID by itself (quirk lss_config_auto_stored) boots with it
    after a power cycle, without store configuration."""
    require_service(lss, "configure_node_id")
    documented_quirk(lss.dut, fx.LssConfigAutoStored, evidence, "the device stores by store configuration only")
    if "node_id" not in lss.auto_stored:
        not_applicable("the device stores its bit rate by itself, not its node-ID")
    stored_node_id_survives_power_cycle(lss, store=False)
