"""``restore --from SNAPSHOT``: its arguments (the work, which imports the DUT layer, is in restore_actions.py)."""

from __future__ import annotations

import argparse
from pathlib import Path

from encoder_conformance.cli import usage
from encoder_conformance.cli.usage import bus_arguments


def _cmd_restore(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.cli.restore_actions import RestoreRequest, restore_from_snapshot

    bus = usage.bench_bus(args, "a built-in simulator has nothing to restore")
    request = RestoreRequest(Path(args.snapshot), bus, args.node_id, args.timeout, args.force, args.power_on_cmd,
                             args.power_off_cmd)
    return restore_from_snapshot(request)


def add_restore_parser(sub: argparse._SubParsersAction) -> None:
    """``restore --from SNAPSHOT``: put a device back as a run's snapshot found it."""
    restore = sub.add_parser("restore", help="put a device back as a run's snapshot found it (after a crash)")
    restore.add_argument("--from", dest="snapshot", required=True,
                         help="the run's device-snapshot.json (in its report directory)")
    bus_arguments(restore)
    restore.add_argument("--timeout", type=float, default=60.0, help="seconds the restore may take (default 60)")
    restore.add_argument("--power-on-cmd", help="shell command that switches the device on first (a crash during "
                         "a power cycle leaves it off)")
    restore.add_argument("--power-off-cmd", help="shell command that switches the device off: with --power-on-cmd, "
                         "lets the restore power-cycle a device that applies an LSS node-ID only at power-on")
    restore.add_argument("--force", action="store_true",
                         help="restore even if the device's serial number differs from the snapshot's")
    restore.set_defaults(func=_cmd_restore)
