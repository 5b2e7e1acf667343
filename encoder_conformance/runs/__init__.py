"""Many runs at once: parallel stations, pytest sessions forked from a pre-loaded server, the fault matrix,
the variant matrix, repeated runs and a busy-host companion."""
