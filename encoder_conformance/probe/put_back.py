"""What the probe wrote, put back: every write is preceded by a read of the value it replaces, and at the end
each value is written back, newest first, and read back to prove it (a device belongs to its owner)."""

from __future__ import annotations

from dataclasses import dataclass, field

from encoder_conformance.probe.link import Answer, ProbeLink


@dataclass
class PutBack:
    """The ledger: the first value seen of each entry the probe changed."""

    link: ProbeLink
    found: dict[tuple[int, int], bytes] = field(default_factory=dict)
    failures: list[str] = field(default_factory=list)

    def write(self, index: int, sub: int, data: bytes, force_segment: bool = False) -> Answer:
        """Write ``data`` once the value it replaces is known; an unreadable entry is not written."""
        if (index, sub) not in self.found:
            before = self.link.read(index, sub)
            if not before.ok:
                return before
            assert before.data is not None
            self.found[index, sub] = before.data
        return self.link.write(index, sub, data, force_segment)

    def remember(self, index: int, sub: int, data: bytes) -> None:
        """A value read earlier that a reset may have lost: put back like a written one."""
        self.found.setdefault((index, sub), data)

    def restore(self) -> list[str]:
        """Write every found value back and read it back; the entries that did not come back (empty: all did)."""
        for (index, sub), data in reversed(list(self.found.items())):
            now = self.link.read(index, sub)
            if now.data == data:
                continue
            answer = self.link.write(index, sub, data)
            again = self.link.read(index, sub)
            if again.data != data:
                self.failures.append(f"{index:04X}h sub {sub}: found {data.hex(' ').upper()}, now "
                                     f"{again.describe()} (put-back write: {answer.describe()})")
        return self.failures
