"""Pure models the twin and the suites share: the encoder's position arithmetic (CiA 406), the NMT state
machine (CiA 301) and the timing statistics both judge frames with. No bus, no pytest."""
