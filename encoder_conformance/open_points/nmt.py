"""Open readings of the NMT area: the state a device enters after its initialisation (CiA 301 §7.3.2.2)."""

from __future__ import annotations

from encoder_conformance.open_points.record import OpenReading

READINGS: list[OpenReading] = [
    OpenReading(
        point="self-starting-device",
        question="May a device enter operational by itself after power-on, reset node and reset communication?",
        source="CiA 301 v4.2.0 §7.3.2.2 (NMT state diagram): after initialisation the device enters pre-operational "
               "autonomously; CiA 302-2 object 1F80h bit 3 (and a manual's own autostart object: WDGA manual M "
               "§7.10, T 7.18, 1F80h = 08h; WayCon WCAN manual M §3, §5, object 2104h = 1, factory value not "
               "stated) makes it a self-starting device that enters operational on its own",
        readings=("the object says pre-operational: every reset ends in pre-operational",
                  "the object says start (as delivered or as stored): every reset ends in operational, and a test "
                  "that needs pre-operational sends NMT enter pre-operational and checks it got there"),
        variant="autostart_set_at_delivery",
        variant_text="the quirk's autostart object holds its operational value by default: after every boot-up "
                     "the node enters operational by itself, as its manual documents",
        modules=("test_nmt", "test_nmt_state_machine", "test_heartbeat"),
        requires=("heartbeat_producer",),
        requires_effects=("nmt_autostart_object",),
        shares_twin=False,
    ),
]
