"""Configuration a bench brings: the station file and the CAN bus settings (with where each came from)."""
