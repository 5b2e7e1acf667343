"""Open readings of the SDO area: object access, segmented and block transfer (CiA 301 §7.2.4, §7.5.2).

No copy of CiA 301 v4.2.0 was at hand. The rules below were checked against public texts that reproduce it (the
SDO abort-code tables of device manuals, CANopenNode 301/CO_SDOserver.h, whose protocol notes follow CiA 301
closely): what they confirm is given as a paraphrase, with the source named where it is quoted. Section and table
numbers agree with other public citations of CiA 301 v4.2.0 but were not seen in the text itself.
"""

from __future__ import annotations

from encoder_conformance.open_points.record import OpenReading

SDO_PROTOCOL = ("test_sdo_protocol", "test_sdo_fuzz")
ABORT_ANY_TIME = ('CiA 301 v4.2.0 §7.2.4.2 (SDO services), abort SDO transfer: the client and the server of an SDO '
                  'may each abort a transfer at any time (so CANopen references describe the service, e.g. the '
                  'ars-informatica CANopen pages, "Abort SDO Transfer"); §7.2.4.3.17: an abort carries the '
                  'multiplexer of the transfer it ends. The protocols of §7.2.4.3 give no rule for an initiate '
                  'request that arrives while a segmented transfer of the same SDO is open')

SHORT_FRAMES = ('CiA 301 v4.2.0 §7.2.4.3.1 (SDO protocols, general): every SDO request and response is drawn with '
                'a data field of 8 bytes (byte 0 the command specifier, bytes 1-3 the multiplexer, bytes 4-7 data or '
                'reserved), and the protocols of §7.2.4.3 give no rule for a frame with a shorter data field: no abort '
                'code of table 22 names it (05040001h "Client/server command specifier not valid or unknown" is the '
                'nearest), and ISO 11898-1 lets a data frame carry 0-8 bytes. What no reading allows: two answers to '
                'one frame, an answer naming another multiplexer than the request it serves, a server that stops '
                'serving')

READINGS: list[OpenReading] = [
    OpenReading(
        point="error-history-empty-entry",
        question="May a read of an error history entry (1003h sub n) above the number of errors recorded (sub 0) "
                 "be refused with 08000024h, rather than answered with a value?",
        source='CiA 301 v4.2.0 §7.5.2.4 (object 1003h): sub-index 00h gives the number of errors recorded from '
               'sub-index 01h on (so manuals that reprint 1003h say it, e.g. TR-Electronic LA-46 manual §7.4), so '
               'the entries above it hold no error; §7.2.4.3.17 table 22: '
               '"0800 0024h No data available". The CiA conformance test tool accepts 08000024h in its case '
               'Emergency 03 (read of 1003h sub 1)',
        readings=("the empty entry is read (a value, e.g. 0)",
                  "the read is refused with 08000024h (no data available); a write is refused as to any read-only "
                  "entry (06010002h), as CANopenNode does"),
        variant="empty_history_no_data",
        variant_text="a read of a 1003h entry above sub 0's count aborts 08000024h (no data available)",
        modules=("test_object_dictionary",),
        requires=("emcy",),
    ),
    OpenReading(
        point="sdo-request-while-transfer-open",
        question="An initiate request arrives while a segmented transfer of the same SDO is open: may the server "
                 "abort the open transfer before it serves the new request?",
        source=ABORT_ANY_TIME,
        readings=("the new request is served, the open transfer dropped without a frame",
                  "the open transfer is aborted (an abort naming its multiplexer, any code), then the new request is "
                  "served",
                  "the new request is refused with an abort echoing its multiplexer (our inference expects it "
                  "served: a warning)"),
        variant="interrupt_aborts_open_transfer",
        variant_text="an initiate request during an open segmented transfer draws an abort 08000000h naming the "
                     "open transfer, then its own answer",
        modules=SDO_PROTOCOL,
        requires=("segmented_sdo",),
    ),
    OpenReading(
        point="sdo-request-taken-by-open-transfer",
        question="An initiate request arrives while a segmented transfer is open: may the server take it as a "
                 "wrong frame of the open transfer (abort 05040001h naming that transfer) and leave the request "
                 "itself unanswered, serving the client's next one?",
        source=ABORT_ANY_TIME + '; table 22: "0504 0001h Client/server command specifier not valid or unknown": '
                                'during a segmented upload only a segment request (or an abort) is valid',
        readings=("the new request is served (with or without an abort of the open transfer first)",
                  "an abort 05040001h (or another code) naming the open transfer only; the new request is not "
                  "answered, and sent again it is served (CANopenNode)"),
        variant="interrupt_consumed_by_open_transfer",
        variant_text="an initiate request during an open segmented transfer is taken as a wrong segment: abort "
                     "05040001h naming the open transfer, no answer to the request itself",
        modules=SDO_PROTOCOL,
        requires=("segmented_sdo",),
    ),
    OpenReading(
        point="sdo-initiate-reserved-bits",
        question="An initiate request has a bit set that CiA 301 marks \"always 0\" (upload 41h-5Fh, download with "
                 "bit 4): may the server refuse it as an invalid command, and must that abort echo the request's "
                 "multiplexer?",
        source='CiA 301 v4.2.0 §7.2.4.3.6 (initiate SDO upload protocol): byte 0 of the request is ccs = 2 and '
               'bits 4-0 "x: not used, always 0" (§7.2.4.3.3, initiate SDO download: bit 4 likewise), so a request '
               'with them set is no valid initiate; §7.2.4.3.17 table 22: "0504 0001h Client/server command '
               'specifier not valid or unknown". No text says which multiplexer an abort of a frame that is no valid '
               'request carries: the CiA conformance test tool accepts any for an unknown command (CTT SDO 07), and '
               'CANopenNode (301/CO_SDOserver.c: only 40h starts an upload) names the last valid request\'s',
        readings=("the request served as if the reserved bits were 0: its answer (or abort) echoes its multiplexer",
                  "the request refused as an invalid command: abort 05040001h with any multiplexer (CANopenNode: the "
                  "previous transfer's), and no other answer"),
        variant="initiate_reserved_bits_refused",
        variant_text="an initiate request with a reserved bit set (upload 41h-5Fh, download bit 4) is refused: abort "
                     "05040001h naming the previous initiate's multiplexer, as CANopenNode does",
        modules=("test_sdo_fuzz",),
    ),
    OpenReading(
        point="sdo-short-frame",
        question="An SDO request frame has fewer than 8 data bytes: may the server refuse it with an abort rather than "
                 "ignore it, and which multiplexer does that abort name?",
        source=SHORT_FRAMES,
        readings=("the frame is ignored: no answer, the next request served",
                  "the frame is refused: one abort (any code, naming any multiplexer, e.g. the last request's), the "
                  "next request served"),
        variant="short_frame_aborted",
        variant_text="an SDO frame under 8 bytes is refused: abort 05040001h naming the multiplexer of the last "
                     "initiate served (0000h.00 before the first)",
        modules=("test_sdo_fuzz",),
    ),
    OpenReading(
        point="sdo-short-frame-served",
        question="An SDO request frame has fewer than 8 data bytes but every field its request needs (index and "
                 "sub-index of an upload, the data an expedited download's n announces): may the server serve it?",
        source=SHORT_FRAMES,
        readings=("the frame is ignored or aborted (open point sdo-short-frame)",
                  "the frame is served as the request its bytes carry, missing bytes read as 0 (python-canopen 2.4's "
                  "LocalNode answers a 4-byte upload request and ignores shorter ones; a widely used C++ CANopen "
                  "library takes a 6-byte initiate download and answers a 5-byte upload request)"),
        variant="short_frame_served",
        variant_text="an SDO frame under 8 bytes that carries its request (an upload's index and sub-index, an "
                     "expedited download's announced data) is served as that request padded with zeros; others are "
                     "ignored",
        modules=("test_sdo_fuzz",),
    ),
    OpenReading(
        point="sdo-transfer-left-open",
        question="A client leaves a segmented transfer half-finished: may the server end it by itself after a "
                 "time-out, and when?",
        source='CiA 301 v4.2.0 §7.2.4.3.17 table 22: "0504 0000h SDO protocol timed out"; CiA 301 gives no '
               'time-out value (the profile\'s timing.sdo_transfer_timeout_ms bounds it)',
        readings=("the transfer stays open until the client's next request",
                  "the server aborts it with 05040000h naming its multiplexer, within the device's time-out"),
        variant="left_open_transfer_times_out",
        variant_text="a segmented transfer without a request for 25 ms (a short time-out) is aborted 05040000h "
                     "naming its entry",
        modules=("test_sdo_protocol",),
        requires=("segmented_sdo",),
    ),
    OpenReading(
        point="sdo-block-subblock-timeout",
        question="A block download segment comes out of sequence: when does the server acknowledge (or abort), "
                 "and how long may it wait for the rest of the sub-block?",
        source='CiA 301 v4.2.0 §7.2.4.3 (SDO block download): the server confirms a sub-block with ackseq, the '
               'sequence number of the last segment it received successfully, and the client goes on after it '
               '(CANopenNode 301/CO_SDOserver.h: "sequence number of last segment that was received successfully '
               'during the last block download"); no time is given for a sub-block that stays incomplete; table 22: '
               '05040003h (invalid sequence number), 05040000h (SDO protocol timed out). CTT SDO 27 (a block read '
               'whose client confirms with ackseq 128) accepts 05040001h, 05040003h or 08000000h',
        readings=("the acknowledgement (ackseq 0) at once",
                  "the segment ignored, the acknowledgement after the device's sub-block time-out (within "
                  "timing.sdo_transfer_timeout_ms), as CANopenNode does",
                  "an abort 05040003h (or 05040000h after the time-out) naming the entry"),
        variant="slow_subblock_timeout",
        variant_text="a block download segment out of sequence is ignored; the sub-block is acknowledged after "
                     "timing.sdo_transfer_timeout_ms without a further segment",
        modules=("test_sdo_block",),
        requires=("block_sdo",),
    ),
]
