"""Which tests apply: profile-driven parametrisation, capability skips, destructive gates."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from encoder_conformance.coverage import Kind
from encoder_conformance.plugin.options import settings_of
from encoder_conformance.plugin.skips import not_selected
from encoder_conformance.profile.schema import Capabilities, DeviceProfile, EntrySpec
from encoder_conformance.profile.value_domain import probe_values

#: fixture name -> which profile entries it is parametrised with
ENTRY_FIXTURES = {
    "od_entry": lambda e: True,
    "readable_entry": lambda e: e.readable,
    "read_only_entry": lambda e: e.access in ("ro", "const") and not e.no_data,
    "write_only_entry": lambda e: e.access == "wo" and not e.no_data,
    "default_entry": lambda e: e.checks_default,
}
#: fixture name -> which entries, where the choice needs the profile: (profile, index, sub, entry)
PROFILE_ENTRY_FIXTURES = {
    "value_domain_entry": lambda p, i, s, e: e.writable and bool(probe_values(p, i, s)),
}
EMPTY_REASON = {
    "od_entry": "the profile declares no objects",
    "readable_entry": "the profile declares no readable objects",
    "read_only_entry": "the profile declares no read-only objects",
    "write_only_entry": "the profile declares no write-only objects",
    "default_entry": "the profile declares no factory defaults to check",
    "value_domain_entry": "the profile declares no writable entry with a restricted value domain (min/max/allowed)",
}


def entry_id(index: int, sub: int, entry: EntrySpec) -> str:
    """Test ids that read as sentences: '0x6001.00 Measuring units per revolution'."""
    return f"0x{index:04X}.{sub:02X} {entry.name}"


def _selectors() -> dict[str, Callable[[DeviceProfile, int, int, EntrySpec], bool]]:
    by_entry = {name: (lambda w: lambda p, i, s, e: w(e))(wanted) for name, wanted in ENTRY_FIXTURES.items()}
    return {**by_entry, **PROFILE_ENTRY_FIXTURES}


def parametrize_from_profile(metafunc: pytest.Metafunc) -> None:
    profile = settings_of(metafunc.config).loaded.profile
    for fixture, wanted in _selectors().items():
        if fixture not in metafunc.fixturenames:
            continue
        params = [
            pytest.param((index, sub, obj, entry), id=entry_id(index, sub, entry))
            for index, sub, obj, entry in profile.iter_entries()
            if wanted(profile, index, sub, entry)
        ]
        if not params:
            reason = f"{Kind.NOT_APPLICABLE.value}: {EMPTY_REASON[fixture]}"
            params = [pytest.param(None, id="none", marks=pytest.mark.skip(reason=reason))]
        metafunc.parametrize(fixture, params)


def _capability_present(capabilities: Capabilities, name: str) -> bool:
    value = getattr(capabilities, name)
    return bool(value)


def apply_capability_marks(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip tests whose ``requires(...)`` capabilities the profile lacks (reason names them)."""
    profile = settings_of(config).loaded.profile
    known = set(Capabilities.model_fields)
    for item in items:
        wanted: list[str] = []
        for mark in item.iter_markers("requires"):
            if not mark.args or not all(isinstance(a, str) for a in mark.args):
                raise pytest.UsageError(
                    f"{item.nodeid}: use pytest.mark.requires('capability', ...) with capability names"
                )
            wanted += mark.args
        unknown = [w for w in wanted if w not in known]
        if unknown:
            raise pytest.UsageError(
                f"{item.nodeid}: unknown capability {', '.join(unknown)}; known: {', '.join(sorted(known))}"
            )
        missing = [w for w in wanted if not _capability_present(profile.capabilities, w)]
        if missing:
            item.add_marker(pytest.mark.skip(
                reason=f"not applicable: profile {profile.id} lacks capability {', '.join(missing)} "
                       f"(capabilities.{missing[0]} in {settings_of(config).loaded.path.name})"
            ))


def destructive_last(items: list[pytest.Item]) -> None:
    """Tests that change what the device remembers run after all others (stable order otherwise).

    A run stopped half-way has then changed as little as possible, and the factory-default checks
    of a device in delivery state see it before any test stored something.
    """
    items.sort(key=lambda item: item.get_closest_marker("destructive") is not None)


def check_gates(item: pytest.Item) -> None:
    """Destructive tests need --allow-destructive on hardware."""
    settings = settings_of(item.config)
    if item.get_closest_marker("destructive") and not settings.allow_destructive:
        not_selected("destructive (changes what the device remembers): run with --allow-destructive")

