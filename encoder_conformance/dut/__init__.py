"""The device under test, seen from the tester's side of the bus: the connection and its trace, SDO/NMT/LSS/PDO
access with the waits each service owes, the bench (power switch, actuator), and custody of what the run
changes (snapshot, restore, store watch) so a device is left as found."""
