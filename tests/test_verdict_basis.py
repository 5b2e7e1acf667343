"""Verdicts say what they rest on; a device that breaks only a rule we inferred gets a warning, not a failure.

Issue 9: the WDGA manual lists the transmission types it supports and says nothing about type 0, which
CiA 301 allows. A twin that accepts every CiA 301 type (variant ``cia301_transmission_types``) must pass
with warnings by default and fail under --strict-inferred.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from encoder_conformance.profile.loader import load_profile
from encoder_conformance.profile.value_domain import refusal_basis
from tests.suite_session import run_suite

WDGA = "wachendorff-wdga-mt"
VARIANT = ["--ec-profile", WDGA, "--ec-sim-fault", "cia301_transmission_types"]
SELECTION = [*VARIANT, "-k", "value_domain"]


def _properties(junit: Path) -> dict[str, list[tuple[str, str]]]:
    return {
        case.get("name", ""): [(p.get("name", ""), p.get("value", "")) for p in case.iter("property")]
        for case in ET.parse(junit).getroot().iter("testcase")
    }


def test_refusal_basis_of_transmission_types_and_manual_ranges():
    profile = load_profile(WDGA).profile
    assert refusal_basis(profile, 0x1800, 2, 0)[0] == "inferred"  # the manual does not list type 0
    assert refusal_basis(profile, 0x1800, 2, 241)[0] == "cia"  # reserved by CiA 301 table 72 (issue 40)
    assert refusal_basis(profile, 0x1800, 2, 253)[0] == "inferred"  # CiA's, and not in the manual's list
    assert refusal_basis(profile, 0x2101, 0, 0)[0] == "manual"  # node-ID range printed in the manual


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The value-domain suite against a CiA-conformant WDGA twin: as by default, and strict."""
    default = run_suite(tmp_path_factory.mktemp("default"), *SELECTION)[0]
    strict_folder = tmp_path_factory.mktemp("strict")
    strict = run_suite(strict_folder, *SELECTION, "--ec-strict")[0]
    return default, strict


def test_conformant_device_passes_with_warnings(runs):
    default, _ = runs
    assert default.returncode == 0, default.output[-3000:]
    assert "warnings: rules we only inferred were broken" in default.output
    assert "inferred: 4 warning" in default.output
    assert "[inferred: capabilities.tpdo_transmission_types (refusal: inferred)]" in default.output


def test_strict_inferred_fails_the_same_device(runs):
    _, strict = runs
    assert strict.returncode == 1, strict.output[-3000:]
    assert "inferred: 4 failed" in strict.output


def test_junit_carries_basis_and_warning(tmp_path):
    completed = run_suite(tmp_path, *VARIANT, "-k", "value_domain and 1800")[0]
    assert completed.returncode == 0, completed.output[-3000:]
    properties = _properties(tmp_path / "report" / "junit.xml")
    case = next(v for k, v in properties.items() if "0x1800.02" in k)
    assert ("verdict", "warning") in case
    assert ("verdict_basis", "inferred") in case
    assert any(name == "inferred_problem" and "1800h.02" in value for name, value in case)


def test_abort_code_family_mode(tmp_path):
    """A device answering a write to a read-only entry with 06010000h (the family of 06010002h) fails
    with exact abort codes and passes with --abort-codes family, which notes the family match."""
    selection = ["--ec-profile", WDGA, "--ec-sim-fault", "write_ro_unsupported_access", "-k",
                 "test_read_only_entry_refuses_write and 0x1000"]
    exact = run_suite(tmp_path / "exact", *selection)[0]
    assert exact.returncode == 1, exact.output[-3000:]
    family = run_suite(tmp_path / "family", *selection, "--ec-abort-codes", "family")[0]
    assert family.returncode == 0, family.output[-3000:]
    report = (tmp_path / "family" / "report" / "report.html").read_text(encoding="utf-8")
    assert "family (--abort-codes)" in report  # the mode is in the report's environment table
    assert "accepted by family" in report  # and the test's evidence says what was accepted


def test_run_strict_maps_to_the_prefixed_strict(monkeypatch):
    """`encoder-conformance run --strict` asks pytest for --ec-strict (pytest's own --strict is another thing)."""
    from encoder_conformance.cli import main as cli
    from encoder_conformance.plugin import interrupt

    seen: list[list[str]] = []
    monkeypatch.setattr(interrupt, "catch_early", lambda: None)  # this process keeps its own signal handling
    monkeypatch.setattr(pytest, "main", lambda argv: seen.append(argv) or 0)
    assert cli.main(["run", "--profile", WDGA, "--strict"]) == 0
    assert "--ec-strict" in seen[0]
    assert "--strict" not in seen[0]
