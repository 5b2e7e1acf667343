"""The encoder's own function as an executable reference (CiA 406 and the profile's quirks).

Pure Python, no I/O: ``position`` (shaft angle -> position value, preset offset), ``cam`` (CAM
state with hysteresis), ``work_area``, ``speed``, ``limit_switch`` (POSITAL's flag bits),
``objects`` (where each role lives), ``settings`` (the inputs, read alike from the twin and from a
device) and ``reference`` (the stateful whole). The twin computes its values with it and the
suites take their expectations from it, so the two cannot disagree silently; its own invariants
are property-tested in tests/test_encoder_model.py.
"""

from encoder_conformance.models.encoder.reference import EncoderReference
from encoder_conformance.models.encoder.settings import EncoderDescription, EncoderSettings, read_settings

__all__ = ["EncoderDescription", "EncoderReference", "EncoderSettings", "read_settings"]
