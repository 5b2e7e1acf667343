"""``dut.sdo``: the device's SDO server as the tester reaches it: canopen's client for normal access, raw request
frames for byte-exact checks, the protocol client for transfers step by step, and the windows its answers owe."""

from __future__ import annotations

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.link.frames import Mark
from encoder_conformance.dut.sdo.identity import DeviceIdentity, read_identity
from encoder_conformance.dut.sdo.sdo_client import SdoProtocolClient
from encoder_conformance.dut.sdo.sdo_frames import SdoResponse


class SdoFace:
    """SDO access to the device (what the link's methods do, named by the protocol)."""

    def __init__(self, dut: DeviceLink) -> None:
        self._dut = dut

    def read(self, index: int, sub: int = 0) -> bytes:
        """Upload through canopen's client; aborts raise ``SdoAborted``, a time-out AssertionError."""
        return self._dut.read(index, sub)

    def write(self, index: int, sub: int, data: bytes) -> None:
        """Download through canopen's client (the journal's ``write`` puts a test's change back)."""
        self._dut.write(index, sub, data)

    def request(self, request: bytes, timeout: float | None = None) -> SdoResponse | None:
        """One raw request frame; its answer matched by content, or None within ``timeout``."""
        return self._dut.sdo_request(request, timeout=timeout)

    def expect_abort(self, request: bytes) -> SdoResponse:
        """A request that must be refused: its answer (AssertionError where none came)."""
        return self._dut.expect_abort(request)

    def send(self, request: bytes) -> Mark:
        """One raw request frame, not waiting for an answer; a mark before it."""
        return self._dut.send_sdo(request)

    def protocol(self) -> SdoProtocolClient:
        """A client that runs transfers step by step (segmented, block), each frame judged."""
        return SdoProtocolClient(self._dut)

    def identity(self) -> DeviceIdentity:
        """Everything the device says about itself (1000h, 1008h-100Ah, 1018h)."""
        return read_identity(self._dut)

    @property
    def timeout_s(self) -> float:
        """How long an answer the device owes is waited for."""
        return self._dut.sdo_timeout

    @property
    def silence_s(self) -> float:
        """How long to watch for an answer that must not come."""
        return self._dut.sdo_silence_s
