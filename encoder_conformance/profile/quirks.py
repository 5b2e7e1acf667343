"""The quirk effects the simulator and the suites know how to act on.

A profile quirk may name one of these effects (``effect:``) with its parameters
(``params:``). A quirk without an effect is documentation only: it still appears in the
report as a documented deviation. Adding an effect means teaching both the simulator
(encoder_conformance/sim) and the suites about it; list it here with what its params mean.
"""

from __future__ import annotations

EFFECTS: dict[str, str] = {
    "silent_until_bus_traffic": (
        "automatic bit-rate detection: after power-on the device sends nothing (no boot-up) until it "
        "has seen a frame on the bus. params: {}"
    ),
    "cob_ids_follow_node_id_until_store": (
        "PDO and EMCY COB-IDs follow the node-id only until the first store of the communication "
        "parameters; restore defaults re-enables the tracking. params: {}"
    ),
    "writes_preop_only": (
        "writes to the listed objects are refused outside pre-operational. "
        "params: {objects: [index, ...], abort_code: int}"
    ),
    "node_id_object": (
        "node-id is configured through a manufacturer object, effective after reset. "
        "params: {index: int, subindex: int, persistence: auto|store}"
    ),
    "bitrate_object": (
        "bit rate is configured through a manufacturer object (LSS table codes). "
        "params: {index: int, subindex: int, persistence: auto|store}"
    ),
    "error_register_without_generic_bit": (
        "1001h shows a specific error bit without bit 0 (generic) that CiA 301 requires. params: {}"
    ),
    "transmission_type_255_timer_0_disables": (
        "a TPDO with transmission type 255 and event timer 0 is not sent at all. params: {}"
    ),
    "pdo_send_repeat_counters": (
        "manufacturer send-repeat counters (e.g. SIKO 2800h/2801h). params: {tpdo1: {counter: index, "
        "comm: index (optional, default 1800h), ...}: the event-driven TPDO (type 254/255); counter 0 = "
        "sent by its event timer only (timer 0 = not sent, no change-driven sending); n >= 1 with event "
        "timer 0 = each position change sends it n times (the twin: one frame per change poll, 5 ms); "
        "timer > 0 = the timer wins, the counter is ignored; tpdo2: {counter: index, comm: index "
        "(optional, default 1801h), ...}: the SYNC-driven TPDO; counter 0 = every n-th SYNC without "
        "limit; k >= 1 = every n-th SYNC but only k times, the count restarting when the payload differs "
        "from the last one sent and when the TPDOs restart (NMT reset, start, a PDO parameter written); "
        "counter_max: int (larger counter values count as counter_max)}. Other keys are documentation"
    ),
    "bits_forced_at_init": (
        "bits of a (stored) value are forced to 1 at initialisation; the stored value itself is kept. "
        "params: {index: int, subindex: int, forced_bits: int, at: [power_on, nmt_81h, nmt_82h] "
        "(the events; default all three)}"
    ),
    "store_reboots_without_reply": (
        "writing the signature to the store object is not answered by SDO; the device stores its "
        "storable values, reboots (silent) and sends a boot-up after reboot_ms. params: {index: int, "
        "subindex: int, reboot_ms: number, signature_u32: int, wrong_signature_abort: int (the twin's "
        "answer to any other value; default 08000020h, nothing stored, no reboot)}"
    ),
    "writes_need_scaling_bit": (
        "writes to the listed objects are refused unless 6000h bit 2 (scaling) is set. "
        "params: {objects: [index, ...], abort_code: int}"
    ),
    "abort_code": (
        "the device answers a situation with a different abort code than CiA 301 names. "
        "params: {situation: write_ro|read_wo|no_object|no_subindex|length_high|length_low|"
        "value_high|value_low|wrong_state|store_signature, codes: [int, ...]}"
    ),
    "store_object_reads_back": (
        "1010h/1011h subs read back a value other than the CiA capability word. params: {value: int}"
    ),
    "store_automatic": "parameters are stored automatically on every write; 1010h is absent. params: {}",
    "position_frozen_during_execution": (
        "the position value does not update while certain writes are processed (the SDO reply comes "
        "first). params: {objects: [index, ...], duration_ms: number, durations_ms: {'0xIIII': ms, "
        "'0x6000.scaling_bit_set': ms} (optional, per object)}"
    ),
    "second_node": (
        "the device answers on a second node-id as a redundant channel (e.g. WayCon MH); the twin puts "
        "the sibling on the bus. params: {node_id_offset: int, profile: id (optional, the sibling's "
        "profile; default the same)}"
    ),
    "manufacturer_encoder_objects": (
        "the encoder function lives in manufacturer objects instead of 6000h..6004h. params: "
        "{equivalents: {manufacturer index: CiA 406 index}, scaling_bit: int|null (bit of the "
        "operating-parameter object that enables scaling; null = the scaling objects always apply)}"
    ),
    "limit_switch_flags": (
        "limit switches set flag bits in the process value. params: {value_object: index, "
        "enable_object: index, position_mask: int, min: {object, enable_bit, flag_bit}, "
        "max: {object, enable_bit, flag_bit}, applies_to: [tpdo, sdo]}"
    ),
    "fixed_tpdo_mapping": (
        "TPDOs without mapping objects carry a fixed payload. params: {mapping: {comm index: "
        "[[index, sub, bits], ...]}, cyclic: {tpdo, period_object, period_unit_ms} (optional: sent "
        "every period, sub 2 ignored), sync: {tpdo, counter_subindex} (optional: every n-th SYNC, "
        "n = 1..255), polled: {tpdo} (optional: answers an RTR on its COB-ID in operational)}"
    ),
    "guarding_heartbeat_exclusive": (
        "node guarding and the heartbeat producer exclude each other: a producer time > 0 sets the guard "
        "time to 0; a non-zero guard time written while the producer runs is refused. params: "
        "{producer_object: index, guard_time_object: index, guard_time_write_while_producer_abort: int}"
    ),
    "restore_excludes": (
        "1011h restore-all leaves the listed objects as they are (CiA 301: every parameter, including "
        "those the device stores by itself, returns to its default). params: {objects: [index, ...]}"
    ),
    "nmt_autostart_object": (
        "after boot-up the device enters operational by itself when an object holds a given value "
        "(instead of CiA 302-2 1F80h bit semantics). params: {index, subindex, operational_value: int}"
    ),
    "reload_immediate": (
        "1011h sub-indices that make saved values current at once (no reset), and parameter sets saved "
        "by 1010h sub-indices. params: {reload_immediate: {1011h sub: 1010h sub whose saved values it "
        "loads}, app_sets: {saved_by: {1010h sub: set number}, objects: ['0xIIII.S', ...]}, "
        "test_object: '0xIIII.S' (the parameter the suite may change: in every set and saved by every "
        "source sub; omit to skip the test)}"
    ),
    "manufacturer_store_object": (
        "a second 'save' object stores manufacturer parameters that 1010h does not; they take effect "
        "after a reset. params: {index, subindex, signature: int, saves: ['0xIIII', ...], "
        "test_object: '0xIIII.S' (the saved parameter the suite may change; omit to skip the test), "
        "wrong_signature_abort: int (optional)}"
    ),
    "signed_position_range": (
        "position and preset are SIGNED32; multiturn profiles split the measuring range into "
        "-TMR/2 .. TMR/2 - 1, singleturn profiles count 0 .. TMR - 1. params: {objects: [index, ...]}"
    ),
}
