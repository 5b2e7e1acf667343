"""Command line: ``encoder-conformance run | accept | restore | store | lss | sim | sim-control | profile | faults |
fault-matrix | readings | variant-matrix | vcan | firmware-ci``.

Exit codes of ``run``, ``restore`` and ``lss`` follow exit_codes.RunExit; a usage error (bad option,
unreadable profile) is 4 for every command; a command whose output pipe closed (``| head``) ends quietly with 141.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import os
import signal
import sys
import traceback
from collections.abc import Callable
from functools import partial

from encoder_conformance.cli import usage
from encoder_conformance.cli.accept import add_accept_parser
from encoder_conformance.cli.faults import add_fault_parsers
from encoder_conformance.cli.firmware_ci import add_firmware_ci_parser
from encoder_conformance.cli.history import add_history_parser
from encoder_conformance.cli.lss import add_lss_parser
from encoder_conformance.cli.profile import add_profile_parser
from encoder_conformance.cli.readings import add_readings_parsers
from encoder_conformance.cli.restore import add_restore_parser
from encoder_conformance.cli.run import add_run_parser
from encoder_conformance.cli.sim import add_sim_parsers
from encoder_conformance.cli.store import add_store_parser
from encoder_conformance.cli.usage import OneLineParser, UsageError, bus_arguments
from encoder_conformance.cli.vcan_command import add_vcan_parser
from encoder_conformance.errors import ProfileError
from encoder_conformance.exit_codes import RunExit, interrupted_by

#: the commands, in the order ``--help`` lists them: each module adds its parser(s), with ``func`` the handler
COMMANDS: tuple[Callable[[argparse._SubParsersAction], None], ...] = (
    add_run_parser,
    add_restore_parser,
    add_store_parser,
    partial(add_lss_parser, parser_class=OneLineParser, bus_arguments=bus_arguments),
    partial(add_history_parser, parser_class=OneLineParser),
    partial(add_accept_parser, bus_arguments=bus_arguments),
    add_firmware_ci_parser,
    add_sim_parsers,
    add_profile_parser,
    add_fault_parsers,
    add_readings_parsers,
    add_vcan_parser,
)
#: the commands that hand arguments they do not know on (to pytest, to the vcan program, to run)
PASS_ON_UNKNOWN = ("run", "vcan", "firmware-ci")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="encoder-conformance", description=__doc__,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    for add_command in COMMANDS:
        add_command(sub)
    return parser


#: the commands that run a pytest session of the suites in this process: the garbage collector pauses until its
#: tests are collected
GC_PAUSED = ("run", "accept")


def main(argv: list[str] | None = None) -> int:
    from encoder_conformance.plugin.interrupt import EARLY_SIGNALS, catch_early

    catch_early()  # a Ctrl-C during start-up must end the run, also where the interpreter drops the exception
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra and args.command not in PASS_ON_UNKNOWN:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    args.argv = list(sys.argv[1:] if argv is None else argv)  # as given: what parallel stations pass on
    if args.command in GC_PAUSED and len(getattr(args, "station", None) or ()) <= 1:
        # a run's start-up (~800 modules, pydantic's models, ~700 items) made ~190 garbage collections, 0.09-0.14 s
        # before its first test, and nearly all it builds lives until the run's end: the plugin freezes it and
        # collects again once the tests are collected (hooks.pytest_collection_finish)
        gc.disable()
    try:
        status = int(args.func(args, extra))
        return RunExit.INTERRUPTED if EARLY_SIGNALS and status == RunExit.PASSED else status
    except UsageError as exc:
        return usage.report(f"encoder-conformance {args.command}", str(exc))
    except ProfileError as exc:
        return usage.report(f"encoder-conformance {args.command}", usage.profile_error_text(exc))
    except BrokenPipeError:  # the reader of our output went away (`| head`): no bug of the tool
        return output_closed()
    except Exception:  # a bug of the tool: exit 3, never 1 (which says the device is non-conformant)
        traceback.print_exc()
        print(f"encoder-conformance {args.command}: internal error of the tool: please report it with the output "
              "above", file=sys.stderr)
        return RunExit.INTERNAL_ERROR
    except KeyboardInterrupt:  # before the run took the device into custody: nothing to put back
        print("interrupted", file=sys.stderr)
        # exit now with the documented code: an interrupt that struck inside code the interpreter ran for
        # a plugin can make it end "killed by SIGINT" (-2) after a normal return (seen at ~0.9 s into a run)
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(interrupted_by(EARLY_SIGNALS[-1]) if EARLY_SIGNALS else RunExit.INTERRUPTED)


def console_main() -> None:
    """The command (console script and ``python -m``): ``main``, then end the process at once. Skipping the
    interpreter's finalisation (tearing down a heap of pytest items, hypothesis and pydantic models) saves
    0.3-0.6 s after a run's verdict, measured after a Ctrl-C, where every tenth of a second counts against
    "ends within 2 s". Nothing is lost: the session is over, files and the history are closed, and only
    daemon threads are left."""
    import logging

    try:
        status = main()
        sys.stdout.flush()  # what is still buffered: a closed pipe shows here
    except BrokenPipeError:
        status = output_closed()
    logging.shutdown()
    with contextlib.suppress(BrokenPipeError):
        sys.stderr.flush()
    os._exit(status)


def output_closed() -> int:
    """stdout's reader went away (``| head``): stop quietly, as Python's docs advise (note on SIGPIPE): what is left
    of the output goes to devnull; exit 141, as a program ended by SIGPIPE."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    return interrupted_by(signal.SIGPIPE)


if __name__ == "__main__":
    console_main()
