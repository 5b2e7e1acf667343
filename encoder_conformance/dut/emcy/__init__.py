"""EMCY: the ways to make a device send an emergency (the bench's error stimulus, a SYNC of the wrong length)."""
