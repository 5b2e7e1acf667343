"""Open readings of the lss area (see the package docstring)."""

from __future__ import annotations

from .model import OpenReading

READINGS: list[OpenReading] = []
