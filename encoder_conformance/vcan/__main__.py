"""``python -m encoder_conformance.vcan ACTION ...``: the ``vcan`` command (command.py); ``hub [--daemon] DIR``
runs the hub itself (what ``start_hub`` launches)."""

import sys

from encoder_conformance.vcan import command, hub

if sys.argv[1:2] == ["hub"]:
    sys.exit(hub.main(sys.argv[2:]))
sys.exit(command.main(sys.argv[1:]))
