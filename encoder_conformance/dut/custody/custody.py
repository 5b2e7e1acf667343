"""A device on a bench belongs to someone: take it into the run's custody and give it back as found.

``take`` is the pre-flight and the snapshot: the node answers at its node-id, it is the profile's
product, every configurable value is read as found, the node is reset, and the values it loads
from its memory are read as stored; the snapshot file is written before the first test.

``give_back`` runs at the end of the run, on Ctrl-C/SIGTERM and after a crash (and later from
``encoder-conformance restore --from``). When the run sent anything that may have changed the
stored configuration, it resets the node, writes back what differs from the stored snapshot,
stores it with the device's own store commands, resets again and checks; then it writes back the
values that were in use when the run began, and checks them. An encoder's preset is no value to
write back: its reference point is given back by presetting (``reference_custody``), the stored one
with the stored values, the one found after the values in use. Every step has a deadline.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.cia.cia301 import COMMAND_FOR_STATE, STATE_NAMES, NmtState
from encoder_conformance.deadline import Deadline
from encoder_conformance.dut.bench.power import BenchPower
from encoder_conformance.dut.bench.reference_point import ReferencePoint
from encoder_conformance.dut.custody.aliased_values import AliasOutcome, AliasRepair, Key, label, no_reset_gives_back
from encoder_conformance.dut.custody.reference_custody import ReferenceCustody
from encoder_conformance.dut.custody.restore_record import Change, RestoreRecord
from encoder_conformance.dut.custody.snapshot import (
    Snapshot,
    SnapshotEntry,
    custody_keys,
    hex_or_none,
    is_stored,
    read_values,
)
from encoder_conformance.dut.custody.write_plan import plan_writes
from encoder_conformance.dut.link.device import DeviceLink, wake_if_silent
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.nmt.commands import reset_and_reach, reset_node_and_wait, send_command
from encoder_conformance.dut.sdo.identity import identity_mismatch, read_identity
from encoder_conformance.dut.sdo.sdo_frames import abort_name
from encoder_conformance.dut.store.boot_memory import errors_after_boot, memory_note
from encoder_conformance.dut.store.persist import CannotPersist, StoreCommand, store_commands_for
from encoder_conformance.dut.store.restart_watch import RestartWatch
from encoder_conformance.dut.store.store_watch import StoreWatch
from encoder_conformance.errors import BusLostError, DutLostError, IdentityMismatch, PreflightError


class Custody:
    """One device's snapshot and restore for one run."""

    def __init__(self, dut: DeviceLink, snapshot_path: Path | None, watch: StoreWatch) -> None:
        self.dut = dut
        self.snapshot_path = snapshot_path
        self.watch = watch
        self.restarts = RestartWatch(dut.node_id)
        dut.frames.add_listener(self.restarts)
        self.snapshot: Snapshot | None = None
        self.record: RestoreRecord | None = None
        self.power: BenchPower | None = None  # the bench's power switch, once a test used it
        self.reference = ReferenceCustody(dut)
        #: put back first what a test changed outside the object dictionary (an LSS node-ID): each step
        #: returns None or what it could not put back
        self.first_steps: list[Callable[[], str | None]] = []

    # -- take --------------------------------------------------------------------------------------
    def take(self, profile_sha256: str, read_stored: bool = True) -> Snapshot:
        """Pre-flight and snapshot; raises PreflightError with what to check.

        ``read_stored=False`` (acceptance) skips the reset that shows what the device stored: a run that
        sends no store command cannot change it, and a reset costs a boot-up (4 s on a POSITAL).
        """
        try:
            return self._take(profile_sha256, read_stored)
        except (AssertionError, DutLostError) as exc:
            if isinstance(exc, BusLostError):
                raise PreflightError(str(exc)) from None
            first = str(exc).splitlines()[0]
            raise PreflightError(
                f"node {self.dut.node_id} does not answer SDO reliably ({first}); a CANopen device must serve "
                "SDO on 600h/580h + node-id. Check --node-id, the bit rate and that no other tool talks to it"
            ) from None

    def _take(self, profile_sha256: str, read_stored: bool) -> Snapshot:
        dut = self.dut
        keys = custody_keys(dut.profile)
        with dut.in_custody():
            before = dut.frames.mark()
            # the first request may only wake the device (automatic bit rate) or be lost while a remote
            # endpoint sets up (python-can-remote drops frames in its first ~20 ms): a short first try
            answered = dut.responds(timeout=dut.sdo_silence_s) or dut.responds()
            snapshot = Snapshot(dut.profile.id, profile_sha256, dut.node_id, {}, answered, None)
            self.snapshot = snapshot
            if answered:
                self._check_identity(snapshot)
                found = read_values(dut, keys)
                snapshot.reference_found = self.reference.read()
                snapshot.entries = [self._entry(k, found[k], None) for k in keys]
                snapshot.found_state = self._state_seen(before)
                self._save()
                if not read_stored:
                    return snapshot
            if not (self.restarts.shows_stored or reset_and_reach(dut)):  # a fresh boot-up shows what is stored
                raise PreflightError(
                    f"no answer from node {dut.node_id}: no SDO answer and no boot-up after NMT reset node. "
                    "Check --node-id, the bit rate, termination, wiring and power"
                )
            if not answered:
                self._check_identity(snapshot)
            stored = read_values(dut, keys)
            snapshot.boot_emcy = errors_after_boot(dut)  # e.g. 5000h: no valid stored data (``boot_memory``)
            snapshot.reference_stored = self.reference.read()
            found_values = {e.key: e.found for e in snapshot.entries}
            snapshot.entries = [self._entry(k, None, stored[k], found_values.get(k)) for k in keys]
            return self._save()

    def _entry(self, key: Key, found: bytes | None, stored: bytes | None,
               found_hex: str | None = None) -> SnapshotEntry:
        entry = self.dut.profile.entry(*key)
        assert entry is not None
        return SnapshotEntry(key[0], key[1], entry.name, entry.persisted_by,
                             found_hex if found is None else found.hex(), hex_or_none(stored))

    def _check_identity(self, snapshot: Snapshot) -> None:
        identity = read_identity(self.dut)
        snapshot.identity = identity.as_report()
        problem = identity_mismatch(identity, self.dut.profile)
        if problem:
            raise IdentityMismatch(problem)

    def _state_seen(self, since: Mark) -> int | None:
        """The NMT state of the last heartbeat the node sent before the run touched it (None: none seen)."""
        beats = self.dut.frames.since(since, self.dut.is_heartbeat)
        states = [b.data[0] for b in beats if b.data and b.data[0] != NmtState.BOOT_UP]
        return states[-1] if states else None

    def _save(self) -> Snapshot:
        assert self.snapshot is not None
        if self.snapshot_path is not None:
            self.snapshot.save(self.snapshot_path)
        return self.snapshot

    def note_lss_node_id(self, node_id: int) -> None:
        """An LSS test is about to give the device ``node_id``: the snapshot file says so before it happens."""
        if self.snapshot is not None and node_id not in self.snapshot.lss_node_ids:
            self.snapshot.lss_node_ids.append(node_id)
            self._save()

    def lss_settled(self) -> None:
        """The LSS put-back brought the device back to its node-ID: nothing left to look for."""
        if self.snapshot is not None and self.snapshot.lss_node_ids:
            self.snapshot.lss_node_ids.clear()
            self._save()

    def stored_changes_since_snapshot(self) -> list[str]:
        """After the tests sent store commands: reset node and list the stored values that now differ."""
        if self.snapshot is None or self.watch.total == 0:
            return []
        keys = [e.key for e in self.snapshot.entries if e.stored is not None]
        reset_node_and_wait(self.dut)
        loaded = read_values(self.dut, keys)
        return [c.describe() for c in self._differences(loaded, lambda e: e.target_stored(), keys)]

    # -- give back ---------------------------------------------------------------------------------
    def give_back(self, seconds: float, check_stored: bool = False) -> RestoreRecord:
        """Put the device back as found within ``seconds``; idempotent (the first call does the work)."""
        if self.record is not None:
            return self.record
        started = time.monotonic()
        deadline = Deadline(seconds, "the restore")
        record = RestoreRecord(None if self.snapshot_path is None else str(self.snapshot_path))
        record.run_store_commands = dict(self.watch.counts)
        self.record = record
        if self.snapshot is None or not self.snapshot.entries:
            record.done = True
            return record
        self.watch.restoring = True
        try:
            with self.dut.in_custody():
                self._give_back(record, deadline, check_stored or self.watch.total > 0, history_unknown=check_stored)
            record.done = True
        except DutLostError as exc:
            record.fail(f"the device could not be reached: {exc}")
        except TimeoutError as exc:
            record.fail(str(exc))
        finally:
            self.watch.restoring = False
            record.restore_store_commands = self.watch.total_by_restore
            record.seconds = round(time.monotonic() - started, 3)
        return record

    def _give_back(self, record: RestoreRecord, deadline: Deadline, check_stored: bool, history_unknown: bool) -> None:
        dut = self.dut
        snapshot = self.snapshot
        assert snapshot is not None
        if dut.lost and not (dut.device_lost and reset_and_reach(dut)):  # a silent device: one NMT reset node
            raise DutLostError(dut.lost)
        mark = dut.frames.mark()  # before the switch is told to switch on: a boot-up during its command counts
        if self.power is not None and self.power.ensure_on():  # Ctrl-C between power off and on
            record.written.append(f"power switched on again ({self.power.description})")
            wake_if_silent(dut)
            if not self.first_steps:  # else they wait for the device where it is (e.g. unconfigured: no boot-up)
                dut.wait_bootup(mark)
        for step in list(self.first_steps):
            problem = step()
            if problem:
                record.fail(problem)
        send_command(dut, "pre-operational")
        if not (dut.responds() or dut.responds()):
            raise DutLostError("no SDO answer after NMT enter pre-operational")
        keys = [e.key for e in snapshot.entries]
        now = read_values(dut, keys)
        record.left_changed = self._differences(now, lambda e: e.target_found())
        if check_stored and self._give_back_stored(record, deadline, now, history_unknown):
            now = read_values(dut, keys)  # a reset or writes since the first read
        if check_stored:  # what it says after the give-back's last boot-up
            record.memory = memory_note(snapshot.boot_emcy, errors_after_boot(dut),
                                        self.watch.total + self.watch.total_by_restore)
        targets = {e.key: v for e in snapshot.entries if (v := e.target_found()) is not None}
        written = self._write(record, deadline, {k: v for k, v in targets.items() if now.get(k) != v}, now)
        self._give_back_reference(record, deadline, snapshot.reference_in_use, record.left_changed)  # scaled units
        # nothing written or preset since ``now`` was read (and it showed no difference): it is still ``now``
        after = read_values(dut, keys) if record.written or record.left_changed else now
        if written and self._repair_aliases(record, deadline, targets, written, after):
            after = read_values(dut, keys)
        for change in self._differences(after, lambda e: e.target_found()):
            record.fail(f"not restored: {change.describe()}")
        self._back_to_found_state(record)

    def _give_back_stored(self, record: RestoreRecord, deadline: Deadline, now: dict[Key, bytes | None],
                          history_unknown: bool) -> bool:
        """Reset, compare with what was stored, write and store what differs, reset and check; True if it
        reset the device or wrote to it (the values in use may then differ from ``now``).

        After a restore-defaults command the device's memory may have lost groups whose values
        equal their defaults (nothing shows it over the bus): then every group is stored again.
        Where the device restarted since the tests last wrote to it (a power cycle), the values in use
        ``now`` are what it stored: no reset and no second read.
        """
        dut = self.dut
        snapshot = self.snapshot
        assert snapshot is not None
        stored = [e for e in snapshot.entries if e.stored is not None and is_stored(dut.profile.entry(*e.key))]
        stored_keys = [e.key for e in stored]
        shows_stored = self.restarts.shows_stored
        self._reset(deadline)
        loaded = {k: now.get(k) for k in stored_keys} if shows_stored else read_values(dut, stored_keys)
        record.stored_changed = self._differences(loaded, lambda e: e.target_stored(), stored_keys)
        defaults_restored = any(kind.startswith("restore defaults") for kind in self.watch.counts)
        reference = self.reference.stored_to_give_back(
            snapshot.reference_stored, self.reference.store_may_have_changed(self.watch.counts, history_unknown))
        if not record.stored_changed and not defaults_restored and reference is None:
            return not shows_stored
        targets = {e.key: e.target_stored() for e in stored}
        differing = {k: v for k, v in targets.items() if v is not None and loaded.get(k) != v}
        written = self._write(record, deadline, differing, loaded)
        aliases = self._alias_order(record, {k: differing[k] for k in written if k in differing}, written,
                                    read_values(dut, sorted(set(written))))
        preset = self._give_back_reference(record, deadline, reference, record.stored_changed)
        try:
            keys = stored_keys if defaults_restored else sorted(differing)
            commands = store_commands_for(dut.profile, keys + (self.reference.store_keys() if preset else []))
        except CannotPersist as exc:
            record.fail(f"cannot store the restored values: {exc}")
            return True  # as below: it may have reset the device and written, so the values in use are read again
        self._store(record, deadline, commands)
        for key in aliases.conflicting:  # each alone with its own command (where two share one, the check says so)
            dut.write(*key, differing[key])
            record.written.append(f"{label(key)} = {differing[key].hex(' ').upper()} and stored alone: "
                                  f"{aliases.describe()}")
            self._store(record, deadline, store_commands_for(dut.profile, [key]))
        self._reset(deadline)
        reloaded = read_values(dut, stored_keys)
        for change in self._differences(reloaded, lambda e: e.target_stored(), stored_keys):
            record.fail(f"stored value not restored: {change.describe()}")
        problem = self.reference.check(reference, "stored") if preset and reference is not None else None
        if problem:
            record.fail(problem)
        return True

    def _give_back_reference(self, record: RestoreRecord, deadline: Deadline, target: ReferencePoint | None,
                             changes: list[Change]) -> bool:
        """Preset to ``target`` where the reference point differs (a Change in ``changes``); True if it preset."""
        if target is None:
            return False
        deadline.check("giving back the reference point")
        outcome = self.reference.give_back(target, settle=not self.restarts.shows_stored)
        if outcome.change:
            changes.append(Change(*outcome.change))
        if outcome.done:
            record.written.append(outcome.done)
        if outcome.problem:
            record.fail(outcome.problem)
        return outcome.done is not None

    def _differences(self, values: dict[Key, bytes | None], target, keys: list[Key] | None = None) -> list[Change]:  # noqa: ANN001
        assert self.snapshot is not None
        wanted = None if keys is None else set(keys)
        changes = []
        for entry in self.snapshot.entries:
            if wanted is not None and entry.key not in wanted:
                continue
            expected = target(entry)
            if expected is not None and values.get(entry.key) != expected:
                changes.append(Change(entry.label, expected.hex(), hex_or_none(values.get(entry.key))))
        return changes

    def _write(self, record: RestoreRecord, deadline: Deadline, targets: dict[Key, bytes],
               current: dict[Key, bytes | None]) -> list[Key]:
        """Carry out the write plan; refused steps are tried once more after the others. The keys written."""
        refused, written = [], []
        for step in plan_writes(self.dut.profile, targets, current):
            deadline.check(f"writing {step.label}")
            try:
                self.dut.write(*step.key, step.value)
                record.written.append(step.label)
                written.append(step.key)
            except SdoAbortedError as exc:
                refused.append((step, exc))
        for step, _ in [r for r in refused if not r[0].temporary]:
            deadline.check(f"writing {step.label}")
            try:
                self.dut.write(*step.key, step.value)
                record.written.append(step.label + " (second attempt)")
                written.append(step.key)
            except SdoAbortedError as exc:
                record.fail(f"{step.label} refused: {abort_name(exc.code)}")
        return written

    def _store(self, record: RestoreRecord, deadline: Deadline, commands: list[StoreCommand]) -> None:
        for command in commands:
            deadline.check(f"storing with {command.label}")
            command.issue(self.dut)
            record.store_commands.append(command.label)

    def _alias_order(self, record: RestoreRecord, targets: dict[Key, bytes], written: list[Key],
                     after: dict[Key, bytes | None]) -> AliasOutcome:
        """Entries a write to another changed (``aliased_values``) written again in an order that works; the outcome
        names those no order gives back."""
        dut = self.dut
        outcome = AliasRepair(partial(read_values, dut), lambda key, value: dut.write(*key, value)).repair(
            targets, after, written)
        record.written += outcome.written
        return outcome

    def _repair_aliases(self, record: RestoreRecord, deadline: Deadline, targets: dict[Key, bytes],
                        written: list[Key], after: dict[Key, bytes | None]) -> bool:
        """Entries a write to another changed (``aliased_values``): written in an order that works, else given back
        by NMT reset node where they were the stored values at the start; True if it wrote (read back again)."""
        dut = self.dut
        outcome = self._alias_order(record, targets, written, after)
        problem = no_reset_gives_back(self.snapshot, outcome) if outcome.conflicting else None
        if problem or not outcome.conflicting:
            if problem:
                record.fail(problem)
            return bool(outcome.written)
        self._reset(deadline)  # CiA 301 §7.2.8.3.2.2: reset node loads the stored values
        record.written.append(f"NMT reset node: {outcome.describe()}, so only a reset gives back "
                              f"{', '.join(label(k) for k in outcome.conflicting)} (their stored values, as found)")
        now = read_values(dut, list(targets))
        self._write(record, deadline, {k: v for k, v in targets.items()
                                       if now.get(k) != v and k not in outcome.conflicting}, now)
        self._give_back_reference(record, deadline, self.snapshot.reference_in_use if self.snapshot else None, [])
        return True

    def _reset(self, deadline: Deadline) -> None:
        """Make the device show what it stored: reset node, unless it restarted since the last write to it."""
        dut = self.dut
        if self.restarts.shows_stored:
            return
        deadline.check("reset node")
        if not reset_and_reach(dut):
            raise DutLostError(f"no boot-up within {dut.profile.timing.bootup_max_ms:.0f} ms after reset node")

    def _back_to_found_state(self, record: RestoreRecord) -> None:
        state = self.snapshot.found_state if self.snapshot else None
        if state is None:
            return
        command = COMMAND_FOR_STATE.get(state)
        if command is not None and command != "pre-operational":
            send_command(self.dut, command)
            record.written.append(f"NMT {command} (found {STATE_NAMES.get(state, '?')})")
