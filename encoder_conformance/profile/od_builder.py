"""Build a canopen ObjectDictionary from a profile (the simulator's data model, EDS export)."""

from __future__ import annotations

import canopen
from canopen.objectdictionary import ODArray, ODRecord, ODVariable

from encoder_conformance.profile import datatypes
from encoder_conformance.profile.schema import DeviceProfile, EntrySpec, ObjectSpec, resolve_node_id_expression

_ACCESS_TO_EDS = {"const": "const", "ro": "ro", "wo": "wo", "rw": "rw", "rwr": "rwr", "rww": "rww"}


def initial_value(profile: DeviceProfile, index: int, sub: int, entry: EntrySpec, node_id: int) -> int | str:
    """The value a factory-fresh twin holds: the default, or the simulator's per-unit value."""
    sim = profile.simulator
    per_unit: dict[tuple[int, int], int | str] = {
        (0x1018, 3): sim.revision_number,
        (0x1018, 4): sim.serial_number,
        (0x650B, 0): sim.serial_number,  # CiA 406 serial number: the same as 1018h sub 4
        (0x1009, 0): sim.hardware_version,
        (0x100A, 0): sim.software_version,
    }
    for key in (f"0x{index:04X}.{sub}", f"0x{index:04X}" if sub == 0 else None):
        if key is not None:
            for given, given_value in sim.values.items():
                if given.lower() == key.lower():
                    return given_value
    if (index, sub) in per_unit and entry.default is None:
        return per_unit[(index, sub)]
    value = resolve_node_id_expression(entry.default, node_id)
    if value is None:  # no default given: the lowest valid value, so the twin never holds an invalid one
        if entry.type in datatypes.STRING_TYPES:
            return ""
        return entry.min if entry.min is not None and entry.min > 0 else 0
    return value


def _variable(
    profile: DeviceProfile, name: str, index: int, sub: int, entry: EntrySpec, node_id: int
) -> ODVariable:
    var = ODVariable(name, index, sub)
    var.data_type = datatypes.type_code(entry.type)
    var.access_type = _ACCESS_TO_EDS[entry.access]
    var.pdo_mappable = entry.pdo_mappable
    var.min = entry.min
    var.max = entry.max
    value = initial_value(profile, index, sub, entry, node_id)
    if isinstance(entry.default, str) and entry.type not in datatypes.STRING_TYPES:
        var.default_raw = entry.default  # type: ignore[attr-defined]  # why: canopen's EDS writer reads it, undeclared
    elif entry.default is not None:
        var.default_raw = str(entry.default)  # type: ignore[attr-defined]  # why: as above
    var.default = value  # type: ignore[assignment]  # why: canopen says int, yet its own EDS reader stores str too
    var.value = value  # type: ignore[assignment]  # why: as for default
    var.description = entry.manual or ""
    return var


def _add_object(
    od: canopen.ObjectDictionary, profile: DeviceProfile, index: int, obj: ObjectSpec, node_id: int
) -> None:
    if obj.object_kind == "var":
        od.add_object(_variable(profile, obj.name, index, 0, obj.entries()[0], node_id))
        return
    container = ODArray(obj.name, index) if obj.object_kind == "array" else ODRecord(obj.name, index)
    for sub, entry in obj.entries().items():
        container.add_member(_variable(profile, entry.name, index, sub, entry, node_id))
    od.add_object(container)


def build_object_dictionary(profile: DeviceProfile, node_id: int | None = None) -> canopen.ObjectDictionary:
    """A canopen ObjectDictionary holding the profile's objects with their twin values."""
    node = node_id if node_id is not None else profile.bus.node_id
    od = canopen.ObjectDictionary()
    od.node_id = node
    if isinstance(profile.bus.bitrate, int):
        od.bitrate = profile.bus.bitrate
    for index, obj in sorted(profile.objects.items()):
        _add_object(od, profile, index, obj, node)
    info = od.device_information
    info.vendor_name = profile.identity.vendor_name
    info.vendor_number = profile.identity.vendor_id
    info.product_name = profile.identity.product_name
    info.product_number = profile.identity.product_code
    info.nr_of_TXPDO = profile.capabilities.tpdos  # type: ignore[assignment]  # why: a count; canopen says bool
    info.nr_of_RXPDO = profile.capabilities.rpdos  # type: ignore[assignment]  # why: as above
    info.simple_boot_up_slave = True
    info.allowed_baudrates = set(profile.bus.bitrates)
    return od
