"""The ``lss`` command's arguments: ``scan``, ``set-node-id``, ``set-bitrate`` (the work is in lss_actions.py).

Light on purpose: the command line builds every parser at start-up, so this imports neither python-can
nor canopen until an ``lss`` command runs.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from encoder_conformance.cia.cia305 import BIT_TIMING_TABLE_0, MAX_NODE_ID, UNCONFIGURED_NODE_ID
from encoder_conformance.cli import usage

BusArguments = Callable[..., None]


def _number(text: str) -> int:
    """argparse type: a 32-bit number, decimal or 0x-hex."""
    try:
        value = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number (decimal or 0x...)") from None
    if not 0 <= value <= 0xFFFFFFFF:
        raise argparse.ArgumentTypeError(f"{text} does not fit 32 bits")
    return value


def _node_id(text: str) -> int:
    """argparse type: a node-ID LSS may configure (1..127, or 255 for 'unconfigured')."""
    value = _number(text)
    if not (1 <= value <= MAX_NODE_ID or value == UNCONFIGURED_NODE_ID):
        raise argparse.ArgumentTypeError(f"node-ID {text}: give 1..{MAX_NODE_ID} ({UNCONFIGURED_NODE_ID} makes the "
                                         "device unconfigured)")
    return value


def bit_timing_index(text: str) -> int:
    """argparse type: a bit rate in bit/s ('500000', '500k', '1M') -> its index in CiA 305 table 0."""
    scaled = text.strip().lower().replace("k", "000").replace("m", "000000")
    by_rate = {rate: index for index, rate in BIT_TIMING_TABLE_0.items()}
    if not scaled.isdigit() or int(scaled) not in by_rate:
        valid = ", ".join(str(rate) for rate in sorted(by_rate, reverse=True))
        raise argparse.ArgumentTypeError(f"{text!r} is not in CiA 305 bit-timing table 0; valid bit/s: {valid}")
    return by_rate[int(scaled)]


def _delay_ms(text: str) -> int:
    value = _number(text)
    if value > 0xFFFF:
        raise argparse.ArgumentTypeError(f"switch delay {text} ms: at most 65535")
    return value


def _cmd_lss(args: argparse.Namespace, extra: list[str]) -> int:

    from encoder_conformance.cli import lss_actions as lss
    from encoder_conformance.profile.loader import load_profile

    bus = usage.bench_bus(args, "for twins start 'encoder-conformance sim --profile ID --copies N --unconfigured "
                                "--listen HOST:PORT' and give --can-interface remote --can-channel ws://HOST:PORT/")
    if args.response_ms <= 0:
        args.parser.error("--response-ms must be above 0")
    profile = load_profile(args.profile).profile if args.profile else None  # ProfileError: a usage error
    options = lss.LssOptions(bus, args.response_ms / 1000, profile)
    if args.lss_command == "scan":
        return lss.scan(options, args.json)
    if (args.vendor is None) != (args.product is None):
        args.parser.error("--vendor and --product go together (switch state selective needs both)")
    target = lss.Target(args.serial, args.vendor, args.product, args.revision)
    if args.lss_command == "set-node-id":
        return lss.set_node_id(options, target, args.new_node_id, args.store)
    return lss.set_bitrate(options, target, args.bit_index, args.store, args.activate)


def add_lss_parser(sub: argparse._SubParsersAction, parser_class: type[argparse.ArgumentParser],
                   bus_arguments: BusArguments) -> None:
    """``lss`` and its three commands under ``sub``."""
    lss = sub.add_parser("lss", help="CiA 305 LSS: list unconfigured devices, give one a node-id or bit rate")
    lsub = lss.add_subparsers(dest="lss_command", required=True, parser_class=parser_class)
    common = argparse.ArgumentParser(add_help=False)
    bus_arguments(common, node_id=False)
    common.add_argument("--response-ms", type=float, default=50.0,
                        help="LSS response window in ms (default 50): each step nobody answers costs this much")
    common.add_argument("--profile", help="device profile: vendor-ID and product code (and revision range) from it")
    chosen = argparse.ArgumentParser(add_help=False)
    chosen.add_argument("--serial", type=_number, required=True, help="serial number (1018h sub 4), e.g. from scan")
    chosen.add_argument("--vendor", type=_number, help="vendor-ID (1018h sub 1)")
    chosen.add_argument("--product", type=_number, help="product code (1018h sub 2)")
    chosen.add_argument("--revision", type=_number, help="revision (1018h sub 3); default: found by identify")
    chosen.add_argument("--store", action="store_true", help="store configuration: the device keeps it at power-off")

    scan = lsub.add_parser("scan", parents=[common], help="list every unconfigured device (fastscan; changes none)")
    scan.add_argument("--json", action="store_true", help="print the result as one JSON object")
    node_id = lsub.add_parser("set-node-id", parents=[common, chosen], help="give one device a node-id")
    node_id.add_argument("new_node_id", metavar="NEW_ID", type=_node_id)
    bitrate = lsub.add_parser("set-bitrate", parents=[common, chosen], help="set one device's bit rate")
    bitrate.add_argument("bit_index", metavar="BITRATE", type=bit_timing_index, help="bit/s, e.g. 250000 or 250k")
    bitrate.add_argument("--activate", type=_delay_ms, metavar="DELAY_MS",
                         help="also send activate bit timing with this switch delay: the device changes rate")
    for parser in (scan, node_id, bitrate):
        parser.set_defaults(func=_cmd_lss, parser=parser)
