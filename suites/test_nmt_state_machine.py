"""Generated sequences of NMT commands, SDO reads and writes, heartbeat changes and SYNCs, checked after
every step against the CiA 301 model of a node (encoder_conformance/models/nmt.py, hypothesis stateful).

Each step is one of: an NMT command (all five, to the node, to all nodes, or start / enter
pre-operational to another node-ID, which must change nothing); an SDO write of a value the model
follows (1017h, TPDO event timers, the transmission type and valid bit of a SYNC-driven TPDO, one
application parameter, each only where the profile declares it rw and stored by a store command); an
SDO read of one of them; a SYNC. After every step: the heartbeat's state byte is the model's state,
no TPDO came while the node was not operational, a read shows what the model holds (values survive a
state change, and come back to what the device has stored after reset communication, 1000h-1FFFh, or
reset node, everything), no SDO answer in stopped, and a SYNC-driven TPDO in operational. A write of a PDO
parameter outside pre-operational may be refused with 08000022h (CiA 301 v4.2.0 §7.2.4.3.17 table 22; open reading
pdo-config-refused-in-operational): the model then keeps the value.

"Stored" is what the device held when the test began: between tests the device's values are its
stored configuration (a customer's, on a bench). Nothing is stored (1010h) or restored (1011h); a
value the device stores by itself on every write (persisted_by auto) is followed only for 1017h,
which the heartbeat tests write too, and its written value counts as stored.

A fixed tour (TOUR) walks every transition and check once; then hypothesis generates sequences, as
many as the active profile's counts allow, capped (SETTINGS). The tour's two resets are always made;
the generated ones spend RESET_BUDGET_S, so a device that takes seconds to boot (POSITAL, about 4 s)
gets no more than the tour's. Without a heartbeat producer (POSITAL) the state shows in the services:
SDO answered or not, and the SYNC TPDO in operational.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import pytest
from canopen.sdo.exceptions import SdoAbortedError
from hypothesis import HealthCheck, note, settings
from hypothesis import strategies as st
from hypothesis.control import currently_in_test_context
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule, run_state_machine_as_test

from encoder_conformance.cia.cia301 import (
    COB_ID_INVALID,
    PDO_MAPPING_OFFSET,
    STATE_NAMES,
    NmtCommand,
    NmtState,
    can_id_of,
)
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.custody import SettingsJournal
from encoder_conformance.dut.link import NO_SDO_IN_STOPPED, Mark, format_frames
from encoder_conformance.dut.nmt import HeartbeatObserver, describe, newest_state, raise_if_held_by_error, settled_state
from encoder_conformance.dut.sdo import upload_request
from encoder_conformance.dut.store import STORE_GROUPS, changeable_parameter
from encoder_conformance.models.nmt import NmtModel, Tracked
from encoder_conformance.profile import datatypes
from encoder_conformance.profile import quirk_effects as fx
from encoder_conformance.profile.value_domain import declared_domain

pytestmark = pytest.mark.spec("CiA 301 §7.3.2.2 (NMT state diagram, services per state, initialisation)")

_active = settings()
#: a handful of sequences under the CI profile (each step waits for frames the device owes); more on a bench
SETTINGS = settings(
    max_examples=max(2, _active.max_examples // 25), stateful_step_count=min(_active.stateful_step_count, 20),
    deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    report_multiple_bugs=False,  # one shrunk sequence is enough to read; each replay costs device time
)
#: seconds of NMT resets per test beyond the fixed tour's two: a twin boots in milliseconds, a device that takes
#: 300 ms gets a few more, the POSITAL (about 4 s) none
RESET_BUDGET_S = 2.0
#: a frame the device owes (heartbeat with the new state, SDO answer, SYNC TPDO) is waited for this much longer
#: than the profile's limit: this test judges states and values, not timing (the timing suites do), and a
#: tester on a loaded host may see frames late; a wait ends as soon as the frame comes
SLACK_S = 0.5
STATE_COMMANDS = ["start", "stop", "pre-operational"]
RESETS = ["reset-node", "reset-communication"]
COMMAND = {"start": NmtCommand.START, "stop": NmtCommand.STOP, "pre-operational": NmtCommand.ENTER_PRE_OPERATIONAL,
           "reset-node": NmtCommand.RESET_NODE, "reset-communication": NmtCommand.RESET_COMMUNICATION}


@dataclass(frozen=True)
class Write:
    """One SDO write a step may make."""

    key: tuple[int, int]
    value: int

    def __str__(self) -> str:
        return f"write {self.key[0]:04X}h.{self.key[1]:02X} = {self.value}"


#: stored only by a command: 1010h, or a manufacturer's store object (which this test never writes)
BY_COMMAND = (*STORE_GROUPS, "manufacturer_store")


def _stored_by_command(profile, index: int, sub: int, also: tuple[str, ...] = ()) -> bool:
    """rw, readable, an integer of at most 4 bytes (expedited), stored only by a store command (or ``also``)."""
    entry = profile.entry(index, sub)
    size = datatypes.size_bytes(entry.type) if entry is not None else None
    return (entry is not None and entry.writable and entry.readable and entry.persisted_by in (*BY_COMMAND, *also)
            and size is not None and size <= 4)


def _valid_values(profile, index: int, sub: int, values: list[int]) -> list[int]:
    domain = declared_domain(profile, index, sub)
    return [v for v in dict.fromkeys(values) if domain is None or v in domain]


def _sync_tpdo(profile) -> int | None:
    """The first TPDO whose type 1 (every SYNC) and valid bit the profile lets a step write."""
    for comm in sorted(i for i in profile.objects if 0x1800 <= i <= 0x19FF):
        if (_stored_by_command(profile, comm, 1) and _stored_by_command(profile, comm, 2)
                and 1 in profile.capabilities.tpdo_transmission_types and _maps_something(profile, comm)
                and _sync_driven_layouts(profile, comm)):
            return comm
    return None


def _sync_driven_layouts(profile, comm: int) -> bool:
    """False for a TPDO whose fixed layout (quirk fixed_tpdo_mapping) sends it otherwise (cyclic, polled)."""
    fixed = profile.params_of(fx.FixedTpdoMapping)
    if fixed is None or comm not in fixed.mapping:
        return True
    syncs = fixed.sync if isinstance(fixed.sync, list) else [fixed.sync] if fixed.sync is not None else []
    return comm in {s.tpdo for s in syncs}


def _maps_something(profile, comm: int) -> bool:
    fixed = profile.params_of(fx.FixedTpdoMapping)
    mapping = profile.entry(comm + PDO_MAPPING_OFFSET, 0)
    return (fixed is not None and comm in fixed.mapping) or (mapping is not None and bool(mapping.default))


class DeviceValues:
    """What the steps write, and what the device held before the test (its stored configuration)."""

    def __init__(self, dut, evidence) -> None:
        profile = dut.profile
        self.dut = dut
        self.writes: list[Write] = []
        self.stored: dict[tuple[int, int], Tracked] = {}
        autostart = profile.params_of(fx.NmtAutostartObject)
        period = profile.timing.heartbeat_state_period_ms  # states, not timing: each change shows within ~1 period
        # 1017h also where the device stores every write itself (as the heartbeat fixture writes it): the model
        # then takes the written value as the stored one
        if profile.capabilities.heartbeat_producer and _stored_by_command(profile, 0x1017, 0, also=("auto",)):
            self._add(0x1017, 0, [period, 2 * period], weight=2)
        for comm in sorted(i for i in profile.objects if 0x1800 <= i <= 0x19FF):
            if _stored_by_command(profile, comm, 5):
                self._add(comm, 5, [0, period])
        self.sync_tpdo = _sync_tpdo(profile)
        if self.sync_tpdo is not None:
            cob_id = self._add(self.sync_tpdo, 1, [])
            self._add_values(cob_id, [cob_id.stored & ~COB_ID_INVALID, cob_id.stored | COB_ID_INVALID])
            kind = self._add(self.sync_tpdo, 2, [1])
            self._add_values(kind, [kind.stored])
        avoid = {autostart.index} if autostart is not None else set()
        app = changeable_parameter(profile, lambda index, e: index >= 0x2000 and index not in avoid
                                   and e.persisted_by in BY_COMMAND)
        if app is not None and _stored_by_command(profile, app.index, app.sub):
            value = self._add(app.index, app.sub, [app.new_value])
            self._add_values(value, [value.stored])
        self.boot_state = NmtState.PRE_OPERATIONAL
        if autostart is not None:
            quirk_id = profile.quirk(fx.NmtAutostartObject).id  # there: autostart is not None
            if dut.read_uint(autostart.index, autostart.subindex) == autostart.operational_value:
                self.boot_state = NmtState.OPERATIONAL
            evidence.deviation(quirk_id, f"after a reset the node enters {STATE_NAMES[int(self.boot_state)]} "
                                         f"({autostart.index:04X}h.{autostart.subindex:02X} as stored)")

    def _add(self, index: int, sub: int, values: list[int], weight: int = 1) -> Tracked:
        entry = self.dut.profile.entry(index, sub)
        size = datatypes.size_bytes(entry.type) or 4
        stored = int.from_bytes(self.dut.read(index, sub), "little")
        forced = [q.params for q in self.dut.profile.quirks_with(fx.BitsForcedAtInit) if q.params.key == (index, sub)]
        preop = any(q.params.covers(index, sub) for q in self.dut.profile.quirks_with(fx.WritesPreopOnly))
        tracked = Tracked(index, sub, size, stored, stored, preop_only=preop, auto_stored=entry.persisted_by == "auto",
                          forced_bits=forced[0].forced_bits if forced else 0,
                          forced_at=frozenset(forced[0].at) if forced else frozenset())
        self.stored[(index, sub)] = tracked
        self._add_values(tracked, values * weight)
        return tracked

    def _add_values(self, tracked: Tracked, values: list[int]) -> None:
        valid = _valid_values(self.dut.profile, tracked.index, tracked.sub, values)
        self.writes += [Write((tracked.index, tracked.sub), v) for v in valid]

    def model(self) -> NmtModel:
        model = NmtModel(self.dut.node_id, boot_state=self.boot_state)
        for t in self.stored.values():
            model.track(replace(t, current=t.stored))
        return model


def _changes(found: DeviceValues, model: NmtModel) -> list[Write]:
    """One write per followed value that changes it (the SYNC TPDO's to type 1 and valid where possible)."""
    armed = {}
    if found.sync_tpdo is not None:
        cob_id = model.values[(found.sync_tpdo, 1)]
        armed = {(found.sync_tpdo, 1): cob_id.stored & ~COB_ID_INVALID, (found.sync_tpdo, 2): 1}
    chosen: dict[tuple[int, int], Write] = {}
    for write in found.writes:
        if write.key in armed:
            if write.value == armed[write.key]:
                chosen[write.key] = write
        elif write.key not in chosen and write.value != model.values[write.key].stored:
            chosen[write.key] = write
    return list(chosen.values())


#: a walk through every transition and check, run before the generated sequences (which, a few under the CI
#: profile, may leave some out): each command to the node and to all nodes, commands to another node in
#: operational and stopped, reads in each state, SYNCs in and outside operational, both resets after changes;
#: ``change_other`` changes the values ``change_all`` may leave as stored (the armed SYNC TPDO's COB-ID where it
#: is stored valid), so that a state change or reset communication that reloads them shows on every profile
TOUR = [
    ("change_all",), ("state_command", "start", "node"), ("sync",), ("read_all",),
    ("state_command", "pre-operational", "other node"), ("state_command", "stop", "all nodes"), ("read_all",),
    ("sync",), ("state_command", "start", "other node"), ("state_command", "pre-operational", "node"),
    ("read_all",), ("change_other",), ("state_command", "start", "all nodes"), ("sync",),
    ("state_command", "stop", "node"), ("state_command", "start", "node"),
    ("state_command", "pre-operational", "all nodes"), ("read_all",),
    ("reset", "reset-communication", "all nodes"), ("read_all",), ("change_all",), ("state_command", "stop", "node"),
    ("reset", "reset-node", "node"), ("read_all",), ("change_all",), ("state_command", "start", "node"), ("sync",),
]


class ResetBudget:
    """Seconds the test may spend in resets (the boot-up and the wait for the state after it), shared by every
    generated sequence."""

    def __init__(self, seconds: float) -> None:
        self.left = seconds
        self.done = 0
        self.spent = 0.0

    def spend(self, seconds: float) -> None:
        self.left -= seconds
        self.spent += seconds
        self.done += 1

    def allows(self) -> bool:
        """Another reset fits: what is left covers the mean reset so far (the tour's two, at first)."""
        return self.left > 0 and self.left >= (self.spent / self.done if self.done else 0.0)


def _other_node(dut) -> int:
    """A node-ID that is neither the device's nor its sibling's (quirk second_node)."""
    sibling = dut.profile.params_of(fx.SecondNode)
    taken = {dut.node_id, dut.node_id + (sibling.node_id_offset if sibling is not None else 0)}
    return next(n for n in ((dut.node_id + k - 1) % 127 + 1 for k in range(1, 128)) if n not in taken)


@dataclass
class NmtRun:
    """One test's inputs to its machines (the fixed tour's and each generated sequence's): the device, the settings
    journal, the values followed, the reset budget, another node-ID, and the steps of each machine run."""

    dut: DeviceUnderTest
    journal: SettingsJournal
    found: DeviceValues
    budget: ResetBudget
    other: int  # a node-ID nobody on the bench has
    steps: list[int] = field(default_factory=list)  # steps of each machine run (the tour's first)
    writes: list[Write | None] = field(init=False)
    keys: list[tuple[int, int]] = field(init=False)

    def __post_init__(self) -> None:
        self.writes = list(self.found.writes) or [None]
        self.keys = sorted(self.found.stored) or [(0x1000, 0)]


def _from_run(choices: Callable[[NmtRun], list]) -> st.SearchStrategy:
    """A value sampled from a list of the machine's run: a module-level machine gets its per-run inputs through
    ``run`` (the factory given to ``run_state_machine_as_test``), its rules draw them through ``st.runner()``."""
    return st.runner().flatmap(lambda machine: st.sampled_from(choices(machine.run)))


class NmtMachine(RuleBasedStateMachine):
    """The device against the CiA 301 model of a node, one step at a time (rules), checked after every step
    (invariants); the fixed tour calls the same rules in a fixed order."""

    def __init__(self, run: NmtRun) -> None:
        super().__init__()
        self.run = run
        self.dut = run.dut
        self.found = run.found
        self.model = run.found.model()
        self.step = 0
        self.log: list[str] = []
        self.quiet_since: Mark | None = None  # since when no TPDO may come (not operational, settled)
        self.settled = self.dut.frames.mark()  # since when every heartbeat must carry the model's state
        self.checked = self.settled  # the last heartbeat check
        run.steps.append(0)
        self._start()

    # -- set-up: pre-operational, values as stored, heartbeat on ------------------------
    def _start(self) -> None:
        dut = self.dut
        dut.nmt.command("pre-operational")
        assert dut.responds() or dut.responds(), "no SDO answer after NMT enter pre-operational"
        for key, tracked in self.model.values.items():
            if int.from_bytes(dut.read(*key), "little") != tracked.stored:
                self.run.journal.write(*key, tracked.stored.to_bytes(tracked.size, "little"))
        beat = next((w for w in self.found.writes if w.key == (0x1017, 0)), None)
        if beat is not None:
            self.run.journal.write(0x1017, 0, beat.value.to_bytes(2, "little"))
            self.model.write(beat.key, beat.value)
        mark = dut.frames.mark()
        self._confirm(mark, "set-up: pre-operational")
        self._say(f"set-up: followed values as stored, heartbeat {self.model.heartbeat_ms} ms", mark)

    def _say(self, text: str, mark: Mark) -> None:
        self.step += 1
        self.run.steps[-1] += 1
        seen = format_frames(self.dut.frames.since(mark)[-8:])
        line = f"step {self.step}: {text} -> model {STATE_NAMES[self.model.heartbeat_byte]}\n{seen}"
        self.log.append(line)
        if currently_in_test_context():
            note(line)

    def _confirm(self, mark: Mark, why: str) -> None:
        """Wait for the frame that proves the model's state; from then on TPDOs must stop if not operational."""
        if self.model.heartbeat_ms:
            self._expect_heartbeat(mark, self.model.heartbeat_byte, why)
        else:
            self._confirm_by_services(why)
        self.settled = self.dut.frames.mark()
        if self.model.pdo_allowed:
            self.quiet_since = None
        elif self.quiet_since is None:  # just left operational: silent from now on
            self.quiet_since = self.dut.frames.mark()

    def _heartbeat_wait_s(self) -> float:
        return HeartbeatObserver(self.dut, self.model.heartbeat_ms).window_s + SLACK_S

    def _expect_heartbeat(self, mark: Mark, state: int | None, why: str) -> None:
        """A heartbeat after ``mark`` (reporting ``state``, if given) within settle time + 2 periods + slack."""
        dut = self.dut
        wait = self._heartbeat_wait_s()
        if dut.wait_heartbeat(mark, wait, state=state) is None:
            seen = dut.frames.since(mark, dut.is_heartbeat)[-6:]
            wanted = f"state {state:02X}h ({STATE_NAMES.get(state)})" if state is not None else "any state"
            raise AssertionError(f"{why}: no heartbeat with {wanted} within {wait * 1000:.0f} ms (1017h = "
                                 f"{self.model.heartbeat_ms} ms): the heartbeat reports "
                                 f"{describe(newest_state(dut, mark))}; heartbeats seen:\n"
                                 f"{format_frames(seen) or '  none'}")

    def _confirm_by_services(self, why: str) -> None:
        """Without heartbeat: no SDO answer in stopped, an answer otherwise (polled within the settle time)."""
        dut = self.dut
        deadline = Deadline(dut.profile.timing.nmt_settle_ms / 1000 + dut.sdo_timeout + SLACK_S)
        while True:
            answered = dut.sdo_request(upload_request(0x1000, 0), timeout=dut.sdo_silence_s) is not None
            if answered == self.model.sdo_answered or deadline.expired():
                break
        assert answered == self.model.sdo_answered, (
            f"{why}: SDO {'answered' if answered else 'not answered'}, the model is "
            f"{STATE_NAMES[self.model.heartbeat_byte]}")

    # -- rules -----------------------------------------------------------------------
    @rule(name=st.sampled_from(STATE_COMMANDS), to=st.sampled_from(["node", "all nodes", "other node"]))
    def state_command(self, name: str, to: str) -> None:
        dut = self.dut
        if to == "other node" and name == "stop":
            name = "start"  # another node on a bench is only ever started or sent back to pre-operational
        target = {"node": dut.node_id, "all nodes": 0, "other node": self.run.other}[to]
        before = self.model.state
        mark = dut.nmt.command(name, target)
        self.model.command(COMMAND[name], target)
        why = f"NMT {name} to {'node ' + str(target) if target else 'all nodes'} from {STATE_NAMES[before]}"
        if self.model.state is not before or to == "node" or to == "all nodes":
            self._confirm(mark, why)
        elif self.model.heartbeat_ms:
            wrong = {"start": 0x05, "pre-operational": 0x7F}[name]
            if wrong != int(before):
                HeartbeatObserver(dut, self.model.heartbeat_ms).expect_not_state(mark, wrong, why)
        self._say(why, mark)

    @precondition(lambda self: self.run.budget.allows())
    @rule(name=st.sampled_from(RESETS), to=st.sampled_from(["node", "all nodes"]))
    def reset(self, name: str, to: str) -> None:
        dut = self.dut
        target = dut.node_id if to == "node" else 0
        began = time.monotonic()
        mark = dut.nmt.command(name, target)
        self.model.command(COMMAND[name], target)
        boot = dut.wait_bootup(mark)
        why = f"NMT {name} to {'node ' + str(target) if target else 'all nodes'}"
        assert boot is not None, (f"{why}: no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms\n"
                                  f"{format_frames(dut.frames.since(mark)[-8:]) or '  no frames'}")
        if self.model.heartbeat_ms:  # the state the reset ends in, once settled (an early beat may precede a start)
            state = settled_state(dut, mark, boot, self.model.heartbeat_ms, SLACK_S)
            assert state == self.model.heartbeat_byte, (
                f"{why}: after the boot-up the heartbeat reports {describe(state)}, the reset ends in "
                f"{describe(self.model.heartbeat_byte)} (CiA 301 §7.3.2.2; the boot state as stored)")
        self._confirm(mark, f"{why}, after the boot-up")
        self._say(f"{why} (boot-up seen; values back to stored)", mark)
        self._heartbeat_back_to_the_set_up_period()
        self.run.budget.spend(time.monotonic() - began)  # the boot-up and the first beats of a stored heartbeat

    def _heartbeat_back_to_the_set_up_period(self) -> None:
        """A reset brought back a stored heartbeat slower than the one the set-up wrote (a customer's 1000 ms, say):
        read that it did, then write the set-up's again; every later step would wait up to a stored period for the
        beat that shows its state (seen: 44 s of one bench run at 1000 ms)."""
        beat = next((w for w in self.found.writes if w.key == (0x1017, 0)), None)
        if beat is None or not beat.value or self.model.heartbeat_ms <= beat.value:
            return
        self.read((0x1017, 0))  # the stored value, as the model holds after the reset
        self.write(beat)

    @rule(write=_from_run(lambda run: run.writes))
    def write(self, write: Write | None) -> None:
        if write is None or not self.model.may_write(write.key):
            return  # stopped, or a pre-operational-only object outside pre-operational: nothing sent
        tracked = self.model.values[write.key]
        mark = self.dut.frames.mark()
        refused: tuple[int, str] | None = None
        try:
            self.run.journal.write(*write.key, write.value.to_bytes(tracked.size, "little"))
        except SdoAbortedError as exc:  # judged outside the handler: no library exception rides along
            refused = (exc.code, str(exc))
        if refused is not None:
            where = STATE_NAMES[self.model.heartbeat_byte]
            assert self.model.refusal_allowed(write.key, refused[0]), f"{write} refused in {where}: {refused[1]}"
            self._say(f"{write}: refused in {where} with 08000022h (present device state), value kept", mark)
            return
        self.model.write(write.key, write.value)
        if write.key == (0x1017, 0) and write.value:
            self._confirm(mark, f"heartbeat after {write}")
        self._say(str(write), mark)

    @rule(key=_from_run(lambda run: run.keys))
    def read(self, key: tuple[int, int]) -> None:
        dut = self.dut
        mark = dut.frames.mark()
        if not self.model.sdo_answered:
            reply = dut.sdo_request_unanswered(upload_request(*key), "SDO request in stopped", NO_SDO_IN_STOPPED)
            assert reply is None, f"SDO answered in stopped: {reply.describe()}"
            self._say(f"read {key[0]:04X}h.{key[1]:02X}: no answer (stopped)", mark)
            return
        reply = dut.sdo_request(upload_request(*key), timeout=dut.sdo_timeout + SLACK_S)
        where = f"read {key[0]:04X}h.{key[1]:02X} in {STATE_NAMES[self.model.heartbeat_byte]}"
        assert reply is not None, f"{where}: no answer within {dut.sdo_timeout * 1000:.0f} ms"
        assert not reply.is_abort, f"{where}: {reply.describe()}"
        if key in self.model.values:
            tracked = self.model.values[key]
            value = int.from_bytes(reply.raw[4:4 + tracked.size], "little")
            assert value == tracked.current, (
                f"{tracked.label} reads {value}, the model holds {tracked.current} (stored {tracked.stored}; "
                "a reset brings back the stored value, a state change keeps the value)")
        self._say(f"read {key[0]:04X}h.{key[1]:02X}", mark)

    @rule()
    def sync(self) -> None:
        dut = self.dut
        mark = dut.send_sync()
        comm = self.found.sync_tpdo
        if comm is not None and self.model.pdo_allowed and self._sync_armed(comm):
            cob_id = can_id_of(self.model.expected((comm, 1)))
            tpdo = dut.tpdo.at(comm)
            pdo = dut.frames.wait_for(tpdo.frames(cob_id), tpdo.answer_s + SLACK_S, mark)  # owed: answer window
            assert pdo is not None, f"no TPDO {cob_id:03X}h on a SYNC in operational ({comm:04X}h type 1, valid)"
        # outside operational the invariant judges what came, now or after the next step (teardown waits)
        self._say("SYNC", mark)

    def _sync_armed(self, comm: int) -> bool:
        return self.model.expected((comm, 2)) == 1 and not self.model.expected((comm, 1)) & COB_ID_INVALID

    # -- the fixed tour's own steps -----------------------------------------------------
    def change_all(self) -> None:
        """Every followed value to another value than stored (the SYNC TPDO armed: type 1, valid)."""
        for write in _changes(self.found, self.model):
            self.write(write)

    def change_other(self) -> None:
        """Every followed value to one that is neither stored nor current, where the writes offer one."""
        for key, tracked in self.model.values.items():
            other = next((w for w in self.found.writes
                          if w.key == key and w.value not in (tracked.stored, tracked.current)), None)
            if other is not None:
                self.write(other)

    def read_all(self) -> None:
        keys = self.run.keys
        for key in keys if self.model.sdo_answered else keys[:1]:  # in stopped one unanswered read will do
            self.read(key)

    def check(self) -> None:
        self.heartbeat_shows_the_state()
        self.no_pdo_outside_operational()

    def teardown(self) -> None:
        """A TPDO owed to the last step's SYNC would come within the PDO window: wait for it, then judge."""
        if self.quiet_since is not None and self.dut.usable:
            # the TPDO must not come (outside operational): a silence window, not a settle time
            self.dut.frames.quiet_period(lambda m: False, self.dut.pdo_silence_s)
            self.no_pdo_outside_operational()

    # -- after every step ------------------------------------------------------------
    @invariant()
    def heartbeat_shows_the_state(self) -> None:
        """Every heartbeat since the state was confirmed carries its byte; one is waited for only when the
        last is older than the observer's window (no heartbeat owed since)."""
        if not self.model.heartbeat_ms:
            return
        dut = self.dut
        beats = dut.frames.since(self.settled, lambda m: dut.is_heartbeat(m) and bool(m.data) and m.data[0] != 0)
        fresh = dut.frames.since(self.checked, lambda m: dut.is_heartbeat(m) and bool(m.data) and m.data[0] != 0)
        if not beats or (not fresh and time.monotonic() - self.checked.time > self._heartbeat_wait_s()):
            mark = dut.frames.mark()
            self._expect_heartbeat(mark, None, "heartbeat producer running (1017h > 0)")
            beats += dut.frames.since(mark, lambda m: dut.is_heartbeat(m) and bool(m.data) and m.data[0] != 0)
        self.checked = dut.frames.mark()
        wrong = [b for b in beats if b.data[0] != self.model.heartbeat_byte]
        assert not wrong, (
            f"heartbeat reports {wrong[0].data[0]:02X}h ({STATE_NAMES.get(wrong[0].data[0], '?')}), the node is "
            f"{self.model.heartbeat_byte:02X}h ({STATE_NAMES[self.model.heartbeat_byte]}):\n"
            f"{format_frames(wrong[:4])}")

    @invariant()
    def no_pdo_outside_operational(self) -> None:
        if self.quiet_since is None:
            return
        pdos = self.dut.frames.since(self.quiet_since, lambda m: self.dut.is_pdo(m) or self._is_tracked_tpdo(m))
        assert not pdos, (f"{len(pdos)} TPDO(s) in {STATE_NAMES[self.model.heartbeat_byte]}:\n"
                          f"{format_frames(pdos[:5])}")

    def _is_tracked_tpdo(self, msg) -> bool:
        comm = self.found.sync_tpdo
        return comm is not None and self.dut.tpdo.at(comm).frames(can_id_of(self.model.expected((comm, 1))))(msg)


def test_nmt_sequences_follow_the_cia301_model(dut, settings_journal, back_to_preoperational, evidence):
    """Any sequence of NMT commands, SDO reads and writes and SYNCs leaves the device in the state, with the
    values and the traffic CiA 301 gives for it (heartbeat byte, SDO and PDO per state, reloads on reset)."""
    evidence.rests_on("cia", "CiA 301 §7.3.2.2 (state diagram, initialisation reloads, services per state), "
                             "§7.2.8.3.1 (NMT addressing), §7.2.8.3.2.2 (heartbeat state byte)")
    # the model knows no error behaviour: an error the device keeps may hold it out of operational at any step
    raise_if_held_by_error(dut, "the NMT state model")
    found = DeviceValues(dut, evidence)
    run = NmtRun(dut, settings_journal, found, ResetBudget(RESET_BUDGET_S), _other_node(dut))
    evidence.note("followed values: " + (", ".join(f"{t.label} (stored {t.stored})" for t in found.stored.values())
                                         or "none (only the NMT state)"))
    started = time.monotonic()
    tour = NmtMachine(run)
    try:
        for method, *args in TOUR:
            getattr(tour, method)(*args)
            tour.check()
        tour.teardown()
    except AssertionError as exc:
        raise AssertionError(f"{exc}\nthe fixed tour's steps so far:\n" + "\n".join(tour.log)) from None
    evidence.measure("fixed tour", time.monotonic() - started, "s")
    run.budget.left = RESET_BUDGET_S  # the tour's resets are owed in any case; the budget is for the generated ones
    run_state_machine_as_test(lambda: NmtMachine(run), settings=SETTINGS)
    evidence.measure("state-machine run", time.monotonic() - started, "s")
    steps, budget = run.steps, run.budget
    evidence.note(f"fixed tour: {steps[0]} steps; generated: {len(steps) - 1} sequences, {sum(steps[1:])} steps "
                  f"(set-up and steps that sent something); {budget.done} resets in all, the generated ones within "
                  f"a {RESET_BUDGET_S:g} s budget; other node-ID {run.other}")
