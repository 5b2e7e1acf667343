"""Every reading the texts allow passes: the suites against each conformant variant of the twin.

The open readings (encoder_conformance/open_points/) list each point where CiA or a manual leaves a choice,
with the sentence it comes from; each has a variant of the twin that plays the reading the default twin
does not. Here every variant runs against the suite modules its point concerns, on every representative
profile where it applies: 0 failures, and at least one test judged per run.
"""

from __future__ import annotations

import re

import pytest

from encoder_conformance.open_points import all_readings
from encoder_conformance.paths import SUITES_DIR
from encoder_conformance.runs.variant_matrix import (
    REPRESENTATIVE_PROFILES,
    combine,
    format_runs,
    in_plan_order,
    plan,
    run_shared,
)
from encoder_conformance.sim.fault_catalogue import FAULTS, TARGET_MODULES, VARIANTS

#: its sessions run ahead (tests/runs_ahead.py): the foreground keeps no slot of the background's
FOREGROUND_SLOTS = 0

#: a source a vendor can look up: a CiA document with its version and a section or table, or a manual's section
_CITABLE = re.compile(r"(CiA 30[1-9]|CiA 4\d\d)( v\d[\d.]*)? (§|table |figure )\d|manual|M §|§\d")


def test_every_reading_is_complete_and_citable():
    """Each point says what is open, where the text says so, which readings pass, and what plays the other."""
    problems = []
    for reading in all_readings():
        if len(reading.readings) < 2:
            problems.append(f"{reading.point}: fewer than two readings")
        if not _CITABLE.search(reading.source):
            problems.append(f"{reading.point}: source names no document and section: {reading.source!r}")
        if re.search(r"\w+\.(md|py|yaml|txt)\b|reference/|seeds/", reading.source):
            problems.append(f"{reading.point}: source names a file of this repository: {reading.source!r}")
        missing = [m for m in reading.modules if not (SUITES_DIR / f"{m}.py").exists()]
        if missing or not reading.modules:
            problems.append(f"{reading.point}: suite modules {missing or 'none'} do not exist")
        if reading.variant in FAULTS:
            problems.append(f"{reading.point}: variant {reading.variant} is also a fault")
    assert problems == []
    assert len({r.point for r in all_readings()}) == len(all_readings()), "a point id is used twice"


def test_every_variant_is_in_the_catalogue_with_its_modules():
    for reading in all_readings():
        assert VARIANTS[reading.variant] == reading.variant_text
        assert TARGET_MODULES[reading.variant] == reading.modules


def test_every_reading_applies_to_some_representative_profile():
    """A reading no profile can play is never tried: the matrix would prove nothing about it."""
    planned = {reading.point for reading, _ in plan()}
    assert sorted({r.point for r in all_readings()} - planned) == []


def sessions_ahead(runs) -> dict:
    """The variant matrix's runs (runs/variant_matrix.py run_variants: the readings combine puts on one twin)."""
    workdir = runs.mktemp("variants")
    return {("variants", profile, tuple(r.point for r in readings)):
            lambda profile=profile, readings=readings: run_shared(profile, readings, workdir)
            for profile, readings in combine(plan(REPRESENTATIVE_PROFILES))}


@pytest.fixture(scope="module")
def variant_runs(runs_ahead):
    """As run_variants, most runs made ahead."""
    return in_plan_order(plan(REPRESENTATIVE_PROFILES), runs_ahead.results(sessions_ahead(runs_ahead)).values())


def test_every_conformant_variant_passes_on_every_profile_where_it_applies(variant_runs):
    print(format_runs(variant_runs))
    failing = [f"{run.reading.variant} on {run.profile}: {run.bad or f'exit {run.result.returncode}'}"
               f"{'' if run.judged else ' (no test judged)'}" for run in variant_runs if not run.ok]
    assert failing == [], format_runs(variant_runs)


def test_readings_share_a_twin_only_where_no_variant_hides_another():
    """combine(): every (reading, profile) runs exactly once; readings on one twin override no method in common
    (a mixin in front would hide the other's), and a shared twin plays one profile."""
    from encoder_conformance.sim.twin import overridden_methods

    pairs = plan(REPRESENTATIVE_PROFILES)
    runs = combine(pairs)
    assert sorted((r.point, p) for p, readings in runs for r in readings) == sorted((r.point, p) for r, p in pairs)
    for profile, readings in runs:
        taken: set[tuple[str, str]] = set()
        for reading in readings:
            overridden = overridden_methods(reading.variant)
            assert overridden, f"{reading.variant}: no mixin found (is every behaviour imported?)"
            assert not overridden & taken, f"{reading.variant} on {profile} shares a method with another variant"
            taken |= overridden
    assert len(runs) < len(pairs), "no two readings ever share a twin"
