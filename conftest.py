"""The suites' pytest set-up, beside them (copied into the wheel with them).

The plugin (options, hooks, reports) is encoder_conformance/plugin/hooks.py, registered by the package's
``pytest11`` entry point; it is named here too so that a checkout works without installing the package
(a plugin is registered once under its module name). This file adds what only lives beside the suites:
their fixtures, which are modules of the fixtures/ folder next to it.
"""

pytest_plugins = [
    "encoder_conformance.plugin.hooks",
    "fixtures.bus",
    "fixtures.simulator",
    "fixtures.dut",
    "fixtures.periodic",
    "fixtures.evidence",
    "fixtures.emcy",
    "fixtures.tpdo",
    "fixtures.lss",
    "fixtures.encoder",
]
