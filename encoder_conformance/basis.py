"""What a verdict rests on: a CiA clause, the device's manual, or our own inference (shared by the profile
model, which marks inferred value domains, and the reports, which count verdicts per basis)."""

from __future__ import annotations

from typing import Literal

Basis = Literal["cia", "manual", "inferred"]
BASES: tuple[Basis, ...] = ("cia", "manual", "inferred")
