"""EDS (CiA 306) import and export for device profiles, one module per job.

Import: vendor EDS files are first cleaned into a temporary copy (``ini_text``: BOM and encoding,
odd casing, comments, duplicated sections and keys, missing ``[DummyUsage]`` entries, number
formats; ``repair``: object sections, CompactSubObj arrays), then read with ``canopen.import_od``
(``importer``); every repair is reported. The object dictionary becomes profile-shaped
``objects:`` entries, or a whole profile draft with TODO notes (``draft``).

Export (``export``): a profile becomes an EDS through ``od_builder.build_object_dictionary`` and
canopen's exporter, so other CANopen tools can drive the simulated twin.
"""

from encoder_conformance.profile.eds.draft import profile_draft_from_eds
from encoder_conformance.profile.eds.draft_yaml import write_profile_draft
from encoder_conformance.profile.eds.export import export_eds
from encoder_conformance.profile.eds.importer import EdsImport, objects_from_eds, read_eds
from encoder_conformance.profile.eds.numbers import normalise_node_id_formula, parse_number
from encoder_conformance.profile.eds.repair import CleanedEds, clean_eds

__all__ = [
    "CleanedEds", "EdsImport", "clean_eds", "export_eds", "normalise_node_id_formula", "objects_from_eds",
    "parse_number", "profile_draft_from_eds", "read_eds", "write_profile_draft",
]
