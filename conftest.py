"""The suites' pytest set-up, beside them (copied into the wheel with them).

The plugin (options, hooks, reports) is encoder_conformance/plugin/hooks.py, registered by the package's
``pytest11`` entry point; it is named here too so that a checkout works without installing the package
(a plugin is registered once under its module name). This file adds what only lives beside the suites:
their fixtures, the modules of the fixtures/ folder next to it, registered under the package's own name
(encoder_conformance/plugin/fixtures: ``fixtures`` is a PyPI name too), and the options' former spellings
(plugin/former_spellings.py: ``--station`` for ``--ec-station``, for one release, only in the suites' sessions).
"""

pytest_plugins = [
    "encoder_conformance.plugin.hooks",
    "encoder_conformance.plugin.former_spellings",
    "encoder_conformance.plugin.fixtures.bus",
    "encoder_conformance.plugin.fixtures.simulator",
    "encoder_conformance.plugin.fixtures.dut",
    "encoder_conformance.plugin.fixtures.periodic",
    "encoder_conformance.plugin.fixtures.evidence",
    "encoder_conformance.plugin.fixtures.emcy",
    "encoder_conformance.plugin.fixtures.tpdo",
    "encoder_conformance.plugin.fixtures.lss",
    "encoder_conformance.plugin.fixtures.encoder",
]
