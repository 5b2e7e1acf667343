"""Open readings of the PDO area: communication parameters, mapping and transmission (CiA 301 §7.2.2, §7.5.2.35-38)."""

from __future__ import annotations

from .model import OpenReading

READINGS: list[OpenReading] = [
    OpenReading(
        point="tpdo-transmission-types-not-listed",
        question="A manual lists the transmission types its device supports and is silent about the others: "
                 "may the device accept a type CiA 301 defines that the manual does not list?",
        source="CiA 301 v4.2.0 §7.5.2.35, table 71 (transmission types 0, 1-240, 252-255 are defined; which a "
               "device supports is the manufacturer's choice); the manual's PDO chapter lists only some",
        readings=("types the manual does not list are refused (06090030h)",
                  "every type CiA 301 defines is accepted (the refusal is only inferred: a warning)"),
        variant="cia301_transmission_types",
        variant_text="18xxh sub 2 accepts every transmission type CiA 301 defines (0..240, 252..255), also those "
                     "the profile leaves out because its manual does not list them",
        modules=("test_value_domain",),
    ),
]
