"""``encoder-conformance store``: the store commands a factory sends, each confirmed, and what was done said.

The commands are those the run's own restore uses (``dut/store/persist.py``): 1010h sub 1 'save' where the profile
declares it (it covers every group), else the sub-index of each group the profile's entries are stored by, and
a manufacturer's store object (a store that reboots is confirmed by its boot-up).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.config.bus import BusConfig
from encoder_conformance.dut import DeviceUnderTest
from encoder_conformance.dut.link import connection
from encoder_conformance.dut.link.device import wake_if_silent
from encoder_conformance.dut.sdo.identity import identity_mismatch, read_identity
from encoder_conformance.dut.sdo.sdo_frames import abort_name
from encoder_conformance.dut.store.persist import CannotPersist, StoreCommand, store_commands_for
from encoder_conformance.errors import BusSetupError, DutLostError, UsageError
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.profile.schema import DeviceProfile

STORED_BY_COMMAND = ("store_all", "store_comm", "store_app", "store_manufacturer", "manufacturer_store")


@dataclass(frozen=True)
class StoreRequest:
    profile: DeviceProfile
    bus: BusConfig
    node_id: int


def factory_commands(profile: DeviceProfile) -> list[StoreCommand]:
    """The commands that store every entry the profile says is kept by a store command; UsageError if none."""
    keys = []
    for index, sub, _name, entry in profile.iter_entries():
        if entry.persisted_by in STORED_BY_COMMAND:
            try:
                store_commands_for(profile, [(index, sub)])
            except CannotPersist:
                continue  # a group without a sub-index the profile declares: nothing to send for it
            keys.append((index, sub))
    commands = store_commands_for(profile, keys)
    if not commands:
        raise UsageError(f"--profile {profile.id}: declares no store command (capabilities.store_subindices, a "
                         "store quirk) for any entry: nothing to send")
    return commands


def store_parameters(request: StoreRequest) -> int:
    """Connect, check the node is the profile's product, send each store command; the exit code (RunExit)."""
    commands = factory_commands(request.profile)
    try:
        with connection.connected(request.bus.kwargs, request.bus.describe()) as (network, frames):
            dut = DeviceUnderTest(network, frames, request.profile, request.node_id)
            problem = _not_the_device(dut)
            if problem:
                return _fail(problem, RunExit.COULD_NOT_TEST)
            store_s = request.profile.timing.store_max_ms / 1000
            dut.node.sdo.RESPONSE_TIMEOUT = max(dut.sdo_timeout, store_s)  # a store may take its documented time
            return _send(dut, commands)
    except BusSetupError as exc:
        return _fail(str(exc), RunExit.COULD_NOT_TEST)


def _not_the_device(dut: DeviceUnderTest) -> str | None:
    """None if the node answers and reports the profile's product; else why the store is not sent."""
    wake_if_silent(dut)
    if not (dut.responds() or dut.responds()):
        return (f"no answer from node {dut.node_id} to an SDO read of 1000h: check --node-id, the bus, the bit rate "
                "and that the device is on")
    try:
        return identity_mismatch(read_identity(dut), dut.profile)
    except (AssertionError, DutLostError) as exc:
        return f"node {dut.node_id} stopped answering while its identity was read: {exc}"


def _send(dut: DeviceUnderTest, commands: list[StoreCommand]) -> int:
    for command in commands:
        started = time.monotonic()
        try:
            command.issue(dut)
        except SdoAbortedError as exc:
            return _fail(f"node {dut.node_id} refused {command.label}: abort {exc.code:08X}h "
                         f"({abort_name(exc.code)}); nothing more sent", RunExit.NON_CONFORMANT)
        except AssertionError as exc:
            lost = dut.device_lost
            return _fail(f"{command.label} to node {dut.node_id}: {str(exc).splitlines()[0]}",
                         RunExit.COULD_NOT_TEST if lost or not command.reboots else RunExit.NON_CONFORMANT)
        how = "boot-up after the store" if command.reboots else "confirmed by the device's SDO answer"
        print(f"stored: {command.label} to node {dut.node_id}, {how} in {(time.monotonic() - started) * 1000:.0f} ms")
    print(f"node {dut.node_id} keeps what it held ({dut.profile.id}): {len(commands)} store command(s) confirmed")
    return RunExit.PASSED


def _fail(text: str, code: int) -> int:
    print(f"store: {text}", file=sys.stderr)
    return code
