"""``faults``, ``fault-matrix``, ``repeat``: the twin's faults, and many runs against it."""

from __future__ import annotations

import argparse
from pathlib import Path

from encoder_conformance.cli import usage
from encoder_conformance.cli.usage import positive_int
from encoder_conformance.paths import DEFAULT_PROFILE


def _cmd_fault_matrix(args: argparse.Namespace, extra: list[str]) -> int:
    import tempfile

    from encoder_conformance.profile.loader import load_profile
    from encoder_conformance.runs.fault_matrix import format_matrix, run_matrix
    from encoder_conformance.sim.fault_catalogue import faults_for

    usage.check_profile("--profile", args.profile)
    usage.check_faults("--fault", args.fault)  # before the baseline run: a typo must not cost its 12 s
    faults = args.fault or faults_for(load_profile(args.profile).profile.effects)
    with tempfile.TemporaryDirectory(prefix="fault-matrix-") as workdir:
        baseline, results = run_matrix(args.profile, faults, Path(workdir), args.select, workers=args.workers,
                                       targeted=args.targeted)
    print(format_matrix(baseline, results))
    broken = {n for n, o in baseline.outcomes.items() if o in ("failed", "error", "internal")}
    uncaught = [t for t in baseline.keys_with("passed")
                if not any(t in r.keys_with("failed") | r.keys_with("error") for r in results)]
    if broken:
        print(f"the fault-free twin fails {len(broken)} test(s): {sorted(broken)[:10]}")
    if uncaught:
        print(f"{len(uncaught)} test(s) no fault makes fail: {uncaught}")
    return 1 if broken or uncaught else 0


def _cmd_repeat(args: argparse.Namespace, extra: list[str]) -> int:
    import tempfile

    from encoder_conformance.runs.repeat import repeat_runs

    usage.check_profile("--profile", args.profile)
    usage.check_faults("--variant", [args.variant] if args.variant else [])
    with tempfile.TemporaryDirectory(prefix="repeat-") as workdir:
        result = repeat_runs(args.profile, args.runs, Path(workdir), args.select, args.parallel, args.busy,
                             args.variant)
    print(result.format())
    return 1 if result.failing() else 0


def _cmd_faults(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.sim.fault_catalogue import FAULTS, VARIANTS

    for name, text in sorted(FAULTS.items()):
        print(f"{name:32s} {text}")
    print("\nconformant variants (a CiA-conformant device against a rule the profile only infers):")
    for name, text in sorted(VARIANTS.items()):
        print(f"{name:32s} {text}")
    return 0


def add_fault_parsers(sub: argparse._SubParsersAction) -> None:
    """``faults``, ``fault-matrix``, ``repeat``: the twin's faults, and many runs against it."""
    matrix = sub.add_parser("fault-matrix", help="run the suites once per fault: which tests catch which fault")
    matrix.add_argument("--profile", default=DEFAULT_PROFILE)
    matrix.add_argument("--fault", action="append", default=[],
                        help="only these faults (default: every fault that can show on the profile)")
    matrix.add_argument("-k", dest="select", help="pytest -k expression selecting the tests")
    matrix.add_argument("--workers", type=positive_int, default=2, help="suite runs in parallel (default 2)")
    matrix.add_argument("--targeted", action="store_true",
                        help="run each fault only against the suite modules it is made for (faster)")
    matrix.set_defaults(func=_cmd_fault_matrix)

    repeat = sub.add_parser("repeat", help="repeat a run against the twin, several at a time: which verdicts are "
                                           "stable (timing limits on a loaded PC)")
    repeat.add_argument("--profile", default=DEFAULT_PROFILE)
    repeat.add_argument("--runs", type=positive_int, default=20, help="runs in all (default 20)")
    repeat.add_argument("--parallel", type=positive_int, default=2, help="runs at a time (default 2)")
    repeat.add_argument("--busy", action="store_true", help="beside a process that keeps one core busy")
    repeat.add_argument("-k", dest="select", help="pytest -k expression selecting the tests")
    repeat.add_argument("--variant", help="the twin plays this conformant variant ('readings' lists them)")
    repeat.set_defaults(func=_cmd_repeat)

    faults = sub.add_parser("faults", help="list the simulator's named faults")
    faults.set_defaults(func=_cmd_faults)
