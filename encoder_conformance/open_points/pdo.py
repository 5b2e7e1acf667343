"""Open readings of the PDO area: communication parameters, mapping and transmission (CiA 301 §7.2.2, §7.5.2.35-38)."""

from __future__ import annotations

from encoder_conformance.open_points.record import OpenReading

READINGS: list[OpenReading] = [
    OpenReading(
        point="tpdo-transmission-types-not-listed",
        question="A manual lists the transmission types its device supports and is silent about the others: "
                 "may the device accept a type CiA 301 defines that the manual does not list?",
        source="CiA 301 v4.2.0 §7.5.2.37, table 72 (transmission types 0, 1-240, 252-255 are defined; which a "
               "device supports is the manufacturer's choice); the manual's PDO chapter lists only some",
        readings=("types the manual does not list are refused (06090030h)",
                  "every type CiA 301 defines is accepted (the refusal is only inferred: a warning)"),
        variant="cia301_transmission_types",
        variant_text="18xxh sub 2 accepts every transmission type CiA 301 defines (0..240, 252..255), also those "
                     "the profile leaves out because its manual does not list them",
        modules=("test_value_domain",),
    ),
    OpenReading(
        point="pdo-config-refused-in-operational",
        question="May a device refuse a write to a PDO's communication or mapping parameters (e.g. a TPDO COB-ID) "
                 "in operational, where it accepts the same write in pre-operational?",
        source='CiA 301 v4.2.0 §7.2.4.3.17 table 22: "0800 0022h Data cannot be transferred or stored to the '
               'application because of the present device state"; §7.5.2.35-38 say a PDO parameter changes only '
               'while the PDO is not valid, not that it changes in every NMT state. The WDGA manual restricts PDO '
               'parameterisation to pre-operational: "Die Zustandsparametrierung kann nur im '
               'Pre-Operational-Status durchgefuehrt werden" (M §8.5.1)',
        readings=("the write is served in operational as in pre-operational",
                  "the write is refused in operational with 08000022h and the value stays (the WDGA-like device)"),
        variant="pdo_config_refused_in_operational",
        variant_text="writes to 14xxh-1Bxxh (PDO communication and mapping parameters) in operational abort "
                     "08000022h (present device state)",
        modules=("test_nmt_state_machine", "test_pdo", "test_pdo_comm", "test_pdo_timing", "test_pdo_mapping",
                 "test_sync_objects", "test_heartbeat"),
        requires=("tpdos",),
    ),
    OpenReading(
        point="tpdo-inhibit-and-sync-start-fixed-while-valid",
        question="May a TPDO refuse a change of its inhibit time (18xxh sub 3) or SYNC start value (sub 6) while "
                 "it is valid (sub 1 bit 31 = 0)?",
        source='CiA 301 v4.2.0 §7.5.2.37 (TPDO communication parameter): the inhibit time (sub-index 03h) and the '
               'SYNC start value (sub-index 06h) are not to be changed while the PDO exists (bit 31 of sub-index 01h '
               'is 0b); TR-Electronic\'s CM-36 and LA-46 manuals say it of the inhibit time ("The value must not be '
               'changed while the PDO exists"), lely-core, which follows CiA 301 v4.2.0, and CANopenNode refuse both '
               'while the PDO is valid (06090030h)',
        readings=("the change is accepted while the TPDO is valid",
                  "the change is refused while the TPDO is valid (any abort, 06090030h as CANopenNode) and accepted "
                  "with sub 1 bit 31 set: the tests write sub 3 and sub 6 with the TPDO not valid, and put them back "
                  "the same way"),
        variant="pdo_params_fixed_while_valid",
        variant_text="18xxh sub 3 (inhibit time) and sub 6 (SYNC start value) refuse a change (06090030h) while the "
                     "TPDO is valid",
        modules=("test_pdo_comm", "test_pdo_timing"),
        requires=("tpdos",),
    ),
    OpenReading(
        point="cyclic-timer-vs-event-timer",
        question="The manual lists a cyclic timer 6200h (default 0001h) beside TPDO1's event timer 1800h sub 5 "
                 "(default 0000h): are they two values, or one value a write to either sets?",
        source='WDGA manual T 6.6 (p. 23): 6200h "Cyclic-Timer", "Änderung / Anzeige der Transmissions Periode '
               'für TPDO1", Unsigned16, rw, default 0001h; T 6.3 (p. 21): 1800h sub 5 event timer, default 0000h, '
               'in ms (M §8.5.3, 30 ms = 1Eh); the manual does not say how they relate. CiA 406 v3.0 and later are '
               'read as tying 6200h to TPDO1\'s event timer, both in ms (not checked against the text of CiA 406)',
        readings=("two values: a write to one leaves the other as it is",
                  "one value: a write to either sets both, while each loads its own stored value or default at a "
                  "reset (fresh from the factory 6200h = 0001h beside 1800h sub 5 = 0000h, which no order of "
                  "writes gives back: the run's custody gives it back by NMT reset node where the values in use "
                  "were the stored ones; an acceptance writes neither)"),
        variant="cyclic_timer_aliases_event_timer",
        variant_text="6200h (cyclic timer) and 1800h sub 5 (TPDO1 event timer) are one value: a write to either "
                     "sets both; a reset loads each from its own stored value or default",
        modules=("test_sdo_protocol", "test_pdo", "test_pdo_timing", "test_heartbeat", "test_object_dictionary"),
        requires=("tpdos",),
        requires_effects=("cyclic_timer_relation_unstated",),
    ),
    OpenReading(
        point="valid-pdo-needs-a-mapping",
        question="May a device refuse to make a PDO valid (18xxh/14xxh sub 1 bit 31 cleared) while its mapping "
                 "maps nothing (1Axxh/16xxh sub 0 = 0)?",
        source="CiA 301 v4.2.0 §7.5.2.36-38: sub 0 = 0 disables the mapping, and the PDO procedure makes the PDO "
               "valid after the mapping; the text does not say a PDO with nothing mapped must be accepted as valid. "
               "CANopenNode refuses it (06090030h: the mapping must be configured before enabling the PDO)",
        readings=("a PDO with nothing mapped is made valid (and sends nothing, or an empty frame)",
                  "a valid COB-ID is refused (06090030h) while the PDO maps nothing: a test that needs a valid PDO "
                  "uses one that maps something"),
        variant="valid_pdo_needs_a_mapping",
        variant_text="18xxh/14xxh sub 1 with bit 31 cleared is refused (06090030h) while 1Axxh/16xxh sub 0 = 0",
        modules=("test_pdo_comm", "test_pdo_mapping", "test_pdo", "test_pdo_timing"),
        requires=("tpdos", "tpdo_delivered_invalid_and_empty"),  # played where a TPDO is delivered that way
    ),
]
