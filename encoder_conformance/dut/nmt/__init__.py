"""NMT: the one way between states (``nmt_states``), seen by what each state answers (the heartbeat), observers of
the NMT and heartbeat services, the state a reset ends in, errors a device keeps that hold a check."""
