"""Read the device's identity (1000h, 1008h, 1018h) and compare it with the profile."""

from __future__ import annotations

from dataclasses import dataclass

from canopen.sdo.exceptions import SdoAbortedError

from encoder_conformance.dut.link.device import DeviceLink
from encoder_conformance.dut.sdo.patient_read import read_patiently
from encoder_conformance.profile.schema import DeviceProfile

#: what a device without a serial number reads (SIKO WV58M manual p.37-38: 650Bh = FFFFFFFFh "not supported")
NO_SERIAL = (0, 0xFFFFFFFF)


@dataclass(frozen=True)
class DeviceIdentity:
    device_type: int | None
    device_name: str | None
    vendor_id: int | None
    product_code: int | None
    revision: int | None
    serial: int | None
    malformed: tuple[str, ...] = ()  # objects whose answer did not have the size of their type
    serial_650b: int | None = None  # CiA 406 650Bh, read where 1018h has no serial number

    @property
    def unit_serial(self) -> int | None:
        """The unit's serial number from 1018h sub 4, else 650Bh (neither 0 nor FFFFFFFFh: "not supported")."""
        if self.serial is not None:
            return self.serial
        return self.serial_650b if self.serial_650b not in (None, *NO_SERIAL) else None

    def as_report(self) -> dict[str, str]:
        def hex_or_dash(value: int | None) -> str:
            return "-" if value is None else f"0x{value:08X}"

        return {
            "vendor-id (1018h.1)": hex_or_dash(self.vendor_id),
            "product code (1018h.2)": hex_or_dash(self.product_code),
            "revision (1018h.3)": hex_or_dash(self.revision),
            "serial number (1018h.4)": "-" if self.serial is None else f"{self.serial} (0x{self.serial:08X})",
            "device type (1000h)": hex_or_dash(self.device_type),
            "device name (1008h)": self.device_name or "-",
            **({"serial number (650Bh)": f"{self.serial_650b} (0x{self.serial_650b:08X})" if self.unit_serial
                else f"- (0x{self.serial_650b:08X}: no serial number)"}
               if self.serial is None and self.serial_650b is not None else {}),
        }


def _optional_u32(dut: DeviceLink, index: int, sub: int, malformed: list[str]) -> int | None:
    try:
        data = read_patiently(dut, index, sub)
    except SdoAbortedError:
        return None
    if len(data) != 4:
        malformed.append(f"{index:04X}h.{sub:02X} ({len(data)} bytes)")
    return int.from_bytes(data, "little")


def text_of(data: bytes) -> str:
    """A VISIBLE_STRING as text: UTF-8 where it decodes as such (some devices hold it), else latin-1."""
    data = data.rstrip(b"\x00")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def read_identity(dut: DeviceLink) -> DeviceIdentity:
    """Everything the device says about itself; absent objects read as None."""
    try:
        name = text_of(read_patiently(dut, 0x1008, 0))
    except SdoAbortedError:
        name = None
    malformed: list[str] = []
    serial = _optional_u32(dut, 0x1018, 4, malformed)
    serial_key = serial_650b_key(dut.profile)
    return DeviceIdentity(
        device_type=_optional_u32(dut, 0x1000, 0, malformed),
        device_name=name,
        vendor_id=_optional_u32(dut, 0x1018, 1, malformed),
        product_code=_optional_u32(dut, 0x1018, 2, malformed),
        revision=_optional_u32(dut, 0x1018, 3, malformed),
        serial=serial,
        malformed=tuple(malformed),
        serial_650b=_optional_u32(dut, *serial_key, malformed) if serial is None and serial_key else None,
    )


def serial_650b_key(profile: DeviceProfile) -> tuple[int, int] | None:
    """Where the profile keeps the CiA 406 serial number 650Bh (sub 1 of a record, or sub 0), if it has one."""
    return next(((0x650B, sub) for sub in (1, 0) if profile.entry(0x650B, sub) is not None), None)


def identity_mismatch(identity: DeviceIdentity, profile: DeviceProfile) -> str | None:
    """A reason to stop the run when the device is plainly another product than the profile's.

    Only a device that differs in vendor-id AND product code (or in device type where the
    profile has no 1018h values) counts: a single wrong field is a conformance failure that
    the identity tests report, not a reason to stop. Answers of the wrong size are such failures
    too (the object dictionary tests report them), not evidence of another product.
    """
    if identity.malformed:
        return None
    expected = profile.identity
    checks = [
        ("vendor-id", expected.vendor_id, identity.vendor_id),
        ("product code", expected.product_code, identity.product_code),
    ]
    declared = [(name, want, got) for name, want, got in checks if want is not None]
    if not declared and expected.device_type is not None:
        declared = [("device type", expected.device_type, identity.device_type)]
    if declared and all(want != got for _, want, got in declared):
        found = ", ".join(f"{name} {'-' if got is None else f'0x{got:08X}'}" for name, _, got in declared)
        wanted = ", ".join(f"{name} 0x{want:08X}" for name, want, _ in declared)
        return (
            f"wrong device for profile {profile.id}: it reports {found} but the profile expects {wanted}. "
            f"Choose the matching --device-profile (encoder-conformance profile list)"
        )
    return None
