"""Open readings of the errors area (see the package docstring)."""

from __future__ import annotations

from .model import OpenReading

READINGS: list[OpenReading] = []
