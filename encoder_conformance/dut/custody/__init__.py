"""Custody: the snapshot as found, the journal of settings a test changed, the give-back (write order, aliased
entries, the reference point) and its record, so a device is left as found."""
