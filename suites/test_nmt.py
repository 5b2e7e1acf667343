"""NMT state machine, boot-up and per-state service gating (CiA 301 §7.3.2, §7.2.8.3.2.1)."""

from __future__ import annotations

import pytest

from encoder_conformance.cia.cia301 import COB_ID_INVALID, HEARTBEAT_BASE, PDO_MAPPING_OFFSET, STATE_NAMES, cob_id_valid
from encoder_conformance.dut.link import NO_SDO_IN_STOPPED, format_frames
from encoder_conformance.dut.nmt import (
    HeartbeatObserver,
    NmtObserver,
    ServiceObserver,
    describe,
    expected_after_reset,
    raise_if_held_out_of,
    settled_state,
)
from encoder_conformance.dut.sdo import sdo_frames
from encoder_conformance.dut.store import STORE_GROUPS, CannotPersist, changeable_parameter, other_valid_value
from encoder_conformance.dut.tpdo import TpdoUnderTest, pdo_stimulus
from encoder_conformance.plugin.skips import not_applicable
from encoder_conformance.plugin.suite_helpers import documented_quirk
from encoder_conformance.profile import quirk_effects as fx

pytestmark = pytest.mark.spec("CiA 301 §7.3.2 (NMT state machine)")

TRANSITIONS = [
    ("pre-operational", "start", 0x05),
    ("pre-operational", "stop", 0x04),
    ("operational", "pre-operational", 0x7F),
    ("operational", "stop", 0x04),
    ("stopped", "start", 0x05),
    ("stopped", "pre-operational", 0x7F),
]


@pytest.fixture
def nmt(dut, settings_journal, back_to_preoperational, request, evidence) -> NmtObserver:
    """Observe the state by heartbeat, or by SDO answers and SYNC-driven TPDOs on devices without one."""
    if dut.profile.capabilities.heartbeat_producer:
        return HeartbeatObserver(dut, request.getfixturevalue("state_heartbeat"))
    comm = request.getfixturevalue("sync_tpdo")
    if comm is None:
        not_applicable("no heartbeat and no SYNC-driven TPDO to observe the NMT state with")
    evidence.note(f"NMT state observed through {ServiceObserver.method} (the profile has no heartbeat producer)")
    return ServiceObserver(dut, comm)


@pytest.mark.spec("CiA 301 §7.2.8.3.2.1 (boot-up protocol)")
@pytest.mark.parametrize("reset", ["reset-node", "reset-communication"])
def test_bootup_after_reset(dut, reset, evidence):
    """After NMT reset node / reset communication the device sends one boot-up frame 700h+id [00h]."""
    mark = dut.nmt.command(reset)
    boot = dut.wait_bootup(mark)
    assert boot is not None, (
        f"no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms after {reset}\n"
        f"{format_frames(dut.frames.since(mark)) or '  no frames'}"
    )
    elapsed_ms = (boot.timestamp - dut.frames.since(mark, lambda m: not m.is_rx)[0].timestamp) * 1000
    evidence.measure("boot-up delay", elapsed_ms, "ms", 0, dut.profile.timing.bootup_max_ms)
    assert boot.dlc == 1, f"boot-up frame has DLC {boot.dlc}, CiA 301 requires 1"


@pytest.mark.parametrize(("start", "command", "expected"), TRANSITIONS,
                         ids=[f"{s} --{c}--> {e:02X}h" for s, c, e in TRANSITIONS])
def test_transition(dut, nmt, start, command, expected):
    """Each NMT command moves the device to its target state (heartbeat state byte, or services)."""
    nmt.go_to(start)  # seen there first: a device that starts itself would otherwise be judged from operational
    mark = nmt.command(command)
    nmt.expect_state(mark, expected, f"{command} from {start}")


def test_broadcast_command_applies(dut, nmt):
    """An NMT command to node-id 0 (all nodes) is obeyed like an addressed one."""
    nmt.go_to("pre-operational")
    mark = nmt.command("start", node_id=0)
    nmt.expect_state(mark, 0x05, "start remote node to all nodes (node-id 0)")


def test_command_for_other_node_ignored(dut, nmt):
    """An NMT command addressed to another node-id leaves the device in its state."""
    other = dut.node_id % 127 + 1
    nmt.go_to("pre-operational")
    mark = nmt.command("start", node_id=other)
    nmt.expect_not_state(mark, 0x05, f"start command addressed to node {other}")


def test_no_sdo_in_stopped(dut, nmt):
    """In stopped the device does not answer SDO requests (only NMT and error control remain)."""
    nmt.go_to("stopped")
    response = dut.sdo_request_unanswered(sdo_frames.upload_request(0x1000, 0), "SDO request in stopped",
                                          NO_SDO_IN_STOPPED)
    assert response is None, f"SDO answered in stopped: {response.describe()}"


def _made_valid(dut, comm: int, settings_journal, evidence) -> bool:
    """The TPDO is valid (18xxh sub 1 bit 31 clear), if need be by clearing the bit (put back afterwards)."""
    cob_id = dut.read_uint(comm, 1)
    if not cob_id & COB_ID_INVALID:
        return True
    entry = dut.profile.entry(comm, 1)
    if entry is None or not entry.writable:
        return False
    settings_journal.write(comm, 1, cob_id_valid(cob_id).to_bytes(4, "little"))
    evidence.note(f"{comm:04X}h.01 bit 31 cleared (TPDO valid) for the test")
    return True


@pytest.fixture
def sync_tpdo(dut, settings_journal, evidence):
    """Make sure one TPDO is sent on every SYNC (set 18xxh sub 2 = 1 and clear sub 1 bit 31 if needed,
    put back afterwards; e.g. SIKO PDO2 is disabled after every init)."""
    types = dut.profile.capabilities.tpdo_transmission_types
    for comm in sorted(i for i in dut.profile.objects if 0x1800 <= i <= 0x19FF):
        mapping = dut.profile.entry(comm + PDO_MAPPING_OFFSET, 0)
        kind = dut.profile.entry(comm, 2)
        if kind is None or (mapping is not None and dut.read_uint(comm + PDO_MAPPING_OFFSET, 0) == 0):
            continue
        synchronous = 1 <= dut.read_uint(comm, 2) <= 240
        if not (synchronous or (kind.writable and 1 in types)):
            continue
        if not _made_valid(dut, comm, settings_journal, evidence):
            continue
        if not synchronous:
            TpdoUnderTest(dut, settings_journal, comm, 1).configure(trans_type=1)  # sub 2 writable: see above
            evidence.note(f"{comm:04X}h.02 set to 1 (synchronous, every SYNC) for the test")
        return comm
    return None


def _complete_tpdos(profile) -> list[int]:
    """TPDOs the profile gives a transmission type (18xxh sub 2) and a mapping (1Axxh sub 0) to, or whose
    behaviour a fixed-layout quirk declares (e.g. POSITAL: cyclic by 2200h)."""
    found = profile.params_of(fx.FixedTpdoMapping)
    fixed = set(found.mapping) if found is not None else set()
    return [comm for comm in sorted(i for i in profile.objects if 0x1800 <= i <= 0x19FF)
            if comm in fixed or (profile.entry(comm, 2) is not None
                                 and profile.entry(comm + PDO_MAPPING_OFFSET, 0) is not None)]


SHAFT_VALUES = {0x6004, 0x6008, 0x6030}  # position and speed: what a turning shaft changes (CiA 406)


def _shaft_moves_a_tpdo(profile) -> bool:
    """True for an encoder with a TPDO that maps a value the shaft changes (its change makes it send)."""
    if not profile.capabilities.encoder:
        return False
    for comm in _complete_tpdos(profile):
        mapping = profile.objects.get(comm + PDO_MAPPING_OFFSET)
        entries = mapping.entries() if mapping is not None else {}
        if any(isinstance(e.default, int) and e.default >> 16 in SHAFT_VALUES for s, e in entries.items() if s):
            return True
    return False


def _skip_without_trigger(dut, sync_tpdo, shaft) -> None:
    """Skip where neither a SYNC nor the shaft can make a TPDO go out (its silence would prove nothing)."""
    if not _complete_tpdos(dut.profile):
        not_applicable("no TPDO of the profile has both a transmission type (18xxh sub 2) and a "
                    "mapping (1Axxh): what would make it send is not declared")
    if sync_tpdo is None and not (shaft is not None and _shaft_moves_a_tpdo(dut.profile)):
        not_applicable("no TPDO can be made to transmit on SYNC (18xxh sub 2 fixed, or type 1 not "
                    "accepted) and the device is no encoder whose shaft the bench turns: its event-driven TPDOs "
                    "wait for a manufacturer event this bench cannot cause")


@pytest.mark.requires("tpdos")
@pytest.mark.parametrize("state", ["pre-operational", "stopped"])
def test_no_pdo_outside_operational(dut, sync_tpdo, nmt, shaft, state):
    """No TPDO is sent in pre-operational or stopped, although SYNCs arrive and the shaft turns."""
    _skip_without_trigger(dut, sync_tpdo, shaft)
    nmt.go_to(state)
    mark = pdo_stimulus(dut, shaft)
    pdos = dut.frames.since(mark, dut.is_pdo)
    assert not pdos, f"{len(pdos)} TPDO(s) in {state}:\n{format_frames(pdos[:5])}"


@pytest.mark.requires("tpdos")
def test_pdo_in_operational(dut, sync_tpdo, nmt, shaft):
    """In operational the same stimulus makes the device send TPDOs (so the silence above means something)."""
    _skip_without_trigger(dut, sync_tpdo, shaft)
    nmt.go_to("operational")
    mark = pdo_stimulus(dut, shaft, until=dut.is_pdo)
    pdos = dut.frames.since(mark, dut.is_pdo)
    assert pdos, "no TPDO in operational during 10 SYNCs and a turning shaft: check the default PDO configuration"


def test_stopped_sends_only_error_control(dut, nmt, shaft):
    """In stopped the device sends nothing but heartbeats, whatever happens on the bus."""
    nmt.go_to("stopped")
    mark = pdo_stimulus(dut, shaft)
    dut.send_sdo(sdo_frames.upload_request(0x1000, 0))
    own = dut.frames_from_node(mark, dut.sdo_silence_s)
    others = [m for m in own if m.arbitration_id != HEARTBEAT_BASE + dut.node_id]
    assert not others, f"frames other than heartbeat in stopped:\n{format_frames(others[:5])}"


def _unstored_change(dut, settings_journal, wanted, prefer=()):
    """Change one storable parameter without storing it; (what, the value it had = its stored value).

    Between tests the device's values are its stored configuration (each test puts back what it
    changes, the run restored nothing yet), so the value read before the change is what a reset
    must bring back (CiA 301: the stored value, the factory default only where nothing is stored).
    """
    found = changeable_parameter(dut.profile, wanted, prefer=prefer)
    if found is None:
        return None, None
    stored = dut.read(found.index, found.sub)
    new_value = found.new_value.to_bytes(len(stored), "little")
    if new_value == stored:  # the stored configuration holds the value the profile suggests: take another
        other = other_valid_value(dut.profile, found.index, found.sub, found.new_value)
        if other is None:
            return None, None
        new_value = other.to_bytes(len(stored), "little")
    settings_journal.write(found.index, found.sub, new_value)
    return found, int.from_bytes(stored, "little")


@pytest.mark.spec("CiA 301 §7.3.2.2.3 (reset node: application parameters to their stored/default values)")
def test_reset_node_reloads_application_parameters(dut, settings_journal, evidence):
    """An unstored change of an application parameter is undone by NMT reset node (back to the stored value)."""
    found, stored = _unstored_change(dut, settings_journal, lambda index, e: index >= 0x2000
                                     and e.persisted_by in STORE_GROUPS)
    if found is None:
        not_applicable("the profile declares no writable application parameter with a default")
    dut.nmt.reset_node()
    observed = dut.read_uint(found.index, found.sub)
    evidence.note(f"{found.label}: stored {stored}, changed without storing, {observed} after reset node")
    assert observed == stored, f"{found.label}: {observed} after reset node, expected the stored value {stored}"


@pytest.mark.spec("CiA 301 §7.3.2.2.3 (reset communication: 1000h-1FFFh to their stored/default values)")
def test_reset_communication_reloads_communication_parameters(dut, settings_journal, evidence):
    """An unstored change of a communication parameter (1017h first) is undone by NMT reset communication."""
    found, stored = _unstored_change(dut, settings_journal, lambda index, e: index < 0x2000
                                     and e.persisted_by in STORE_GROUPS, prefer=(0x1017,))
    if found is None:
        not_applicable("no communication parameter is stored on command (all persisted_by auto/none)")
    mark = dut.nmt.command("reset-communication")
    assert dut.wait_bootup(mark) is not None, "no boot-up after reset communication"
    observed = dut.read_uint(found.index, found.sub)
    evidence.note(f"{found.label}: stored {stored}, changed without storing, {observed} after reset communication")
    assert observed == stored, (
        f"{found.label} = {observed} after reset communication, expected the stored value {stored}"
    )


def _boots_into(dut, settings_journal, evidence) -> int:
    """Reset node; after the boot-up, switch the heartbeat on (RAM only) and return the state it reports."""
    dut.nmt.reset_node()
    period = dut.profile.timing.heartbeat_state_period_ms
    mark = dut.frames.mark()
    settings_journal.write(0x1017, 0, period.to_bytes(2, "little"))
    beat = dut.wait_heartbeat(mark, (dut.profile.timing.nmt_settle_ms + 3 * period) / 1000)
    assert beat is not None, f"no heartbeat within {3 * period} ms after 1017h = {period} ms"
    evidence.note(f"heartbeat after reset node reports {beat.data[0]:02X}h ({STATE_NAMES.get(beat.data[0], '?')})")
    return beat.data[0]


@pytest.mark.destructive
@pytest.mark.requires("heartbeat_producer")
def test_autostart_object_starts_device_after_reset(dut, settings_journal, evidence):
    """Documented autostart object set and stored: after reset node the device is operational without NMT start.

    Put back afterwards (value, store, reset node), and the device must then boot into pre-operational again.
    """
    params = documented_quirk(dut, fx.NmtAutostartObject, evidence,
                              "the device boots into pre-operational and waits for NMT start (CiA 301)")
    index, sub = params.key
    original = dut.read(index, sub)
    operational = params.operational_value.to_bytes(len(original), "little")
    dut.write(index, sub, operational)
    try:
        try:
            how = dut.store.persist(index, sub)
        except CannotPersist as exc:
            not_applicable(f"{exc}")
        evidence.note(f"{index:04X}h.{sub:02X} = {operational.hex(' ').upper()}, stored with {how}")
        state = _boots_into(dut, settings_journal, evidence)
        if state != 0x05:
            raise_if_held_out_of(dut, 0x05, "the autostart object")
        assert state == 0x05, (
            f"documented: {index:04X}h = {params.operational_value} starts the device after boot-up; "
            f"the heartbeat reports {state:02X}h ({STATE_NAMES.get(state, '?')}) instead of 05h (operational)"
        )
    finally:
        if dut.usable:
            dut.write(index, sub, original)
            dut.store.persist(index, sub)
            settings_journal.restore()
    state = _boots_into(dut, settings_journal, evidence)
    wanted = 0x05 if params.operational_value == int.from_bytes(original, "little") else 0x7F
    assert state == wanted, (f"after putting {index:04X}h back ({original.hex(' ').upper()}) the device boots into "
                             f"{describe(state)}, not {describe(wanted)}")


@pytest.mark.spec("CiA 301 §7.3.2.2 (NMT state diagram: after initialisation, pre-operational); CiA 302-2 1F80h bit 3")
@pytest.mark.requires("heartbeat_producer")
@pytest.mark.parametrize("reset", ["reset-node", "reset-communication", "power-on"])
def test_state_after_reset(dut, reset, settings_journal, request, evidence):
    """Each reset (NMT reset node, reset communication, power-on) ends in pre-operational, as the heartbeat after the
    boot-up reports (7Fh), unless the device is documented self-starting (its autostart object, 1F80h bit 3)."""
    expected = expected_after_reset(dut)
    evidence.rests_on("manual" if expected.state == 0x05 else "cia", expected.why)
    if expected.quirk_id is not None:
        evidence.deviation(expected.quirk_id, expected.why)
    period = dut.read_uint(0x1017)
    mark = dut.frames.mark()
    if reset == "power-on":
        request.getfixturevalue("power_cycle")()  # not available without a power switch
    else:
        dut.nmt.command(reset)
    boot = dut.wait_bootup(mark)
    assert boot is not None, f"no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms after {reset}"
    if not period:  # no heartbeat after the reset: switched on by SDO, which pre-operational and operational offer
        assert dut.responds() or dut.responds(), (
            f"after {reset} and its boot-up the device answers no SDO: it is in neither pre-operational nor "
            f"operational ({expected.why})\n{format_frames(dut.frames.since(mark)[-6:])}")
        period = dut.profile.timing.heartbeat_state_period_ms
        settings_journal.write(0x1017, 0, period.to_bytes(2, "little"))
    state = settled_state(dut, mark, boot, period)
    evidence.note(f"after {reset}: the heartbeat reports {describe(state)}; expected {describe(expected.state)}")
    assert state == expected.state, (
        f"after {reset} the device is in {describe(state)} (heartbeat after its boot-up), expected "
        f"{describe(expected.state)}: {expected.why}\n{format_frames(dut.frames.since(mark, dut.is_heartbeat)[-4:])}")
