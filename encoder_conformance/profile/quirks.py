"""Profile quirks: a documented deviation, optionally with an effect the simulator and suites act on.

``Quirk`` is a quirk chosen by its ``effect``: a quirk with an effect carries that effect's typed
parameters (``quirk_effects.py``); a quirk without one is documentation only (free-form params),
yet it still appears in the report as a documented deviation. ``effect_table()`` renders the
effects for device_profiles/README.md, so the table can never drift from the models.

Each effect's quirk class is made the first time a quirk names the effect (``quirk_class``), not at import: the
44 classes and a union of them cost ~0.15 s of every run's start-up, and a profile uses a handful. A quirk is
validated by its own class (a validation error keeps its location under the quirk's key).
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING, Annotated, Any, Literal, TypeAlias

from pydantic import BaseModel, ConfigDict, Field, PlainValidator, TypeAdapter, create_model
from pydantic_core import PydanticCustomError

from encoder_conformance.profile.quirk_effects import EFFECT_MODELS, EffectParams

DOCUMENTATION_ONLY = "none"  # the union tag of a quirk without an effect


class QuirkBase(BaseModel):
    """A documented deviation of this device from the CiA texts (or an ambiguity we resolved)."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)

    title: str
    manual: str = Field(description="manual section that documents the behaviour")
    deviates_from: str | None = Field(default=None, description="the CiA clause the device departs from")
    description: str
    effect: str | None = Field(default=None, description="behaviour the simulator and suites act on")
    params: Any = None


class DocumentedQuirk(QuirkBase):
    """A quirk without an effect: documentation (its params may hold values for a proposed effect)."""

    effect: None = None
    params: dict[str, Any] = Field(default_factory=dict)


def _quirk_class(model: type[EffectParams]) -> type[QuirkBase]:
    try:
        default: Any = model()
    except ValueError:
        default = ...  # the effect has required parameters
    # a Literal of a value known only at run time: a type to pydantic, an ordinary value to the checker
    effect_type: Any = Literal[model.effect]
    return create_model(
        f"{model.__name__}Quirk",
        __base__=QuirkBase,
        __doc__=model.__doc__,
        effect=(effect_type, ...),
        params=(model, default),
    )


@cache
def quirk_class(effect: str) -> type[QuirkBase]:
    """The quirk class of an effect (KeyError for an unknown one), made at its first use."""
    return _quirk_class(EFFECT_MODELS[effect])


def _effect_tag(value: Any) -> str:
    effect = value.get("effect") if isinstance(value, dict) else getattr(value, "effect", None)
    return DOCUMENTATION_ONLY if effect is None else str(effect)


def _validate_quirk(value: Any) -> QuirkBase:
    """A quirk by its effect's class; an effect no model names is an ``unknown_effect`` error."""
    if isinstance(value, QuirkBase):
        return value
    tag = _effect_tag(value)
    if tag == DOCUMENTATION_ONLY:
        return DocumentedQuirk.model_validate(value)
    if tag not in EFFECT_MODELS:
        raise PydanticCustomError("unknown_effect",
                                  f"unknown quirk effect; known effects: {', '.join(sorted(EFFECT_MODELS))}")
    return quirk_class(tag).model_validate(value)  # its errors keep their locations, under the quirk's key


if TYPE_CHECKING:
    # The checker cannot follow a class chosen at run time: to it, a quirk is what every class is, a QuirkBase.
    Quirk: TypeAlias = QuirkBase
else:
    Quirk = Annotated[QuirkBase, PlainValidator(_validate_quirk)]
_QUIRK: TypeAdapter[QuirkBase] = TypeAdapter(Quirk)


def parse_quirk(data: dict[str, Any]) -> QuirkBase:
    """A quirk from its mapping (as a profile writes it)."""
    return _QUIRK.validate_python(data)


#: effect -> its one-line meaning (the model's docstring)
EFFECTS: dict[str, str] = {name: " ".join((model.__doc__ or "").split()) for name, model in EFFECT_MODELS.items()}


def effect_table() -> str:
    """The effects and their parameters as a markdown table (device_profiles/README.md)."""
    rows = ["| effect | what the device does | params |", "|---|---|---|"]
    for name, model in sorted(EFFECT_MODELS.items()):
        params = []
        for field, info in model.model_fields.items():
            description = info.description or ""
            if description.startswith("documentation only"):
                continue
            required = "" if not info.is_required() else " (required)"
            params.append(f"`{field}`{required}: {description}")
        rows.append(f"| `{name}` | {EFFECTS[name]} | {'<br>'.join(params) or '-'} |")
    return "\n".join(rows) + "\n"
