"""CANopen data-type names used in profiles, mapped to canopen's type codes and sizes."""

from __future__ import annotations

from functools import lru_cache

from canopen.objectdictionary import datatypes as dt

#: Canonical CiA 301 names -> canopen data-type code.
CANONICAL: dict[str, int] = {
    "BOOLEAN": dt.BOOLEAN,
    "INTEGER8": dt.INTEGER8,
    "INTEGER16": dt.INTEGER16,
    "INTEGER24": dt.INTEGER24,
    "INTEGER32": dt.INTEGER32,
    "INTEGER40": dt.INTEGER40,
    "INTEGER48": dt.INTEGER48,
    "INTEGER56": dt.INTEGER56,
    "INTEGER64": dt.INTEGER64,
    "UNSIGNED8": dt.UNSIGNED8,
    "UNSIGNED16": dt.UNSIGNED16,
    "UNSIGNED24": dt.UNSIGNED24,
    "UNSIGNED32": dt.UNSIGNED32,
    "UNSIGNED40": dt.UNSIGNED40,
    "UNSIGNED48": dt.UNSIGNED48,
    "UNSIGNED56": dt.UNSIGNED56,
    "UNSIGNED64": dt.UNSIGNED64,
    "REAL32": dt.REAL32,
    "REAL64": dt.REAL64,
    "VISIBLE_STRING": dt.VISIBLE_STRING,
    "OCTET_STRING": dt.OCTET_STRING,
    "UNICODE_STRING": dt.UNICODE_STRING,
    "DOMAIN": dt.DOMAIN,
}

#: Short spellings as the manuals print them (U32, S16, I32, string ...).
ALIASES: dict[str, str] = {
    "BOOL": "BOOLEAN",
    **{f"U{n}": f"UNSIGNED{n}" for n in (8, 16, 24, 32, 40, 48, 56, 64)},
    **{f"I{n}": f"INTEGER{n}" for n in (8, 16, 24, 32, 40, 48, 56, 64)},
    **{f"S{n}": f"INTEGER{n}" for n in (8, 16, 24, 32, 40, 48, 56, 64)},
    "STRING": "VISIBLE_STRING",
}

_SIZES_BITS: dict[str, int] = {
    "BOOLEAN": 8,  # transported as one byte over SDO
    **{f"INTEGER{n}": n for n in (8, 16, 24, 32, 40, 48, 56, 64)},
    **{f"UNSIGNED{n}": n for n in (8, 16, 24, 32, 40, 48, 56, 64)},
    "REAL32": 32,
    "REAL64": 64,
}

STRING_TYPES = frozenset({"VISIBLE_STRING", "OCTET_STRING", "UNICODE_STRING", "DOMAIN"})


@lru_cache(maxsize=256)  # asked for every value the twin encodes (TPDO payloads, position reads); ~40 names
def canonical_name(name: str) -> str:
    """Return the canonical CiA name of ``name`` or raise ValueError naming the choices."""
    upper = name.strip().upper()
    upper = ALIASES.get(upper, upper)
    if upper not in CANONICAL:
        choices = ", ".join(sorted(CANONICAL)) + " (or U8/U16/U32/I16/S32/... short forms)"
        raise ValueError(f"unknown data type {name!r}; use one of {choices}")
    return upper


@lru_cache(maxsize=256)
def size_bytes(name: str) -> int | None:
    """Size in bytes of a fixed-size type, None for strings and domains."""
    bits = _SIZES_BITS.get(canonical_name(name))
    return None if bits is None else bits // 8


def is_signed(name: str) -> bool:
    """True for INTEGERxx types."""
    return canonical_name(name).startswith("INTEGER")


def as_signed(name: str, value: int) -> int:
    """An integer as its type reads it: a SIGNED value kept in its unsigned (two's complement) form made negative."""
    size = size_bytes(name)
    if size and is_signed(name) and value >= 1 << (8 * size - 1):
        return value - (1 << (8 * size))
    return value


def value_range(name: str) -> tuple[int, int] | None:
    """Inclusive (min, max) representable by an integer type, None for others."""
    canon = canonical_name(name)
    size = size_bytes(canon)
    if size is None or canon.startswith("REAL"):
        return None
    if canon == "BOOLEAN":
        return 0, 1
    bits = size * 8
    if is_signed(canon):
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return 0, (1 << bits) - 1


def type_code(name: str) -> int:
    """canopen data-type code of ``name``."""
    return CANONICAL[canonical_name(name)]


def name_of_code(code: int) -> str:
    """Canonical name of a canopen data-type code."""
    for name, value in CANONICAL.items():
        if value == code:
            return name
    raise ValueError(f"unknown CANopen data-type code 0x{code:04X}")


#: string types whose profile (and EDS) default is written as hex bytes ("01 0A FF"), as CiA 306 and canopen
HEX_STRING_TYPES = frozenset({"OCTET_STRING", "DOMAIN"})


def parse_hex_bytes(text: str) -> bytes:
    """'01 0A ff', '010AFF' or '0x010AFF' as bytes; raises ValueError naming the text."""
    compact = "".join(text.split())
    if compact.lower().startswith("0x"):
        compact = compact[2:]
    try:
        return bytes.fromhex(compact)
    except ValueError:
        raise ValueError(f"{text!r} is not hex bytes (write OCTET_STRING/DOMAIN values as e.g. '01 0A FF')") from None


def string_bytes(name: str, text: str) -> bytes:
    """A string value as the device sends it: OCTET_STRING/DOMAIN from hex, UNICODE_STRING as UTF-16LE,
    VISIBLE_STRING as latin-1 (UTF-8 where a character lies outside latin-1, as some EDS files hold)."""
    canon = canonical_name(name)
    if canon in HEX_STRING_TYPES:
        return parse_hex_bytes(text)
    if canon == "UNICODE_STRING":
        return text.encode("utf-16-le")
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError:
        return text.encode("utf-8")
