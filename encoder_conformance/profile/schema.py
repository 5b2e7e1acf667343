"""Device profile model: what a device must look like and how it may deviate.

A profile is data (YAML under device_profiles/). It is validated strictly: unknown keys,
wrong types and missing fields are errors (see loader.py for the messages). The model is
immutable once loaded.

This module is over 400 lines because it is the one schema of a profile file: its sections
(identity, bus, capabilities, timing, objects, simulator) are read and changed together.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property
from typing import Annotated, Any, Generic, Literal, overload

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from encoder_conformance.basis import Basis
from encoder_conformance.cia.cia305 import AUTO_BIT_RATE_INDEX, BIT_TIMING_TABLE_0
from encoder_conformance.profile import datatypes
from encoder_conformance.profile.quirk_effects import EffectParams, P
from encoder_conformance.profile.quirks import Quirk, QuirkBase
from encoder_conformance.profile.value_set import ValueSet

SCHEMA_VERSION = 1

Access = Literal["ro", "wo", "rw", "rwr", "rww", "const"]
Persistence = Literal[
    "none",  # read-only, dynamic or constant: nothing to persist
    "volatile",  # lost at reset, cannot be stored
    "store_all",  # kept only after 1010h sub 1 (or the sub named by the group below)
    "store_comm",  # 1010h sub 2
    "store_app",  # 1010h sub 3
    "store_manufacturer",  # 1010h sub 4 (or another manufacturer sub)
    "auto",  # written to non-volatile memory by the device itself on every write
    "manufacturer_store",  # stored by a manufacturer-specific object (see the quirks)
]

_NODEID_EXPR = re.compile(r"^\$NODEID\s*\+\s*(0x[0-9A-Fa-f]+|\d+)$|^(0x[0-9A-Fa-f]+|\d+)\s*\+\s*\$NODEID$")
_ACCESS_ALIASES = {"co": "const", "c": "const", "r": "ro", "w": "wo"}


class StrictModel(BaseModel):
    """Base: unknown keys are errors, values are not silently coerced, instances are frozen."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


def _access(value: Any) -> Any:
    if isinstance(value, str):
        return _ACCESS_ALIASES.get(value.strip().lower(), value.strip().lower())
    return value


@overload
def resolve_node_id_expression(value: int | str, node_id: int) -> int | str: ...
@overload
def resolve_node_id_expression(value: int | str | None, node_id: int) -> int | str | None: ...
def resolve_node_id_expression(value: int | str | None, node_id: int) -> int | str | None:
    """Turn '$NODEID+0x180' into an int for ``node_id``; other values pass through."""
    if isinstance(value, str):
        match = _NODEID_EXPR.match(value.strip())
        if match:
            return int(match.group(1) or match.group(2), 0) + node_id
    return value


def is_node_id_expression(value: object) -> bool:
    """True if ``value`` is a '$NODEID+offset' formula."""
    return isinstance(value, str) and bool(_NODEID_EXPR.match(value.strip()))


def _allowed_text(value: Any) -> Any:
    """``allowed`` must parse as a value set; the error names the text and the bad part."""
    if value is not None:
        ValueSet.parse(value)
    return value


def _check_allowed(entry: EntrySpec, limits: tuple[int, int] | None) -> None:
    """``allowed`` must lie inside the type range and min/max, and hold the default."""
    values = entry.value_set
    if values is None:
        return
    text = entry.allowed
    if limits is None:
        raise ValueError(f"allowed {text!r}: only integer types have allowed values, not {entry.type}")
    low, high = values.minimum, values.maximum
    assert low is not None  # ValueSet.parse never gives an empty set
    assert high is not None
    if low < limits[0] or high > limits[1]:
        raise ValueError(f"allowed {text!r} goes outside {entry.type} ({limits[0]}..{limits[1]})")
    if entry.min is not None and low < entry.min:
        raise ValueError(f"allowed {text!r} holds {low}, below min {entry.min}")
    if entry.max is not None and high > entry.max:
        raise ValueError(f"allowed {text!r} holds {high}, above max {entry.max}")
    if isinstance(entry.default, int) and entry.default not in values:
        raise ValueError(f"default {entry.default} is not in allowed {text!r}")


class EntrySpec(StrictModel):
    """One value in the object dictionary (a VAR, or one sub-index of a RECORD/ARRAY)."""

    name: str
    type: str
    access: Annotated[Access, Field(description="ro, wo, rw, rwr, rww or const (co)")]
    default: int | str | None = Field(
        default=None,
        description="factory default the device must show; '$NODEID+0x180' formulas allowed; "
        "null for dynamic or per-unit values",
    )
    dynamic: bool = Field(default=False, description="value changes at run time (default not checked)")
    per_unit: bool = Field(default=False, description="value differs per unit, e.g. a serial number")
    no_data: bool = Field(
        default=False,
        description="present without data: the device answers an upload with 08000024h (CiA 301 §7.2.4.3.17, "
        "no data available), e.g. an ARRAY element above sub 0's count; no test reads or writes it",
    )
    min: int | None = None
    max: int | None = None
    allowed: str | None = Field(
        default=None,
        description="values the device accepts, e.g. '0..4, 6..9' (integers and inclusive a..b ranges)",
    )
    domain_basis: Basis = Field(
        default="manual",
        description="what says values outside min/max/allowed are refused: 'manual' (the manual states the range), "
        "'cia' (a CiA text does), 'inferred' (our reading, e.g. of a manual that only lists what it supports)",
    )
    pdo_mappable: bool = False
    persisted_by: Persistence = "none"
    manual: str | None = Field(default=None, description="manual section/table the facts come from")
    notes: str | None = None

    _check_access = field_validator("access", mode="before")(_access)

    _check_allowed_text = field_validator("allowed", mode="before")(_allowed_text)

    @field_validator("type")
    @classmethod
    def _known_type(cls, value: str) -> str:
        return datatypes.canonical_name(value)

    @model_validator(mode="after")
    def _consistent(self) -> EntrySpec:
        if self.default is not None and (self.dynamic or self.per_unit):
            raise ValueError("give either a default or dynamic/per_unit: true, not both")
        if self.default is not None and self.no_data:
            raise ValueError("an entry with no_data: true holds no value; give no default")
        limits = datatypes.value_range(self.type)
        if (isinstance(self.default, str) and self.type not in datatypes.STRING_TYPES
                and not is_node_id_expression(self.default)):
            raise ValueError(
                f"default {self.default!r} is a string but type {self.type} is numeric; "
                "write a number or a '$NODEID+0x180' formula"
            )
        if isinstance(self.default, str) and self.type in datatypes.HEX_STRING_TYPES:
            datatypes.parse_hex_bytes(self.default)  # ValueError names the text and the expected form
        if limits and isinstance(self.default, int) and not limits[0] <= self.default <= limits[1]:
            raise ValueError(f"default {self.default} does not fit {self.type} ({limits[0]}..{limits[1]})")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError(f"min {self.min} is greater than max {self.max}")
        _check_allowed(self, limits)
        return self

    @property
    def value_set(self) -> ValueSet | None:
        """``allowed`` parsed, or None when the entry declares none."""
        return None if self.allowed is None else ValueSet.parse(self.allowed)

    @property
    def checks_default(self) -> bool:
        """True when the device's value right after restore-defaults must equal ``default``."""
        return self.default is not None and self.readable

    @property
    def readable(self) -> bool:
        """An upload gives a value (not a write-only entry, nor one present without data)."""
        return self.access != "wo" and not self.no_data

    @property
    def writable(self) -> bool:
        """A download may be tried (an entry present without data is left alone)."""
        return self.access in ("wo", "rw", "rwr", "rww") and not self.no_data


class ObjectSpec(StrictModel):
    """One index: either a plain VAR (type/access given) or a RECORD/ARRAY (subs given)."""

    name: str
    manual: str = Field(description="manual section/table the facts come from")
    kind: Literal["var", "record", "array"] | None = None
    subs: dict[int, EntrySpec] | None = None
    # VAR fields, only when there are no subs
    type: str | None = None
    access: Access | None = None
    default: int | str | None = None
    dynamic: bool = False
    per_unit: bool = False
    no_data: bool = False
    min: int | None = None
    max: int | None = None
    allowed: str | None = None
    domain_basis: Basis = "manual"
    pdo_mappable: bool = False
    persisted_by: Persistence = "none"
    notes: str | None = None

    _check_access = field_validator("access", mode="before")(_access)
    _check_allowed_text = field_validator("allowed", mode="before")(_allowed_text)

    @model_validator(mode="after")
    def _var_or_record(self) -> ObjectSpec:
        if self.subs is None:
            if self.kind not in (None, "var"):
                raise ValueError(f"kind {self.kind!r} needs 'subs'")
            if self.type is None or self.access is None:
                raise ValueError("a VAR object needs 'type' and 'access' (or give 'subs' for a record/array)")
            EntrySpec(**self._var_fields())  # validates the VAR fields as an entry
        else:
            if self.kind == "var":
                raise ValueError("kind 'var' cannot have 'subs'")
            defaults = {name: info.default for name, info in type(self).model_fields.items()}
            given = [
                k for k, v in self._var_fields().items() if k not in ("name", "manual", "notes") and v != defaults[k]
            ]
            if given:
                raise ValueError(f"{', '.join(given)} belong(s) to the sub-indices when 'subs' is given")
            if not self.subs:
                raise ValueError("'subs' is empty")
            for sub in self.subs:
                if not 0 <= sub <= 0xFF:
                    raise ValueError(f"sub-index {sub} is outside 0..255")
        return self

    def _var_fields(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "type": self.type,
            "access": self.access,
            "default": self.default,
            "dynamic": self.dynamic,
            "per_unit": self.per_unit,
            "no_data": self.no_data,
            "min": self.min,
            "max": self.max,
            "allowed": self.allowed,
            "domain_basis": self.domain_basis,
            "pdo_mappable": self.pdo_mappable,
            "persisted_by": self.persisted_by,
            "manual": self.manual,
            "notes": self.notes,
        }

    @property
    def object_kind(self) -> Literal["var", "record", "array"]:
        if self.subs is None:
            return "var"
        return self.kind or "record"

    def entries(self) -> dict[int, EntrySpec]:
        """Sub-index -> entry; a VAR is sub-index 0. Entries inherit the object's manual reference."""
        return dict(self.entry_table)

    @cached_property
    def entry_table(self) -> dict[int, EntrySpec]:
        """``entries()`` made once (the object is frozen; its entries too): a WDGA run asked ~10,000 times, each
        time copying every sub-index's model to inherit the manual (0.2-0.4 s of the run)."""
        if self.subs is None:
            return {0: EntrySpec(**self._var_fields())}
        return {
            sub: entry if entry.manual else entry.model_copy(update={"manual": self.manual})
            for sub, entry in sorted(self.subs.items())
        }


class RevisionRange(StrictModel):
    """Accepted 1018h sub 3 values, inclusive."""

    min: int = 0
    max: int = 0xFFFFFFFF


class SerialFormat(StrictModel):
    """How the manual says the serial number (1018h sub 4) looks, as the decimal text on the label.

    Without it the suite checks only what any device with a serial number shows: neither 0 nor FFFFFFFFh
    (our inference: FFFFFFFFh is what a device without a serial number reads, e.g. SIKO 650Bh).
    """

    pattern: str = Field(description="regular expression the decimal serial number must match in full, e.g. "
                                     "'[0-9]{8}' for eight digits")
    manual: str = Field(description="the manual's section that states the format")

    @field_validator("pattern")
    @classmethod
    def _compiles(cls, value: str) -> str:
        try:
            re.compile(value)
        except re.error as exc:
            raise ValueError(f"not a regular expression: {exc}") from None
        return value

    def matches(self, serial: int) -> bool:
        return re.fullmatch(self.pattern, str(serial)) is not None


class Identity(StrictModel):
    vendor_name: str
    product_name: str
    vendor_id: int | None = Field(description="1018h sub 1; null if the device has no 1018h")
    product_code: int | None = None
    revision: RevisionRange | None = None
    serial_format: SerialFormat | None = Field(
        default=None, description="the serial number's format where the manual states it (default: any value "
        "but 0 and FFFFFFFFh, our inference)")
    device_type: int | None = Field(description="1000h value; null if the manual does not give it")
    device_name: str | None = Field(default=None, description="1008h text, if the manual gives it")
    order_code: str | None = Field(default=None, description="order code (EDS [DeviceInfo] OrderCode)")
    manual: str = Field(description="title, document number and edition of the source manual")


class BusDefaults(StrictModel):
    node_id: int = Field(ge=1, le=127, description="node-id the device has on delivery")
    bitrate: int | Literal["auto"] = Field(description="bit rate on delivery, or 'auto' for detection")
    bitrates: list[int] = Field(description="bit rates the device supports, bit/s")
    node_id_set_by: list[Literal["sdo", "lss", "switches", "fixed", "other"]]
    bitrate_set_by: list[Literal["sdo", "lss", "switches", "fixed", "auto", "other"]]
    bit_timing_table: dict[int, int] | None = Field(
        default=None, description="the device's LSS bit-timing table 0 (index -> bit/s) where its manual gives "
        "one that differs from CiA 305's (default: CiA 305 table 0)")
    manual: str

    def lss_table(self) -> dict[int, int]:
        return self.bit_timing_table or BIT_TIMING_TABLE_0

    def lss_bit_indices(self) -> frozenset[int]:
        """The LSS table-0 indices the device accepts: its bit rates, and 9 where it detects the rate itself."""
        indices = {index for index, rate in self.lss_table().items() if rate in self.bitrates}
        if self.bitrate == "auto" or "auto" in self.bitrate_set_by:
            indices.add(AUTO_BIT_RATE_INDEX)
        return frozenset(indices)


LssService = Literal[
    "switch_global",
    "switch_selective",
    "configure_node_id",
    "configure_bit_timing",
    "activate_bit_timing",
    "store_configuration",
    "inquire_identity",
    "inquire_node_id",
    "identify_remote_slave",
    "identify_non_configured",
    "fastscan",
]


class CamCapability(StrictModel):
    channels: int = Field(ge=1, le=254)
    cams_per_channel: int = Field(ge=1, le=8)


class Capabilities(StrictModel):
    """What the device implements. Tests needing a capability the profile lacks are skipped."""

    cia406: bool = Field(description="implements the CiA 406 encoder object range (6000h...)")
    encoder_class: Literal["C1", "C2", "C3"] | None = None
    encoder: bool = Field(default=True, description="false for devices that are not encoders (drives)")
    multiturn: bool = False
    heartbeat_producer: bool
    heartbeat_consumer_entries: int = 0
    node_guarding: bool = False
    emcy: bool = True
    sync_consumer: bool = True
    sync_producer: bool | Literal["may"] = Field(
        default=False, description="whether the device generates SYNC (1005h bit 30, period 1006h; CiA 301 v4.2.0 "
        "§7.5.2.5): no (false: bit 30 is refused with 06090030h, as a device that cannot generate SYNC must), yes "
        "(true: bit 30 is accepted), or 'may' (a generic class profile: either reading passes)")
    segmented_sdo: bool = True
    block_sdo: bool = False
    store_subindices: list[int] = Field(default_factory=list, description="1010h subs that store")
    restore_subindices: list[int] = Field(default_factory=list, description="1011h subs that restore")
    tpdos: int = Field(ge=0, le=512)
    rpdos: int = Field(default=0, ge=0, le=512)
    tpdo_transmission_types: list[int] = Field(
        default_factory=lambda: [*range(0, 241), 252, 253, 254, 255],
        description="accepted 18xxh sub 2 values",
    )
    tpdo_transmission_types_refusal: Basis = Field(
        default="inferred",
        description="what says the 18xxh sub 2 values outside tpdo_transmission_types are refused: 'manual' where "
        "the manual says so, 'inferred' (default) where it only lists the types it supports",
    )
    pdo_granularity: int | None = Field(
        default=None, ge=0, le=64,
        description="PDO mapping granularity in bits (EDS [DeviceInfo] Granularity; 0: the mapping cannot change)",
    )
    pdo_dummy_mapping: list[Annotated[int, Field(ge=1, le=7)]] = Field(
        default_factory=list,
        description="data-type indices a PDO mapping entry may name as a dummy (CiA 301 §7.4.7.1; EDS [DummyUsage] "
        "DummyNNNN = 1), e.g. [2, 3, 4, 5, 6, 7]; empty: no dummy mapping",
    )
    lss: list[LssService] = Field(default_factory=list)
    scaling: bool = False
    preset: bool = False
    speed: bool = False
    work_area: bool = False
    cam: CamCapability | None = None


class HeartbeatTolerance(StrictModel):
    """Timing tolerance of periodic frames (heartbeat, event-timer TPDOs). CiA 301 gives none: inferred."""

    abs_ms: float = Field(default=2.0, gt=0)
    rel: float = Field(default=0.10, gt=0, lt=1)
    late_frames: float = Field(
        default=0.05, ge=0, lt=0.5,
        description="share of frames that may be further than the tolerance from the fitted schedule (a frame "
        "delayed by bus arbitration or a busy tester), none by more than half a period",
    )

    def allowed_ms(self, period_ms: float) -> float:
        """Per-interval tolerance: max(abs, rel * period)."""
        return max(self.abs_ms, self.rel * period_ms)


class Timing(StrictModel):
    bootup_max_ms: float = Field(gt=0, description="reset/power-on to boot-up message")
    sdo_response_max_ms: float = Field(gt=0)
    pdo_response_max_ms: float = Field(
        default=10, gt=0, description="SYNC or RTR to the TPDO it triggers; CiA 301 gives no bound, so the "
        "default is this suite's inference (a device that is slower widens the windows a silence is checked in)")
    nmt_settle_ms: float = Field(default=100, gt=0, description="NMT command to new state visible")
    store_max_ms: float = Field(default=1000, gt=0)
    emcy_response_max_ms: float = Field(
        default=100, gt=0, description="an error's cause to its EMCY; CiA 301 gives no bound, so the default is this "
        "suite's inference (an expected EMCY is waited for 4 x this, at least 0.3 s; a check that no EMCY comes "
        "watches this plus the tester's part measured at the start of the run: dut/link/windows.py)")
    lss_response_ms: float = Field(
        default=50, gt=0, description="LSS request to the slave's answer; CiA 305 gives no bound, so the default "
        "is this suite's inference (each LSS request nobody should answer waits this long)")
    sdo_transfer_timeout_ms: float = Field(
        default=1000, gt=0, description="the longest the device waits for the client's next frame of an open SDO "
        "transfer (a segment request, the rest of a block download's sub-block) before it ends the transfer by "
        "itself (abort 05040000h) or acknowledges the segments received in order; CiA 301 gives no value, so the "
        "default is this suite's inference (1000 ms: CANopenNode's default SDO server time-out); a test that needs "
        "the device's time-out to pass waits this plus the answer window")
    heartbeat_test_period_ms: int = Field(default=50, ge=1, description="1017h value used by the tests")
    heartbeat_state_period_ms: int = Field(
        default=10, ge=1, description="1017h value where a test watches the heartbeat's state byte, not its timing "
        "(NMT state tests): each state change shows within about one period, so a short one is waited for less; "
        "our choice, not a CiA value (raise it for a device that refuses or cannot keep 10 ms)")
    heartbeat_intervals: int = Field(
        default=50, ge=50, description="intervals measured per periodic check (heartbeat, event timer): at least 50, "
        "so that p95/p99 of the intervals mean something")
    heartbeat_tolerance: HeartbeatTolerance = HeartbeatTolerance()
    manual: str | None = None
    documented: dict[str, str] = Field(
        default_factory=dict, description="timing figure -> the manual's section that gives it (e.g. "
        "sdo_response_max_ms: 'M §5.3.2'): a documented response time is a promise, so a window is never shorter; "
        "a figure not listed is this suite's default or guess, and windows are sized from what the device is "
        "measured to answer in (dut/link/windows.py)")

    @model_validator(mode="after")
    def _documented_figures(self) -> Timing:
        figures = {name for name in type(self).model_fields if name.endswith("_ms")}
        unknown = sorted(set(self.documented) - figures)
        if unknown:
            raise ValueError(f"timing.documented names no timing figure: {', '.join(unknown)} "
                             f"(figures: {', '.join(sorted(figures))})")
        return self


class SimulatorSpec(StrictModel):
    """Values the simulated twin uses where the manual leaves them per unit."""

    serial_number: int = 1
    revision_number: int = 0
    hardware_version: str = ""
    software_version: str = ""
    bootup_delay_ms: float = Field(default=5, ge=0)
    values: dict[str, int | str] = Field(
        default_factory=dict, description="object key ('0x6002' or '0x1018.3') -> value for per-unit entries"
    )


@dataclass(frozen=True)
class FoundQuirk(Generic[P]):
    """A quirk the profile declares for an effect: its id (the deviation a verdict relies on), the quirk as written
    (title, manual section) and its typed params."""

    id: str
    quirk: QuirkBase
    params: P


class DeviceProfile(StrictModel):
    schema_version: Literal[1]
    id: str = Field(pattern=r"^[a-z0-9][a-z0-9._-]*$")
    title: str
    abstract: bool = Field(default=False, description="a base for 'extends:', not a device of its own")
    eds: str | None = Field(default=None, description="EDS file (relative to the profile) to take objects from")
    identity: Identity
    bus: BusDefaults
    capabilities: Capabilities
    timing: Timing
    objects: dict[int, ObjectSpec] = Field(default_factory=dict)
    quirks: dict[str, Quirk] = Field(default_factory=dict)
    simulator: SimulatorSpec = SimulatorSpec()
    sdo_fuzz_never_write: dict[int, str] = Field(
        default_factory=dict,
        description="object index -> why the SDO fuzzer must never send a download to it (beyond 1010h/1011h, "
        "the preset and the node-ID, bit-rate, store and zeroing objects its quirks declare)",
    )
    todo: list[str] = Field(
        default_factory=list,
        description="assumptions not yet confirmed against the manual (e.g. a draft from an EDS); runs with the "
        "profile say 'draft profile: N assumptions unconfirmed'; `profile validate --todo` lists them",
    )

    @model_validator(mode="after")
    def _indices_in_range(self) -> DeviceProfile:
        for index in self.objects:
            if not 0x1000 <= index <= 0xFFFF:
                raise ValueError(f"object index 0x{index:04X} is outside 0x1000..0xFFFF")
        return self

    def entry(self, index: int, sub: int = 0) -> EntrySpec | None:
        """The expected entry at index/sub, or None if the profile does not declare it."""
        obj = self.objects.get(index)
        return None if obj is None else obj.entries().get(sub)

    def quirks_with(self, params: type[P]) -> list[FoundQuirk[P]]:
        """The quirk lookup: every quirk with the effect of the ``params`` model, in the profile's order (most
        effects are declared once; ``writes_preop_only`` may come from several manual sections)."""
        return [FoundQuirk(quirk_id, quirk, quirk.params) for quirk_id, quirk in self.quirks.items()
                if quirk.effect == params.effect]

    def quirk(self, params: type[P]) -> FoundQuirk[P] | None:
        """The quirk with the effect of the ``params`` model (the first where several are), if any."""
        return next(iter(self.quirks_with(params)), None)

    def params_of(self, params: type[P]) -> P | None:
        """Only the typed params of ``quirk(params)``."""
        found = self.quirk(params)
        return None if found is None else found.params

    def has_effect(self, params: type[EffectParams]) -> bool:
        return params.effect in self.effects

    @property
    def effects(self) -> frozenset[str]:
        """The quirk effects this profile declares."""
        return frozenset(q.effect for q in self.quirks.values() if q.effect)

    def iter_entries(self) -> list[tuple[int, int, ObjectSpec, EntrySpec]]:
        """All (index, sub, object, entry) in index order."""
        return [
            (index, sub, obj, entry)
            for index, obj in sorted(self.objects.items())
            for sub, entry in obj.entries().items()
        ]
