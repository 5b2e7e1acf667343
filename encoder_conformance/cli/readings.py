"""Command line: ``encoder-conformance readings`` (the open points) and ``variant-matrix`` (every reading passes)."""

from __future__ import annotations

import argparse
import tempfile
import textwrap
from pathlib import Path

from encoder_conformance.cli import usage as usage
from encoder_conformance.cli.usage import positive_int


def _cmd_readings(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.open_points import all_readings

    for reading in all_readings():
        print(f"{reading.point}  (variant: {reading.variant}; suites: {', '.join(reading.modules)})")
        for label, text in (("open", reading.question), ("source", reading.source)):
            print(textwrap.fill(text, 110, initial_indent=f"  {label}: ", subsequent_indent="    "))
        for number, accepted in enumerate(reading.readings, 1):
            print(textwrap.fill(accepted, 110, initial_indent=f"  reading {number}: ", subsequent_indent="    "))
    return 0


def _cmd_variant_matrix(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.runs.variant_matrix import REPRESENTATIVE_PROFILES, format_runs, plan, run_variants

    for profile in args.profile:
        usage.check_profile("--profile", profile)
    usage.check_faults("--variant", args.variant)
    profiles = tuple(args.profile) or REPRESENTATIVE_PROFILES
    pairs = [(r, p) for r, p in plan(profiles) if not args.variant or r.variant in args.variant]
    with tempfile.TemporaryDirectory(prefix="variant-matrix-") as workdir:
        runs = run_variants(pairs, Path(workdir), workers=args.workers)
    print(format_runs(runs))
    return 0 if all(run.ok for run in runs) else 1


def add_readings_parsers(sub: argparse._SubParsersAction) -> None:
    """The ``readings`` and ``variant-matrix`` commands."""
    readings = sub.add_parser("readings", help="the points where CiA or a manual allows more than one behaviour: "
                                               "the source sentence, the readings accepted, the twin variant")
    readings.set_defaults(func=_cmd_readings)
    matrix = sub.add_parser("variant-matrix", help="run the suites against each conformant variant of the twin "
                                                   "on each profile where it applies (exit 1 on a false failure)")
    matrix.add_argument("--profile", action="append", default=[],
                        help="profile id or file (repeat; default: one per family and the self-test profiles)")
    matrix.add_argument("--variant", action="append", default=[], help="only these variants (repeat)")
    matrix.add_argument("--workers", type=positive_int, default=2, help="suite runs in parallel (default 2)")
    matrix.set_defaults(func=_cmd_variant_matrix)
