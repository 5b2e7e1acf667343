"""``store --profile P --node-id N``: its arguments (the work, which imports the DUT layer, is in store_actions.py)."""

from __future__ import annotations

import argparse

from encoder_conformance.cli import usage
from encoder_conformance.cli.usage import bus_arguments

EPILOG = ("Exit codes: 0 stored, every store command confirmed by the device; 1 the device refused one (its abort "
          "code named) or a store that reboots sent no boot-up; 4 usage (options, a profile without a store "
          "command); 69 the bus, no answer at the node-ID, another product than the profile's, or no answer to "
          "the store; 130 Ctrl-C.")


def _cmd_store(args: argparse.Namespace, extra: list[str]) -> int:
    from encoder_conformance.cli.store_actions import StoreRequest, store_parameters
    from encoder_conformance.profile.loader import load_profile

    usage.check_profile("--profile", args.profile)
    profile = load_profile(args.profile).profile
    bus = usage.bench_bus(args, "the built-in simulator keeps nothing for you")
    return store_parameters(StoreRequest(profile, bus, args.node_id or profile.bus.node_id))


def add_store_parser(sub: argparse._SubParsersAction) -> None:
    """``store``: make the device keep what it holds now, as a factory does (1010h 'save', the profile's commands)."""
    store = sub.add_parser(
        "store", help="store the device's parameters as a factory does (1010h 'save' per the profile)",
        description="Send the store commands the profile declares (1010h sub 1 'save' where the device has it, "
                    "else each group's sub-index, and a manufacturer's store object), each confirmed by the "
                    "device's answer: what a simulator's storage file or a device's flash should hold before a run.",
        epilog=EPILOG)
    store.add_argument("--profile", required=True, help="the device's profile (YAML file or shipped id)")
    bus_arguments(store)
    store.set_defaults(func=_cmd_store)
