"""Open readings of the LSS area (CiA 305 layer setting services; see the package docstring).

No copy of CiA 305 v3.0.0 was at hand. Its rules below were checked against public texts that implement or reprint
it (CANopenNode, lely-core, which follows CiA 305 v3.0.0, and device manuals such as TR-Electronic's CM-36 manual):
what they confirm is given as a paraphrase with the source named; what they do not is marked "(not checked against
the text of CiA 305)". The rules are cited by the heading of the service or table (the document's section numbers
were not at hand). The manuals' sentences and sections are the texts'. The WDGA manual (Wachendorff WDGA CANopen
technical manual, "M") is German; its sentences are quoted with a translation.
"""

from __future__ import annotations

from encoder_conformance.open_points.record import OpenReading

LSS = ("test_lss",)
#: the WDGA sentence both node-ID points come from (M §8.2.4, after store configuration and switch state global 0)
NEW_BOOT_UP = ('Wachendorff WDGA manual M §8.2.4: "Danach muss ein neuer Boot-up ausgelöst werden (z. B. durch '
               'Spannungsreset)" (then a new boot-up must be triggered, e.g. by a power reset)')

READINGS: list[OpenReading] = [
    OpenReading(
        point="lss-node-id-activation",
        question="A manual asks for 'a new boot-up' after a node-ID was configured by LSS: does the configured "
                 "node-ID become active only at power-on (from what store configuration kept), or also at NMT "
                 "reset communication, as CiA 305 v3 has it?",
        source=NEW_BOOT_UP + '; M §4.2 (node-ID by SDO): "wird erst nach dem manuellen Reset des Drehgebers '
               '(Spannungs-Reset oder NMT-Reset) wirksam" (takes effect only after a manual reset: power reset or '
               'NMT reset); CiA 305 v3.0.0, configure node-ID service: the configured node-ID is pending and becomes '
               'the active one at NMT reset communication (so CANopenNode and lely-core implement it, and '
               'TR-Electronic\'s CM-36 manual §3.7.6: inquire node-ID reports the new node-ID only after NMT reset '
               'communication)',
        readings=("the configured node-ID becomes active only at the next power-on, from what was stored; NMT reset "
                  "communication boots the device at the node-ID it had",
                  "the configured (pending) node-ID becomes active at NMT reset communication: the device boots "
                  "with it (CiA 305 v3; a boot-up the manual's 'new boot-up' allows)"),
        variant="lss_node_id_at_reset_comm",
        variant_text="a node-ID configured by LSS becomes active at NMT reset communication, also where the "
                     "profile's manual applies it at power-on (quirk lss_only_in_states, activation power_cycle)",
        modules=LSS,
        requires=("lss",),
        requires_effects=("lss_only_in_states",),
    ),
    OpenReading(
        point="lss-unconfigured-start",
        question="An unconfigured device (node-ID FFh) is given a valid node-ID: does it start (boot-up) when it "
                 "leaves the LSS configuration state, or only at a new boot-up the master triggers (power-on, "
                 "with the node-ID stored)?",
        source=NEW_BOOT_UP + "; CiA 305 v3.0.0, configure node-ID service and the LSS FSA: an LSS slave "
               "whose active node-ID is FFh continues its NMT initialisation with the pending node-ID when switched "
               "to the LSS waiting state (not checked against the text of CiA 305: CANopenNode 305/CO_LSSslave.c "
               "does a reset communication then, lely-core waits for an NMT reset; the LSS slave state diagram of "
               "CiA 305 v3.0.0 and its transitions would settle it)",
        readings=("the device boots with the new node-ID when it leaves the configuration state (CiA 305 v3)",
                  "the device stays silent until a new boot-up: after store configuration and a power cycle it "
                  "boots with the stored node-ID (the manual's procedure, M §8.2.4)"),
        variant="lss_unconfigured_waits_for_reset",
        variant_text="an unconfigured node given a node-ID stays silent when it leaves the LSS configuration "
                     "state; it boots with the stored node-ID at the next power-on",
        modules=LSS,
        requires=("lss",),
        requires_effects=("lss_only_in_states",),
        excluded_by_effects=("unconfigured_node_id",),  # FAULHABER p.42: boots as soon as it has a valid node-ID
    ),
    OpenReading(
        point="lss-unconfigured-start-at-nmt-reset",
        question="An unconfigured device (node-ID FFh) is given a valid node-ID and the master switches it back to "
                 "the waiting state: does it start at once, or only at the next NMT reset the master sends?",
        source="CiA 305 v3.0.0 figure 33 (configure node-ID, as lely-core cites it) and the LSS slave states (not "
               "checked against the text of CiA 305): CANopenNode 305/CO_LSSslave.c starts the slave when it is "
               "switched to the waiting state; "
               "lely-core (src/co/nmt.c, which follows CiA 305 v3.0.0) keeps a slave with node-ID FFh in "
               "initialisation until an NMT reset node or reset communication, addressed to all nodes since it has "
               "no node-ID to be addressed by",
        readings=("the device boots with the new node-ID when it leaves the configuration state (CANopenNode)",
                  "the device boots with the new node-ID at the next NMT reset to all nodes (lely-core): the suite "
                  "sends reset communication to all nodes where no boot-up came"),
        variant="lss_unconfigured_boots_at_nmt_reset",
        variant_text="an unconfigured node given a node-ID stays in initialisation when it leaves the LSS "
                     "configuration state and boots with it at the next NMT reset to all nodes (lely-core)",
        modules=LSS,
        requires=("lss:configure_node_id",),
        excluded_by_effects=("unconfigured_node_id", "lss_only_in_states"),
    ),
    OpenReading(
        point="lss-activate-bit-timing-state",
        question="Does an LSS slave obey activate bit timing (15h) in the LSS waiting state too, or only in the "
                 "configuration state?",
        source='CiA 305 v3.0.0, LSS FSA, services per LSS state, as TR-Electronic reproduces it (CM-36 user '
               'manual TR-ECE-BA-DGB-0128 §3.7.1, "State behavior of the supported services"): "Activate bit timing '
               'parameters: LSS waiting No, LSS configuration Yes"; CANopenNode 305/CO_LSSslave.c handles 15h only '
               'in the configuration state. No text requires a slave to obey it in the waiting state',
        readings=("obeyed in every LSS state (the twin's default)",
                  "obeyed only in the configuration state (CANopenNode); the suite sends it in the configuration "
                  "state, where both readings obey it"),
        variant="lss_activate_only_in_configuration",
        variant_text="activate bit timing is obeyed only in the LSS configuration state (ignored while waiting)",
        modules=LSS,
        requires=("lss:activate_bit_timing",),
    ),
    OpenReading(
        point="lss-configure-node-id-ffh",
        question="A manual gives the configure node-ID range without FFh: may the device refuse node-ID FFh "
                 "(unconfigured), so that LSS cannot make it unconfigured?",
        source='Wachendorff WDGA manual M §8.2.6: "Der Wertebereich für die Node-ID des Drehgebers liegt zwischen '
               '00h und 7Fh" (the node-ID range is 00h to 7Fh); CiA 305 v3.0.0, configure node-ID service: 1..127 '
               'and FFh are valid, FFh makes the slave unconfigured (so CANopenNode and lely-core accept them, and '
               'Vector\'s CANoe CANopen test feature set gives the range 1..127 and 255)',
        readings=("FFh accepted (error 0): the unconfigured start-up and fastscan are judged",
                  "FFh refused (error 1, as the manual's range says): not judged (configure FFh, and every test "
                  "that needs an unconfigured device, skip with this reason)"),
        variant="lss_node_id_ffh_refused",
        variant_text="configure node-ID FFh (unconfigured) is refused with error 1, as a node-ID range of 00h..7Fh "
                     "says",
        modules=LSS,
        requires=("lss",),
        requires_effects=("lss_node_id_range",),
    ),
    OpenReading(
        point="lss-bit-timing-beyond-profile",
        question="May a device accept configure bit timing table-0 indices its profile does not list: 9 "
                 "(automatic bit-rate detection) and 5 (100 kbit/s in older LSS tables, reserved in CiA 305 v3)?",
        source="CiA 305 v3.0.0, configure bit timing parameters, table 0 (bit timing): index 9 is automatic "
               "bit-rate detection, optional; index 5 is reserved (so CANopenNode 305/CO_LSS.h and lely-core give "
               "the table); older LSS tables give index 5 to 100 kbit/s, as the WDGA manual (M §8.2.5, T 8.9) and "
               "TR-Electronic's LA-46 manual (§3.9.4.2) still do (which DSP 305 version did is not checked). Which "
               "a device supports is its manual's to say; a generic profile lists no auto-detection and no 100 kbit/s",
        readings=("refused (error 1 or FFh) where the profile does not list the rate",
                  "accepted: a warning (the refusal rests on the profile's list, our inference), never a failure"),
        variant="lss_bit_timing_auto_and_100k",
        variant_text="configure bit timing also accepts table-0 index 9 (automatic detection) and 5 (100 kbit/s in "
                     "older tables), whatever the profile lists",
        modules=LSS,
        requires=("lss:configure_bit_timing",),
    ),
]
