"""What a check that did not judge the device says, as a closed set: why it did not run, and what that makes of the
verdict (pure data; every layer may use it).

A check outside the run's **scope** (``Kind.NOT_APPLICABLE``, ``NOT_EQUIPPED``, ``NOT_SELECTED``) is listed, never
counted for or against the device. A check in scope that did not judge is **not testable** (the device's state kept
it from running, or what the device did left nothing to compare: the area is INCOMPLETE) or **inconclusive** (the
tester's host was late: the verdict is at most PASS WITH WARNINGS). Each such reason is a :class:`Hold`; the
false-PASS matrix (``runs/false_pass_matrix.py``) keeps a twin fault for every hold that depends on the device, so
no way of ending a test without a judgement can turn a defective device into a PASS.
"""

from __future__ import annotations

from enum import Enum, StrEnum


class Kind(StrEnum):
    """Why a check gave no verdict; the value is the first words of its message ("not applicable: ...")."""

    NOT_APPLICABLE = "not applicable"  # scope: the profile (or the device's documented answer) does not apply it
    NOT_EQUIPPED = "not available"  # scope: the station lacks what it needs (power switch, shaft drive, ...)
    NOT_SELECTED = "not selected"  # scope: the run's options left it out (--allow-destructive, -k)
    NOT_TESTABLE = "not testable"  # in scope: the device's state kept it from running, or it could not judge
    INCONCLUSIVE = "inconclusive"  # in scope: the tester's host was late

    @property
    def in_scope(self) -> bool:
        """A check of this kind belonged to the run: it makes the verdict INCOMPLETE or PASS WITH WARNINGS."""
        return self in (Kind.NOT_TESTABLE, Kind.INCONCLUSIVE)


class Hold(Enum):
    """Every reason a check in scope ended without judging the device (a closed set: a new one needs a member here,
    and, where it depends on the device, a twin fault in the false-PASS matrix)."""

    # (kind, what it means, whether a device can cause it)
    PERSISTENT_ERROR = (Kind.NOT_TESTABLE, "the device keeps an error no reset clears and stays out of the state the "
                                           "check needs", True)
    VALUES_CHANGED = (Kind.NOT_TESTABLE, "every value the check compares changed between its reads: nothing could be "
                                         "compared", True)
    NO_READABLE_LONG_ENTRY = (Kind.NOT_TESTABLE, "every entry over 4 bytes refused its read: no segmented transfer "
                                                 "to judge", True)
    NO_EMCY_FROM_TRIGGER = (Kind.NOT_TESTABLE, "the device sent no EMCY for the bench's error stimulus", True)
    EMCY_NOT_REPEATED = (Kind.NOT_TESTABLE, "the device did not repeat the EMCY often enough to measure", True)
    NO_TPDO_ON_CHANGE = (Kind.NOT_TESTABLE, "the TPDO sent nothing on a change in operational", True)
    NO_USABLE_TPDO = (Kind.NOT_TESTABLE, "no TPDO the profile makes usable is usable as the device is configured "
                                         "(nothing mapped, or disabled with a read-only COB-ID)", True)
    UNTYPED = (Kind.NOT_TESTABLE, "a skip whose reason the suite did not type (a defect of the suite: report it)",
               False)
    HOST_LATE = (Kind.INCONCLUSIVE, "the tester's host was late at the moments that count", False)
    CLOCKS_APART = (Kind.INCONCLUSIVE, "the tester's and the adapter's clocks cannot be compared", False)
    STIMULUS_LATE = (Kind.INCONCLUSIVE, "the tester did not make its stimulus inside the window", False)

    def __init__(self, kind: Kind, meaning: str, device_dependent: bool) -> None:
        self.kind = kind
        self.meaning = meaning
        self.device_dependent = device_dependent


#: the message prefixes of each kind (a scope skip of pytest's own, e.g. a skip marker, is read by its prefix)
PREFIXES: dict[str, Kind] = {kind.value: kind for kind in Kind}


def kind_of(message: str, unnamed: Kind = Kind.NOT_TESTABLE) -> Kind:
    """The kind a skip's message names by its first words; a message that names none is ``unnamed``: not testable
    for a skip in a run (an untyped skip must never count as out of scope)."""
    head = message.split(":", 1)[0].strip().lower()
    return PREFIXES.get(head, unnamed)


def hold_named(name: str | None) -> Hold | None:
    """The hold of that name (as ``run-summary.json`` keeps it), None for none or an unknown name."""
    return Hold.__members__.get(name or "")
