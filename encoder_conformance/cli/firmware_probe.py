"""``firmware-ci --probe EDS``: the profile probed from the simulator firmware-ci started (the same command, bus and
restart handling as the run), kept in the report folder as an artifact, then the run's profile.

The probe is ``profile from-eds EDS --probe`` in a process of its own under the bus's environment (the user-space
bus reaches only processes started with it). A simulator that ends by itself meanwhile stops the probe at once
(exit 69, naming it); a probe that ends non-zero (69 device gone, 70 a value not put back) ends the job with its
code, and no run.
"""

from __future__ import annotations

import argparse
import contextlib
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from encoder_conformance.errors import UsageError
from encoder_conformance.exit_codes import DESCRIPTIONS, RunExit

PROBED_ID = "probed-profile"  # the artifact: <report>/probed-profile.yaml (a profile's id is its file's name)
POLL_S = 0.2  # how often the probe's process and the simulator's keeper are looked at


def check_probe(args: argparse.Namespace) -> int:
    """``--probe EDS`` given alone (not with ``--profile``) and readable: the EDS's node-ID (the probe's and the run's
    default); UsageError naming the option otherwise."""
    from encoder_conformance.profile.eds import profile_draft_from_eds

    if args.profile:
        raise UsageError(f"give --profile or --probe, not both (--probe {args.probe} writes the profile the run uses)")
    eds = Path(args.probe)
    if not eds.is_file():
        raise UsageError(f"--probe {eds}: no such file; give the path of your device's EDS")
    try:
        draft, _todos = profile_draft_from_eds(eds, PROBED_ID)
    except (OSError, ValueError) as exc:
        raise UsageError(f"--probe {eds}: not an EDS this tool can read: {exc}") from None
    return int(draft["bus"]["node_id"])


def probe(args: argparse.Namespace, node_id: int, report: Path, env: dict[str, str],
          simulator_exited: Callable[[], str | None]) -> Path | int:
    """Probe the running simulator; the probed profile's path, or the exit code to end the job with."""
    out = report / f"{PROBED_ID}.yaml"
    command = [sys.executable, "-m", "encoder_conformance", "profile", "from-eds", str(Path(args.probe).resolve()),
               "--probe", "--can-interface", "socketcan", "--can-channel", args.can_channel,
               "--node-id", str(node_id), "-o", str(out), "--force"]
    print(f"firmware-ci: probing node {node_id} with {args.probe}; the profile goes to {out}", file=sys.stderr)
    process = subprocess.Popen(command, env=env)
    exited = simulator_exited()
    while process.poll() is None and exited is None:
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(timeout=POLL_S)
        exited = simulator_exited()
    if exited is not None:
        _stop(process)
        print(f"firmware-ci: the simulator exited by itself during the probe ({exited}; see {env['FWCI_LOG']}): the "
              "probe resets the device once (NMT reset node), so a simulator that ends there must be restarted in a "
              f"loop (README \"Firmware CI\"); no profile, no run; exit {RunExit.COULD_NOT_TEST}: infrastructure",
              file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    if process.returncode != 0:
        status = RunExit.USAGE_ERROR if process.returncode == 1 else process.returncode  # 1: the EDS, not the device
        print(f"firmware-ci: the probe ended with {process.returncode} "
              f"({DESCRIPTIONS.get(status, 'see its output above')}); no run; exit {status}", file=sys.stderr)
        return status
    return out


def _stop(process: subprocess.Popen[bytes]) -> None:
    """End the probe (SIGTERM, then SIGKILL after its grace time)."""
    process.terminate()
    try:
        process.wait(timeout=5)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
