"""The quirk effects the simulator and the suites act on: one typed parameter model per effect.

A profile quirk may name an effect (``effect:``) with its parameters (``params:``); the model of
that effect validates them (an unknown or misspelled key is an error naming file, line and key).
A quirk without an effect is documentation only: it still appears in the report as a documented
deviation. Keys a manual documents but no code acts on are declared as documentation fields
(``documentation only`` in their description), so that a typo is still caught.

Adding an effect: write its model here (the docstring says what the device does, each field
what it means, its ``effect`` name: defining it registers it in EFFECT_MODELS), then teach the simulator and the
suites.
This module is over 400 lines because it is the catalogue of the effects (44), one small model
each: split, a reader would have to look in several places for one table.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field

from encoder_conformance.cia.cia301 import SAVE_SIGNATURE, SdoAbortCode
from encoder_conformance.profile.object_key import ObjectIndex, ObjectKey, ObjectKeyField

Situation = Literal["write_ro", "read_wo", "no_object", "no_subindex", "length_high", "length_low",
                    "value_high", "value_low", "wrong_state", "store_signature"]
InitEvent = Literal["power_on", "nmt_81h", "nmt_82h"]
Documentation = Any  # a key a manual documents that no code acts on
P = TypeVar("P", bound="EffectParams")  # a params model, for typed lookups (``profile.params_of``)


def _all_init_events() -> list[InitEvent]:
    return ["power_on", "nmt_81h", "nmt_82h"]


def _tpdo_and_sdo() -> list[Literal["tpdo", "sdo"]]:
    return ["tpdo", "sdo"]


def _doc(what: str) -> Any:
    return Field(default=None, description=f"documentation only: {what}")


#: effect name -> its params model; every model that names an ``effect`` registers itself when it is defined
EFFECT_MODELS: dict[str, type[EffectParams]] = {}


class EffectParams(BaseModel):
    """Base of the parameter models: strict keys, immutable. A subclass that sets ``effect`` is an effect's model
    (registered in EFFECT_MODELS); one that does not is a shared base (NoParams, ObjectList, ObjectAt)."""

    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True)
    effect: ClassVar[str]

    @classmethod
    def __pydantic_init_subclass__(cls, **kwargs: Any) -> None:
        super().__pydantic_init_subclass__(**kwargs)
        if "effect" in vars(cls):
            if cls.effect in EFFECT_MODELS:
                raise TypeError(f"effect {cls.effect!r} has two models: {EFFECT_MODELS[cls.effect].__name__} "
                                f"and {cls.__name__}")
            EFFECT_MODELS[cls.effect] = cls


class NoParams(EffectParams):
    """An effect without parameters."""


class SilentUntilBusTraffic(NoParams):
    """Automatic bit-rate detection: after power-on the device sends nothing (no boot-up) until it
    has seen a frame on the bus."""

    effect = "silent_until_bus_traffic"


class CobIdsFollowNodeIdUntilStore(NoParams):
    """PDO and EMCY COB-IDs follow the node-id only until the first store of the communication
    parameters; restore defaults re-enables the tracking."""

    effect = "cob_ids_follow_node_id_until_store"


class ErrorRegisterWithoutGenericBit(NoParams):
    """1001h shows a specific error bit without bit 0 (generic) that CiA 301 requires."""

    effect = "error_register_without_generic_bit"


class ErrorAtStartUpDocumented(EffectParams):
    """The manual documents an error the device reports at every start-up as normal (e.g. until a first
    configuration): goods-in does not fail the device for these EMCY codes."""

    effect = "error_at_start_up_documented"
    codes: list[int] = Field(min_length=1, description="the EMCY error codes the manual documents at start-up")


class TransmissionType255Timer0Disables(NoParams):
    """A TPDO with transmission type 255 and event timer 0 is not sent at all."""

    effect = "transmission_type_255_timer_0_disables"


class BlockTransferUnconfirmed(NoParams):
    """The manual mentions SDO block transfer without protocol detail (or against CiA 301) and the profile
    does not declare it (``block_sdo: false``): a block initiate may be served as CiA 301 describes or
    refused with 05040001h; either is recorded, neither fails."""

    effect = "block_transfer_unconfirmed"


class StoreAutomatic(NoParams):
    """Parameters are stored automatically on every write; 1010h is absent."""

    effect = "store_automatic"


class ObjectList(EffectParams):
    """An effect that applies to a list of objects."""

    objects: list[ObjectIndex] = Field(default_factory=list, description="the object indices it applies to")

    @property
    def indices(self) -> frozenset[int]:
        return frozenset(self.objects)


class WritesPreopOnly(ObjectList):
    """Writes to the listed objects (every sub-index) or entries (one sub-index each) are refused outside
    pre-operational. A profile may have several such quirks (different manual sections, different codes)."""

    effect = "writes_preop_only"
    entries: list[ObjectKeyField] = Field(default_factory=list, description="single entries, e.g. '0x1800.2'")
    abort_code: int | None = Field(default=None, description="the abort sent (default: CiA's wrong-state code)")

    def covers(self, index: int, sub: int) -> bool:
        """The quirk applies to a write of ``index``/``sub``."""
        return index in self.indices or ObjectKey(index, sub) in self.entries


class WritesNeedScalingBit(ObjectList):
    """Writes to the listed objects are refused unless 6000h bit 2 (scaling) is set."""

    effect = "writes_need_scaling_bit"
    abort_code: int | None = Field(default=None, description="the abort sent (default: CiA's wrong-state code)")


class RestoreExcludes(ObjectList):
    """1011h restore-all leaves the listed objects as they are (CiA 301: every parameter, including
    those the device stores by itself, returns to its default)."""

    effect = "restore_excludes"


class SignedPositionRange(ObjectList):
    """Position and preset are SIGNED32; multiturn profiles split the measuring range into
    -TMR/2 .. TMR/2 - 1, singleturn profiles count 0 .. TMR - 1."""

    effect = "signed_position_range"
    type: Documentation = _doc("the data type the manual gives")


class ObjectAt(EffectParams):
    """An effect on one object entry."""

    index: ObjectIndex = Field(description="object index")
    subindex: int = Field(default=0, description="sub-index")

    @property
    def key(self) -> ObjectKey:
        return ObjectKey(self.index, self.subindex)


class NodeIdObject(ObjectAt):
    """Node-id is configured through a manufacturer object, effective after reset."""

    effect = "node_id_object"
    persistence: Literal["auto", "store"] = Field(default="auto", description="stored by itself, or by a store command")
    store_subindex: Documentation = _doc("the 1010h sub-index that stores it")
    store_index: Documentation = _doc("the store object that stores it")
    store_signature: Documentation = _doc("the signature of that store object")


class BitrateObject(ObjectAt):
    """Bit rate is configured through a manufacturer object (LSS table codes)."""

    effect = "bitrate_object"
    persistence: Literal["auto", "store"] = Field(default="auto", description="stored by itself, or by a store command")
    store_subindex: Documentation = _doc("the 1010h sub-index that stores it")
    autobaud_code: Documentation = _doc("the table code meaning automatic bit-rate detection")


class BitsForcedAtInit(ObjectAt):
    """Bits of a (stored) value are forced to 1 at initialisation; the stored value itself is kept."""

    effect = "bits_forced_at_init"
    forced_bits: int = Field(description="the bits set at each listed event")
    at: list[InitEvent] = Field(default_factory=_all_init_events,
                                description="the initialisation events (default all three)")


class StoreRebootsWithoutReply(ObjectAt):
    """Writing the signature to the store object is not answered by SDO; the device stores its
    storable values, reboots (silent) and sends a boot-up after reboot_ms."""

    effect = "store_reboots_without_reply"
    reboot_ms: float | None = Field(default=None, description="reboot time (default: the profile's boot-up delay)")
    signature_u32: int = Field(default=SAVE_SIGNATURE, description="the signature as U32 (little-endian on the bus)")
    signature: list[int] | None = Field(default=None, description="the signature's bytes as the manual prints them")
    wrong_signature_abort: int | None = Field(
        default=None, description="the twin's answer to any other value (default 08000020h; nothing stored, no reboot)")
    state_after: Documentation = _doc("the NMT state after the reboot")
    wrong_signature: Documentation = _doc("what the manual says about other values")

    @property
    def signature_bytes(self) -> bytes:
        return bytes(self.signature) if self.signature else self.signature_u32.to_bytes(4, "little")


class NmtAutostartObject(ObjectAt):
    """After boot-up the device enters operational by itself when an object holds a given value
    (instead of CiA 302-2 1F80h bit semantics)."""

    effect = "nmt_autostart_object"
    operational_value: int = Field(description="the value that means 'enter operational by itself'")
    allowed: Documentation = _doc("the values the object accepts")
    values: Documentation = _doc("what each value means")
    store_index: Documentation = _doc("the store object that keeps it")


class ManufacturerStoreObject(ObjectAt):
    """A second 'save' object stores manufacturer parameters that 1010h does not; they take effect
    after a reset."""

    effect = "manufacturer_store_object"
    signature: int = Field(default=SAVE_SIGNATURE, description="the signature as U32")
    saves: list[ObjectKeyField] = Field(default_factory=list, description="the parameters it saves")
    test_object: ObjectKeyField | None = Field(
        default=None, description="the saved parameter the suite may change (omit to skip the test)")
    wrong_signature_abort: int | None = Field(default=None, description="the abort for another value")
    subindex_documented: Documentation = _doc("whether the manual gives the sub-index")
    effective: Documentation = _doc("when the saved values take effect")
    restored_by: Documentation = _doc("what restores them")

    @property
    def signature_bytes(self) -> bytes:
        return self.signature.to_bytes(4, "little")


class AbortCode(EffectParams):
    """The device answers a situation with a different abort code than CiA 301 names."""

    effect = "abort_code"
    situation: Situation = Field(description="the situation whose CiA 301 code the device replaces")
    codes: list[int] = Field(min_length=1, description="the codes the device sends (the twin sends the first)")


class StoreObjectReadsBack(EffectParams):
    """1010h/1011h subs read back a value other than the CiA capability word."""

    effect = "store_object_reads_back"
    value: int = Field(default=0, description="the value read back")


class PositionFrozenDuringExecution(ObjectList):
    """The position value does not update while certain writes are processed (the SDO reply comes first)."""

    effect = "position_frozen_during_execution"
    duration_ms: float = Field(default=0, description="the freeze after a write to a listed object")
    durations_ms: dict[str, float] = Field(
        default_factory=dict, description="per object ('0xIIII', or '0x6000.scaling_bit_set'), overriding duration_ms")


class SecondNode(EffectParams):
    """The device answers on a second node-id as a redundant channel (e.g. WayCon MH); the twin puts
    the sibling on the bus."""

    effect = "second_node"
    node_id_offset: int = Field(default=1, description="the sibling's node-id minus this node's")
    profile: str | None = Field(default=None, description="the sibling's profile (default: the same)")


class ManufacturerEncoderObjects(EffectParams):
    """The encoder function lives in manufacturer objects instead of 6000h..6004h."""

    effect = "manufacturer_encoder_objects"
    equivalents: dict[ObjectIndex, ObjectIndex] = Field(
        default_factory=dict, description="manufacturer index -> the CiA 406 index it stands for")
    scaling_bit: int | None = Field(
        default=2, description="bit of the operating-parameter object that enables scaling (null: always scaled)")


class LimitSwitch(BaseModel):
    """One limit switch of ``limit_switch_flags``."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    object: ObjectIndex = Field(description="the object holding the limit")
    enable_bit: int = Field(description="bit of the enable object that switches it on")
    flag_bit: int = Field(description="bit of the process value it sets")
    condition: Documentation = _doc("the comparison as the manual words it")


class LimitSwitchFlags(EffectParams):
    """Limit switches set flag bits in the process value."""

    effect = "limit_switch_flags"
    value_object: ObjectIndex = Field(description="the object carrying the process value")
    enable_object: ObjectIndex = Field(description="the object whose bits enable the switches")
    position_mask: int = Field(default=0xFFFFFFFF, description="the bits of the value that hold the position")
    min: LimitSwitch | None = Field(default=None, description="flag while the position is below the limit")
    max: LimitSwitch | None = Field(default=None, description="flag while the position is above the limit")
    applies_to: list[Literal["tpdo", "sdo"]] = Field(default_factory=_tpdo_and_sdo,
                                                    description="where the flags show")
    status_bits_zero_mask: Documentation = _doc("bits the manual says read 0")
    sdo_read_of_value_object: Documentation = _doc("what an SDO read shows, as far as the manual says")


class CyclicTpdo(BaseModel):
    """A fixed-layout TPDO sent every period."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    tpdo: ObjectIndex = Field(description="its communication object")
    period_object: ObjectIndex = Field(description="the object holding the period")
    period_unit_ms: float = Field(default=1, description="the period object's unit")


class SyncTpdo(BaseModel):
    """A fixed-layout TPDO sent on every n-th SYNC."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    tpdo: ObjectIndex = Field(description="its communication object")
    counter_subindex: int = Field(default=2, description="the sub-index holding n (1..255)")


class PolledTpdo(BaseModel):
    """A fixed-layout TPDO that answers an RTR on its COB-ID in operational."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    tpdo: ObjectIndex = Field(description="its communication object")
    rtr_dlc: Documentation = _doc("the DLC of the remote frame")
    states: Documentation = _doc("the NMT states it answers in")


class FixedTpdoMapping(EffectParams):
    """TPDOs without mapping objects carry a fixed payload."""

    effect = "fixed_tpdo_mapping"
    mapping: dict[ObjectIndex, list[tuple[ObjectIndex, int, int]]] = Field(
        default_factory=dict, description="communication index -> [[index, sub, bits], ...]")
    cyclic: CyclicTpdo | list[CyclicTpdo] | None = Field(default=None, description="sent every period (sub 2 ignored)")
    sync: SyncTpdo | list[SyncTpdo] | None = Field(default=None, description="sent on every n-th SYNC")
    polled: PolledTpdo | list[PolledTpdo] | None = Field(default=None, description="answers an RTR")
    payload: Documentation = _doc("the payload as the manual describes it")

    @staticmethod
    def _listed(value: Any) -> list[Any]:
        return [] if value is None else value if isinstance(value, list) else [value]

    @property
    def cyclic_tpdos(self) -> list[CyclicTpdo]:
        return self._listed(self.cyclic)

    @property
    def sync_tpdos(self) -> list[SyncTpdo]:
        return self._listed(self.sync)

    @property
    def polled_tpdos(self) -> list[PolledTpdo]:
        return self._listed(self.polled)


class GuardingHeartbeatExclusive(EffectParams):
    """Node guarding and the heartbeat producer exclude each other: a producer time > 0 sets the guard
    time to 0; a non-zero guard time written while the producer runs is refused."""

    effect = "guarding_heartbeat_exclusive"
    producer_object: ObjectIndex = Field(default=0x1017, description="the heartbeat producer time object")
    guard_time_object: ObjectIndex = Field(default=0x100C, description="the guard time object")
    guard_time_write_while_producer_abort: int = Field(
        default=SdoAbortCode.CANNOT_STORE, description="the abort for a guard time written while the producer runs")
    life_time_factor_object: Documentation = _doc("the life time factor object")
    on_producer_enabled: Documentation = _doc("what happens when the producer starts")


class RepeatCounter(BaseModel):
    """One send-repeat counter of ``pdo_send_repeat_counters``."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    counter: ObjectIndex = Field(description="the counter object")
    comm: ObjectIndex | None = Field(default=None, description="the TPDO's communication object (default per TPDO)")
    trigger: Documentation = _doc("what triggers a send")
    sends_per_change: Documentation = _doc("how many frames a change sends")
    requires_event_timer_zero: Documentation = _doc("whether the event timer must be 0")
    limits: Documentation = _doc("what the counter limits")
    restart_on: Documentation = _doc("what restarts the count")


class PdoSendRepeatCounters(EffectParams):
    """Manufacturer send-repeat counters (e.g. SIKO 2800h/2801h). tpdo1, the event-driven TPDO (type
    254/255): counter 0 = sent by its event timer only (timer 0 = not sent, no change-driven
    sending); n >= 1 with event timer 0 = each position change sends it n times (the twin: one frame
    per change poll, 5 ms); timer > 0 = the timer wins, the counter is ignored. tpdo2, the
    SYNC-driven TPDO: counter 0 = every n-th SYNC without limit; k >= 1 = every n-th SYNC but only k
    times, the count restarting when the payload differs from the last one sent and when the TPDOs
    restart (NMT reset, start, a PDO parameter written)."""

    effect = "pdo_send_repeat_counters"
    tpdo1: RepeatCounter | None = Field(default=None, description="the event-driven TPDO's counter (comm: 1800h)")
    tpdo2: RepeatCounter | None = Field(default=None, description="the SYNC-driven TPDO's counter (comm: 1801h)")
    counter_max: int = Field(default=255, description="larger counter values count as counter_max")

    @property
    def per_change(self) -> dict[int, int]:
        """comm index -> counter object: sends per position change."""
        return {} if self.tpdo1 is None else {self.tpdo1.comm or 0x1800: self.tpdo1.counter}

    @property
    def sync_limit(self) -> dict[int, int]:
        """comm index -> counter object: SYNC-driven sends in all."""
        return {} if self.tpdo2 is None else {self.tpdo2.comm or 0x1801: self.tpdo2.counter}


class AppSets(BaseModel):
    """Parameter sets saved by 1010h sub-indices."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    saved_by: dict[int, int] = Field(default_factory=dict, description="1010h sub -> set number")
    objects: list[ObjectKeyField] = Field(default_factory=list, description="the objects of every set")


class ReloadImmediate(EffectParams):
    """1011h sub-indices that make saved values current at once (no reset), and parameter sets saved
    by 1010h sub-indices."""

    effect = "reload_immediate"
    reload_immediate: dict[int, int] = Field(
        default_factory=dict, description="1011h sub -> the 1010h sub whose saved values it loads")
    app_sets: AppSets = Field(default_factory=AppSets, description="parameter sets saved by 1010h sub-indices")
    test_object: ObjectKeyField | None = Field(
        default=None, description="the parameter the suite may change: in every set and saved by every source sub")
    store: Documentation = _doc("what each 1010h sub stores")
    restore_after_reset: Documentation = _doc("the 1011h subs that act after a reset")
    read_value: Documentation = _doc("what the subs read back")



NmtStateName = Literal["pre-operational", "operational", "stopped"]


class LssOnlyInStates(EffectParams):
    """LSS (CiA 305) answers only in the listed NMT states (its frames are ignored in the others), and a
    node-ID configured by LSS becomes active as ``activation`` says."""

    effect = "lss_only_in_states"
    states: list[NmtStateName] = Field(description="the NMT states in which LSS frames are obeyed")
    activation: Literal["reset_communication", "power_cycle"] = Field(
        default="reset_communication",
        description="when a configured node-ID becomes active: NMT reset communication (CiA 305 v3) or only at "
        "the next power-on, from what was stored (legacy)")


class LssConfigAutoStored(EffectParams):
    """The device stores a node-ID / bit timing configured by LSS by itself (no store configuration
    service needed): it survives a power cycle."""

    effect = "lss_config_auto_stored"
    auto_stored: list[Literal["node_id", "bit_timing"]] = Field(description="what is stored at once")
    lss_cob_ids: Documentation = _doc("the LSS COB-IDs the manual gives")


class UnconfiguredNodeId(EffectParams):
    """Node-ID 255 marks the node as unconfigured: after power-on it sends no boot-up and only LSS
    answers, until LSS gives it a valid node-ID; then NMT initialisation continues with that ID."""

    effect = "unconfigured_node_id"
    unconfigured_node_id: Literal[255] = Field(default=255, description="the node-ID that means unconfigured")
    bootup_after_valid_node_id: bool = Field(
        default=False, description="true: boots as soon as a valid node-ID is configured; false (CiA 305): when "
        "switched back to the waiting state")
    cob_ids_reset_to_default: list[ObjectKeyField] = Field(
        default_factory=list, description="COB-IDs set to their node-ID based defaults when it gets a valid ID")
    cob_ids_persist_by: Documentation = _doc("the store object that keeps those COB-IDs")


class LssNodeIdRange(EffectParams):
    """The manual gives a configure node-ID range other than CiA 305's 1..127 (and FFh): the suite
    does not judge the values the two disagree on."""

    effect = "lss_node_id_range"
    node_id_range: tuple[int, int] = Field(description="lowest and highest node-ID the manual allows")


class CamLowBelowHigh(EffectParams):
    """A CAM low limit (6310h..6317h) is accepted only below the same cam's high limit (6320h..6327h)
    as it stands when the low limit is written, so the high limit must be written first; a low limit
    at or above it is refused. A window whose low limit lies above its high limit cannot be set."""

    effect = "cam_low_below_high"
    abort_code: int = Field(default=SdoAbortCode.MAX_BELOW_MIN,
                            description="the abort sent for a low limit at or above the high limit")
    low: Documentation = _doc("the low-limit objects")
    high: Documentation = _doc("the high-limit objects")


class SpeedScalingObject(EffectParams):
    """The speed value (6030h) is increments per second multiplied by a manufacturer factor
    ``scaling_object`` sub 1 / sub 2 (default 1/1)."""

    effect = "speed_scaling_object"
    index: ObjectIndex = Field(default=0x6030, description="the speed object")
    scaling_object: ObjectIndex = Field(description="the object whose sub 1 / sub 2 multiply the speed")


class OffsetIsZeroingPoint(EffectParams):
    """The offset value (6509h) is the device's own zeroing point (the encoder value at which the
    position reads the preset, in its own units), not CiA 406's preset minus position: the suites do
    not judge it against the preset, and the run gives the reference point back by the position."""

    effect = "offset_is_zeroing_point"
    formula: Documentation = _doc("the manual's formula for the offset value")


class PhysicalRevolutions(EffectParams):
    """The sensor distinguishes more revolutions than 6502h shows: the position arithmetic (and the
    twin) uses ``revolutions`` as the physical range, so that every total measuring range the
    device allows divides it."""

    effect = "physical_revolutions"
    revolutions: int = Field(gt=0, description="revolutions the sensor distinguishes")
    shown: Documentation = _doc("what 6502h reads instead")


class ModuleMaxIsRange(EffectParams):
    """650Ah sub 3 reads the number of position values (the measuring range), one more than the largest
    position value CiA 406 names there; it follows the range all the same."""

    effect = "module_max_is_range"
    index: Documentation = _doc("the module identification object")
    subindex: Documentation = _doc("the max position sub-index")
    printed: Documentation = _doc("the value the manual prints")
    likely: Documentation = _doc("the value CiA 406's meaning would give")


class ZeroingObject(ObjectAt):
    """Writing ``trigger_value`` to a manufacturer object sets the position to 0 (like a preset of 0); a
    further zeroing works only after ``rearm_value`` was written (edge-triggered)."""

    effect = "zeroing_object"
    trigger_value: int = Field(default=1, description="the value that zeroes the position")
    rearm_value: int = Field(default=0, description="the value that arms the next zeroing")
    duration_ms: float = Field(default=0, ge=0, description="execution time after the write (position frozen)")


class MappingLengthDiffers(EffectParams):
    """A default PDO mapping entry gives another length than the mapped object's size (CiA 301: the length of
    the object), e.g. a 64-bit object mapped with 32 bits."""

    effect = "mapping_length_differs"
    entry: ObjectKeyField = Field(description="the mapping entry, e.g. '0x1A02.1'")
    mapping: int = Field(description="the mapping value the manual gives (index | sub-index | length)")
    object_bits: Documentation = _doc("the object's size in bits")
    mapped_bits: Documentation = _doc("the length the mapping gives")


class MappingChangeWhileValid(EffectParams):
    """The mapping is changed with the PDO valid: sub 0 = 0 alone unlocks the entries (the manual's procedure
    never sets COB-ID bit 31, CiA 301 §7.5.2.38 step 1), so mapping writes are accepted while the PDO is valid."""

    effect = "mapping_change_while_valid"
    procedure: Documentation = _doc("the manual's procedure, in its own words")



class ErrorHistoryKeepsFirst(EffectParams):
    """1003h keeps the first errors signalled (a manual's wording, e.g. WDGA T 6.1): a new error is entered after
    the older ones, none once the list is full. CiA 301 enters it at sub 1 (newest first): the suites accept either
    order where a profile has this effect, and the twin plays the manual's."""

    effect = "error_history_keeps_first"
    index: Documentation = _doc("the error history object")
    entries: Documentation = _doc("the number of entries the manual gives")


class EmcyInStopped(NoParams):
    """The manual lists EMCY as available in Stopped (CiA 301 §7.3.2.2: not in Stopped); the suites record an
    EMCY in Stopped instead of failing the device, and the twin sends it."""

    effect = "emcy_in_stopped"


class HeartbeatConsumerEmcy(EffectParams):
    """A heartbeat-consumer time-out (1016h) sends this EMCY, as the manual documents (CiA 301 names 8130h
    'life guard error or heartbeat error' but requires no EMCY)."""

    effect = "heartbeat_consumer_emcy"
    code: int = Field(ge=0, le=0xFFFF, description="the EMCY error code the time-out sends")


class SyncCobIdAnyCanId(EffectParams):
    """1005h accepts any CAN-ID of min..max as the manual prints it, restricted ones included (CiA 301 §7.3.5
    refuses those): the suites record the answer to a restricted CAN-ID instead of judging it."""

    effect = "sync_cob_id_any_can_id"
    index: Documentation = _doc("the SYNC COB-ID object")
    min: int = Field(ge=0, le=0x7FF, description="the lowest CAN-ID the manual allows")
    max: int = Field(ge=0, le=0x7FF, description="the highest CAN-ID the manual allows")

class CyclicTimerRelationUnstated(EffectParams):
    """The manual lists a cyclic timer (CiA 406 6200h) beside TPDO1's event timer (1800h sub 5) with other
    defaults and does not say how they relate: two values, or one (a write to either sets both). The suites
    accept either; the twin plays two values, its variant one."""

    effect = "cyclic_timer_relation_unstated"
    cyclic_timer: ObjectKeyField = Field(description="the cyclic timer entry (ms)")
    event_timer: ObjectKeyField = Field(description="the TPDO event timer entry (ms)")
