"""EDS export: a profile becomes an EDS through od_builder and canopen's exporter, so other CANopen
tools can drive the simulated twin."""

from __future__ import annotations

import logging
from datetime import datetime
from pathlib import Path

import canopen
from canopen.objectdictionary import ODVariable
from canopen.objectdictionary import eds as canopen_eds

from encoder_conformance.profile.schema import DeviceProfile

logger = logging.getLogger(__name__)


# --------------------------------------------------------------------------- export


def _od_variable(od: canopen.ObjectDictionary, index: int, sub: int) -> ODVariable:
    obj = od[index]
    return obj if isinstance(obj, ODVariable) else obj[sub]


def _only_profile_defaults(profile: DeviceProfile, od: canopen.ObjectDictionary) -> None:
    """An EDS states factory defaults: drop the twin's per-unit/run-time values from DefaultValue."""
    for index, sub, _obj, entry in profile.iter_entries():
        var = _od_variable(od, index, sub)
        if entry.default is None:
            var.default = None
            var.default_raw = None  # type: ignore[attr-defined]  # why: canopen's EDS writer reads it, undeclared
        if isinstance(var.value, str) and var.data_type in (
            canopen.objectdictionary.OCTET_STRING,
            canopen.objectdictionary.DOMAIN,
        ):
            var.value = None  # canopen's DCF writer wants bytes here


def _limits_from_allowed(profile: DeviceProfile, od: canopen.ObjectDictionary) -> None:
    """An EDS has no value list: LowLimit/HighLimit are the ``allowed`` set's bounds where min/max are absent."""
    for index, sub, _obj, entry in profile.iter_entries():
        allowed = entry.value_set
        if not allowed:
            continue
        var = _od_variable(od, index, sub)
        if entry.min is None:
            var.min = allowed.minimum
        if entry.max is None:
            var.max = allowed.maximum


def export_eds(profile: DeviceProfile, path: Path, node_id: int | None = None) -> Path:
    """Write ``profile`` as an EDS (or a DCF with the twin's values if ``path`` ends in .dcf)."""
    from encoder_conformance.profile.od_builder import build_object_dictionary

    path = Path(path)
    od = build_object_dictionary(profile, node_id)
    _only_profile_defaults(profile, od)
    _limits_from_allowed(profile, od)
    info = od.device_information
    info.LSS_supported = bool(profile.capabilities.lss)
    info.order_code = profile.identity.order_code
    info.granularity = profile.capabilities.pdo_granularity
    for dummy in profile.capabilities.pdo_dummy_mapping:  # written as [DummyUsage] DummyNNNN = 1
        var = ODVariable(f"Dummy{dummy:04d}", dummy, 0)
        var.data_type, var.access_type = dummy, "const"
        od.add_object(var)
    revision = profile.identity.revision
    if revision is not None and revision.min == revision.max:
        info.revision_number = revision.min
    od.comments = f"Generated from device profile {profile.id} by encoder_conformance.\n{profile.title}"
    now = datetime.now()
    file_info = {  # a fresh dict: canopen's export_eds mutates its shared default argument
        "FileName": path.name,
        "FileVersion": 1,
        "FileRevision": 0,
        "EDSVersion": "4.0",
        "Description": profile.title,
        "CreationDate": now.strftime("%m-%d-%Y"),
        "CreationTime": now.strftime("%I:%M%p"),
        "CreatedBy": "encoder_conformance",
        "ModificationDate": now.strftime("%m-%d-%Y"),
        "ModificationTime": now.strftime("%I:%M%p"),
        "ModifiedBy": "encoder_conformance",
    }
    # canopen adds its own FileInfo defaults (EdsVersion=4.2) unless the OD carries imported ones
    setattr(od, "__edsFileInfo", dict(file_info))  # read by canopen as od.__edsFileInfo (not mangled)
    dcf = path.suffix.lower() == ".dcf"
    with path.open("w", encoding="utf-8") as fp:
        canopen_eds.export_eds(od, fp, file_info, device_commisioning=dcf)
    return path
