"""Object keys as profiles write them: an index alone ("0x6000", 0x6000, "6000h") or with a
sub-index ("0x1800.02", "0x2348.1", [0x1800, 2])."""

from __future__ import annotations

from typing import Annotated, Any, NamedTuple

from pydantic import BeforeValidator, PlainSerializer


def parse_index(value: Any) -> int:
    """0x6001 (int), '0x6001', '6001h' or '6001' (hexadecimal) -> 0x6001."""
    if isinstance(value, bool):
        raise ValueError(f"{value!r} is not an object index")
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        text = value.strip().lower()
        text = text[:-1] if text.endswith("h") else text
        try:
            return int(text, 16)
        except ValueError:
            pass
    raise ValueError(f"{value!r} is not an object index (write 0x6000, '0x6000' or '6000h')")


class ObjectKey(NamedTuple):
    """An object index and sub-index."""

    index: int  # type: ignore[assignment]  # why: CiA's name; the field shadows tuple.index (as it always has)
    sub: int = 0

    @classmethod
    def parse(cls, value: Any) -> ObjectKey:
        """'0x2348.1' / '0x1800.02' (sub-index decimal or 0x-hex), an index alone, or [index, sub]."""
        if isinstance(value, ObjectKey):
            return value
        if isinstance(value, (list, tuple)) and len(value) == 2:
            return cls(parse_index(value[0]), int(value[1]))
        if isinstance(value, str) and "." in value:
            index, _, sub = value.partition(".")
            try:
                return cls(parse_index(index), int(sub, 0) if sub.lower().startswith("0x") else int(sub))
            except ValueError:
                raise ValueError(f"{value!r} is not an object key (write '0x1800.2')") from None
        return cls(parse_index(value), 0)

    def __str__(self) -> str:
        return f"0x{self.index:04X}.{self.sub}"


#: a pydantic field type: an object index written any of the ways parse_index accepts
ObjectIndex = Annotated[int, BeforeValidator(parse_index)]
#: a pydantic field type: an ObjectKey written any of the ways ObjectKey.parse accepts
ObjectKeyField = Annotated[ObjectKey, BeforeValidator(ObjectKey.parse), PlainSerializer(str)]
