"""The catalogue of the simulator's named faults: what each breaks and which suites it is made for.

Each fault is one deliberate deviation from CiA 301 (or from the profile), committed by the simulator to prove that
each conformance test can fail. This module is data only, so that the plugin and the command line can list and check
faults without importing the simulator's engine; the faults themselves are small classes next to the behaviour they
break (``sim/engine/faults.py`` wires them). tests/test_fault_matrix.py runs the suites against every fault and shows
which tests catch it; each fault names the suite modules it is made for, so that the matrix can run it against those
alone.
It is over 400 lines because it is one table: a line or two per fault, grouped by area.
"""

from __future__ import annotations

from collections.abc import Iterable

from encoder_conformance.open_points import variant_modules, variants
from encoder_conformance.sim.hold_faults import HOLD_FAULTS

#: (the suite modules a group of faults is made for, the group). The CI fault matrix runs each
#: fault against its own modules only; ``encoder-conformance fault-matrix`` can run the full product.
FAULT_GROUPS: list[tuple[tuple[str, ...], dict[str, str]]] = [
    (  # identity
        ("test_identity",),
        {
            "wrong_vendor_id": "1018h sub 1 reads a vendor-id one higher than the profile's",
            "wrong_device_type": "1000h reads the profile's value with the profile number changed",
            "wrong_device_name": "1008h reads a different manufacturer device name",
            "wrong_product_code": "1018h sub 2 reads a product code one higher than the profile's",
            "wrong_revision": "1018h sub 3 reads 0xFFFFFFFF (a revision no manual covers)",
            "wrong_identity_size": "1018h sub 0 reads one more than the highest sub-index",
            "serial_mismatch": "1018h sub 4 differs from the serial number in 650Bh",
            "serial_unset": "1018h sub 4 reads FFFFFFFFh, what a unit without a serial number reads",
        },
    ),
    (  # object dictionary / SDO
        ("test_object_dictionary", "test_sdo_fuzz", "test_value_domain"),
        {
            "missing_object": "the last declared object of the profile does not exist (aborts 06020000h)",
            "wrong_default": "every writable UNSIGNED value starts one higher than its factory default",
            "tpdo_mappings_empty": "every TPDO mapping is empty after each reload (sub 0 = 0): no default mapping "
                                   "(test_factory_default; the TPDO tests are not testable)",
            "wrong_size": "expedited uploads of 32-bit objects carry 2 bytes",
            "write_ro_accepted": "writes to ro/const objects are confirmed (and ignored)",
            "wrong_abort_write_ro": "writes to ro/const objects abort with 08000000h instead of 06010002h",
            "read_wo_allowed": "reads of wo objects return 0 instead of aborting 06010001h",
            "wrong_abort_no_object": "access to a missing object aborts 06090011h instead of 06020000h",
            "wrong_abort_no_subindex": "access to a missing sub-index aborts 06020000h instead of 06090011h",
            "write_rw_ignored": "writes to rw objects are confirmed but the value does not change",
            "no_sdo_response": "SDO requests are never answered (the device looks dead)",
            "ignore_unknown_command": "SDO requests with a reserved or block command specifier get no answer",
            "abort_without_multiplexer": "SDO abort frames carry index 0000h sub 00 instead of the request's",
            "value_domain_ignored": "writes outside an entry's declared min/max/allowed values are accepted",
            "reserved_transmission_types_accepted": "18xxh sub 2 accepts the transmission types CiA 301 reserves "
                                                    "(241..251)",
        },
    ),
    (  # SDO protocol, byte-exact: expedited sizes, segmented and block transfer (CiA 301 §7.2.4.3)
        ("test_sdo_protocol", "test_sdo_block"),
        {
            "size_mismatch_accepted": "writes with more or fewer bytes than the data type are confirmed",
            "toggle_bit_ignored": "segments with a toggle bit that does not alternate are served",
            "segmented_upload_truncated": "the last segment of a segmented upload lacks its last byte",
            "long_reads_refused": "every read of an entry over 4 bytes is refused (08000000h)",
            "segment_size_ignored": "a download segment's n bits are ignored: all 7 bytes are taken as data",
            "client_abort_ignored": "an abort from the client leaves the transfer open: the next segment continues it",
            "open_transfer_blocks_requests": "while a segmented transfer is open, initiate requests go unanswered",
            "download_response_wrong_mux": "download confirmations (60h) carry the next sub-index",
            "expedited_upload_padded": "expedited uploads of 1- and 2-byte entries carry 4 bytes (the size bits say 4)",
            "unsized_download_takes_four_bytes": "an expedited download without size indicator is taken as 4 bytes "
                                                 "(refused for smaller objects)",
            "block_initiate_unanswered": "a device without block transfer does not answer a block initiate",
            "block_crc_wrong": "block transfer CRCs start from FFFFh (upload end frame wrong, right download CRC "
                               "refused)",
            "block_crc_unchecked": "a block download with a wrong CRC is written",
            "block_seqno_unchecked": "block download segments are taken whatever their sequence number",
            "block_upload_truncated": "the end of a block upload says one more unused byte: the data comes one short",
            "block_end_size_ignored": "the n of end block download is ignored: the padding is taken as data",
            "block_size_unchecked": "a block upload with block size 0 or over 127 is served",
            "last_segment_confirmed_then_aborted": "a segmented download's last segment is confirmed before the write "
                                                   "is checked: a refused one draws the confirmation, then the abort",
        },
    ),
    (  # SDO, late answers: test_sdo_block's block transfers would end the late-frame window (its rule)
        ("test_sdo_protocol",),
        {
            "confirmed_late_after_abort": "a refused segmented download's last segment draws its abort and, 330 ms "
                                          "later, a confirmation (after the tester's silence window: caught by "
                                          "late-frame attribution)",
        },
    ),
    (  # SDO fuzzing: what only odd request sequences show
        ("test_sdo_fuzz",),
        {
            "dead_after_short_frame": "after an SDO frame shorter than 8 bytes the SDO server never answers again",
            "double_abort": "every SDO abort frame is sent twice",
            "answers_short_frame_with_garbage": "an SDO frame under 8 bytes is answered with its bytes padded to 8",
            "answers_client_abort": "a client's abort transfer request is answered (with the same frame)",
            "crashes_on_interleaved_initiate": "a 2nd initiate in a segmented transfer stops SDO until a reset",
            "emcy_on_unknown_command": "an abort for an unknown SDO command specifier also sends an EMCY (8100h)",
            "silent_after_reserved_command": "after an SDO request with ccs 7 (reserved): no SDO answer, no heartbeat",
            "sdo_reply_wrong_mux": "SDO initiate responses and aborts name the next sub-index (start-up check fails)",
        },
    ),
    (  # NMT
        ("test_nmt", "test_nmt_state_machine"),
        {
            "no_bootup_after_reset": "no boot-up message after reset node / reset communication",
            "ignore_start": "NMT start remote node is ignored",
            "ignore_stop": "NMT stop remote node is ignored",
            "ignore_enter_preop": "NMT enter pre-operational is ignored",
            "ignore_broadcast": "NMT commands to node 0 (all nodes) are ignored",
            "reset_comm_keeps_state": "NMT reset communication is ignored",
            "reset_node_keeps_values": "NMT reset node does not reload the application parameters",
            "sdo_in_stopped": "SDO requests are answered in stopped",
            "sdo_late_in_stopped": "an SDO request in stopped is answered 330 ms later (after the tester's silence "
                                   "window on every shipped profile: caught by late-frame attribution)",
            "pdo_outside_operational": "TPDOs are also sent in pre-operational and stopped",
            "wrong_heartbeat_state": "the heartbeat reports operational (05h) while pre-operational",
            "respond_to_other_node": "NMT commands addressed to another node-id are obeyed",
            "autostart_ignored": "the device stays pre-operational although its autostart object says start",
            "heartbeat_state_stale": "the heartbeat keeps the state byte of its (re)start (boot-up or 1017h write) "
                                     "after NMT state changes",
            "reset_comm_keeps_comm_values": "NMT reset communication boots again but reloads nothing (1000h-1FFFh keep "
                                            "their unstored changes)",
            "reset_comm_reloads_application": "NMT reset communication also reloads the application area (as reset "
                                              "node does)",
            "preop_reloads_communication": "entering pre-operational from operational or stopped reloads "
                                           "1000h-1FFFh (a plain state change loses unstored changes)",
            "tpdo_not_resumed_after_stopped": "after NMT stop the TPDOs stay silent in operational until the next "
                                              "reset",
            "self_starts_after_reset": "after every boot-up (power-on, reset node, reset communication) the node "
                                       "enters operational by itself (no autostart object says so)",
        },
    ),
    (  # PDO
        ("test_pdo", "test_pdo_repeat"),
        {
            "sync_tpdo_every_sync": "a TPDO with transmission type n (1..240) is sent on every SYNC, not every n-th",
            "sync_tpdo_off_by_one": "a TPDO with transmission type n (1..240) is sent on every (n+1)-th SYNC",
            "type_255_timer_0_sends": "type 255 with event timer 0 sends on change (quirk says it disables the TPDO)",
            "event_timer_outside_operational": "TPDO event timers keep firing after the device left operational "
                                               "(SYNC-driven TPDOs stop)",
            "send_repeat_counter_ignored": (
                "quirk pdo_send_repeat_counters ignored: the change-driven TPDO goes out once per change whatever "
                "its counter (e.g. SIKO 2800h), the SYNC-driven one on every n-th SYNC without the limit (2801h)"
            ),
            "forced_bits_not_applied": (
                "quirk bits_forced_at_init ignored: the value (e.g. SIKO 1801h sub 1) keeps its stored bits at init"
            ),
        },
    ),
    (  # PDO communication parameters: COB-ID bits, transmission types, SYNC counter, gating
        ("test_pdo_comm",),
        {
            "cob_id_valid_bit_ignored": "a TPDO whose COB-ID has bit 31 set (not valid) is sent all the same",
            "cob_id_change_while_valid_accepted": "a TPDO COB-ID write that changes bits 0-29 while the PDO is valid "
                                                  "is accepted",
            "restricted_cob_id_accepted": "a valid PDO COB-ID with a restricted CAN-ID (CiA 301 §7.3.5) is accepted",
            "rtr_ignored": "a remote frame on a TPDO that answers RTR (type 252/253, polled layout) is not answered",
            "rtr_bit_30_ignored": "every valid TPDO answers a remote frame on its COB-ID, also with bit 30 set (no "
                                  "RTR) or a type that is not RTR-driven",
            "type_0_sends_every_sync": "a TPDO of transmission type 0 is sent on every SYNC, changed or not",
            "change_of_state_ignored": "an event-driven TPDO (254/255) is not sent when its mapped value changes "
                                       "(only its event timer sends it)",
            "sync_start_value_ignored": "18xxh sub 6 (SYNC start value) is ignored: SYNC TPDOs count from the "
                                        "first SYNC whatever its counter",
            "sync_counter_overflow_unchecked": "1019h accepts the reserved values 1 and 241..255",
            "tpdo_on_sync_outside_operational": "after leaving operational (to pre-operational or stopped) the "
                                                "SYNC-driven TPDOs (and RTR answers) go on; event timers and the "
                                                "change check stop",
            "change_tpdo_outside_operational": "after leaving operational event-driven TPDOs are still sent on a "
                                               "change of their mapped value; SYNC TPDOs and timers stop",
            "tpdo_late_after_leaving_operational": "each TPDO sent in operational is sent once more 40 ms after "
                                                   "leaving it (after the heartbeat shows the new state: caught by "
                                                   "late-frame attribution)",
            "preop_only_writes_accepted": "quirk writes_preop_only ignored: the listed objects are writable in "
                                          "operational too",
        },
    ),
    (  # PDO timing: SYNC-to-TPDO latency, inhibit time
        ("test_pdo_timing",),
        {
            "event_timer_slow_20pct": "TPDO event timers run 20 % slower than 18xxh sub 5 says",
            "inhibit_ignored": "a change-driven TPDO (254/255) goes out at once inside its inhibit time (18xxh sub 3)",
            "inhibit_drops_events": "a change inside a TPDO's inhibit time is dropped instead of sent when the time "
                                    "is over",
            "sync_tpdo_late": "SYNC-driven TPDOs go out 3 x the profile's pdo_response_max_ms after their SYNC",
        },
    ),
    (  # heartbeat
        ("test_heartbeat", "test_error_control"),
        {
            "guarding_heartbeat_coexist": (
                "a heartbeat producer leaves the guard time alone, and guard times are accepted meanwhile"
            ),
            "heartbeat_slow_20pct": "the heartbeat period is 20 % longer than 1017h says",
            "heartbeat_jitter": "every 4th heartbeat comes 30 % of the period late",
            "heartbeat_ignores_zero": "writing 0 to 1017h does not stop the heartbeat",
            "heartbeat_wrong_dlc": "heartbeat frames carry 2 data bytes",
        },
    ),
    (  # store / restore
        ("test_store_restore", "test_manufacturer_store"),
        {
            "store_not_persisted": "1010h 'save' is confirmed, automatic storing claimed, but nothing is kept",
            "store_wrong_signature_accepted": "1010h/1011h accept any signature",
            "restore_ineffective": "1011h 'load' is confirmed but stored values survive the next reset",
            "reload_not_immediate": "1011h reload sub-indices (quirk reload_immediate) act only after a reset",
            "manufacturer_store_not_persisted": (
                "the manufacturer store object (quirk manufacturer_store_object) saves nothing"
            ),
            "store_reboot_confirmed": "the store-by-reboot command (quirk store_reboots_without_reply) is answered",
        },
    ),
    (  # LSS (CiA 305)
        ("test_lss",),
        {
            "lss_configure_not_answered": "configure node-ID is carried out but never answered",
            "lss_inquire_late_in_waiting": "inquire node-ID in the waiting state is answered late, just before the "
                                           "master's next LSS frame (after the tester's window: caught by late-frame "
                                           "attribution)",
            "lss_node_id_range_unchecked": "configure node-ID accepts 0 and 128..254 (error 0)",
            "lss_bit_timing_unchecked": "configure bit timing accepts any table and index (error 0)",
            "lss_bit_timing_refused": "configure bit timing refuses every index (error 1)",
            "lss_only_in_stopped": "LSS frames are obeyed only in NMT stopped",
            "lss_ignored_in_stopped": "LSS frames are ignored in NMT stopped",
            "lss_activate_ignored": "activate bit timing does nothing: no silence, no switch to the configured rate",
            "lss_configuration_in_waiting": "configure, store and inquire are answered in the waiting state too",
            "lss_selective_ignores_serial": "switch state selective matches whatever serial number it is given",
            "lss_inquire_wrong_serial": "inquire serial number answers the serial number plus one",
            "lss_identify_answered_when_configured": "identify non-configured remote slave is answered by a "
                                                     "configured node",
            "lss_identify_ignores_ranges": "identify remote slave is answered whatever the revision and serial "
                                           "ranges",
            "lss_fastscan_ignores_checked_bit": "fastscan steps compare one bit too few (the checked bit is ignored)",
            "lss_fastscan_completes_early": "fastscan enters the configuration state whenever LSSNext < LSSSub, "
                                            "before the serial number was checked (CANopenNode PR#647)",
            "lss_fastscan_reset_ignored": "fastscan BitChecked 80h is answered but does not restart a scan",
            "lss_node_id_active_immediately": "a node-ID configured by LSS is active at once, not after NMT reset "
                                              "communication",
            "lss_store_not_persisted": "store configuration answers success and keeps nothing",
            "lss_unconfigured_boots": "a node with node-ID 255 (unconfigured) boots and answers SDO at 7FFh/67Fh",
            "lss_obeyed_in_any_state": "LSS frames are obeyed in every NMT state (quirk lss_only_in_states ignored)",
            "lss_auto_store_ignored": "a node-ID configured by LSS is not stored by itself (quirk "
                                      "lss_config_auto_stored ignored)",
        },
    ),
    (  # emcy
        ("test_emcy",),
        {
            "emcy_wrong_cob_id": "EMCY frames are sent on 080h + node-id + 1",
            "emcy_valid_bit_ignored": "EMCYs are sent while 1014h bit 31 (not valid) is set",
            "emcy_without_generic_bit": "1001h and the EMCY's byte 2 show the specific error bit without bit 0 "
                                        "(generic)",
            "emcy_inhibit_ignored": "the EMCY inhibit time 1015h is ignored: EMCYs follow each other at once",
            "sync_length_error_silent": "a SYNC of the wrong length for 1019h records no error and sends no EMCY",
            "emcy_only_first": "after its first EMCY the device sends no other (1001h and 1003h still record "
                               "the errors)",
            "emcy_no_error_reset": "no EMCY 0000h (error reset) when the cause of the errors goes away",
            "emcy_in_stopped": "EMCYs are sent in stopped too",
            "sync_length_unchecked": "a SYNC whose length does not match 1019h is taken without the EMCY 8240h",
            "heartbeat_consumer_timeout_silent": "a heartbeat-consumer time-out (1016h) sends no EMCY",
        },
    ),
    (  # error history 1003h
        ("test_emcy_history",),
        {
            "error_history_not_recorded": "errors are not entered in 1003h (its count stays)",
            "error_history_oldest_first": "1003h enters a new error after the older ones (the newest at the "
                                          "highest sub-index)",
            "error_history_count_unlimited": "1003h sub 0 counts on past the number of entries the list has",
            "error_history_not_cleared": "writing 0 to 1003h sub 0 is confirmed but the history stays",
            "error_history_any_value_accepted": "1003h sub 0 accepts any value (each clears the history)",
        },
    ),
    (  # SYNC consumer objects (1005h)
        ("test_sync_objects",),
        {
            "sync_generate_bit_accepted": "1005h accepts bit 30 (generate SYNC) although the device cannot "
                                          "produce SYNC",
            "sync_restricted_can_id_accepted": "1005h accepts restricted CAN-IDs",
            "sync_cob_id_ignored": "SYNC is taken on 080h whatever 1005h says",
            "sync_producer_never_stops": "a SYNC producer keeps sending SYNC after 1006h is set back to 0",
            "sync_late_after_stop": "1006h = 0 stops the SYNC, but one more comes 330 ms later (after the tester's "
                                    "window: caught by late-frame attribution)",
        },
    ),
    (  # the generated sequences against the reference model (and the preset checks)
        ("test_encoder_position", "test_encoder_properties"),
        {
            "preset_ignored": "a preset (6003h) write is confirmed but the position does not move",
        },
    ),
    (  # encoder function: position, preset, scaling, code sequence, speed (CiA 406)
        ("test_encoder_position",),
        {
            "preset_wrong_sign": "the preset offset is computed as unshifted position - preset instead of "
                                 "preset - unshifted position",
            "wrap_wrong_value": "the position wraps at the total measuring range minus 1 (never shows the last "
                                "value)",
            "direction_ignored": "the code sequence bit (6000h bit 0) is ignored: the position counts up clockwise",
            "scaling_ignored": "the scaling bit, 6001h and 6002h are ignored: the position is the physical counts",
            "offset_not_shown": "6509h keeps 0 after a preset (the position still moves to the preset)",
            "module_identification_stale": "650Ah sub 2/3 (min/max position) keep their factory values after the "
                                           "measuring range changed",
            "limit_switch_flags_ignored": "the process value carries no limit-switch flag bits (quirk "
                                          "limit_switch_flags ignored)",
            "zeroing_ignored": "writing 1 to the zeroing object (quirk zeroing_object) leaves the position",
            "zeroing_rearm_ignored": "the zeroing object zeroes on every 1, also without the 0 that re-arms it",
            "operating_status_stale": "6500h keeps showing the factory 6000h value after 6000h changed",
            "speed_wrong_unit": "6030h is in revolutions per minute instead of measuring units per second",
            "tpdo_position_unscaled": "TPDOs carry the physical counts without scaling and offset (SDO shows the "
                                      "right position)",
        },
    ),
    (  # PDO mapping (CiA 301 §7.5.2.38)
        ("test_pdo_mapping",),
        {
            "mapping_accepted_while_valid": "TPDO mapping writes are accepted while the PDO is valid (COB-ID bit 31 "
                                            "clear)",
            "mapping_entries_while_enabled_count": "mapping entries are accepted while sub 0 is not 0",
            "mapping_change_while_valid_refused": (
                "quirk mapping_change_while_valid ignored: mapping writes are refused while the PDO is valid (the "
                "manual's own procedure, e.g. WDGA M §8.5.4, fails)"
            ),
            "non_mappable_object_accepted": "a mapping entry naming an object that is not PDO-mappable is accepted",
            "missing_object_mapped": "a mapping entry naming an object that does not exist is accepted",
            "mapping_length_unchecked": "sub 0 = n is accepted although the entries exceed 64 bits",
            "payload_not_matching_mapping": "TPDOs carry the mapped objects in reverse order (a single entry one "
                                            "byte late)",
            "fixed_mapping_writable": "read-only (fixed) mapping entries accept writes and change; without mapping "
                                      "objects (a fixed payload), writes to 1A00h are confirmed",
            "default_mapping_wrong_length": "the first TPDO mapping entry starts 8 bits longer than its object",
        },
    ),
    (  # CAM (CiA 406 6300h-6337h)
        ("test_cam",),
        {
            "cam_polarity_ignored": "the CAM polarity register (6302h) is ignored",
            "cam_hysteresis_ignored": "the CAM hysteresis (6330h+n) is ignored: a cam switches off at its limit",
            "cam_edge_off_by_one": "the CAM high limit no longer belongs to the window (active up to high - 1)",
            "cam_on_unscaled_value": "the CAMs compare the physical counts (without scaling and preset offset) "
                                     "with their limits",
            "cam_enable_ignored": "the CAM enable register (6301h) is ignored: every cam is evaluated",
            "cam_low_order_ignored": "quirk cam_low_below_high ignored: a CAM low limit at or above the high limit "
                                     "is accepted",
        },
    ),
    (  # work area (CiA 406 6400h-6402h)
        ("test_work_area",),
        {
            "work_area_flags_swapped": "6400h reads 04h above the work area and 02h below it (swapped)",
        },
    ),
]
FAULTS: dict[str, str] = {name: text for _, group in FAULT_GROUPS for name, text in group.items()}

#: Variants: the twin behaves as a device that a strictness option judges differently: one that follows CiA where the
#: profile's rule is only our inference (--strict-inferred fails it), one that answers with an abort code of the right
#: family (--abort-codes). They stay out of the fault matrix; tests/test_verdict_basis.py shows what each option makes.
#: conformant variants that are not an open reading: a device judged by --abort-codes (passes only with family)
ABORT_FAMILY_VARIANTS: dict[str, str] = {
    "write_ro_unsupported_access": "writes to ro/const objects abort with 06010000h (unsupported access), the "
                                   "family of CiA 301's 06010002h: fails with --abort-codes exact, passes with family",
}
#: conformant variants a shipped profile cannot judge: the device of a vendor EDS the profile must be probed from
#: (``profile from-eds --probe``); tests/test_probe_no_data.py runs each with its probed profile
PROBED_VARIANTS: dict[str, str] = {
    "empty_arrays": "an ARRAY from 2000h on with a read-only sub 0 holds as many elements as sub 0 counts: an element "
                    "above it aborts 08000024h (all of them where the EDS gave sub 0 no DefaultValue, CiA 306)",
}
#: conformant variants: each open reading's (encoder_conformance.open_points), the abort-family and the probed ones
VARIANTS: dict[str, str] = {**variants(), **ABORT_FAMILY_VARIANTS, **PROBED_VARIANTS}
#: every name the simulator's --fault takes
SIMULATOR_DEVIATIONS: dict[str, str] = {**FAULTS, **VARIANTS, **{n: h.text for n, h in HOLD_FAULTS.items()}}
#: fault -> the suite modules (file stems under suites/) it is made for
TARGET_MODULES: dict[str, tuple[str, ...]] = {
    **{name: modules for modules, group in FAULT_GROUPS for name in group},
    **variant_modules(), **{name: hold.modules for name, hold in HOLD_FAULTS.items()},
}


#: faults that break a documented quirk's behaviour: they can only show on a profile with that effect
QUIRK_EFFECT_OF_FAULT: dict[str, str] = {
    "guarding_heartbeat_coexist": "guarding_heartbeat_exclusive",
    "reload_not_immediate": "reload_immediate",
    "manufacturer_store_not_persisted": "manufacturer_store_object",
    "store_reboot_confirmed": "store_reboots_without_reply",
    "type_255_timer_0_sends": "transmission_type_255_timer_0_disables",
    "send_repeat_counter_ignored": "pdo_send_repeat_counters",
    "forced_bits_not_applied": "bits_forced_at_init",
    "autostart_ignored": "nmt_autostart_object",
    "lss_obeyed_in_any_state": "lss_only_in_states",
    "lss_auto_store_ignored": "lss_config_auto_stored",
    "limit_switch_flags_ignored": "limit_switch_flags",
    "cam_low_order_ignored": "cam_low_below_high",
    "zeroing_ignored": "zeroing_object",
    "preop_only_writes_accepted": "writes_preop_only",
    "zeroing_rearm_ignored": "zeroing_object",
    "mapping_change_while_valid_refused": "mapping_change_while_valid",
}


#: faults the fault matrix judges with --strict-inferred: the suites can only see them through a rule they
#: infer (a broken inferred rule is a warning by default, so the matrix could never see the fault caught).
#: Only faults that need it: strictness on another fault would let an inferred check hide that the
#: documented check meant to catch it does not.
#: - cam_edge_off_by_one: that the high limit belongs to the window is inferred (WDGA example CAM1 0..2048,
#:   CAM2 2049..4095); the fault shows only at the high limit itself.
#: - change_of_state_ignored: that a 254/255 TPDO with timer 0 is sent on a change of its mapped position is
#:   our reading of "event-driven" (CiA 301 §7.5.2.37 leaves the event to the manufacturer or profile).
#: - sync_tpdo_late: CiA 301 bounds no SYNC-to-TPDO latency; the limit is the profile's pdo_response_max_ms,
#:   our inference unless a manual gives it.
#: - unsized_download_takes_four_bytes: that a server takes an entry's own size for an expedited download without
#:   size indicator (rather than refusing it) is our reading of CiA 301 §7.2.4.3.3 ("unspecified number of bytes").
#: - emcy_on_unknown_command: that a refused SDO request draws no EMCY is our reading of CiA 301 §7.2.7.1.
#: - sync_length_unchecked: CiA 301 names EMCY 8240h (unexpected SYNC data length) but does not require it.
#: - open_transfer_blocks_requests: a server's handling of a transfer left open is ours; serial_unset: the format.
#: Judged without it (the rule that catches them is documented):
#: - work_area_flags_swapped: 02h above / 04h below is CiA 406 6400h and WDGA T 6.9; only the edges are
#:   inferred, and the swap shows at every position outside the area, not only at an edge;
#: - cam_hysteresis_ignored: it breaks the hold past the limit when leaving (common to every reading of
#:   CiA 406), not the inferred switch-on point (a cam without hysteresis switches on at the limit too);
#: - cam_enable_ignored: a disabled cam changes state as the position crosses its window (WDGA M 7.5 "only
#:   enabled cams can change state"), not only the inferred value 0 of its bit;
#: - the position, preset, speed and TPDO faults, cam_polarity_ignored, cam_on_unscaled_value and
#:   cam_low_order_ignored break CiA 406 or the profile's manual directly.
JUDGED_STRICTLY: frozenset[str] = frozenset({"cam_edge_off_by_one", "change_of_state_ignored", "sync_tpdo_late",
                                             "unsized_download_takes_four_bytes", "emcy_on_unknown_command",
                                             "sync_length_unchecked", "serial_unset", "open_transfer_blocks_requests",
                                             "sync_length_error_silent"})


def faults_for(effects: Iterable[str]) -> list[str]:
    """The faults that can show on a device whose profile quirks have ``effects`` (sorted)."""
    present = set(effects)
    return sorted(f for f in FAULTS if QUIRK_EFFECT_OF_FAULT.get(f) in (None, *present))
