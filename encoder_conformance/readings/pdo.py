"""Open readings of the PDO area: communication parameters, mapping and transmission (CiA 301 §7.2.2, §7.5.2.35-38)."""

from __future__ import annotations

from encoder_conformance.readings.model import OpenReading

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
]
