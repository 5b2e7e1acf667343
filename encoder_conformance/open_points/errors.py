"""Open readings of the errors area: EMCY, SYNC and NMT error control (CiA 301 §7.2.5, §7.2.7, §7.2.8).

No copy of CiA 301 v4.2.0 was at hand. The rules below were checked against public texts that implement or
reproduce it (CANopenNode, lely-core, device manuals that reprint its objects): what they confirm is given as a
paraphrase with the source named; what they do not is marked "(not checked against the text of CiA 301)". The
object section numbers (§7.5.2.n) agree with other public citations of CiA 301 v4.2.0 but were not seen in the
text itself.
"""

from __future__ import annotations

from encoder_conformance.open_points.record import OpenReading

ERROR_BEHAVIOUR = ('CiA 301 v4.2.0, object 1029h (error behaviour, §7.5.2.32): a serious device failure in '
                   'operational, such as a communication error, sends the device to pre-operational by default; '
                   '1029h may make it keep its NMT state (01h) or enter stopped (02h) instead (so the FAULHABER MC '
                   'communication manual §3.8 and the WDGA manual M §7.9 describe it, and the 1029h tables of other '
                   'CANopen manuals, e.g. DIS Sensors QG65D §8.1.10, table 23)')

READINGS: list[OpenReading] = [
    OpenReading(
        point="sync-producer",
        question="May a device generate SYNC (1005h bit 30 accepted, SYNC every 1006h µs), or must it refuse bit 30?",
        source='CiA 301 v4.2.0 §7.5.2.5 (object 1005h): bit 30 (gen): 0 = the device does not generate SYNC, 1 = it '
               'generates SYNC; a device that cannot generate SYNC answers an attempt to set bit 30 with an SDO abort '
               '0609 0030h (so the Applied Motion ST10-C-CE CANopen manual, table 9, reprints the 1005h entry); '
               '§7.5.2.6 (object 1006h): 0 disables the SYNC transmission. A profile declares which '
               '(capabilities.sync_producer: no, yes, may)',
        readings=("bit 30 refused (06090030h), 1005h unchanged: the device cannot generate SYNC",
                  "bit 30 accepted: with 1006h > 0 the device sends SYNC on the 1005h CAN-ID every 1006h µs, none "
                  "with 1006h = 0 (CANopenNode's demo device)"),
        variant="sync_producer",
        variant_text="1005h bit 30 (generate SYNC) is accepted; with 1006h > 0 the twin sends SYNC every 1006h µs, the "
                     "first 100 ms after the write (CANopenNode's demo: 49 ms)",
        modules=("test_sync_objects",),
        requires=("sync_producer",),
    ),
    OpenReading(
        point="sync-consumer-timeout",
        question="Does a SYNC consumer watch 1006h: no SYNC for more than the communication cycle period an error "
                 "that keeps the device out of operational until a reset?",
        source='CiA 301 v4.2.0 §7.5.2.6 (object 1006h, communication cycle period): the SYNC interval in µs; a SYNC '
               'consumer may use it to watch the SYNC (not checked against the text of CiA 301: CANopenNode raises '
               '8100h after 1.5 periods without SYNC, and the CiA conformance test tool sets 1006h to 0 with the '
               'SYNC consumer enabled in its case Synchronization 04; the description of 1006h in §7.5.2.6 would '
               'settle it); §7.2.7.1 table 21: 8100h (communication, generic); ' + ERROR_BEHAVIOUR,
        readings=("1006h only paces a producer: no error without SYNC",
                  "no SYNC within 1.5 periods records 8100h (1001h bit 4) with its EMCY; the error holds the device "
                  "in pre-operational (CANopenNode clears the error at the next SYNC; the NMT state stays until a "
                  "command or reset): a test that writes 1006h puts it back and clears the error"),
        variant="sync_timeout_error",
        variant_text="with 1006h > 0, no SYNC for 1.5 periods raises 8100h (communication); while it is active the "
                     "node falls back from operational to pre-operational; a reset clears it",
        modules=("test_pdo_comm", "test_pdo", "test_sync_objects"),
        requires=("sync_consumer",),
    ),
    OpenReading(
        point="communication-error-leaves-operational",
        question="A communication error (heartbeat consumer time-out 8130h, SYNC length 8240h) is active: does the "
                 "device stay operational, or leave it for pre-operational until the error is gone?",
        source=ERROR_BEHAVIOUR + '; the WDGA manual: a CAN-bus fault in operational changes the device to '
               'pre-operational by default (M §7.9, object 1029h)',
        readings=("the NMT state stays as it is (1029h sub 1 = 01h; CiA 301's default for a serious failure is "
                  "pre-operational, so a device that stays with 1029h absent or 00h is not conformant there: the "
                  "suite does not judge which errors a device classes as serious)",
                  "the device enters pre-operational and NMT start does not hold while the error is active: an EMCY "
                  "test clears what it raised (or resets), a test that needs operational checks it got there"),
        variant="comm_error_enters_preoperational",
        variant_text="while 1001h bit 4 (communication error) is set the node falls back from operational to "
                     "pre-operational (also right after NMT start); a reset clears the error",
        modules=("test_emcy", "test_heartbeat", "test_pdo_timing"),
        requires=("emcy",),
    ),
    OpenReading(
        point="persistent-error-holds-pre-operational",
        question="The device finds a failure at every start-up that no reset clears (e.g. its non-volatile memory "
                 "cannot be read): may it refuse to stay in operational?",
        source=ERROR_BEHAVIOUR + '; §7.2.7.1 table 21: 5000h (device hardware). CANopenNode\'s Linux demo device '
               'started without its storage files reports EMCY 5000h with 1001h = 01h after every boot-up and '
               'leaves operational at once (its default NMT control: no operational while 1001h is set)',
        readings=("no failure at start-up: NMT start reaches operational",
                  "a failure found at every start-up (1001h set again after each reset communication) keeps the "
                  "device in pre-operational: a test that needs operational, or a device without an error, is not "
                  "testable and says so (a skip naming 1001h and the newest 1003h entry), never a failure"),
        variant="device_error_at_start",
        variant_text="after every boot-up the twin reports EMCY 5000h with 1001h bit 0, which no reset clears (an "
                     "error reset EMCY keeps it in 1001h), and NMT start leaves it in pre-operational",
        # one module per way a test meets the kept error: the NMT observers, start_operational and the error reset
        # precondition, no_error_left, the state model, the LSS state check (the periodic capture's event-timer
        # stream: tests/test_persistent_error.py, without a whole capture per profile)
        modules=("test_nmt", "test_emcy", "test_pdo", "test_nmt_state_machine", "test_lss"),
        requires=("emcy", "heartbeat_producer"),
        shares_twin=False,
        verdict="INCOMPLETE",  # conformant, but the checks that need operational are not testable: no PASS
    ),
    OpenReading(
        point="persistent-error-start-from-stopped",
        question="A device that keeps a failure no reset clears gets NMT start in stopped: does it take the start "
                 "and fall back to pre-operational, or refuse it and stay stopped?",
        source=ERROR_BEHAVIOUR + '; CiA 301 v4.2.0 §7.3.2.2 (NMT state diagram): in stopped the device offers no '
               'SDO, only NMT and error control',
        readings=("the start is taken and the error behaviour sends the device to pre-operational (CANopenNode)",
                  "the start is refused and the device stays stopped: the check for the kept error brings it out "
                  "of stopped (NMT reset communication and its boot-up) before it reads 1001h by SDO"),
        variant="device_error_at_start_stays_stopped",
        variant_text="the device_error_at_start failure, and NMT start leaves the node where it is (stopped stays "
                     "stopped, pre-operational stays pre-operational)",
        modules=("test_nmt", "test_emcy", "test_pdo"),
        requires=("emcy", "heartbeat_producer"),
        shares_twin=False,
        verdict="INCOMPLETE",  # conformant, but the checks that need operational are not testable: no PASS
    ),
    OpenReading(
        point="sync-processing-cycle",
        question="Two SYNCs come closer together than the device takes to process one: must it count both?",
        source="CiA 301 v4.2.0 §7.2.5 (SYNC protocol) gives no shortest SYNC interval a consumer must resolve; "
               "§7.5.2.6: 1006h sets the SYNC period in µs. The profile's timing.pdo_response_max_ms bounds SYNC to "
               "TPDO, so the tester spaces SYNCs by that (or by the TPDO a SYNC brings)",
        readings=("every SYNC is counted however close to the previous one",
                  "SYNCs within one processing cycle count once (CANopenNode's demo on Linux: a 1 ms cycle)"),
        variant="sync_processing_cycle",
        variant_text="a SYNC less than 1 ms after the last SYNC the TPDO engine took is merged with it",
        modules=("test_pdo", "test_pdo_comm", "test_pdo_timing", "test_sync_objects", "test_nmt",
                 "test_nmt_state_machine"),
        requires=("tpdos",),
    ),
]
