"""CiA numbers, each defined once: CiA 301 (communication: COB-IDs, SDO, NMT, abort codes, signatures)
and CiA 305 (layer setting services). Vocabulary only: no I/O, no behaviour."""
