"""``encoder-conformance lss scan | set-node-id | set-bitrate``: CiA 305 LSS on the bench.

``scan`` lists every unconfigured device (node-ID FFh) without changing any; ``set-node-id`` and
``set-bitrate`` select one device by its LSS address (switch state selective), configure it, store
the configuration if asked, and switch every device back to waiting state.
Exit codes: 0 done, 1 the device refused (its CiA 305 error code in words), 4 usage error,
69 (could not test) no device answered or the bus could not be opened.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass

from encoder_conformance.cia.cia301 import HEARTBEAT_BASE
from encoder_conformance.cia.cia305 import ADDRESS_PARTS, BIT_TIMING_TABLE_0, UNCONFIGURED_NODE_ID, LssCommand, LssState
from encoder_conformance.config.bus import BusConfig
from encoder_conformance.dut.link import connection
from encoder_conformance.dut.link.frames import FrameLog, Mark
from encoder_conformance.dut.lss.lss_find import FULL_RANGE, error_text, find_revision, scan_unconfigured
from encoder_conformance.dut.lss.lss_master import LssAddress, LssAnswer, LssMaster
from encoder_conformance.errors import BusSetupError, DutLostError, LssStop
from encoder_conformance.exit_codes import RunExit
from encoder_conformance.profile.schema import DeviceProfile

REFUSED = RunExit.NON_CONFORMANT  # 1: the device answered with an error code
NO_ANSWER = RunExit.COULD_NOT_TEST  # 69: no device answered (or no bus)
BOOT_WAIT_S = 2.0  # an unconfigured device boots with its new node-ID when it leaves configuration state


@dataclass(frozen=True)
class LssOptions:
    bus: BusConfig
    response_s: float
    profile: DeviceProfile | None = None


@dataclass(frozen=True)
class Target:
    """The device to select: its serial number and what else is known of its LSS address."""

    serial: int
    vendor: int | None = None
    product: int | None = None
    revision: int | None = None

    def completed(self, profile: DeviceProfile | None) -> Target:
        """Vendor, product (and a single revision) from the profile where not given."""
        if profile is None:
            return self
        known = _known_from(profile)
        return Target(self.serial, self.vendor if self.vendor is not None else known[0],
                      self.product if self.product is not None else known[1],
                      self.revision if self.revision is not None else known[2])


def _known_from(profile: DeviceProfile) -> tuple[int | None, int | None, int | None, None]:
    identity = profile.identity
    revision = identity.revision
    single = revision.min if revision is not None and revision.min == revision.max else None
    return identity.vendor_id, identity.product_code, single, None


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


@contextmanager
def _session(options: LssOptions) -> Iterator[LssMaster]:
    frames = FrameLog()
    network = connection.connect(options.bus.kwargs, options.bus.describe(), frames)
    try:
        yield LssMaster(lambda cob_id, data: network.send_message(cob_id, data), frames, options.response_s)
    finally:
        connection.disconnect(network)


def _guarded(work: Callable[[], int]) -> int:
    """``work()``; the expected failures (no bus, lost bus, no answer, refusal) as a message and exit code."""
    try:
        return work()
    except LssStop as exc:
        _say(f"lss: {exc}")
        return exc.code
    except (BusSetupError, DutLostError) as exc:
        _say(f"lss: {exc}")
        return NO_ANSWER


# -- scan ----------------------------------------------------------------------------------------
def scan(options: LssOptions, as_json: bool = False) -> int:
    """List every unconfigured device; 69 if none answered."""
    known: tuple[int | None, ...] = (None, None, None, None)
    if options.profile is not None:
        known = _known_from(options.profile)
        named = ", ".join(f"{part} 0x{value:08X}" for part, value in zip(ADDRESS_PARTS, known, strict=True)
                          if value is not None)
        scope = f"scanning only devices with {named}" if named else "it names no vendor-ID or product code"
        if "fastscan" not in options.profile.capabilities.lss:
            scope += "; it declares no LSS fastscan, so its devices may not answer a scan"
        _say(f"profile {options.profile.id}: {scope}")

    def work() -> int:
        with _session(options) as master:
            progress = _Progress()
            result = scan_unconfigured(master, known, progress)
        progress.done(len(result.devices))
        if as_json:
            print(json.dumps({"devices": [asdict(a) for a in result.devices], "count": len(result.devices),
                              "seconds": round(result.seconds, 3), "frames": result.frames,
                              "complete": result.repeated is None and not result.unresolved}))
        else:
            for address in result.devices:
                print(f"{address.describe()} ({address.serial})")
            print(f"{len(result.devices)} unconfigured device(s) in {result.seconds:.2f} s "
                  f"({result.frames} LSS frames)")
        if result.widened_to_s is not None:
            _say(f"lss: answers came later than the response window: the scan waited up to "
                 f"{result.widened_to_s * 1000:.0f} ms per step (--response-ms {options.response_s * 1000:.0f})")
        if result.unresolved:
            _say("lss: unconfigured devices answered that no fastscan could find: their vendor-ID or product code "
                 "differs from --profile's, or their answers came later than --response-ms")
        if result.repeated is not None:
            _say(f"lss: {result.repeated.describe()} answered the scan twice: it does not stay in LSS configuration "
                 "state after fastscan (CiA 305), so the list may be incomplete")
        return RunExit.PASSED if result.devices else NO_ANSWER

    return _guarded(work)


class _Progress:
    """'scanning... found 3' on stderr (one updated line on a terminal)."""

    def __init__(self) -> None:
        self.tty = sys.stderr.isatty()
        _say("scanning...")

    def __call__(self, count: int, address: LssAddress) -> None:
        print(f"\rscanning... found {count}", end="" if self.tty else "\n", file=sys.stderr, flush=True)

    def done(self, count: int) -> None:
        if self.tty and count:
            print(file=sys.stderr)


# -- select and configure ------------------------------------------------------------------------
def _select(master: LssMaster, target: Target, profile: DeviceProfile | None) -> LssAddress:
    """Switch state selective to ``target`` (finding what is missing of its address); LssStop if none answers."""
    if target.vendor is None or target.product is None:
        _say(f"vendor and product not given: scanning the unconfigured devices for serial {target.serial}")
        found = [a for a in scan_unconfigured(master).devices if a.serial == target.serial]
        if not found:
            raise LssStop(f"no unconfigured device with serial {target.serial} (0x{target.serial:08X}) answered "
                          "the scan; a configured device is selected by its whole LSS address: give --vendor and "
                          "--product (or a --profile that names them)", NO_ANSWER)
        address = found[0]
    else:
        revision = target.revision
        if revision is None:
            revisions = profile.identity.revision if profile is not None else None
            span = (revisions.min, revisions.max) if revisions is not None else FULL_RANGE
            _say(f"revision not given: finding it with identify remote slave in 0x{span[0]:08X}..0x{span[1]:08X}")
            revision = find_revision(master, target.vendor, target.product, target.serial, span)
            if revision is None:
                raise LssStop(f"no device answered identify remote slave for vendor 0x{target.vendor:08X}, product "
                              f"0x{target.product:08X}, serial 0x{target.serial:08X}: check the numbers, bit rate "
                              "and power; a device without that service needs --revision", NO_ANSWER)
        address = LssAddress(target.vendor, target.product, revision, target.serial)
    master.switch_global(LssState.WAITING)  # only the selected device may hear the configuration
    if not master.switch_selective(address):
        raise LssStop(f"no device answered switch state selective ({address.describe()}): check the address, "
                      "the bit rate and the power", NO_ANSWER)
    print(f"selected {address.describe()}")
    return address


def _checked(command: int, what: str, answer: LssAnswer | None, after_refusal: str = "") -> None:
    """Print that ``what`` is done; LssStop if the device did not answer or refused it."""
    if answer is None:
        raise LssStop(f"the device did not answer {what} (does it support the service?){after_refusal}", NO_ANSWER)
    if answer.error:
        raise LssStop(f"{what}: {error_text(command, answer)}{after_refusal}", REFUSED)
    print(f"{what}: done")


def _store(master: LssMaster, store: bool, what: str) -> None:
    if store:
        _checked(LssCommand.STORE_CONFIGURATION, "store configuration", master.store_configuration(),
                 f"; the new {what} is configured but not stored")
    else:
        print(f"not stored: the device forgets the new {what} at power-off (--store keeps it)")


def set_node_id(options: LssOptions, target: Target, node_id: int, store: bool) -> int:
    """Configure (and store) the node-ID of the selected device."""
    target = target.completed(options.profile)

    def work() -> int:
        with _session(options) as master:
            _select(master, target, options.profile)
            try:
                before = master.inquire_node_id()
                answer = master.configure_node_id(node_id)
                _checked(LssCommand.CONFIGURE_NODE_ID, f"configure node-ID {node_id}", answer)
                _store(master, store, "node-ID")
            finally:
                mark = master.switch_global(LssState.WAITING)
            print(_activation(master, mark, before, node_id))
        return RunExit.PASSED

    return _guarded(work)


def _activation(master: LssMaster, mark: Mark, before: int | None, node_id: int) -> str:
    """When the new node-ID takes effect: an unconfigured device boots with it on leaving configuration state."""
    if before != UNCONFIGURED_NODE_ID:
        was = f" (it is node {before} until then)" if before is not None else ""
        return (f"node-ID {node_id} becomes active after NMT reset communication{was}, or a power cycle on "
                "legacy devices")
    booted = master.frames.wait_for(lambda m: m.is_rx and m.arbitration_id == HEARTBEAT_BASE + node_id
                                    and bytes(m.data) == b"\x00", BOOT_WAIT_S, mark)
    if booted:
        return f"the device was unconfigured: it booted as node {node_id}"
    return (f"the device was unconfigured and sent no boot-up within {BOOT_WAIT_S:.0f} s: it takes node-ID {node_id} "
            "at NMT reset communication, or a power cycle on legacy devices")


def set_bitrate(options: LssOptions, target: Target, index: int, store: bool, activate_ms: int | None) -> int:
    """Configure (and store, and activate) bit timing ``index`` of CiA 305 table 0 in the selected device."""
    target = target.completed(options.profile)
    rate = BIT_TIMING_TABLE_0[index]

    def work() -> int:
        with _session(options) as master:
            _select(master, target, options.profile)
            activated = False
            try:
                _checked(LssCommand.CONFIGURE_BIT_TIMING, f"configure bit timing {rate} bit/s (table 0 index "
                         f"{index})", master.configure_bit_timing(index))
                _store(master, store, "bit rate")
                if activate_ms is not None:
                    master.activate_bit_timing(activate_ms)
                    activated = True
            finally:
                if not activated:  # after activate bit timing the bus changes rate: nothing more at this one
                    master.switch_global(LssState.WAITING)
            if not activated:
                print(f"{rate} bit/s becomes active with activate bit timing (--activate DELAY_MS) or, stored, "
                      "after a power cycle")
            else:
                print(f"activate bit timing sent: the device runs at {rate} bit/s after {activate_ms} ms and is "
                      f"still in LSS configuration state; reopen the adapter at {rate} bit/s (--can-bitrate "
                      f"{rate}): any lss command then switches it back to waiting state")
        return RunExit.PASSED

    return _guarded(work)
