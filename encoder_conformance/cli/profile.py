"""``profile validate | list | effects | from-eds | to-eds``: device profiles on the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from encoder_conformance.cli import usage
from encoder_conformance.cli.usage import UsageError
from encoder_conformance.cli.usage import node_id_arg as node_id_type
from encoder_conformance.errors import ProfileError
from encoder_conformance.exit_codes import RunExit


def _cmd_profile_validate(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.profile.loader import load_profile

    status = 0
    for name in usage.profile_files(args.files):
        try:  # every file is checked and every problem shown, also after one that is missing
            usage.check_profile("profile", name)
        except UsageError as exc:
            print(f"encoder-conformance profile: {exc}", file=sys.stderr)
            status = RunExit.USAGE_ERROR
            continue
        try:
            loaded = load_profile(name)
        except ProfileError as exc:
            print(exc, file=sys.stderr)
            status = status or 1
            continue
        profile = loaded.profile
        open_todos = f", {len(profile.todo)} assumptions unconfirmed (todo:)" if profile.todo else ""
        print(f"{loaded.path}: ok ({profile.id}, {len(profile.iter_entries())} entries, "
              f"{len(profile.quirks)} quirks, sha256 {loaded.sha256[:12]}{open_todos})")
        if args.todo:
            for number, todo in enumerate(profile.todo, 1):
                print(f"  TODO {number}: {todo}")
    return status


def _cmd_profile_effects(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.profile.quirks import effect_table

    print(effect_table(), end="")
    return 0


def _cmd_profile_list(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.profile.loader import iter_own_profiles, iter_profile_ids, load_profile

    own = list(iter_own_profiles(Path.cwd()))
    for ref in [*iter_profile_ids(), *own]:
        try:
            title = load_profile(ref.path).profile.title
        except ProfileError as exc:
            title = f"INVALID: {exc.problems[0]}"
        where = f"(./{ref.path.relative_to(Path.cwd())}) " if ref in own else ""
        print(f"{ref.id:40s} {where}{'(abstract) ' if ref.abstract else ''}{title}")
    return 0


def _cmd_profile_from_eds(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.profile.eds import profile_draft_from_eds, write_profile_draft

    eds = Path(args.eds)
    if not eds.is_file():
        print(f"from-eds: {eds}: no such file; give the path of the device's EDS", file=sys.stderr)
        return RunExit.USAGE_ERROR
    out = Path(args.output) if args.output else None
    usage.check_output_file("-o", out)
    # without --id the id follows the output file's name: a profile's id must equal its file name
    profile_id = args.id or (out.stem if out is not None else None)
    try:
        draft, todos = profile_draft_from_eds(eds, profile_id)
    except (OSError, ValueError) as exc:
        print(f"from-eds: {eds}: {exc}", file=sys.stderr)
        return 1
    out = out or Path(f"{draft['id']}.yaml")
    if out.stem != draft["id"]:
        print(f"from-eds: --id {draft['id']} and -o {out}: a profile's id must equal its file name; give one "
              f"of them only, or make them agree", file=sys.stderr)
        return RunExit.USAGE_ERROR
    if out.exists() and not args.force:
        print(f"from-eds: {out} exists; not overwritten (pass --force to replace it)", file=sys.stderr)
        return RunExit.USAGE_ERROR
    given = [name for name in ("can_interface", "can_channel", "can_bitrate", "node_id", "no_reset")
             if getattr(args, name)]
    if given and not args.probe:
        print(f"from-eds: --{given[0].replace('_', '-')} is an option of the live probe; add --probe (or leave it "
              "out)", file=sys.stderr)
        return RunExit.USAGE_ERROR
    if args.probe:
        probed = _probe(args, draft, todos)
        if isinstance(probed, int):
            return probed
        todos = probed
    write_profile_draft(draft, out, todos)
    print(f"wrote {out} ({len(draft.get('objects', {}))} objects); {len(todos)} assumptions to confirm against "
          f"the manual (listed under todo:, and by `profile validate --todo`):")
    for number, todo in enumerate(todos, 1):
        print(f"  TODO {number}: {todo}")
    _print_warnings(eds, todos)
    return int(getattr(args, "exit_status", RunExit.PASSED))  # the probe's: 70 where a value did not come back


def _print_warnings(eds: Path, todos: list[str]) -> None:
    """The EDS's inconsistencies and what the device contradicts (todos that are warnings), on stderr as well."""
    from encoder_conformance.profile.eds.consistency import WARNING

    for number, todo in enumerate(todos, 1):
        if todo.startswith(WARNING):
            print(f"from-eds: {eds.name}: WARNING (TODO {number}): {todo.removeprefix(WARNING)}", file=sys.stderr)


def _probe(args: argparse.Namespace, draft: dict, todos: list[str]) -> list[str] | int:
    """The live probe's corrections to ``draft``: the todos after it, or an exit code."""
    from encoder_conformance.cli.probe_outcome import vanished
    from encoder_conformance.errors import BusSetupError, DutLostError
    from encoder_conformance.probe.session import ProbeOptions, probe_device

    bus = usage.bench_bus(args, "--probe asks a live device")
    node_id = args.node_id or draft["bus"]["node_id"]
    options = ProbeOptions(bus, node_id, reset=not args.no_reset)
    try:
        result = probe_device(draft, todos, options, say=lambda text: print(text, flush=True))
    except (DutLostError, BusSetupError) as exc:
        print(f"from-eds --probe: {exc}; nothing written", file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    findings = result.findings
    gone = vanished(options, findings)
    if gone is not None:
        print(f"from-eds --probe: {gone}", file=sys.stderr)
        return RunExit.COULD_NOT_TEST
    print(f"probe: node {node_id}, {result.requests} SDO requests in {result.seconds:.1f} s"
          + (f", boot-up {findings.boot_up_ms:.0f} ms after reset node" if findings.boot_up_ms is not None else "")
          + ("; every value written was put back and read back" if result.restored else ""))
    if not result.restored:
        for failure in findings.put_back_failures:
            print(f"from-eds --probe: NOT PUT BACK: {failure}", file=sys.stderr)
    args.exit_status = RunExit.PASSED if result.restored else RunExit.NOT_RESTORED
    return result.todos


def _cmd_profile_to_eds(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.profile.eds import export_eds
    from encoder_conformance.profile.loader import load_profile

    usage.check_profile("profile", args.profile)
    loaded = load_profile(args.profile)
    out = Path(args.output or f"{loaded.profile.id}.eds")
    usage.check_output_file("-o", out)
    export_eds(loaded.profile, out, args.node_id)
    print(f"wrote {out}")
    return 0


def add_profile_parser(sub: argparse._SubParsersAction) -> None:
    """``profile validate | list | effects | from-eds | to-eds``: device profiles on the command line."""
    profile = sub.add_parser("profile", help="validate, list, import from EDS, export to EDS")
    psub = profile.add_subparsers(dest="profile_command", required=True)
    validate = psub.add_parser("validate", help="check profile files and print every problem")
    validate.add_argument("files", nargs="+", metavar="FILE_OR_FOLDER",
                          help="profile files, or folders (every *.yaml in them)")
    validate.add_argument("--todo", action="store_true",
                          help="also list each profile's unconfirmed assumptions (todo:), numbered")
    validate.set_defaults(func=_cmd_profile_validate)
    listing = psub.add_parser("list", help="the shipped profiles, then your own in the current folder and its "
                                               "device_profiles/ (with their paths)")
    listing.set_defaults(func=_cmd_profile_list)
    effects = psub.add_parser("effects", help="the quirk effects and their parameters (a markdown table)")
    effects.set_defaults(func=_cmd_profile_effects)
    from_eds = psub.add_parser("from-eds", help="write a profile draft from a vendor EDS")
    from_eds.add_argument("eds")
    from_eds.add_argument("--id", help="profile id (default: the output file's name, else the EDS file's name)")
    from_eds.add_argument("-o", "--output", help="profile file to write (default: ID.yaml); its name is the id")
    from_eds.add_argument("--force", action="store_true", help="replace an existing output file")
    probe = from_eds.add_argument_group(
        "live probe", "--probe asks the device what the EDS cannot say (entries that exist, sizes, values that change "
        "across a reset, transmission types, abort codes, LSS services, block transfer, SYNC producer, guarding). "
        "Read-only: what it writes it puts back and reads back. It resets the device once (--no-reset: not)")
    probe.add_argument("--probe", action="store_true", help="correct the draft by probing the live device")
    probe.add_argument("--can-interface", help="python-can interface of the bus the device is on")
    probe.add_argument("--can-channel", help="python-can channel")
    probe.add_argument("--can-bitrate", type=usage.bitrate, help="bit rate in bit/s")
    probe.add_argument("--node-id", type=node_id_type, metavar="1..127",
                       help="the device's node-ID (default: the EDS's, else 1)")
    probe.add_argument("--no-reset", action="store_true",
                       help="do not reset the device (values that change only at a reset are not found)")
    from_eds.set_defaults(func=_cmd_profile_from_eds)
    to_eds = psub.add_parser("to-eds", help="export a profile as an EDS")
    to_eds.add_argument("profile")
    to_eds.add_argument("-o", "--output")
    to_eds.add_argument("--node-id", type=node_id_type, metavar="1..127")
    to_eds.set_defaults(func=_cmd_profile_to_eds)
